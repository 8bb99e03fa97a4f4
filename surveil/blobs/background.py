"""Background subtraction into person silhouettes (paper 004 section 6.1).

The paper used a colour codebook; here OpenCV's adaptive Gaussian mixture (MOG2) with shadow
detection stands in. Per frame: MOG2 foreground (shadows, value 127, count as background) ->
morphological opening then closing (elliptical kernels) -> connected components -> components
of at least ``min_person_area_px`` pixels are the silhouettes, relabelled 1..n -> their top
and bottom rows and a distance transform of the outside.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import cv2
import numpy as np

from surveil.blobs.components import components_with_stats
from surveil.blobs.settings import BackgroundConfig
from surveil.camera import Camera, Rig
from surveil.datatypes import Silhouettes
from surveil.validate import require_shape

log = logging.getLogger(__name__)

FOREGROUND = 255  # MOG2 output: 255 foreground, 127 shadow, 0 background
GAIN_BLOCK_PX = 8  # gain compensation compares 8x8 block means of frame and background


def sobel_magnitude(grey: np.ndarray) -> np.ndarray:
    """(H, W) float32 gradient magnitude of a grey image (3x3 Sobel, reflected border).

    >>> g = np.zeros((5, 6), np.uint8); g[:, 3:] = 10
    >>> sobel_magnitude(g)[2].tolist()
    [0.0, 0.0, 40.0, 40.0, 0.0, 0.0]
    """
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    return cv2.magnitude(gx, gy)


def relative_gain(frame: np.ndarray, background: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """(3,) float64 per-channel factor g with g * frame ~ background: the median over the
    ``usable`` pixels of background / frame, channel by channel. Pixels near black or
    saturation in either image do not count (their ratio says nothing); with none left the
    gain is 1. The median, not a ratio of means: a person who appears in one frame (a camera
    that starts late, someone stepping out from behind a pillar) covers pixels that were
    background in the last one.

    frame, background : (H, W, 3) uint8 -- the model passes 8x8 block means (1200 blocks at
        320x240: their noise averages out, so the median is exact to well under a grey level,
        and cheap)
    usable : (H, W) bool

    >>> bg = np.full((4, 4, 3), (100, 120, 80), np.uint8)
    >>> frame = (bg * np.array([1.1, 1.0, 0.8])).astype(np.uint8)
    >>> frame[0, :3] = (20, 200, 40)  # someone in front of the background
    >>> relative_gain(frame, bg, np.ones((4, 4), bool)).round(2).tolist()
    [0.91, 1.0, 1.25]
    """
    f = frame[usable].astype(np.float32)
    b = background[usable].astype(np.float32)
    ok = ((f > 15) & (f < 240) & (b > 15) & (b < 240)).all(axis=1)
    if not ok.any():
        return np.ones(3)
    return np.median(b[ok] / f[ok], axis=0).astype(np.float64)


def distance_to_zero(mask: np.ndarray) -> np.ndarray:
    """(H, W) float32 Euclidean distance of every pixel of ``mask`` (uint8) to the nearest
    zero pixel (``cv2.distanceTransform``, precise), written into a 64-byte aligned array.

    OpenCV's precise transform rounds a few pixels' last bits differently with the
    alignment of its output; arrays that OpenCV allocates for Python have numpy's
    alignment, which varies from call to call, and so did the distances (two runs of four
    scenes differed in 815 of 3124 camera frames, session 54). A fixed alignment makes
    them reproducible.

    >>> m = np.ones((3, 5), np.uint8); m[1, 0] = 0
    >>> distance_to_zero(m)[1].tolist()
    [0.0, 1.0, 2.0, 3.0, 4.0]
    """
    h, w = mask.shape
    raw = np.empty(h * w * 4 + 64, np.uint8)
    start = -raw.ctypes.data % 64
    dist = raw[start : start + h * w * 4].view(np.float32).reshape(h, w)
    cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE, dst=dist)
    return dist


def _ellipse(diameter_px: int) -> np.ndarray | None:
    if diameter_px <= 1:
        return None
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (diameter_px, diameter_px))


def silhouettes_from_mask(
    foreground: np.ndarray, min_area_px: int, max_distance_px: float | None = None
) -> Silhouettes:
    """Person silhouettes from a cleaned foreground mask.

    Parameters
    ----------
    foreground : (H, W) bool or uint8 (non-zero = foreground)
    min_area_px : int
        Components smaller than this are dropped.
    max_distance_px : float, optional
        Clip ``dist_outside_px`` at this distance. The distance transform then runs only on
        the box around the silhouettes widened by it (people cover a small part of a frame:
        about half the cost). None: exact everywhere.

    Returns
    -------
    Silhouettes
        Labels 1..n in the order OpenCV found them (raster order of their first pixel);
        ``dist_outside_px`` is the Euclidean distance to the nearest silhouette pixel
        (clipped at ``max_distance_px``), or the image diagonal (or ``max_distance_px``)
        everywhere when there is no silhouette.

    >>> m = np.zeros((20, 20), bool); m[5:15, 8:12] = True
    >>> s = silhouettes_from_mask(m, 10)
    >>> s.n, s.top_v_px.tolist(), s.bottom_v_px.tolist(), float(s.dist_outside_px[10, 2])
    (1, [5.0], [14.0], 6.0)
    >>> float(silhouettes_from_mask(m, 10, max_distance_px=4.0).dist_outside_px[10, 2])
    4.0
    """
    require_shape("foreground", foreground, (None, None), np.generic)
    fg = foreground.astype(np.uint8, copy=False)
    h, w = fg.shape
    n_all, labels, stats, centres = components_with_stats(fg)
    keep = np.flatnonzero(stats[:, cv2.CC_STAT_AREA] >= max(min_area_px, 1))
    keep = keep[keep > 0]  # component 0 is the background
    relabel = np.zeros(n_all, np.int32)
    relabel[keep] = np.arange(1, len(keep) + 1, dtype=np.int32)
    if n_all > 1:
        # every component lies in their joint box; outside it the labels are 0 either way
        x0, y0, x1, y1 = _joint_box(stats[1:, :4], 0, (h, w))
        labels[y0:y1, x0:x1] = np.take(relabel, labels[y0:y1, x0:x1])
    top = stats[keep, cv2.CC_STAT_TOP].astype(np.float64)
    bottom = top + stats[keep, cv2.CC_STAT_HEIGHT] - 1
    if not len(keep):
        far = np.hypot(h, w) if max_distance_px is None else max_distance_px
        dist = np.full((h, w), far, np.float32)
    elif max_distance_px is None:
        outside = (labels == 0).astype(np.uint8)
        dist = distance_to_zero(outside)
    else:
        dist = _clipped_distance_outside(labels, stats[keep, :4], max_distance_px)
    return Silhouettes(
        labels,
        top,
        bottom,
        dist,
        centres_px=centres[keep].astype(np.float64),
        boxes_px=stats[keep, :4].astype(np.int32),
    )


def _clipped_distance_outside(
    labels: np.ndarray, boxes_px: np.ndarray, max_distance_px: float
) -> np.ndarray:
    """(H, W) float32 min(distance to the nearest non-zero pixel of ``labels``,
    ``max_distance_px``), with the transform run only on the box around ``boxes_px`` (x, y,
    w, h; every non-zero pixel inside) widened by the clip distance: beyond it every pixel
    is farther than that."""
    x0, y0, x1, y1 = _joint_box(boxes_px, math.ceil(max_distance_px) + 1, labels.shape)
    dist = np.full(labels.shape, max_distance_px, np.float32)
    outside = (labels[y0:y1, x0:x1] == 0).view(np.uint8)
    near = distance_to_zero(outside)
    np.minimum(near, np.float32(max_distance_px), out=dist[y0:y1, x0:x1])
    return dist


def _joint_box(boxes_px: np.ndarray, grow: int, shape: tuple[int, int]) -> tuple[int, ...]:
    """x0, y0, x1, y1 (end exclusive) of the box around (n >= 1) x, y, w, h boxes widened
    by ``grow`` and clipped to ``shape`` (H, W)."""
    h, w = shape
    x0 = max(int(boxes_px[:, 0].min()) - grow, 0)
    y0 = max(int(boxes_px[:, 1].min()) - grow, 0)
    x1 = min(int((boxes_px[:, 0] + boxes_px[:, 2]).max()) + grow, w)
    y1 = min(int((boxes_px[:, 1] + boxes_px[:, 3]).max()) + grow, h)
    return x0, y0, x1, y1


def upscale_twice(
    image: np.ndarray, box: tuple[int, ...] | None, outside: float, interpolation: int
) -> np.ndarray:
    """``cv2.resize(image, (2 W, 2 H), interpolation)`` computed on ``box`` (x0, y0, x1, y1
    of ``image``) only; everywhere else the result is ``outside``. Exact when ``image`` is
    ``outside`` outside the box and (for linear interpolation) on the box's rim of one
    pixel, or the box meets the image border there: both resizes then read the same
    neighbours, and at a scale of exactly 2 the interpolation weights depend only on the
    output pixel's parity. People cover a small part of a frame, so this is a fraction of
    the cost. None: no box, all ``outside``.

    >>> a = np.zeros((6, 8), np.float32); a[2:4, 3:5] = 4.0
    >>> full = cv2.resize(a, (16, 12), interpolation=cv2.INTER_LINEAR)
    >>> bool((upscale_twice(a, (2, 1, 6, 5), 0.0, cv2.INTER_LINEAR) == full).all())
    True
    """
    h, w = image.shape[:2]
    out = np.full((2 * h, 2 * w, *image.shape[2:]), outside, image.dtype)
    if box is not None and box[2] > box[0] and box[3] > box[1]:
        x0, y0, x1, y1 = box
        crop = np.ascontiguousarray(image[y0:y1, x0:x1])
        out[2 * y0 : 2 * y1, 2 * x0 : 2 * x1] = cv2.resize(
            crop, (2 * (x1 - x0), 2 * (y1 - y0)), interpolation=interpolation
        )
    return out


def _scale_boxes(boxes_px: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """(n, 4) x, y, w, h boxes of a mask resized by (sx, sy): boxes that hold every pixel the
    nearest-neighbour resize maps from them (one pixel of slack on each side)."""
    x0 = np.floor(boxes_px[:, 0] * sx) - 1
    y0 = np.floor(boxes_px[:, 1] * sy) - 1
    x1 = np.ceil((boxes_px[:, 0] + boxes_px[:, 2]) * sx) + 1
    y1 = np.ceil((boxes_px[:, 1] + boxes_px[:, 3]) * sy) + 1
    return np.column_stack([x0, y0, x1 - x0, y1 - y0]).astype(np.int32)


def floor_polygon_m(centres_m: np.ndarray) -> np.ndarray:
    """(K, 2) the convex hull of the cameras' floor positions (x, y), counter-clockwise
    (x east, y north) from its corner with the smallest (x, y); fewer than 3 corners when the
    cameras stand in a line.

    >>> floor_polygon_m(np.array([[0, 3, 2.5], [4, 0, 2.5], [4, 3, 2], [0, 0, 2], [2, 1, 2]]))
    array([[0., 0.],
           [4., 0.],
           [4., 3.],
           [0., 3.]])
    """
    xy = np.asarray(centres_m, dtype=np.float64)[:, :2]
    hull = xy[cv2.convexHull(xy.astype(np.float32), returnPoints=False).ravel()]
    if len(hull) >= 3:
        e1, e2 = hull[1] - hull[0], hull[2] - hull[1]
        if e1[0] * e2[1] - e1[1] * e2[0] < 0:
            hull = hull[::-1]
    return np.roll(hull, -int(np.lexsort((hull[:, 1], hull[:, 0]))[0]), axis=0)


def distance_to_polygon_m(points_m: np.ndarray, polygon_m: np.ndarray) -> np.ndarray:
    """(N,) distance of 2-D points to a convex polygon (counter-clockwise, K >= 1 corners):
    0 inside, else to the nearest edge.

    >>> square = np.array([[0.0, 0], [2, 0], [2, 2], [0, 2]])
    >>> distance_to_polygon_m(np.array([[1.0, 1], [3, 1], [3, 3]]), square).round(3).tolist()
    [0.0, 1.0, 1.414]
    """
    pts = np.asarray(points_m, dtype=np.float64)
    a = np.asarray(polygon_m, dtype=np.float64)
    b = np.roll(a, -1, axis=0)
    edge = b - a  # (K, 2)
    rel = pts[:, None] - a[None]  # (N, K, 2)
    length2 = np.maximum((edge**2).sum(axis=1), 1e-12)
    t = np.clip((rel * edge[None]).sum(axis=2) / length2, 0.0, 1.0)
    gap = np.linalg.norm(rel - t[..., None] * edge[None], axis=2).min(axis=1)
    if len(a) < 3:
        return gap
    cross = edge[None, :, 0] * rel[..., 1] - edge[None, :, 1] * rel[..., 0]
    return np.where((cross >= 0).all(axis=1), 0.0, gap)


def floor_view_mask(
    camera: Camera, polygon_m: np.ndarray, margin_m: float, shape: tuple[int, int]
) -> np.ndarray:
    """(H, W) bool: the pixels of an image of ``shape`` (the camera's image, or a shrunk copy)
    whose lines of sight meet the floor (z = 0, in front of the camera) within ``margin_m``
    of ``polygon_m`` (:func:`floor_polygon_m`). Pixels that see a wall, a door or the ceiling
    meet the floor plane beyond the room, or never."""
    h, w = shape
    sx, sy = camera.width / w, camera.height / h
    v, u = np.mgrid[0:h, 0:w]
    px = np.column_stack([(u.ravel() + 0.5) * sx - 0.5, (v.ravel() + 0.5) * sy - 0.5])
    origin, rays = camera.backproject(px)
    down = rays[:, 2] < -1e-9
    reach = np.where(down, -origin[2] / np.where(down, rays[:, 2], -1.0), 0.0)
    hit = origin[:2] + reach[:, None] * rays[:, :2]
    inside = distance_to_polygon_m(hit, polygon_m) <= margin_m
    return (down & inside).reshape(h, w)


def shadow_region(
    cfg: BackgroundConfig, rig: Rig, cam: str, shape: tuple[int, int]
) -> np.ndarray | None:
    """The ``shadow_region`` of camera ``cam``'s :class:`BackgroundModel`: where it sees the
    floor (:func:`floor_view_mask`) when ``cfg.shadows_on_floor_only``, else None (shadows
    everywhere). ``shape``: (H, W) of its frames."""
    if not cfg.shadows_on_floor_only:
        return None
    polygon = floor_polygon_m(np.array([c.centre_m for c in rig]))
    return floor_view_mask(rig[cam], polygon, cfg.floor_margin_m, shape)


def learning_frames_after(cfg: BackgroundConfig, framesets_before: int) -> int:
    """Length of the learning phase of a camera whose first frame comes ``framesets_before``
    frame sets into a run: what is left of the run's learning phase, at least
    ``cfg.late_learning_frames``.

    The learning phase assumes the room is empty at the start of a run. A camera that starts
    late must not learn longer than the others: it would learn, at the fast rate, the people
    who walk in when the run's learning phase ends (in the three_people scene the late
    camera's silhouettes shrank at their edges, and the silhouette prior, a product over
    cameras, then vetoed most candidates; docs/blobs.md).

    >>> cfg = BackgroundConfig(learning_frames=30, late_learning_frames=5)
    >>> [learning_frames_after(cfg, n) for n in (0, 15, 40)]
    [30, 15, 5]
    """
    return max(
        cfg.learning_frames - framesets_before, min(cfg.late_learning_frames, cfg.learning_frames)
    )


class BackgroundModel:
    """Stateful MOG2 background model of one camera.

    Parameters
    ----------
    cfg : BackgroundConfig
    shape : (H, W) of the frames this camera delivers.
    learning_frames : length of the learning phase (default ``cfg.learning_frames``; a camera
        that starts late: :func:`learning_frames_after`)
    distance_cap_px : clip ``Silhouettes.dist_outside_px`` at this many frame pixels (about
        half the cost of the distance transform; the pipeline passes what its consumers
        read, :func:`surveil.pipeline.silhouette_distance_cap_px`); None: exact everywhere
    shadow_region : (H, W) bool, optional -- where MOG2's shadows count as shadows; elsewhere
        they are foreground (``cfg.shadows_on_floor_only``: :func:`floor_view_mask`). None:
        everywhere, as MOG2 does by itself.

    The first ``learning_frames`` frames are learnt at ``cfg.learning_rate_initial``
    (default -1: MOG2's automatic 1/n, i.e. a running mean of everything seen so far), later
    frames at the slow ``cfg.learning_rate`` so that people who stand still are not absorbed.
    Silhouettes are still returned during the learning phase.
    """

    def __init__(
        self,
        cfg: BackgroundConfig,
        shape: tuple[int, int],
        learning_frames: int | None = None,
        distance_cap_px: float | None = None,
        shadow_region: np.ndarray | None = None,
    ) -> None:
        if len(shape) != 2 or min(shape) <= 0:
            raise ValueError(f"shape must be (H, W) with positive sizes, got {shape}")
        if distance_cap_px is not None and not distance_cap_px > 0:
            raise ValueError(f"distance_cap_px must be positive or None, got {distance_cap_px}")
        self.cfg = cfg
        self.distance_cap_px = distance_cap_px
        self.learning_frames = cfg.learning_frames if learning_frames is None else learning_frames
        self.shape = (int(shape[0]), int(shape[1]))
        scale = cfg.model_scale
        self._small_size = None
        if scale < 1.0:
            self._small_size = (
                max(1, round(self.shape[1] * scale)),
                max(1, round(self.shape[0] * scale)),
            )
        # kernels are in full-resolution pixels: scale them with the frame
        self._open = _ellipse(round(cfg.open_px * scale))
        self._close = _ellipse(round(cfg.close_px * scale) | 1 if cfg.close_px else 0)
        self._people_grow = _ellipse(round(cfg.people_margin_px * scale) * 2 + 1)
        self._not_shadow: np.ndarray | None = None  # model size: shadows here are foreground
        if shadow_region is not None:
            require_shape("shadow_region", shadow_region, self.shape, np.bool_)
            keep = shadow_region.view(np.uint8)
            if self._small_size is not None:
                keep = cv2.resize(keep, self._small_size, interpolation=cv2.INTER_NEAREST)
            self._not_shadow = keep == 0
        self.reset()

    def reset(self) -> None:
        """Forget the background: the next frame starts a new learning phase."""
        self._mog = cv2.createBackgroundSubtractorMOG2(
            history=self.cfg.history_frames,
            varThreshold=self.cfg.var_threshold,
            detectShadows=True,
        )
        self._mog.setBackgroundRatio(self.cfg.background_ratio)
        self.n_frames = 0
        self._edges: np.ndarray | None = None
        self._edges_frame = 0
        self._background: np.ndarray | None = None  # MOG2's background image, model size
        self._background_frame = 0
        self._full_background: np.ndarray | None = None  # the same at frame size
        self._unlearnt = 0  # frames since the model last learnt (held back for people)
        self._was_background: np.ndarray | None = None  # uint8: last frame's background
        self._background_blocks: np.ndarray | None = None  # its 8x8 block means
        self._blocks_frame = -1
        self.gain = np.ones(3)  # the last frame's per-channel gain (gain_compensation)

    @property
    def learning(self) -> bool:
        """True while in the initial learning phase."""
        return self.n_frames < self.learning_frames

    def background_edges(self) -> np.ndarray | None:
        """(H, W) float32 gradient magnitude of the background image (3x3 Sobel of its grey
        version, at frame size), or None during the learning phase. Recomputed every
        ``cfg.edges_every_frames`` frames and shared (read-only) in between."""
        if self.learning:
            return None
        if self._edges is None or self.n_frames - self._edges_frame >= self.cfg.edges_every_frames:
            image = self.background_image()
            self._edges = sobel_magnitude(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
            self._edges.flags.writeable = False
            self._edges_frame = self.n_frames
        return self._edges

    def background_image(self) -> np.ndarray | None:
        """(H, W, 3) uint8 MOG2's background image at frame size, or None during the learning
        phase. Read again every ``cfg.edges_every_frames`` frames (it changes slowly); until
        then the same read-only array is returned, so callers can cache what they derive
        from it by identity."""
        if self.learning:
            return None
        image = self._background_image()
        if self._full_background is None:  # cleared whenever the model image is read again
            if self._small_size is not None:
                image = cv2.resize(image, self.shape[::-1], interpolation=cv2.INTER_LINEAR)
            else:
                image = image.copy()
            image.flags.writeable = False
            self._full_background = image
        return self._full_background

    def _background_image(self) -> np.ndarray:
        """(h, w, 3) uint8 MOG2's background image at the model's size, read again every
        ``cfg.edges_every_frames`` frames (reading it costs about 0.7 ms; it changes slowly)."""
        stale = self.n_frames - self._background_frame >= self.cfg.edges_every_frames
        if self._background is None or stale:
            self._background = self._mog.getBackgroundImage()
            self._background_frame = self.n_frames
            self._full_background = None
        return self._background

    def _compensate_gain(self, small: np.ndarray) -> np.ndarray:
        """``small`` (the frame at model size) with each channel scaled by its gain against
        the background image (:func:`relative_gain`), on means of 8x8 blocks: the blocks that
        were wholly background in the last frame, or every block when those are fewer than a
        quarter (a light switched on: nearly everything changed). Estimated every
        ``cfg.gain_every_frames`` frames; in between the last gain is applied."""
        if self.n_frames % self.cfg.gain_every_frames and self.n_frames > 1:
            return self._apply_gain(small)
        h, w = small.shape[:2]
        blocks = (max(1, w // GAIN_BLOCK_PX), max(1, h // GAIN_BLOCK_PX))
        background = self._background_image()
        if self._background_blocks is None or self._blocks_frame != self._background_frame:
            self._background_blocks = cv2.resize(background, blocks, interpolation=cv2.INTER_AREA)
            self._blocks_frame = self._background_frame
        frame_blocks = cv2.resize(small, blocks, interpolation=cv2.INTER_AREA)
        usable = np.ones(blocks[::-1], bool)
        if self._was_background is not None:
            clean = cv2.resize(self._was_background, blocks, interpolation=cv2.INTER_AREA) == 255
            if clean.mean() >= 0.25:
                usable = clean
        self.gain = relative_gain(frame_blocks, self._background_blocks, usable)
        return self._apply_gain(small)

    def _apply_gain(self, small: np.ndarray) -> np.ndarray:
        if np.abs(self.gain - 1.0).max() < 0.004:  # under one grey level at 255: skip
            return small
        return cv2.transform(small, np.diag(self.gain))

    def _learn_around(self, small: np.ndarray, labels: np.ndarray, people_px: np.ndarray) -> None:
        """Let MOG2 learn from ``small`` (the frame at model size) every
        ``cfg.people_update_every`` frames, with the silhouettes that hold a tracked person's
        limb (``people_px``, model pixels) painted over with the background image: people
        are never learnt into the background, however long they stay. The rate is the
        per-frame rate times the frames since the model last learnt, so the rest of the
        scene adapts as fast as without people."""
        self._unlearnt += 1
        if self._unlearnt < self.cfg.people_update_every:
            return
        h, w = labels.shape
        uv = np.rint(people_px).astype(np.intp)
        inside = (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
        ids = np.unique(labels[uv[inside, 1], uv[inside, 0]])
        ids = ids[ids > 0]
        frame = small
        if len(ids):
            keep_out = np.isin(labels, ids).view(np.uint8)
            if self._people_grow is not None:
                keep_out = cv2.dilate(keep_out, self._people_grow)
            frame = small.copy()
            np.copyto(frame, self._background_image(), where=keep_out.view(bool)[..., None])
        self._mog.apply(frame, learningRate=min(1.0, self.cfg.learning_rate * self._unlearnt))
        self._unlearnt = 0

    def _upscale(self, small: Silhouettes, cap: float | None) -> tuple[np.ndarray, np.ndarray]:
        """Labels and (unscaled) outside distances of model-size silhouettes at frame size:
        nearest and linear resizes, computed near the silhouettes only when the frame is
        exactly twice the model size and the distances are clipped (:func:`upscale_twice`;
        farther than ``cap`` model pixels from every silhouette they are ``cap``)."""
        size = self.shape[::-1]
        if cap is None or self.shape != (2 * small.labels.shape[0], 2 * small.labels.shape[1]):
            return (
                cv2.resize(small.labels, size, interpolation=cv2.INTER_NEAREST),
                cv2.resize(small.dist_outside_px, size, interpolation=cv2.INTER_LINEAR),
            )
        if small.n == 0:
            box = reach = None
        else:
            box = _joint_box(small.boxes_px, 0, small.labels.shape)
            # where distances are below the cap, plus a rim of two pixels at the cap that the
            # interpolation reads
            reach = _joint_box(small.boxes_px, math.ceil(cap) + 2, small.labels.shape)
        return (
            upscale_twice(small.labels, box, 0, cv2.INTER_NEAREST),
            upscale_twice(small.dist_outside_px, reach, np.float32(cap), cv2.INTER_LINEAR),
        )

    def step(
        self,
        bgr: np.ndarray,
        changed: bool = False,
        background_edges: bool = False,
        people_px: np.ndarray | None = None,
        foreground: bool = False,
    ) -> Silhouettes:
        """Update the model with one frame and return its person silhouettes.

        Parameters
        ----------
        bgr : (H, W, 3) uint8 BGR, H and W as given at construction.
        changed : also return ``Silhouettes.changed`` (what MOG2 found unlike the background
            before the clean-up; the blob stage asks for it when ``change_dilate_px`` >= 0)
        foreground : also return ``Silhouettes.foreground`` (what MOG2 called foreground,
            shadows not included, before the clean-up; the blob stage's foreground share
            test, ``min_foreground_share``)
        background_edges : also return ``Silhouettes.background_edges``
            (:meth:`background_edges`; the blob stage's ghost test)
        people_px : (N, 2) float, optional -- where tracked people's heads and hands project
            in this frame, (u, v) frame pixels. After the learning phase the silhouettes
            that hold one of them are not learnt into the background (``cfg.protect_people``;
            docs/blobs.md, "People are not background"). None or empty: the whole frame is
            learnt, as MOG2 does by itself.
        """
        require_shape("bgr", bgr, (*self.shape, 3), np.uint8)
        rate = self.cfg.learning_rate_initial if self.learning else self.cfg.learning_rate
        small = bgr
        if self._small_size is not None:
            small = cv2.resize(bgr, self._small_size, interpolation=cv2.INTER_AREA)
        if self.cfg.gain_compensation and self.n_frames > 0:
            small = self._compensate_gain(small)
        protect = (
            self.cfg.protect_people
            and not self.learning
            and people_px is not None
            and len(people_px) > 0
        )
        if protect:
            # detect without learning; the model learns below, around the people
            raw = self._mog.apply(small, learningRate=0.0)
        else:
            raw = self._mog.apply(small, learningRate=rate)
            self._unlearnt = 0
        self.n_frames += 1
        if self.cfg.gain_compensation:
            self._was_background = cv2.compare(raw, 0, cv2.CMP_EQ)
        changed_small = raw != 0 if changed else None
        edges = self.background_edges() if background_edges else None
        fg_bool = raw == FOREGROUND
        if self._not_shadow is not None:
            fg_bool |= (raw != 0) & self._not_shadow
        fg = fg_bool.view(np.uint8)
        fg_raw = fg if foreground else None
        if self._open is not None:
            fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, self._open)
        if self._close is not None:
            fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, self._close)
        if self._small_size is None:
            full = silhouettes_from_mask(fg, self.cfg.min_person_area_px, self.distance_cap_px)
            if protect:
                self._learn_around(small, full.labels, np.asarray(people_px, np.float64))
            return dataclasses.replace(
                full,
                changed=changed_small,
                background_edges=edges,
                foreground=None if fg_raw is None else fg_raw.view(bool),
            )
        # components and distances on the small mask too (they cost more than MOG2 at full
        # size), then scaled back to frame pixels
        sx = self.shape[1] / self._small_size[0]
        sy = self.shape[0] / self._small_size[1]
        dist_scale = 0.5 * (sx + sy)
        cap = None if self.distance_cap_px is None else self.distance_cap_px / dist_scale
        sil_small = silhouettes_from_mask(
            fg, round(self.cfg.min_person_area_px / (sx * sy)), max_distance_px=cap
        )
        if protect:
            # pixel centres: u_small = (u + 0.5) / sx - 0.5
            at = (np.asarray(people_px, np.float64) + 0.5) / (sx, sy) - 0.5
            self._learn_around(small, sil_small.labels, at)
        size = self.shape[::-1]
        labels, dist = self._upscale(sil_small, cap)
        dist *= np.float32(dist_scale)
        return Silhouettes(
            labels,
            sil_small.top_v_px * sy,
            (sil_small.bottom_v_px + 1.0) * sy - 1.0,
            dist,
            None
            if changed_small is None
            else cv2.resize(
                changed_small.view(np.uint8), size, interpolation=cv2.INTER_NEAREST
            ).view(bool),
            edges,
            None
            if sil_small.centres_px is None
            else (sil_small.centres_px + 0.5) * (sx, sy) - 0.5,
            None if sil_small.boxes_px is None else _scale_boxes(sil_small.boxes_px, sx, sy),
            None
            if fg_raw is None
            else cv2.resize(fg_raw, size, interpolation=cv2.INTER_NEAREST).view(bool),
        )
