"""Skin model files (``.npz``) and skin training pixels read from synthetic recordings.

File layout (``np.savez_compressed``): ``lut`` (n, n, n) bool, ``bits`` int, ``meta`` a JSON
string, ``format`` = ``"surveil-skin-lut"``, ``version`` = 1.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Callable, Sequence
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
    recording_dir: Path,
    every: int = 1,
    pixel_step: int = 2,
    *,
    cameras: Sequence[str] | None = None,
    background_fraction: float = 1.0,
    rng: np.random.Generator | None = None,
    on_progress: Callable[[int, int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Labelled pixels of an annotated recording: its frames and ``ground_truth/masks``.

    Parameters
    ----------
    recording_dir : a recording with ``ground_truth/masks/<cam>/<frame:06d>.png`` (written by
        ``surveil synth``, or painted by a person: blue channel = ``MaskClass``, green = person
        number, 0 = no person; see docs/formats.md)
    every : use frame sets whose index is a multiple of ``every`` (and which have a mask)
    pixel_step : take every ``pixel_step``-th row and column of each frame
    cameras : only these cameras (default: all)
    background_fraction : keep this random fraction of the non-person pixels (green = 0);
        person pixels are all kept
    rng : draws the background subsample (required when ``background_fraction < 1``)

    Returns
    -------
    pixels : (N, 3) uint8 BGR;  labels : (N,) bool, True where the mask's blue channel is
        ``MaskClass.SKIN`` (a person's skin; the skin-coloured distractors are negatives)
    """
    if background_fraction < 1.0 and rng is None:
        raise ValueError("rng is required when background_fraction < 1")
    rec = open_recording(Path(recording_dir))
    gt = rec.ground_truth_dir
    if gt is None or not (gt / "masks").is_dir():
        raise InputError(
            f"{recording_dir}: no ground_truth/masks to train a skin model on (annotate frames "
            "as ground_truth/masks/<camera>/<frame:06d>.png, see docs/formats.md)"
        )
    wanted = set(rec.camera_names if cameras is None else cameras)
    pixels, labels = [], []
    total = rec.n_framesets
    for fs in rec.framesets():
        if on_progress is not None:
            on_progress(fs.index + 1, total)
        if fs.index % every:
            continue
        for cam, img in fs.images.items():
            if cam not in wanted:
                continue
            mask_path = gt / "masks" / cam / f"{fs.index:06d}.png"
            if not mask_path.is_file():
                continue
            mask = cv2.imread(str(mask_path), cv2.IMREAD_COLOR)
            if mask is None or mask.shape != img.shape:
                raise InputError(f"{mask_path}: unreadable or not the size of its frame")
            px = img[::pixel_step, ::pixel_step].reshape(-1, 3)
            m = mask[::pixel_step, ::pixel_step].reshape(-1, 3)
            keep = m[:, 1] > 0
            if background_fraction >= 1.0:
                keep[:] = True
            elif background_fraction > 0.0:
                keep |= rng.random(len(keep)) < background_fraction
            pixels.append(px[keep])
            labels.append(m[keep, 0] == MaskClass.SKIN)
    if not pixels:
        raise InputError(f"{recording_dir}: no frame of {sorted(wanted)} has a ground-truth mask")
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
    recording_dirs: Sequence[Path],
    rng: np.random.Generator,
    cfg: SkinConfig | None = None,
    every: int = 3,
) -> SkinModel:
    """Train the generic default model on synthetic recordings plus the astronaut photo."""
    cfg = cfg or SkinConfig()
    parts = [
        training_pixels_from_recording(
            d, every, background_fraction=cfg.background_fraction, rng=rng
        )
        for d in recording_dirs
    ]
    parts.append(photo_training_pixels())
    pixels = np.concatenate([p for p, _ in parts])
    labels = np.concatenate([lab for _, lab in parts])
    log.info("default skin model: %d pixels, %d skin", len(labels), int(labels.sum()))
    model = train_skin_model(pixels, labels, cfg, rng)
    names = ", ".join(Path(d).name for d in recording_dirs)
    return dataclasses.replace(
        model, meta={**model.meta, "trained_on": f"{names} + skimage astronaut left half-face"}
    )


def skin_models_dir(rig_path: Path) -> Path:
    """Where per-camera skin models of a rig live: ``<rig dir>/<rig stem>_skin/``."""
    rig_path = Path(rig_path)
    return rig_path.parent / f"{rig_path.stem}_skin"


def train_camera_skin_models(
    recording_dir: Path,
    rng: np.random.Generator,
    cfg: SkinConfig | None = None,
    every: int = 2,
    on_progress: Callable[[int, int], None] | None = None,
) -> dict[str, SkinModel]:
    """One skin model per camera of an annotated recording (paper 004 section 6.2: cameras
    differ in gain and white balance, so each gets its own classifier).

    Each classifier's table is compiled at ``cfg.camera_threshold`` and, with
    ``cfg.bound_by_generic``, ANDed with the generic default model (docs/blobs.md,
    "Per-camera models").
    """
    from surveil.blobs.skin import default_skin_model

    cfg = cfg or SkinConfig()
    rec = open_recording(Path(recording_dir))
    generic = default_skin_model() if cfg.bound_by_generic else None
    models = {}
    for i, cam in enumerate(rec.camera_names):
        pixels, labels = training_pixels_from_recording(
            recording_dir,
            every,
            cameras=[cam],
            background_fraction=cfg.background_fraction,
            rng=rng,
        )
        if not labels.any():
            raise InputError(f"{recording_dir}: camera {cam} has no annotated skin pixel")
        model = train_skin_model(
            pixels, labels, dataclasses.replace(cfg, threshold=cfg.camera_threshold), rng
        )
        meta = {**model.meta, "camera": cam, "trained_on": Path(recording_dir).name}
        if generic is not None:
            model = bound_skin_model(model, generic)
            meta["bounded_by"] = generic.meta.get("trained_on", "generic default model")
        models[cam] = dataclasses.replace(model, meta=meta)
        if on_progress is not None:
            on_progress(i + 1, len(rec.camera_names))
    return models


def bound_skin_model(model: SkinModel, bound: SkinModel) -> SkinModel:
    """``model`` restricted to the colours ``bound`` also calls skin (tables ANDed).

    >>> a, b = np.zeros((32, 32, 32), bool), np.zeros((32, 32, 32), bool)
    >>> a[:2], b[1:] = True, True
    >>> int(bound_skin_model(SkinModel(a, 5), SkinModel(b, 5)).lut.sum()) == 32 * 32
    True
    """
    if model.bits != bound.bits:
        raise ValueError(f"lookup tables differ in bits: {model.bits} and {bound.bits}")
    return dataclasses.replace(model, lut=model.lut & bound.lut)


def load_camera_skin_models(rig_path: Path, camera_names: Sequence[str]) -> dict[str, SkinModel]:
    """The per-camera models saved beside ``rig_path`` (``<cam>.npz``) where they exist, the
    generic default model for the other cameras."""
    from surveil.blobs.skin import default_skin_model

    folder = skin_models_dir(rig_path)
    models = {}
    for cam in camera_names:
        path = folder / f"{cam}.npz"
        models[cam] = load_skin_model(path) if path.is_file() else default_skin_model()
        log.debug("skin model for %s: %s", cam, path if path.is_file() else "default")
    return models
