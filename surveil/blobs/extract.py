"""Skin blobs inside person silhouettes (paper 004 section 6.2)."""

from __future__ import annotations

import math

import cv2
import numpy as np

from surveil.blobs.background import BackgroundModel
from surveil.blobs.components import components_with_stats
from surveil.blobs.settings import BlobConfig
from surveil.blobs.skin import SkinModel
from surveil.datatypes import BlobSet, CameraObservation, Silhouettes
from surveil.validate import require_shape

REFERENCE_WIDTH_PX = 640  # frame width the pixel sizes of BlobConfig.open_px are given for
# Sobel magnitude added to both sides of the ghost test's ratio: on flat surfaces both
# gradients are sensor noise and compression (a few grey levels), and their ratio is
# meaningless there
EDGE_FLOOR = 8.0
OUTLINE_PX = 2  # a blob pixel this close to the outside of every silhouette is on its outline
# a bare forearm with its hand is ~5 times longer than wide; a face with its neck ~2 times
ARM_ASPECT = 3.0
# shoulders are this fraction of a silhouette's height below its top (shoulder height is
# 0.818 of a person's height, Drillis and Contini); a bare forearm's hand is its end
# farther from there
SHOULDER_DROP_REL = 0.18
# where a bare forearm can lie, as fractions of its silhouette's height from the top: below the
# head (the top 0.13 of a person's height; Drillis and Contini) and above the shins (a hanging
# hand's fingertips are 0.62 from the top, the knees 0.715; seen from above, as the room's
# cameras do, a hand swinging while walking reaches 0.75 of the silhouette)
HEAD_ZONE_REL = 0.1
KNEE_REL = 0.8
# ... and a blob reaching into the head's zone is the head's unless its centroid lies farther
# than this from the silhouette's centre column (a head is 0.09 of a person's height wide):
# there it is a forearm raised beside the head
HEAD_HALF_WIDTH_REL = 0.07
LIMBS_PER_PERSON = 3  # a head and two hands: blobs the opening erased only fill these
MIN_OUTLINE_PX = 5  # fewer outline pixels than this: no verdict, the blob is kept


def _open(mask: np.ndarray, diameter_px: int) -> np.ndarray:
    """Morphological opening of a bool mask with an elliptical kernel, outside the frame
    counting as empty (computed on the mask's bounding box: the opening of empty space is
    empty)."""
    x, y, w, h = cv2.boundingRect(mask.view(np.uint8))
    out = np.zeros_like(mask)
    if w and h:
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (diameter_px, diameter_px))
        crop = np.ascontiguousarray(mask[y : y + h, x : x + w]).view(np.uint8)
        opened = cv2.morphologyEx(
            crop, cv2.MORPH_OPEN, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0
        )
        out[y : y + h, x : x + w] = opened > 0
    return out


