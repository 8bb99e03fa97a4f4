"""Skin model files (``.npz``) and skin training pixels read from synthetic recordings.

File layout (``np.savez_compressed``): ``lut`` (n, n, n) bool, ``bits`` int, ``meta`` a JSON
string, ``format`` = ``"surveil-skin-lut"``, ``version`` = 1.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import cv2
import numpy as np

from surveil.blobs.settings import SkinConfig
from surveil.blobs.skin import SkinModel, train_skin_model
from surveil.errors import InputError
from surveil.io.ground_truth import MaskClass
from surveil.io.recording import open_recording

log = logging.getLogger(__name__)

FORMAT_NAME = "surveil-skin-lut"
FORMAT_VERSION = 1


def save_skin_model(model: SkinModel, path: Path) -> None:
    """Write ``model`` to ``path`` (an ``.npz``; compressed)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        np.savez_compressed(
            f,
            format=np.array(FORMAT_NAME),
            version=np.array(FORMAT_VERSION),
            lut=model.lut,
            bits=np.array(model.bits),
            meta=np.array(json.dumps(model.meta, sort_keys=True)),
        )


def load_skin_model(path: Path) -> SkinModel:
    """Read a model written by :func:`save_skin_model`.

    Raises
    ------
    InputError
        The file is missing, not an npz, or not a skin LUT of a known version.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["format"]) != FORMAT_NAME or int(z["version"]) != FORMAT_VERSION:
                raise InputError(
                    f"{path}: not a {FORMAT_NAME} v{FORMAT_VERSION} file "
                    f"(format={z['format']}, version={z['version']})"
                )
            return SkinModel(z["lut"].astype(bool), int(z["bits"]), json.loads(str(z["meta"])))
    except (OSError, KeyError, ValueError) as exc:
        raise InputError(f"{path}: cannot read skin model: {exc}") from None


def training_pixels_from_recording(
    recording_dir: Path, every: int = 1, pixel_step: int = 2
) -> tuple[np.ndarray, np.ndarray]:
    """Labelled pixels of a synthetic recording: its frames and ground-truth masks.

    Parameters
    ----------
    recording_dir : a recording with ``ground_truth/masks/<cam>/<frame:06d>.png``
    every : use frame sets whose index is a multiple of ``every`` (and which have a mask)
    pixel_step : take every ``pixel_step``-th row and column of each frame

    Returns
    -------
    pixels : (N, 3) uint8 BGR;  labels : (N,) bool, True where the mask's blue channel is
        ``MaskClass.SKIN`` (a person's skin; the skin-coloured distractors are negatives)
    """
    rec = open_recording(Path(recording_dir))
    gt = rec.ground_truth_dir
    if gt is None or not (gt / "masks").is_dir():
        raise InputError(f"{recording_dir}: no ground_truth/masks to train a skin model on")
    pixels, labels = [], []
    for fs in rec.framesets():
        if fs.index % every:
            continue
        for cam, img in fs.images.items():
            mask_path = gt / "masks" / cam / f"{fs.index:06d}.png"
            if not mask_path.is_file():
                continue
            mask = cv2.imread(str(mask_path), cv2.IMREAD_COLOR)
            if mask is None or mask.shape != img.shape:
                raise InputError(f"{mask_path}: unreadable or not the size of its frame")
            pixels.append(img[::pixel_step, ::pixel_step].reshape(-1, 3))
            labels.append(mask[::pixel_step, ::pixel_step, 0].ravel() == MaskClass.SKIN)
    if not pixels:
        raise InputError(f"{recording_dir}: no frame has a ground-truth mask")
    return np.concatenate(pixels), np.concatenate(labels)


def photo_training_pixels() -> tuple[np.ndarray, np.ndarray]:
    """Skin and non-skin pixels of scikit-image's bundled ``astronaut`` photograph.

    Skin: the left half of the face (rows 90:170, cols 185:225) less its dark (hair, eyes)
    and low-red pixels. Non-skin: the orange suit, helmet and table (rows 300:512). The right
    half of the face, the flag and the grey backdrop are left out (held out for tests).
    """
    from skimage import data

    bgr = np.ascontiguousarray(data.astronaut()[..., ::-1])
    face = bgr[90:170, 185:225].reshape(-1, 3).astype(np.int16)
    ok = (face.sum(axis=1) > 200) & (face[:, 2] > face[:, 1] + 15) & (face[:, 2] > 110)
    skin = face[ok].astype(np.uint8)
    non = bgr[300:512:2, 0:512:2].reshape(-1, 3)
    return np.concatenate([skin, non]), np.concatenate(
        [np.ones(len(skin), bool), np.zeros(len(non), bool)]
    )


def build_default_skin_model(
    recording_dirs: list[Path], rng: np.random.Generator, cfg: SkinConfig | None = None
) -> SkinModel:
    """Train the generic default model on synthetic recordings plus the astronaut photo."""
    cfg = cfg or SkinConfig()
    parts = [training_pixels_from_recording(d) for d in recording_dirs]
    parts.append(photo_training_pixels())
    pixels = np.concatenate([p for p, _ in parts])
    labels = np.concatenate([lab for _, lab in parts])
    log.info("default skin model: %d pixels, %d skin", len(labels), int(labels.sum()))
    return train_skin_model(pixels, labels, cfg, rng)
