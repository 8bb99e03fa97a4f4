"""Per-camera observations: silhouettes, skin and skin blobs (paper 004 sections 6.1-6.2)."""

from surveil.blobs.background import BackgroundModel, silhouettes_from_mask
from surveil.blobs.extract import SceneryMask, blob_margin_px, extract_blobs, observe
from surveil.blobs.settings import BackgroundConfig, BlobConfig, SkinConfig
from surveil.blobs.skin import (
    SkinModel,
    colour_features,
    compile_skin_lut,
    default_skin_model,
    train_skin_classifier,
    train_skin_model,
)

__all__ = [
    "BackgroundConfig",
    "BackgroundModel",
    "BlobConfig",
    "SceneryMask",
    "SkinConfig",
    "SkinModel",
    "blob_margin_px",
    "colour_features",
    "compile_skin_lut",
    "default_skin_model",
    "extract_blobs",
    "observe",
    "silhouettes_from_mask",
    "train_skin_classifier",
    "train_skin_model",
]
