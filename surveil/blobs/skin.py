"""Per-pixel skin classification compiled into a colour lookup table (paper 004 section 6.2).

The paper trained a neural network per camera. Here any scikit-learn classifier is trained on
colour features (:func:`colour_features`), then evaluated once on the centre of every bin of a
quantised BGR cube; :meth:`SkinModel.classify` is then one table lookup per pixel.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any, Protocol

import numpy as np

from surveil.blobs.settings import SkinConfig
from surveil.validate import readonly, require_shape

log = logging.getLogger(__name__)

COLOUR_SPACES = ("rgi", "ycrcb")
DEFAULT_MODEL_RESOURCE = "skin_default.npz"


class ProbabilisticClassifier(Protocol):
    def predict_proba(self, x: np.ndarray) -> np.ndarray: ...


def colour_features(bgr: np.ndarray, colour_space: str) -> np.ndarray:
    """Features of colours for the classifier.

    Parameters
    ----------
    bgr : (N, 3) uint8 or float, BGR in 0..255
    colour_space : ``"rgi"`` -- normalised chromaticity r = R/S, g = G/S and intensity S/765
        (S = R + G + B); ``"ycrcb"`` -- the BT.601 Y, Cr, Cb (as OpenCV), divided by 255.

    Returns
    -------
    (N, 3) float32

    >>> colour_features(np.array([[0, 0, 255]]), "rgi").astype(np.float64).round(3).tolist()
    [[1.0, 0.0, 0.333]]
    """
    require_shape("bgr", bgr, (None, 3), np.number)
    x = bgr.astype(np.float32) / np.float32(255.0)
    b, g, r = x[:, 0], x[:, 1], x[:, 2]
    match colour_space:
        case "rgi":
            s = r + g + b
            safe = np.where(s > 0, s, np.float32(1.0))
            third = np.float32(1.0 / 3.0)
            rn = np.where(s > 0, r / safe, third)
            gn = np.where(s > 0, g / safe, third)
            return np.stack([rn, gn, s / 3.0], axis=1).astype(np.float32)
        case "ycrcb":
            y = 0.299 * r + 0.587 * g + 0.114 * b
            cr = (r - y) * 0.713 + 0.5
            cb = (b - y) * 0.564 + 0.5
            return np.stack([y, cr, cb], axis=1).astype(np.float32)
    raise ValueError(f"colour_space must be one of {COLOUR_SPACES}, got {colour_space!r}")


@dataclass(frozen=True, slots=True)
class SkinModel:
    """A skin classifier as a lookup table over quantised BGR.

    lut : (n, n, n) bool, n = 2**bits, indexed ``[b >> s, g >> s, r >> s]`` with s = 8 - bits
    bits : 5 or 6
    meta : free-form description (colour space, classifier, training data, scores)
    """

    lut: np.ndarray
    bits: int
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.bits not in (5, 6):
            raise ValueError(f"bits must be 5 or 6, got {self.bits}")
        n = 1 << self.bits
        require_shape("lut", self.lut, (n, n, n), np.bool_)
        readonly(self.lut)

    def classify(self, bgr: np.ndarray, boxes: np.ndarray | None = None) -> np.ndarray:
        """(H, W) bool skin mask of an (H, W, 3) uint8 BGR image (one lookup per pixel).

        boxes : (k, 4) int x0, y0, x1, y1 (end exclusive), optional -- classify only inside
            them (``Silhouettes.boxes``: skin matters only in and near people, a small part
            of most frames); pixels outside every box are False

        >>> m = SkinModel(np.ones((32, 32, 32), bool), 5)
        >>> m.classify(np.zeros((2, 3, 3), np.uint8)).shape
        (2, 3)
        >>> box = np.array([[1, 0, 3, 1]])  # x0, y0, x1, y1
        >>> m.classify(np.zeros((2, 3, 3), np.uint8), box).astype(int).tolist()
        [[0, 1, 1], [0, 0, 0]]
        """
        require_shape("bgr", bgr, (None, None, 3), np.uint8)
        if boxes is None:
            return self._lookup(bgr)
        out = np.zeros(bgr.shape[:2], np.bool_)
        for x0, y0, x1, y1 in np.asarray(boxes, np.int64).reshape(-1, 4).tolist():
            out[y0:y1, x0:x1] = self._lookup(bgr[y0:y1, x0:x1])
        return out

    def _lookup(self, bgr: np.ndarray) -> np.ndarray:
        s = 8 - self.bits
        q = (bgr >> np.uint8(s)).astype(np.int32)
        # flat index b * n^2 + g * n + r
        flat = (q[..., 0] << (2 * self.bits)) | (q[..., 1] << self.bits) | q[..., 2]
        return np.take(self.lut.reshape(-1), flat)


def bin_centres(bits: int) -> np.ndarray:
    """(n^3, 3) float64 BGR centres of every LUT bin, in the LUT's flat (C) order."""
    n = 1 << bits
    step = 256 // n
    c = np.arange(n) * step + (step - 1) / 2.0
    b, g, r = np.meshgrid(c, c, c, indexing="ij")
    return np.stack([b.ravel(), g.ravel(), r.ravel()], axis=1)