def _open_keeping_isolated(
    mask: np.ndarray, diameter_px: int, min_area_px: int
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_open`, except that a connected region of ``mask`` (8-connected) of which the
    opening leaves something, but less than ``min_area_px``, is kept whole. Returns the
    result and the kept regions' pixels.

    The opening is there to cut thin bridges between regions (colour fringes joining a head
    and a hand). A region it would shrink below a blob's size was not joined to anything big:
    a hand seen edge-on, two or three pixels wide. A region of which nothing survives (a
    one-pixel fringe) stays erased. A kept region cannot touch what the opening keeps of the
    other regions (they would be one region), so the result's components are the opened
    ones plus the kept regions unchanged."""
    opened = _open(mask, diameter_px)
    restored = np.zeros_like(mask)
    x, y, w, h = cv2.boundingRect(mask.view(np.uint8))
    if not (w and h):
        return opened, restored
    box = slice(y, y + h), slice(x, x + w)
    n, labels = cv2.connectedComponents(
        np.ascontiguousarray(mask[box]).view(np.uint8), connectivity=8, ltype=cv2.CV_32S
    )
    left = np.bincount(labels[opened[box]], minlength=n)
    keep = (left > 0) & (left < min_area_px)
    keep[0] = False
    restored[box] = np.take(keep, labels)  # a table lookup per pixel; take is the fast one
    return opened | restored, restored


def _majority_silhouette(
    blob_px: np.ndarray, sil_px: np.ndarray, n_blobs: int, n_sil: int
) -> np.ndarray:
    """(n_blobs,) int32: per blob, the silhouette label (>= 1) under most of its pixels
    (``blob_px``, ``sil_px``: blob index and silhouette label of each pixel; 1 when none).

    >>> _majority_silhouette(np.array([0, 0, 0, 1]), np.array([2, 2, 1, 0]), 2, 3).tolist()
    [2, 1]
    """
    votes = np.bincount(blob_px * n_sil + sil_px, minlength=n_blobs * n_sil).reshape(
        n_blobs, n_sil
    )
    votes[:, 0] = -1
    return votes.argmax(axis=1).astype(np.int32)


def _relative_v(v_px: np.ndarray, sil_labels: np.ndarray, silhouettes: Silhouettes) -> np.ndarray:
    """rel_v = (v - top) / (bottom - top) of each row ``v_px`` in its silhouette
    ``sil_labels`` (1-based; 0, no silhouette, is read as silhouette 1: callers mask it)."""
    i = np.maximum(np.asarray(sil_labels), 1) - 1
    top = np.asarray(silhouettes.top_v_px)[i]
    bottom = np.asarray(silhouettes.bottom_v_px)[i]
    return (v_px - top) / np.maximum(bottom - top, 1.0)


def _outside_band(
    ok: np.ndarray,
    restored: np.ndarray,
    centroids: np.ndarray,
    sil_of: np.ndarray,
    silhouettes: Silhouettes,
    cfg: BlobConfig,
) -> np.ndarray:
    """(len(ok),) bool: the restored blobs of ``ok`` (0-based component indices) whose
    centroid lies outside the band [restore_min_rel_v, restore_max_rel_v] of their
    silhouette's height, where a hand hanging at the side is (docs/blobs.md)."""
    comp = ok + 1
    lab = sil_of[comp]
    has = lab > 0
    rel_v = _relative_v(centroids[comp, 1], lab, silhouettes)
    inside = has & (rel_v >= cfg.restore_min_rel_v) & (rel_v <= cfg.restore_max_rel_v)
    return restored[comp] & ~inside


def _scenery_shares(
    blobs: np.ndarray,
    labels: np.ndarray,
    areas: np.ndarray,
    scenery: np.ndarray,
    changed: np.ndarray,
) -> np.ndarray:
    """(len(blobs),) share of each blob's pixels (``blobs``: 0-based component indices) that
    are skin-coloured scenery unchanged to the background model. Counted over the blob
    pixels only: the scenery mask is sparse there, so the count costs a fifth of a
    :func:`pixel_share` over the region."""
    on = (labels > 0) & scenery & ~changed
    hits = np.bincount(labels[on], minlength=len(areas) + 1)
    return hits[blobs + 1] / np.maximum(areas[blobs], 1)


def _at_silhouette_top(
    blobs: np.ndarray,
    labels: np.ndarray,
    stats: np.ndarray,
    sil: np.ndarray,
    centroids: np.ndarray,
    silhouettes: Silhouettes,
    cfg: BlobConfig,
) -> np.ndarray:
    """(len(blobs),) bool: which of ``blobs`` (0-based component indices) have their centroid
    above ``cfg.scenery_min_rel_v`` of their majority silhouette's height, where a head is.
    The closing takes scenery in between limbs and body, not above the head; a dark head
    in front of a skin-coloured board, camouflaged, reads as unchanged scenery (three_people,
    cam0)."""
    lab = np.zeros(len(blobs), np.int64)  # majority silhouette under each blob
    for i, k in enumerate(blobs.tolist()):
        x, y, w, h = (int(v) for v in stats[k + 1, :4])
        box = slice(y, y + h), slice(x, x + w)
        under = sil[box][labels[box] == k + 1]
        lab[i] = np.bincount(under).argmax() if len(under) else 0
    rel_v = _relative_v(centroids[blobs + 1, 1], lab, silhouettes)
    return (lab > 0) & (rel_v < cfg.scenery_min_rel_v)


def _fill_missing_limbs(
    ok: np.ndarray, restored: np.ndarray, areas: np.ndarray, sil_of: np.ndarray
) -> np.ndarray:
    """The blobs of ``ok`` (0-based component indices) with the restored ones only where a
    silhouette has fewer than three plain blobs (a head and two hands): the largest restored
    blobs of each silhouette fill its missing limbs, the rest are dropped.

    ``restored``: (n_labels,) bool per OpenCV component id; ``sil_of``: (n_labels,) the
    majority silhouette of each component (:func:`_majority_silhouette`)."""
    n_sil = int(sil_of.max()) + 1
    plain = ok[~restored[ok + 1]]
    limbs = np.bincount(sil_of[plain + 1], minlength=n_sil)
    admitted = []
    for k in sorted(ok[restored[ok + 1]].tolist(), key=lambda k: (-areas[k], k)):
        if limbs[sil_of[k + 1]] < LIMBS_PER_PERSON:
            limbs[sil_of[k + 1]] += 1
            admitted.append(k)
    return np.sort(np.concatenate([plain, np.array(admitted, np.int64)]))


def split_by_colour(bgr: np.ndarray, mask: np.ndarray, min_delta: float) -> np.ndarray | None:
    """The pixels of ``mask`` in its two chromaticity clusters, with their common border
    removed (so they fall apart into separate components), or None if the clusters are
    closer than ``min_delta``.

    2-means on the normalised chromaticity (r, g) = (R, G) / (R + G + B), started at the mean
    of the tenth of the pixels with the lowest r and of the tenth with the highest:
    deterministic, and blind to shading (a lit and a shaded fold of one shirt have the same
    chromaticity), so it separates a face or hand from the pale shirt it touches (dark skin
    is redder than beige) rather than the shirt's lit side from its shaded side.

    Parameters
    ----------
    bgr : (H, W, 3) uint8
    mask : (H, W) bool
    min_delta : float
        Smallest distance between the cluster centres in (r, g).

    Returns
    -------
    (H, W) bool or None

    >>> img = np.zeros((4, 8, 3), np.uint8)
    >>> img[:, :4] = (40, 58, 92); img[:, 4:] = (150, 180, 200)  # dark skin | beige
    >>> img[2:, 4:] //= 2  # the shirt's shaded half: same chromaticity
    >>> split_by_colour(img, np.ones((4, 8), bool), 0.04).sum(axis=0).tolist()
    [4, 4, 4, 0, 0, 4, 4, 4]
    >>> split_by_colour(img, np.ones((4, 8), bool), 0.5) is None
    True
    """
    require_shape("bgr", bgr, (*mask.shape, 3), np.uint8)
    px = bgr[mask].astype(np.float32)
    if len(px) < 2:
        return None
    rg = px[:, [2, 1]] / np.maximum(px.sum(axis=1, keepdims=True), 1.0)
    lo, hi = np.percentile(rg[:, 0], [10.0, 90.0])
    centres = np.stack([rg[rg[:, 0] <= lo].mean(axis=0), rg[rg[:, 0] >= hi].mean(axis=0)])
    r, g = rg[:, 0].astype(np.float64), rg[:, 1].astype(np.float64)
    for _ in range(10):
        # nearer the second centre <=> beyond the bisector: one dot product per pixel
        (r0, g0), (r1, g1) = centres
        bound = 0.5 * ((r1 * r1 + g1 * g1) - (r0 * r0 + g0 * g0))
        near = ((r * (r1 - r0) + g * (g1 - g0)) > bound).astype(np.intp)
        counts = np.bincount(near, minlength=2)
        sums = np.stack([np.bincount(near, r, 2), np.bincount(near, g, 2)], axis=1)
        new = np.where(counts[:, None] > 0, sums / np.maximum(counts, 1)[:, None], centres)
        # np.allclose(new, centres, atol=1e-3), without its overhead (centres are finite)
        if (np.abs(new - centres) <= 1e-3 + 1e-5 * np.abs(centres)).all():
            break
        centres = new
    if float(np.linalg.norm(centres[0] - centres[1])) < min_delta:
        return None
    cluster = np.full(mask.shape, -1, np.int8)
    cluster[mask] = near
    first, second = cluster == 0, cluster == 1
    ring = np.ones((3, 3), np.uint8)
    near_first = cv2.dilate(first.view(np.uint8), ring) > 0
    near_second = cv2.dilate(second.view(np.uint8), ring) > 0
    return (first & ~near_second) | (second & ~near_first)


def _group_medians(group: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """(n,) median of non-negative ``values`` per ``group`` id 0..n-1 (NaN for an empty group).

    >>> _group_medians(np.array([1, 0, 1, 1]), np.array([5.0, 2.0, 1.0, 3.0]), 3).tolist()
    [2.0, 3.0, nan]
    """
    # one sort on group + value scaled into [0, 1): twice as fast as lexsort
    scale = float(values.max()) + 1.0 if len(values) else 1.0
    order = np.argsort(group + values / scale)
    group, values = group[order], values[order]
    counts = np.bincount(group, minlength=n)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    out = np.full(n, np.nan)
    has = counts > 0
    lo = start[has] + (counts[has] - 1) // 2
    hi = start[has] + counts[has] // 2
    out[has] = 0.5 * (values[lo] + values[hi])
    return out


def revealed_background(
    components: np.ndarray,
    ids: np.ndarray,
    boxes: np.ndarray,
    silhouette_mask: np.ndarray,
    bgr: np.ndarray,
    background_edges: np.ndarray,
    ratio: float,
) -> np.ndarray:
    """Which components are ghosts: revealed background, not something in front of it.

    Taking an object off a skin-coloured table uncovers table that the background model has
    never seen: MOG2 calls it foreground and the skin classifier skin, so it becomes a blob
    that holds a hand tracker to the table while the hand carries the object away. Along
    the outline of a real hand the current image has an edge (the hand's own) where the
    background image has little; along the outline of a ghost the background image has the
    edge (the object that stood there) and the current image has none (the table goes on).
    A component is a ghost when the median current gradient along the part of its outline
    that borders the outside of every silhouette is below ``ratio`` times the background's
    (both plus ``EDGE_FLOOR``). Measured on the bundled scenes: docs/blobs.md.

    Parameters
    ----------
    components : (H, W) int component labels
    ids : (k,) labels to test
    boxes : (k, 4) their bounding boxes x, y, width, height (OpenCV's component stats)
    silhouette_mask : (H, W) bool foreground
    bgr : (H, W, 3) uint8 current frame
    background_edges : (H, W) float32 (``Silhouettes.background_edges``)
    ratio : float

    Returns
    -------
    (k,) bool; False where fewer than ``MIN_OUTLINE_PX`` outline pixels

    >>> img = np.full((20, 20, 3), 120, np.uint8)  # a flat table now...
    >>> sil = np.zeros((20, 20), bool); sil[5:15, 5:15] = True
    >>> comp = sil.astype(np.int32); box = np.array([[5, 5, 10, 10]])
    >>> bg_edges = np.zeros((20, 20), np.float32); bg_edges[4:16, 4:16] = 200.0
    >>> bg_edges[6:14, 6:14] = 0.0  # ...where the background image has a box's outline
    >>> revealed_background(comp, np.array([1]), box, sil, img, bg_edges, 0.6).tolist()
    [True]
    >>> img[5:15, 5:15] = 40  # something dark in front: its own edge
    >>> revealed_background(comp, np.array([1]), box, sil, img, bg_edges, 0.6).tolist()
    [False]
    """
    # everything on the tested components' bounding box (plus the outline's reach)
    boxes = boxes.astype(np.int64)
    m = OUTLINE_PX + 1
    h, w = components.shape
    y0, x0 = max(int(boxes[:, 1].min()) - m, 0), max(int(boxes[:, 0].min()) - m, 0)
    y1 = min(int((boxes[:, 1] + boxes[:, 3]).max()) + m, h)
    x1 = min(int((boxes[:, 0] + boxes[:, 2]).max()) + m, w)
    comp = components[y0:y1, x0:x1]
    d = 2 * OUTLINE_PX + 1
    inner = cv2.erode(
        np.ascontiguousarray(silhouette_mask[y0:y1, x0:x1]).view(np.uint8),
        np.ones((d, d), np.uint8),
        borderType=cv2.BORDER_REPLICATE,
    )
    index = np.full(max(int(comp.max()), int(ids.max())) + 1, -1, np.int64)
    index[ids] = np.arange(len(ids))
    ys, xs = np.nonzero((inner == 0) & (comp > 0))
    group = index[comp[ys, xs]]
    keep = group >= 0
    ys, xs, group = ys[keep] + y0, xs[keep] + x0, group[keep]
    # the current gradient on the same box, one pixel wider for the 3x3 stencil
    gy0, gx0 = max(y0 - 1, 0), max(x0 - 1, 0)
    gy1, gx1 = min(y1 + 1, h), min(x1 + 1, w)
    grey = cv2.cvtColor(bgr[gy0:gy1, gx0:gx1], cv2.COLOR_BGR2GRAY)
    # int16 Sobel read at the outline pixels: 4x faster than sobel_magnitude on the box
    gx = cv2.Sobel(grey, cv2.CV_16S, 1, 0)[ys - gy0, xs - gx0].astype(np.float64)
    gy = cv2.Sobel(grey, cv2.CV_16S, 0, 1)[ys - gy0, xs - gx0].astype(np.float64)
    current = _group_medians(group, np.hypot(gx, gy), len(ids))
    background = _group_medians(group, background_edges[ys, xs].astype(np.float64), len(ids))
    counts = np.bincount(group, minlength=len(ids))
    with np.errstate(invalid="ignore"):
        ghost = current + EDGE_FLOOR < ratio * (background + EDGE_FLOOR)
    return ghost & (counts >= MIN_OUTLINE_PX)


def hand_ends(
    pixels_px: np.ndarray,
    blob_of: np.ndarray,
    centroids_px: np.ndarray,
    shoulders_px: np.ndarray,
    body_heights_px: np.ndarray,
    arm_length_rel: float,
    arm_max_length_rel: float,
    arm_min_width_rel: float,
    hand_length_rel: float,
    arm_zone: bool = False,
) -> np.ndarray:
    """Each blob's point: its centre of mass, or its hand end when it is a bare forearm.

    With short sleeves the forearm is skin too, and its blob's centre of mass lies halfway to
    the elbow, ~15 cm from the hand. A blob whose extent along its principal axis (sqrt(12)
    times the standard deviation, exact for a uniform bar) lies between ``arm_length_rel``
    and ``arm_max_length_rel`` times its silhouette's height, exceeds ``ARM_ASPECT``
    times its width, is at least ``arm_min_width_rel`` times that height wide and has at
    least the pixels of an ``arm_length_rel`` by ``arm_min_width_rel`` bar is such an arm
    (the width and pixel bounds turn away skin-coloured fringes, such as a wooden table's
    edge inside a silhouette, which are as long but thin and sparse); its point becomes the
    centre of mass of its pixels within ``hand_length_rel`` times that height of the tip
    farther from the silhouette's shoulder point (the hand hangs, reaches or rises away from
    the shoulder; the elbow stays within an upper arm's length of it). The shoulder point, not the
    silhouette's centre of mass: that lies at hip height, level with a hanging hand, so both
    tips of a hanging forearm are about as far from it and the elbow often won (docs/blobs.md,
    "Bare forearms"). All blobs at once: per-blob moments by ``np.bincount``.

    Parameters
    ----------
    pixels_px : (P, 2) float64 -- (u, v) of every blob pixel
    blob_of : (P,) int -- index of the blob each pixel belongs to, 0..B-1
    centroids_px : (B, 2) float64 -- their centres of mass
    shoulders_px : (B, 2) float64 -- shoulder point of each blob's silhouette: its centre
        column, ``SHOULDER_DROP_REL`` times its height below its top row
    body_heights_px : (B,) float64 -- height of each blob's silhouette
    arm_length_rel, arm_max_length_rel, arm_min_width_rel, hand_length_rel : float --
        ``BlobConfig``'s bounds, fractions of the silhouette's height
    arm_zone : bool -- only blobs that end above ``KNEE_REL`` of their silhouette's height
        from its top and begin below ``HEAD_ZONE_REL`` of it, or lie beside the head
        (``HEAD_HALF_WIDTH_REL`` from the silhouette's centre column), can be arms
        (``BlobConfig.arm_zone``)

    Returns
    -------
    (B, 2) float64 -- the points; a copy of ``centroids_px`` where no blob is an arm

    >>> yy, xx = np.mgrid[0:40, 0:4]  # a vertical bar 40 px long, 4 px wide
    >>> px = np.column_stack([xx.ravel(), yy.ravel()]).astype(float)
    >>> c = px.mean(axis=0, keepdims=True)
    >>> shoulder = np.array([[1.5, -20.0]])  # above the bar: the hand is its lower end
    >>> hand_ends(px, np.zeros(len(px), int), c, shoulder, np.array([100.0]),
    ...           0.17, 0.5, 0.035, 0.1).round(2).tolist()
    [[1.5, 34.0]]
    """
    n = len(centroids_px)
    out = centroids_px.copy()
    if n == 0 or len(pixels_px) == 0:
        return out
    d = pixels_px - centroids_px[blob_of]
    count = np.maximum(np.bincount(blob_of, minlength=n), 1)
    sxx = np.bincount(blob_of, d[:, 0] ** 2, n) / count
    syy = np.bincount(blob_of, d[:, 1] ** 2, n) / count
    sxy = np.bincount(blob_of, d[:, 0] * d[:, 1], n) / count
    # major eigenvalue and its direction of each 2x2 covariance
    half_diff = 0.5 * (sxx - syy)
    root = np.hypot(half_diff, sxy)
    major = 0.5 * (sxx + syy) + root
    minor = np.maximum(0.5 * (sxx + syy) - root, 0.0)
    angle = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    axis = np.column_stack([np.cos(angle), np.sin(angle)])
    length = np.sqrt(12.0 * major)
    min_width = arm_min_width_rel * body_heights_px
    arm = (
        (length > arm_length_rel * body_heights_px)
        & (length < arm_max_length_rel * body_heights_px)
        & (major > ARM_ASPECT**2 * minor)
        & (12.0 * minor >= min_width**2)
        & (count >= arm_length_rel * body_heights_px * min_width)
    )
    if arm_zone and arm.any():
        # a face with its neck or an ear with its neck, seen from the side or behind, is as long
        # and thin as a forearm, and so is a shin in skin-coloured trousers: a forearm lies
        # between the head and the shins, or beside the head when raised (one raised in front
        # of the face keeps its centre of mass)
        top = np.full(n, np.inf)
        bottom = np.full(n, -np.inf)
        np.minimum.at(top, blob_of, pixels_px[:, 1])
        np.maximum.at(bottom, blob_of, pixels_px[:, 1])
        silhouette_top = shoulders_px[:, 1] - SHOULDER_DROP_REL * body_heights_px
        below_face = top > silhouette_top + HEAD_ZONE_REL * body_heights_px
        beside_head = np.abs(centroids_px[:, 0] - shoulders_px[:, 0]) > (
            HEAD_HALF_WIDTH_REL * body_heights_px
        )
        arm &= below_face | beside_head
        arm &= bottom < silhouette_top + KNEE_REL * body_heights_px
    if not arm.any():
        return out
    # point each arm's axis away from its silhouette's shoulder point
    away = np.einsum("bi,bi->b", centroids_px - shoulders_px, axis)
    axis *= np.where(away < 0, -1.0, 1.0)[:, None]
    t = np.einsum("pi,pi->p", d, axis[blob_of])
    tip = np.full(n, -np.inf)
    np.maximum.at(tip, blob_of, t)
    near_tip = arm[blob_of] & (t >= tip[blob_of] - hand_length_rel * body_heights_px[blob_of])
    m = np.bincount(blob_of[near_tip], minlength=n)
    ok = arm & (m > 0)
    for k in range(2):
        sums = np.bincount(blob_of[near_tip], pixels_px[near_tip, k], n)
        out[ok, k] = sums[ok] / m[ok]
    return out


class SceneryMask:
    """Skin-coloured scenery of one camera: its background model's background image
    classified by the camera's skin model (``BlobConfig.scenery_share``). Classified again
    only when the model reads a new background image (every ``edges_every_frames`` frames).
    """

    def __init__(self, skin_model: SkinModel) -> None:
        self._skin_model = skin_model
        self._image: np.ndarray | None = None
        self._mask: np.ndarray | None = None

    def mask(self, background: BackgroundModel) -> np.ndarray | None:
        """(H, W) bool, read-only: where the background image is skin-coloured; None during
        the learning phase."""
        image = background.background_image()
        if image is None:
            return None
        if image is not self._image:
            self._image = image
            self._mask = self._skin_model.classify(image)
            self._mask.flags.writeable = False
        return self._mask


def extract_blobs(
    skin: np.ndarray,
    silhouettes: Silhouettes,
    cfg: BlobConfig,
    n_people_hint: int | None = None,
    bgr: np.ndarray | None = None,
    scenery: np.ndarray | None = None,
) -> BlobSet:
    """Connected skin regions inside silhouettes, the ceil(lambda * 3 * N_h) largest.

    Parameters
    ----------
    skin : (H, W) bool skin pixels
    silhouettes : Silhouettes of the same frame (same H, W)
    cfg : BlobConfig (``min_blob_area_px``, ``blob_excess`` = lambda, ``silhouette_dilate_px``)
    n_people_hint : N_h; default the number of silhouettes; at least 1
    bgr : (H, W, 3) uint8 frame, optional; with it, blobs too big to be a head or hand are
        split by colour (:func:`split_by_colour`, ``cfg.split_min_delta``) before the size
        filter, else dropped whole; and with it and ``silhouettes.background_edges``, ghosts
        of revealed background are dropped (:func:`revealed_background`,
        ``cfg.ghost_edge_ratio``)
    scenery : (H, W) bool, optional -- where the background image is skin-coloured
        (:class:`SceneryMask`); with it and ``silhouettes.changed``, blobs with at least
        ``cfg.scenery_share`` of their pixels unchanged and on such scenery are dropped

    Returns
    -------
    BlobSet
        Largest first. ``silhouette`` is the majority (dilated) silhouette label under the
        blob; ``rel_v`` = (v - top) / (bottom - top) of that silhouette (0 at its top).

    >>> sk = np.zeros((10, 10), bool); sk[2:4, 2:4] = True
    >>> lab = np.zeros((10, 10), np.int32); lab[1:9, 1:6] = 1
    >>> sil = Silhouettes(lab, np.array([1.0]), np.array([8.0]), np.zeros((10, 10), np.float32))
    >>> cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    >>> b = extract_blobs(sk, sil, cfg)
    >>> b.centroids_px.tolist(), b.areas_px.tolist(), b.rel_v.round(3).tolist()
    ([[2.5, 2.5]], [4], [0.214])
    """
    require_shape("skin", skin, silhouettes.labels.shape, np.bool_)
    if bgr is not None:
        require_shape("bgr", bgr, (*skin.shape, 3), np.uint8)
    region = silhouettes.region(blob_margin_px(cfg, skin.shape[1]))
    if region is None:
        return BlobSet.empty(skin.shape)
    # everything happens near people: on the box around them (the margin keeps every step's
    # reach inside it, so the blobs are those of the whole frame), then back to the frame
    rows, cols = region
    shift = np.array([cols.start, rows.start])
    crop = _extract(
        skin[region],
        silhouettes.crop(region),
        cfg,
        n_people_hint,
        None if bgr is None else bgr[region],
        _open_radius_px(cfg, skin.shape[1]),
        None if scenery is None else scenery[region],
    )
    labels = np.zeros(skin.shape, np.int32)
    labels[region] = crop.labels
    boxes = crop.bboxes_px.copy()
    boxes[:, :2] += shift.astype(np.int32)
    return BlobSet(
        crop.centroids_px + shift,
        crop.areas_px,
        boxes,
        crop.silhouette,
        crop.rel_v,
        labels,
        crop.foreground_share,
        crop.restored,
        None if crop.hand_px is None else crop.hand_px + shift,
    )


def pixel_share(labels: np.ndarray, mask: np.ndarray, n_labels: int) -> np.ndarray:
    """(n_labels,) share of each component's pixels that are set in ``mask`` (0 for an empty
    label).

    >>> lab = np.array([[1, 1, 2, 2]]); fg = np.array([[True, False, False, False]])
    >>> pixel_share(lab, fg, 3).tolist()
    [0.0, 0.5, 0.0]
    """
    area = np.bincount(labels.ravel(), minlength=n_labels)
    hits = np.bincount(labels[mask], minlength=n_labels)
    return hits / np.maximum(area, 1)


def blob_margin_px(cfg: BlobConfig, width_px: int) -> int:
    """How far from a silhouette the blob stage looks, px: its dilation, the opening, the
    ghost test's outline and Sobel stencil, plus slack. Skin beyond this never matters."""
    return cfg.silhouette_dilate_px + _open_radius_px(cfg, width_px) + OUTLINE_PX + 4


def _open_radius_px(cfg: BlobConfig, width_px: int) -> int:
    # the kernel is given for 640-pixel-wide frames: limbs shrink with the frame, and at
    # 320x240 (hands ~6 px) a 3-px opening would erase them
    return round((cfg.open_px - 1) / 2 * width_px / REFERENCE_WIDTH_PX)


def _extract(
    skin: np.ndarray,
    silhouettes: Silhouettes,
    cfg: BlobConfig,
    n_people_hint: int | None,
    bgr: np.ndarray | None,
    radius_px: int,
    scenery: np.ndarray | None = None,
) -> BlobSet:
    """:func:`extract_blobs` on one region (``radius_px``: the opening's, from the frame's
    width)."""
    shape = skin.shape
    sil = silhouettes.labels
    if cfg.silhouette_dilate_px > 0 and silhouettes.n:
        d = 2 * cfg.silhouette_dilate_px + 1
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (d, d))
        # grey dilation grows every label (overlaps go to the larger label)
        sil = cv2.dilate(sil.astype(np.uint16), kernel).astype(np.int32)
    inside = skin & (sil > 0)
    if cfg.change_dilate_px >= 0 and silhouettes.changed is not None:
        changed = silhouettes.changed
        if cfg.change_dilate_px > 0:
            d = 2 * cfg.change_dilate_px + 1
            kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (d, d))
            changed = cv2.dilate(changed.view(np.uint8), kernel).view(bool)
        inside &= changed
    restored = None
    if radius_px > 0:
        if cfg.open_keeps_isolated:
            inside, restored = _open_keeping_isolated(
                inside, 2 * radius_px + 1, cfg.min_blob_area_px
            )
        else:
            inside = _open(inside, 2 * radius_px + 1)
    n_all, labels, stats, centroids = components_with_stats(inside)
    areas = stats[1:, cv2.CC_STAT_AREA].astype(np.int64)
    ok = np.flatnonzero(areas >= max(cfg.min_blob_area_px, 1))
    if cfg.max_blob_area_rel > 0 and len(ok) and silhouettes.n:
        # a head covers ~1 % of (silhouette height)^2; much larger skin-coloured regions are
        # clothing (beige shirts, khaki trousers) that would crowd the real limbs out of the
        # n_keep largest. The reference is the tallest silhouette in the frame, not the
        # blob's own: a person whose clothes match the background falls apart into short
        # pieces, and their head would be "too big" for the piece it sits on
        tallest = float(np.max(silhouettes.bottom_v_px - silhouettes.top_v_px)) + 1.0
        limit = cfg.max_blob_area_rel * tallest**2
        too_big = ok[areas[ok] > limit]
        if len(too_big) and bgr is not None and cfg.split_min_delta > 0:
            # the face or hands of a person in skin-coloured clothes join it: split such
            # regions by colour and size the pieces again
            split = False
            for k in too_big:
                x, y, w, h = stats[k + 1, :4]
                box = slice(y, y + h), slice(x, x + w)
                own = labels[box] == k + 1
                parts = split_by_colour(bgr[box], own, cfg.split_min_delta)
                if parts is not None:
                    inside[box] = (inside[box] & ~own) | parts
                    split = True
            if split:
                n_all, labels, stats, centroids = components_with_stats(inside)
                areas = stats[1:, cv2.CC_STAT_AREA].astype(np.int64)
                ok = np.flatnonzero(areas >= max(cfg.min_blob_area_px, 1))
        ok = ok[areas[ok] <= limit]
    shares = None
    if silhouettes.foreground is not None:
        shares = pixel_share(labels, silhouettes.foreground, n_all)
        if cfg.min_foreground_share > 0 and len(ok):
            ok = ok[shares[ok + 1] >= cfg.min_foreground_share]
    if cfg.min_changed_share > 0 and silhouettes.changed is not None and len(ok):
        changed_share = pixel_share(labels, silhouettes.changed, n_all)
        ok = ok[changed_share[ok + 1] >= cfg.min_changed_share]
    changed = silhouettes.changed
    if cfg.scenery_share > 0 and scenery is not None and changed is not None and len(ok):
        # the wooden table beside a hand: skin-coloured in the background image too, and
        # unchanged to the model; a hand in front of it changes the pixels it covers
        flagged = ok[_scenery_shares(ok, labels, areas, scenery, changed) >= cfg.scenery_share]
        if len(flagged):
            ok = np.setdiff1d(
                ok,
                flagged[
                    ~_at_silhouette_top(flagged, labels, stats, sil, centroids, silhouettes, cfg)
                ],
            )
    edges = silhouettes.background_edges
    if cfg.ghost_edge_ratio > 0 and edges is not None and bgr is not None and len(ok):
        ghosts = revealed_background(
            labels,
            ok + 1,
            stats[ok + 1, :4],
            silhouettes.labels > 0,
            bgr,
            edges,
            cfg.ghost_edge_ratio,
        )
        ok = ok[~ghosts]
    restored_comp = sil_of_all = None
    if restored is not None and restored.any():
        # a restored region is one whole component (pieces of one split by colour keep
        # the flag)
        restored_comp = pixel_share(labels, restored, n_all) > 0
        if len(ok) and restored_comp[ok + 1].any():
            inside = labels > 0
            sil_of_all = _majority_silhouette(
                labels[inside], sil[inside], n_all, int(sil.max()) + 1
            )
            if cfg.restore_min_rel_v > 0 or cfg.restore_max_rel_v < 1:
                ok = ok[~_outside_band(ok, restored_comp, centroids, sil_of_all, silhouettes, cfg)]
            ok = _fill_missing_limbs(ok, restored_comp, areas, sil_of_all)
    n_h = max(n_people_hint if n_people_hint is not None else silhouettes.n, 1)
    n_keep = math.ceil(cfg.blob_excess * 3 * n_h)
    order = ok[np.argsort(-areas[ok], kind="stable")][:n_keep]  # 0-based blob index
    if len(order) == 0:
        return BlobSet.empty(shape)
    comp = order + 1  # OpenCV component ids
    # majority silhouette label under each kept blob
    kept_lut = np.zeros(n_all, bool)
    kept_lut[comp] = True
    sel = np.take(kept_lut, labels)  # np.isin(labels, comp), six times faster
    remap = np.zeros(n_all, np.int64)
    remap[comp] = np.arange(len(comp))
    if sil_of_all is None:
        sil_of = _majority_silhouette(remap[labels[sel]], sil[sel], len(comp), int(sil.max()) + 1)
    else:  # voted already, over every component
        sil_of = sil_of_all[comp]
    cents = centroids[comp].astype(np.float64)
    hand_px = None
    if cfg.arm_length_rel > 0 and silhouettes.centres_px is not None:
        top = np.asarray(silhouettes.top_v_px)[sil_of - 1]
        bottom = np.asarray(silhouettes.bottom_v_px)[sil_of - 1]
        ys, xs = np.nonzero(sel)
        heights = bottom - top + 1.0
        shoulders = np.column_stack(
            [silhouettes.centres_px[sil_of - 1, 0], top + SHOULDER_DROP_REL * heights]
        )
        ends = hand_ends(
            np.column_stack([xs, ys]).astype(np.float64),
            remap[labels[ys, xs]],
            cents,
            shoulders,
            heights,
            cfg.arm_length_rel,
            cfg.arm_max_length_rel,
            cfg.arm_min_width_rel,
            cfg.hand_length_rel,
            cfg.arm_zone,
        )
        if cfg.arm_hand_end == "report":
            # the tracker's inputs stay the centres of mass its rules were tuned to; the
            # hand ends only move the hands it reports (docs/blobs.md, "Bare forearms")
            hand_px = ends
        else:
            cents = ends
    rel_v = _relative_v(cents[:, 1], sil_of, silhouettes)
    out_labels = np.zeros(n_all, np.int32)
    out_labels[comp] = np.arange(1, len(comp) + 1, dtype=np.int32)
    return BlobSet(
        cents,
        areas[order],
        stats[comp, :4].astype(np.int32),
        sil_of,
        rel_v,
        np.take(out_labels, labels),
        None if shares is None else shares[comp],
        None if restored_comp is None else restored_comp[comp],
        hand_px,
    )


def observe(
    bgr: np.ndarray,
    background_model: BackgroundModel,
    skin_model: SkinModel,
    cfg: BlobConfig,
    camera: str,
    n_people_hint: int | None = None,
    scenery: SceneryMask | None = None,
) -> CameraObservation:
    """One camera frame -> silhouettes (updating ``background_model``), skin, blobs; with
    ``scenery`` (this camera's, kept between frames) blobs on skin-coloured scenery are
    dropped as in a run (``cfg.scenery_share``)."""
    silhouettes = background_model.step(bgr, **cfg.background_requests())
    skin = skin_model.classify(bgr, silhouettes.boxes(blob_margin_px(cfg, bgr.shape[1])))
    on_scenery = (
        scenery.mask(background_model) if scenery is not None and cfg.scenery_share > 0 else None
    )
    blobs = extract_blobs(skin, silhouettes, cfg, n_people_hint, bgr, on_scenery)
    return CameraObservation(camera, silhouettes, skin, blobs)