def train_skin_classifier(
    pixels_bgr: np.ndarray,
    labels: np.ndarray,
    cfg: SkinConfig,
    rng: np.random.Generator,
    colour_space: str = "rgi",
) -> ProbabilisticClassifier:
    """Fit a gradient-boosted tree classifier of skin on colour features.

    Parameters
    ----------
    pixels_bgr : (N, 3) uint8 BGR
    labels : (N,) bool, True = skin
    cfg : SkinConfig (``max_iter``, ``max_train_pixels``)
    rng : seeds the subsample and the classifier
    colour_space : see :func:`colour_features`
    """
    from sklearn.ensemble import HistGradientBoostingClassifier

    require_shape("pixels_bgr", pixels_bgr, (None, 3), np.uint8)
    require_shape("labels", labels, (len(pixels_bgr),), np.bool_)
    if labels.all() or not labels.any():
        raise ValueError("labels must hold both skin (True) and non-skin (False) pixels")
    weights = np.ones(len(labels))
    if len(labels) > cfg.max_train_pixels or cfg.balanced:
        # skin is rare in frames: keep up to half the budget of each class; either weight
        # the subsampled classes equally (balanced) or so that the classifier still learns
        # the true skin prior
        half = cfg.max_train_pixels // 2
        keep, w = [], []
        for idx in (np.flatnonzero(labels), np.flatnonzero(~labels)):
            chosen = idx if len(idx) <= half else rng.choice(idx, half, replace=False)
            keep.append(chosen)
            w.append(np.full(len(chosen), len(idx) / len(chosen)))
        keep_idx = np.concatenate(keep)
        pixels_bgr, labels = pixels_bgr[keep_idx], labels[keep_idx]
        weights = np.concatenate(w)
        if cfg.balanced:
            weights = np.where(labels, len(labels) / (2.0 * labels.sum()), 1.0)
            weights[~labels] = len(labels) / (2.0 * (~labels).sum())
    clf = HistGradientBoostingClassifier(
        max_iter=cfg.max_iter,
        learning_rate=0.1,
        max_leaf_nodes=31,
        early_stopping=False,
        random_state=int(rng.integers(2**31 - 1)),
    )
    clf.fit(colour_features(pixels_bgr, colour_space), labels, sample_weight=weights)
    return clf


def compile_skin_lut(
    classifier: ProbabilisticClassifier,
    colour_space: str,
    bits: int = 6,
    threshold: float = 0.5,
    meta: dict[str, Any] | None = None,
) -> SkinModel:
    """Evaluate ``classifier`` (predict_proba column 1 = skin) on every bin centre."""
    centres = bin_centres(bits)
    p = classifier.predict_proba(colour_features(centres, colour_space))[:, 1]
    n = 1 << bits
    lut = (p >= threshold).reshape(n, n, n)
    info = {"colour_space": colour_space, "threshold": float(threshold)}
    info.update(meta or {})
    return SkinModel(lut, bits, info)


def train_skin_model(
    pixels_bgr: np.ndarray,
    labels: np.ndarray,
    cfg: SkinConfig,
    rng: np.random.Generator,
    colour_space: str = "rgi",
) -> SkinModel:
    """Train a skin classifier (:func:`train_skin_classifier`) and compile its LUT.

    Parameters
    ----------
    pixels_bgr : (N, 3) uint8 BGR;  labels : (N,) bool, True = skin
    cfg : SkinConfig (``lut_bits``, ``threshold``, ``max_iter``, ``max_train_pixels``)
    rng : numpy Generator (subsample, classifier seed)
    colour_space : ``"rgi"`` or ``"ycrcb"``
    """
    clf = train_skin_classifier(pixels_bgr, labels, cfg, rng, colour_space)
    meta = {"classifier": "HistGradientBoostingClassifier", "n_train": int(len(labels))}
    return compile_skin_lut(clf, colour_space, cfg.lut_bits, cfg.threshold, meta)


@cache
def default_skin_model() -> SkinModel:
    """The generic skin model shipped as ``surveil/defaults/skin_default.npz``.

    Trained by :func:`surveil.io.skin_model.build_default_skin_model` (see docs/blobs.md) on
    pixels of synthetic recordings (ground-truth masks) plus the face of
    ``skimage.data.astronaut()``. Cached: every caller shares one read-only model.
    """
    from surveil.io.skin_model import load_skin_model

    ref = resources.files("surveil") / "defaults" / DEFAULT_MODEL_RESOURCE
    with resources.as_file(ref) as path:
        return load_skin_model(path)
