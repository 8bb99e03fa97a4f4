"""Carried-object analysis of tracked hands (paper 004 sections 7.2-7.3).

Per hand and camera (pure functions): project the 3D hand, find its skin blob, select a
circular region around it whose radius adapts to the reliability of eq. 28, filter it (inside
the silhouette, connected to the hand, not skin) and reduce it to the hue distribution of its
connected modes. :class:`CarryAnalyser` (stateful) fuses these over cameras and a time window
(eq. 29), freezes a hand's window while it overlaps another hand, optionally subtracts the
person's other hand (dress colour), and decides per hand whether it carries an object.

Choices where the paper leaves freedom (docs/carry.md):

- *Radius adaptation.* Radii grow from the smallest circle that covers the hand blob (and at
  least ``min_radius_m``) to ``max_radius_m`` in ``n_radius_steps``; the first radius whose rim
  is at least ``grow_stop_bg`` background is used (the circle has left the body: a stretched
  hand). If no rim reaches ``inside_bg`` background the hand is inside the silhouette and the
  smallest circle is used (to exclude as much dress as possible); otherwise the radius with
  the most background on its rim.
- *Blob.* The blob under the projected hand, else the nearest blob pixel within
  ``blob_search_m`` (projected); no blob means the hand is not visible in that camera.
  The circle is centred on the blob's pixels near the projection (a forearm with short
  sleeves does not drag it away).
- *Overlap.* Two hands closer than ``overlap_distance_m`` in 3D freeze their windows: no
  samples are added and the estimate from before the overlap is returned, until they are
  ``separation_margin_m`` farther apart; then the window restarts empty (it "begins after the
  instant the circular regions intersect"). In a single camera, a blob claimed by several
  hands goes to the nearest (the others are hidden behind it), and two hands whose circles
  intersect contribute nothing from that camera for that frame.
- *Extent test.* A mode whose same-hue patches continue far beyond the circle (more than
  ``max_mode_extent`` times their area inside it) is dress or furniture, not a carried object
  (see :func:`surveil.carry.hue.connected_modes`).
"""

from __future__ import annotations

import dataclasses
import functools
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from surveil.camera import Camera, Rig
from surveil.carry.fusion import HueWindow, decide_carrying, subtract_distribution
from surveil.carry.hue import NO_HUE, code_density, pixel_hue_codes, region_mode_pdf
from surveil.carry.settings import CarryConfig
from surveil.datatypes import CameraObservation, CarryEstimate, Limb, Phase, TargetSnapshot
from surveil.validate import readonly, require_shape

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------------------------
# pure per-view functions


def rim_background_fraction(
    people: np.ndarray, centre_px: np.ndarray, radii_px: np.ndarray, n_samples: int
) -> np.ndarray:
    """Share of background pixels on circles around a point (the vector v_c of eq. 28).

    Parameters
    ----------
    people : (H, W) bool or integer
        Silhouette mask or silhouette labels (non-zero = person).
    centre_px : (2,) float
        Circle centre ``(u, v)``.
    radii_px : (R,) float
        Circle radii.
    n_samples : int
        Points sampled evenly on each circle; points outside the image are not counted.

    Returns
    -------
    (R,) float64
        Fraction of the in-image rim points that are background, per radius (0 when a circle
        lies entirely outside the image).

    >>> fg = np.zeros((50, 50), bool); fg[:, :25] = True   # the left half is a person
    >>> bg = rim_background_fraction(fg, np.array([25.0, 25.0]), np.array([10.0]), 64)
    >>> bg.round(1).tolist()  # the rim is half in the person
    [0.5]
    """
    require_shape("people", people, (None, None), np.generic)
    h, w = people.shape
    radii = np.asarray(radii_px, np.float64).reshape(-1)
    cos, sin = _unit_circle(n_samples)
    u = np.rint(centre_px[0] + radii[:, None] * cos).astype(np.int64)
    v = np.rint(centre_px[1] + radii[:, None] * sin).astype(np.int64)
    inside = (u >= 0) & (u < w) & (v >= 0) & (v < h)
    if inside.all():  # the usual case: no masking needed
        return np.count_nonzero(people[v, u] == 0, axis=1) / n_samples
    bg = np.zeros(u.shape, bool)
    bg[inside] = people[v[inside], u[inside]] == 0
    n_in = inside.sum(axis=1)
    return np.where(n_in > 0, bg.sum(axis=1) / np.maximum(n_in, 1), 0.0)


def _linspace(start: float, stop: float, n: int) -> np.ndarray:
    """``np.linspace(start, stop, n)`` to the bit (the same arithmetic), at a fifth of the
    cost of its general-purpose argument handling (it runs for every hand and camera)."""
    if n == 1:
        return np.array([start], np.float64)
    out = _arange(n) * ((stop - start) / (n - 1))
    out += start
    out[-1] = stop
    return out


@functools.cache
def _arange(n: int) -> np.ndarray:
    """(n,) read-only float64 ``0, 1, ..., n - 1``."""
    steps = np.arange(n, dtype=np.float64)
    readonly(steps)
    return steps


@functools.cache
def _unit_circle(n_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(cos, sin) of ``n_samples`` angles evenly spaced from 0 (read-only, computed once)."""
    angles = np.linspace(0.0, 2.0 * np.pi, n_samples, endpoint=False)
    cos, sin = np.cos(angles), np.sin(angles)
    readonly(cos, sin)
    return cos, sin


def reliability(background_fraction: np.ndarray | float, rho_min: float) -> np.ndarray:
    """Eq. 28: rho = (n - sum v_c) / n + rho_min, with ``background_fraction`` the first term.

    (The paper's text calls background 1 and foreground 0 but writes the fraction of
    foreground; its examples -- a stretched hand is reliable -- need the background share.)

    >>> float(reliability(0.75, 0.1))
    0.85
    """
    # eq. 28
    return np.asarray(background_fraction, np.float64) + rho_min


def choose_radius(background_fractions: np.ndarray, grow_stop_bg: float, inside_bg: float) -> int:
    """Index of the radius to use among growing radii (section 7.3, radius adaptation).

    The first radius whose rim has at least ``grow_stop_bg`` background; if none reaches
    ``inside_bg`` the smallest (the hand is inside the silhouette); else the one with the most.

    >>> choose_radius(np.array([0.1, 0.3, 0.6, 0.9]), 0.5, 0.2)
    2
    >>> choose_radius(np.array([0.0, 0.1, 0.15]), 0.5, 0.2)
    0
    >>> choose_radius(np.array([0.1, 0.4, 0.3]), 0.5, 0.2)
    1
    """
    # a handful of radii: plain Python beats numpy's per-call cost here
    bg = np.asarray(background_fractions, np.float64).reshape(-1).tolist()
    if len(bg) == 0:
        raise ValueError("background_fractions must hold at least one radius, got none")
    for i, share in enumerate(bg):
        if share >= grow_stop_bg:
            return i
    best = max(bg)
    return 0 if best < inside_bg else bg.index(best)


def find_hand_blob(blob_labels: np.ndarray, point_px: np.ndarray, search_px: float) -> int:
    """Label of the skin blob under a point, else of the nearest blob pixel within reach.

    Parameters
    ----------
    blob_labels : (H, W) int
        ``BlobSet.labels`` (0 none, i + 1 for blob i), or a crop of it.
    point_px : (2,) float
        ``(u, v)`` in the same pixel frame.
    search_px : float
        Largest distance to a blob pixel.

    Returns
    -------
    int
        The blob label (>= 1), or 0 when no blob pixel lies within ``search_px``.

    >>> lab = np.zeros((20, 20), np.int32); lab[5:8, 5:8] = 1; lab[5:8, 14:17] = 2
    >>> find_hand_blob(lab, np.array([6.0, 6.0]), 3), find_hand_blob(lab, np.array([12.0, 6.0]), 3)
    (1, 2)
    >>> find_hand_blob(lab, np.array([10.0, 15.0]), 3)
    0
    """
    h, w = blob_labels.shape
    u, v = float(point_px[0]), float(point_px[1])
    r = int(np.ceil(search_px))
    x0, x1 = max(int(round(u)) - r, 0), min(int(round(u)) + r + 1, w)
    y0, y1 = max(int(round(v)) - r, 0), min(int(round(v)) + r + 1, h)
    if x0 >= x1 or y0 >= y1:
        return 0
    ur, vr = int(np.floor(u + 0.5)), int(np.floor(v + 0.5))
    if 0 <= ur < w and 0 <= vr < h and blob_labels[vr, ur]:
        # the usual case: no other pixel is nearer (ties aside), so no search is needed
        return int(blob_labels[vr, ur])
    win = blob_labels[y0:y1, x0:x1]
    rows, cols = np.nonzero(win)
    if len(rows) == 0:
        return 0
    d2 = (cols + x0 - u) ** 2 + (rows + y0 - v) ** 2
    best = int(np.argmin(d2))
    if d2[best] > search_px**2 + 0.5:  # +0.5: the pixel under the point is always in reach
        return 0
    return int(win[rows[best], cols[best]])


def circle_box(
    centre_px: np.ndarray, radius_px: float, shape: tuple[int, int]
) -> tuple[slice, slice]:
    """Rows and columns of an image that hold every pixel within ``radius_px`` of a point.

    The box is one pixel wider than the circle on every side, so that rounding in the
    distance test cannot put a pixel of the circle outside it, and is clipped to ``shape``.

    Parameters
    ----------
    centre_px : (2,) float
        Circle centre ``(u, v)``.
    radius_px : float
    shape : (H, W)
        The image.

    Returns
    -------
    (slice, slice)
        ``image[box]`` is the box (rows, then columns).

    >>> circle_box(np.array([10.0, 5.0]), 3.0, (8, 40))
    (slice(1, 8, None), slice(6, 15, None))
    """
    h, w = shape
    u, v, r = float(centre_px[0]), float(centre_px[1]), float(radius_px)
    rows = slice(max(int(np.floor(v - r)) - 1, 0), min(int(np.floor(v + r)) + 2, h))
    cols = slice(max(int(np.floor(u - r)) - 1, 0), min(int(np.floor(u + r)) + 2, w))
    return rows, cols


def hand_region(
    foreground: np.ndarray,
    skin: np.ndarray,
    blob: np.ndarray,
    centre_px: np.ndarray,
    radius_px: float,
) -> np.ndarray:
    """The pixels to colour-analyse around a hand (section 7.2.1).

    Inside the circle, keep the foreground (silhouette or blob) component(s) connected to the
    hand blob (8-connectivity), then remove skin and the blob itself.

    Parameters
    ----------
    foreground : (H, W) bool
        Silhouette mask.
    skin : (H, W) bool
        Skin mask.
    blob : (H, W) bool
        The hand's skin blob.
    centre_px : (2,) float
        Circle centre ``(u, v)``.
    radius_px : float

    Returns
    -------
    (H, W) bool

    >>> fg = np.zeros((20, 20), bool); fg[8:12, 2:14] = True; fg[2:4, 2:4] = True
    >>> blob = np.zeros_like(fg); blob[8:12, 2:6] = True
    >>> reg = hand_region(fg, blob, blob, np.array([4.0, 10.0]), 9.0)
    >>> int(reg.sum()), bool(reg[2, 2]), bool(reg[10, 8])  # the far patch is not connected
    (29, False, True)
    """
    require_shape("foreground", foreground, (None, None), np.bool_)
    require_shape("skin", skin, foreground.shape, np.bool_)
    require_shape("blob", blob, foreground.shape, np.bool_)
    h, w = foreground.shape
    yy, xx = np.arange(h)[:, None], np.arange(w)
    disk = (xx - centre_px[0]) ** 2 + (yy - centre_px[1]) ** 2 <= radius_px**2
    cand = disk & (foreground | blob)
    n_labels, labels = cv2.connectedComponents(cand.view(np.uint8), connectivity=8)
    touches_hand = np.zeros(n_labels, bool)
    touches_hand[labels[blob & disk]] = True
    touches_hand[0] = False  # the background of cand
    return touches_hand[labels] & ~skin & ~blob


@dataclass(frozen=True, slots=True)
class HandView:
    """One hand analysed in one camera.

    camera : str
    centre_px : (2,) float64 -- circle centre (u, v), full-image pixels
    radius_px : float -- the radius chosen by the adaptation
    rho : float -- reliability of eq. 28
    pdf : (B,) float64 -- hue distribution of the region's connected modes (mass <= 1)
    modes_deg : (K,) float64 -- hues of the kept modes, strongest first
    n_region_px : int -- pixels in the filtered region
    blob_label : int -- the hand's blob in ``BlobSet.labels``
    depth_m : float -- the hand's depth in the camera, metres
    """

    camera: str
    centre_px: np.ndarray
    radius_px: float
    rho: float
    pdf: np.ndarray
    modes_deg: np.ndarray
    n_region_px: int
    blob_label: int
    depth_m: float


def projected_radius_px(
    camera: Camera, radius_m: float, depth_m: float, cfg: CarryConfig
) -> float:
    """A metric radius at ``depth_m`` in pixels, clipped to the configured pixel range.

    >>> from surveil.camera import look_at
    >>> cam = look_at("c", np.array([0.0, -4, 1]), np.zeros(3), width=640, height=480,
    ...               hfov_deg=60)
    >>> round(projected_radius_px(cam, 0.1, 4.0, CarryConfig()), 1)
    13.9
    """
    r = camera.K[0, 0] * radius_m / max(depth_m, 1e-9)
    return float(min(max(r, cfg.min_radius_px), cfg.max_radius_px))


@dataclass(frozen=True, slots=True)
class HandSpot:
    """Where one hand is in one camera and the circle around it (steps 1-4 of
    docs/carry.md): enough to tell which views are ambiguous before any colour work.

    camera : str
    centre_px : (2,) float64 -- circle centre (u, v), full-image pixels
    radius_px : float -- the radius chosen by the adaptation
    rho : float -- reliability of eq. 28
    blob_label : int -- the hand's blob in ``BlobSet.labels``
    depth_m : float -- the hand's depth in the camera, metres
    roi : (slice, slice) -- rows and columns of the region of interest in the image
    """

    camera: str
    centre_px: np.ndarray
    radius_px: float
    rho: float
    blob_label: int
    depth_m: float
    roi: tuple[slice, slice]


def locate_hand(
    observation: CameraObservation, camera: Camera, hand_m: np.ndarray, cfg: CarryConfig
) -> HandSpot | None:
    """The hand's blob, circle and reliability in one camera (sections 7.2.1 and 7.3).

    Parameters
    ----------
    observation : CameraObservation
        The camera's silhouettes and blobs.
    camera : Camera
    hand_m : (3,) float
        The hand, world frame, metres.
    cfg : CarryConfig

    Returns
    -------
    HandSpot or None
        None when the hand projects outside the image or no skin blob lies near it.
    """
    return locate_hands(observation, camera, np.asarray(hand_m, np.float64).reshape(1, 3), cfg)[0]


def locate_hands(
    observation: CameraObservation, camera: Camera, hands_m: np.ndarray, cfg: CarryConfig
) -> list[HandSpot | None]:
    """:func:`locate_hand` for several hands ((N, 3) world, metres), projected at once."""
    px, depth = camera.project(np.asarray(hands_m, np.float64).reshape(-1, 3))
    seen = camera.in_image(px, depth)
    return [
        _spot(observation, camera, px[i], float(depth[i]), cfg) if seen[i] else None
        for i in range(len(px))
    ]


def _spot(
    observation: CameraObservation, camera: Camera, uv: np.ndarray, z: float, cfg: CarryConfig
) -> HandSpot | None:
    """:func:`locate_hand` for a hand that projects to ``uv`` (in the image) at depth ``z``."""
    r_lo = projected_radius_px(camera, cfg.min_radius_m, z, cfg)
    r_hi = projected_radius_px(camera, cfg.max_radius_m, z, cfg)
    search = max(camera.K[0, 0] * cfg.blob_search_m / z, 1.5)
    h, w = observation.blobs.labels.shape
    half = int(np.ceil(2.0 * r_hi + search)) + 1
    uc, vc = int(round(uv[0])), int(round(uv[1]))
    x0, x1 = max(uc - half, 0), min(uc + half + 1, w)
    y0, y1 = max(vc - half, 0), min(vc + half + 1, h)
    origin = np.array([x0, y0], np.float64)
    blob_labels = observation.blobs.labels[y0:y1, x0:x1]
    hand_px = uv - origin
    label = find_hand_blob(blob_labels, hand_px, search)
    if label == 0:
        return None
    # the blob's pixels in the region of interest lie in its bounding box: compare there only
    bx, by, bw, bh = (int(v) for v in observation.blobs.bboxes_px[label - 1])
    r0, c0 = max(by - y0, 0), max(bx - x0, 0)
    rows, cols = np.nonzero(blob_labels[r0 : by + bh - y0, c0 : bx + bw - x0] == label)
    rows, cols = rows + r0, cols + c0
    # centre on the blob's pixels near the hand (a bare forearm must not drag the circle away)
    du, dv = cols - hand_px[0], rows - hand_px[1]
    d2 = du * du + dv * dv
    for reach in (r_lo, r_hi):
        near = d2 <= reach**2
        if near.any():
            rows, cols = rows[near], cols[near]
            break
    # integer sums are exact: the same centre as the arrays' means, at a third of the cost
    centre = np.array([int(cols.sum()), int(rows.sum())], np.float64) / len(cols)
    r_blob = float(np.sqrt(np.max((cols - centre[0]) ** 2 + (rows - centre[1]) ** 2))) + 0.5
    r_small = min(max(r_lo, r_blob), r_hi)
    radii = _linspace(r_small, r_hi, cfg.n_radius_steps)
    people = observation.silhouettes.labels[y0:y1, x0:x1]
    bg = rim_background_fraction(people, centre, radii, cfg.n_rim_samples)
    k = choose_radius(bg, cfg.grow_stop_bg, cfg.inside_bg)
    return HandSpot(
        camera=camera.name,
        centre_px=centre + origin,
        radius_px=float(radii[k]),
        rho=float(reliability(bg[k], cfg.rho_min)),
        blob_label=label,
        depth_m=z,
        roi=(slice(y0, y1), slice(x0, x1)),
    )


def hand_view(
    bgr: np.ndarray, observation: CameraObservation, spot: HandSpot, cfg: CarryConfig
) -> HandView:
    """The hue distribution of a located hand's region (sections 7.2.1-7.2.2).

    Only the region of interest is processed, and most of the work only on the bounding box
    of the circle; the extent test of :func:`~surveil.carry.hue.connected_modes` looks at the
    whole region of interest.

    Parameters
    ----------
    bgr : (H, W, 3) uint8
        The camera image.
    observation : CameraObservation
        Its silhouettes, skin mask and blobs.
    spot : HandSpot
        The hand in this camera (:func:`locate_hand`).
    cfg : CarryConfig
    """
    roi = spot.roi
    origin = np.array([roi[1].start, roi[0].start], np.float64)
    centre = spot.centre_px - origin
    foreground = observation.silhouettes.labels[roi] > 0
    skin = observation.skin[roi]
    # The region lies inside the circle, so it is built on the circle's box (shifting the
    # centre by the box's integer origin is exact: the same circle). Only the extent test
    # looks further, at the person's non-skin pixels in the whole region of interest; the
    # region is a subset of them, so one hue-code image serves both.
    box = circle_box(centre, spot.radius_px, foreground.shape)
    box_origin = np.array([box[1].start, box[0].start], np.float64)
    blob = observation.blobs.labels[roi][box] == spot.blob_label
    region = hand_region(foreground[box], skin[box], blob, centre - box_origin, spot.radius_px)
    person_codes = pixel_hue_codes(
        bgr[roi], cfg.min_saturation, cfg.min_value, mask=foreground & ~skin
    )
    pdf, modes = region_mode_pdf(
        person_codes[box],
        region,
        n_bins=cfg.hue_bins,
        sigma_deg=cfg.kde_sigma_deg,
        min_peak=cfg.mode_min_peak,
        halfwidth_deg=cfg.mode_halfwidth_deg,
        min_pixels=cfg.mode_min_pixels,
        outer_hue_codes=person_codes,
        region_box=box,
        max_extent=cfg.max_mode_extent,
    )
    return HandView(
        camera=spot.camera,
        centre_px=spot.centre_px,
        radius_px=spot.radius_px,
        rho=spot.rho,
        pdf=pdf,
        modes_deg=modes,
        n_region_px=int(np.count_nonzero(region)),
        blob_label=spot.blob_label,
        depth_m=spot.depth_m,
    )


def analyse_hand_view(
    bgr: np.ndarray,
    observation: CameraObservation,
    camera: Camera,
    hand_m: np.ndarray,
    cfg: CarryConfig,
) -> HandView | None:
    """Hue distribution and reliability of one hand in one camera (sections 7.2-7.3):
    :func:`locate_hand` (same arguments, and its None when the hand is not seen), then
    :func:`hand_view` on ``bgr``, the (H, W, 3) uint8 camera image."""
    spot = locate_hand(observation, camera, hand_m, cfg)
    return None if spot is None else hand_view(bgr, observation, spot, cfg)


def dress_view_hist(
    bgr: np.ndarray,
    observation: CameraObservation,
    camera: Camera,
    centre_m: np.ndarray,
    radius_m: float,
    cfg: CarryConfig,
    exclude_circles: np.ndarray | None = None,
) -> tuple[np.ndarray, int]:
    """Hue histogram of a person's dress around a point of their body, in one camera.

    The pixels within ``radius_m`` (projected) of ``centre_m`` that are inside a silhouette,
    not skin, not within any of ``exclude_circles`` (the hands: an object held in front of
    the body is not dress) and have a reliable hue (``cfg.min_saturation``,
    ``cfg.min_value``).

    Parameters
    ----------
    bgr : (H, W, 3) uint8
    observation : CameraObservation
    camera : Camera
    centre_m : (3,) float -- world frame, metres
    radius_m : float
    cfg : CarryConfig
    exclude_circles : (K, 3) float, optional -- ``(u, v, r)`` pixel circles to leave out

    Returns
    -------
    hist : (B,) float64
        Counts per hue bin (``cfg.hue_bins``), smoothed with ``cfg.kde_sigma_deg``; not
        normalised (zeros when nothing is seen).
    n_px : int
        Pixels with a hue that went into it.
    """
    px, depth = camera.project(np.asarray(centre_m, np.float64).reshape(1, 3))
    if not camera.in_image(px, depth)[0]:
        return np.zeros(cfg.hue_bins), 0
    centre = px[0]
    radius = camera.K[0, 0] * radius_m / max(float(depth[0]), 1e-9)
    rows, cols = circle_box(centre, radius, bgr.shape[:2])
    yy = np.arange(rows.start, rows.stop)[:, None]
    xx = np.arange(cols.start, cols.stop)[None, :]
    mask = (xx - centre[0]) ** 2 + (yy - centre[1]) ** 2 <= radius**2
    mask &= (observation.silhouettes.labels[rows, cols] > 0) & ~observation.skin[rows, cols]
    if exclude_circles is not None and len(exclude_circles):
        # only circles that reach the region can take pixels out of it
        gaps = np.hypot(exclude_circles[:, 0] - centre[0], exclude_circles[:, 1] - centre[1])
        for u, v, r in exclude_circles[gaps < radius + exclude_circles[:, 2]]:
            mask &= (xx - u) ** 2 + (yy - v) ** 2 > r * r
    if not mask.any():
        return np.zeros(cfg.hue_bins), 0
    codes = pixel_hue_codes(bgr[rows, cols], cfg.min_saturation, cfg.min_value, mask=mask)
    n_px = int(np.count_nonzero(codes != NO_HUE))
    if n_px == 0:
        return np.zeros(cfg.hue_bins), 0
    return code_density(codes, cfg.hue_bins, cfg.kde_sigma_deg), n_px


# ---------------------------------------------------------------------------------------------
# the stateful analyser


def is_analysed_hand(target: TargetSnapshot, cfg: CarryConfig) -> bool:
    """Whether :class:`CarryAnalyser` treats a target as a hand.

    Labelled hands (``LEFT_HAND``/``RIGHT_HAND``) are; so are unlabelled (``UNKNOWN``) targets
    lower than ``cfg.unknown_max_height_m`` (a standing adult's head is higher: after a
    coincidence the trackers are unlabelled for a while, and their carried objects matter
    then). Heads and lost targets are not.

    >>> t = TargetSnapshot(1, 0, Limb.UNKNOWN, Phase.UNLABELLED, np.array([0.0, 0, 1.1]))
    >>> is_analysed_hand(t, CarryConfig())
    True
    """
    if target.phase is Phase.LOST or not np.all(np.isfinite(target.mean_m)):
        return False
    if target.limb.is_hand:
        return True
    return target.limb is Limb.UNKNOWN and float(target.mean_m[2]) < cfg.unknown_max_height_m


@dataclass(slots=True)
class _HandState:
    window: HueWindow
    frozen: bool = False
    last: CarryEstimate | None = None


class CarryAnalyser:
    """Per-hand carried-object estimates over time (paper 004 sections 7.2-7.3, eq. 28-29).

    Parameters
    ----------
    cfg : CarryConfig
    rig : Rig
        Cameras by name; observations of cameras not in the rig are ignored.

    Notes
    -----
    State per hand target: a :class:`~surveil.carry.fusion.HueWindow` ring buffer of
    ``cfg.max_window_samples`` samples, a frozen flag and the last estimate; targets that
    disappear from the input are forgotten, so memory does not grow with time (lost ones are
    kept, not analysed, until they are retired).
    """

    def __init__(self, cfg: CarryConfig, rig: Rig) -> None:
        self.cfg = cfg
        self.rig = rig
        self._cams = rig.as_mapping()
        self._window_ns = int(round(cfg.window_s * 1e9))
        self._hands: dict[int, _HandState] = {}
        self._prev_t_ns: int | None = None  # the previous step's time
        # person -> (dress hue distribution (B,) summing to 1, time of its last update, ns)
        self._dress: dict[int, tuple[np.ndarray, int]] = {}

    def reset(self) -> None:
        """Forget every hand and every person's dress."""
        self._hands.clear()
        self._dress.clear()
        self._prev_t_ns = None

    def dress(self, person: int) -> np.ndarray | None:
        """(B,) hue distribution of the person's dress (sums to 1), or None if not seen."""
        entry = self._dress.get(person)
        return None if entry is None else entry[0]

    def is_frozen(self, target_id: int) -> bool:
        """Whether the hand's window is frozen by an overlap (False for unknown ids)."""
        state = self._hands.get(target_id)
        return state is not None and state.frozen

    def restart(self, target_id: int) -> None:
        """Empty a hand's window (no-op for unknown ids): what it held until now is no longer
        evidence, e.g. once it left the point where it put down or took up an object."""
        state = self._hands.get(target_id)
        if state is not None:
            state.window.clear()
            log.debug("carry: hand %d window restarted on request", target_id)

    def step(
        self,
        t_ns: int,
        images: Mapping[str, np.ndarray],
        observations: Mapping[str, CameraObservation],
        targets: Sequence[TargetSnapshot],
    ) -> dict[int, CarryEstimate]:
        """Analyse one frame set.

        Parameters
        ----------
        t_ns : int
            Time of the frame set, ns on the recording clock.
        images : Mapping[str, (H, W, 3) uint8 BGR]
            Frames by camera name (absent camera = missing frame).
        observations : Mapping[str, CameraObservation]
            The per-camera stage's output for the same frames.
        targets : Sequence[TargetSnapshot]
            All live trackers; the hands among them (:func:`is_analysed_hand`) are analysed.

        Returns
        -------
        dict[int, CarryEstimate]
            One estimate per analysed hand, by tracker id.
        """
        cfg = self.cfg
        hands = [t for t in targets if is_analysed_hand(t, cfg)]
        ids = [t.target_id for t in hands]
        # a lost hand keeps its window and last estimate (not analysed meanwhile; with
        # pause_hidden its samples do not age): re-acquired, it still holds what it held; only
        # targets that are gone (retired) are forgotten
        for gone in set(self._hands) - {t.target_id for t in targets}:
            del self._hands[gone]
        if cfg.pause_hidden and self._prev_t_ns is not None:
            for hidden in set(self._hands) - set(ids):
                self._hands[hidden].window.pause(t_ns - self._prev_t_ns)
        self._prev_t_ns = t_ns
        for tid in ids:
            if tid not in self._hands:
                self._hands[tid] = _HandState(HueWindow(cfg.max_window_samples, cfg.hue_bins))
        if not hands:
            return {}
        pos = np.stack([t.mean_m for t in hands])
        self._update_overlaps(pos, ids)
        active = np.array([not self._hands[i].frozen for i in ids])
        for cam_name, img in images.items():
            obs = observations.get(cam_name)
            cam = self._cams.get(cam_name)
            if obs is None or cam is None:
                continue
            todo = np.flatnonzero(active)
            located = locate_hands(obs, cam, pos[todo], cfg)
            spots = {int(j): sp for j, sp in zip(todo, located, strict=True) if sp is not None}
            # colour work only for the views that count (~15-25 % are ambiguous)
            for j in _unambiguous_views(spots, self._frozen_circles(cam, pos, ~active)):
                view = hand_view(img, obs, spots[j], cfg)
                self._hands[ids[j]].window.push(t_ns, view.rho, view.pdf)
        fused = {tid: self._hands[tid].window.fused(t_ns, self._window_ns) for tid in ids}
        if cfg.subtract_dress:
            self._update_dress(t_ns, images, observations, targets, pos)
        siblings = _siblings(hands) if cfg.subtract_clothing else {}
        out: dict[int, CarryEstimate] = {}
        for t in hands:
            state = self._hands[t.target_id]
            if state.frozen and state.last is not None:
                out[t.target_id] = dataclasses.replace(state.last, t_ns=t_ns, label=t.label)
                continue
            pdf, total_rho = fused[t.target_id]
            sib = siblings.get(t.target_id)
            if sib is not None and fused[sib][1] > 0:
                pdf = subtract_distribution(pdf, fused[sib][0])
            dress = self.dress(t.person) if cfg.subtract_dress and t.person > 0 else None
            if dress is not None:
                pdf = subtract_distribution(pdf, dress)
            since = state.window.oldest_ns(t_ns, self._window_ns)
            est = self._estimate(t, t_ns, pdf, total_rho, since)
            if not state.frozen:
                state.last = est
            out[t.target_id] = est
        return out

    def _update_overlaps(self, pos: np.ndarray, ids: list[int]) -> None:
        """Freeze hands that come within ``overlap_distance_m`` of another hand; unfreeze (and
        restart the window of) those farther than that plus ``separation_margin_m``."""
        cfg = self.cfg
        d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
        np.fill_diagonal(d, np.inf)
        nearest = d.min(axis=1)
        for tid, dist in zip(ids, nearest.tolist(), strict=True):
            state = self._hands[tid]
            if not state.frozen and dist < cfg.overlap_distance_m:
                state.frozen = True
                log.debug("carry: hand %d overlaps another hand; window frozen", tid)
            elif state.frozen and dist > cfg.overlap_distance_m + cfg.separation_margin_m:
                state.frozen = False
                state.window.clear()
                log.debug("carry: hand %d separated; window restarted", tid)

    def _frozen_circles(self, cam: Camera, pos: np.ndarray, frozen: np.ndarray) -> np.ndarray:
        """(K, 3) ``(u, v, r)`` largest circles of the frozen hands that project into ``cam``
        (they are not analysed, but what they hold must not leak into a neighbour)."""
        return self._hand_circles(cam, pos[frozen])

    def _hand_circles(self, cam: Camera, pos: np.ndarray) -> np.ndarray:
        """(K, 3) ``(u, v, r)`` largest circles of the hands at ``pos`` ((N, 3), world) that
        project into ``cam``."""
        if not len(pos):
            return np.zeros((0, 3))
        px, depth = cam.project(pos)
        seen = cam.in_image(px, depth)
        r = cam.K[0, 0] * self.cfg.max_radius_m / np.maximum(depth, 1e-9)
        r = np.clip(r, self.cfg.min_radius_px, self.cfg.max_radius_px)
        return np.column_stack([px, r])[seen]

    def _update_dress(
        self,
        t_ns: int,
        images: Mapping[str, np.ndarray],
        observations: Mapping[str, CameraObservation],
        targets: Sequence[TargetSnapshot],
        hands_m: np.ndarray,
    ) -> None:
        """Update each person's dress distribution from the regions below their head.

        Per region (``dress_drops_m`` below the head, radius ``dress_radius_m``) the hued
        pixels of every camera are pooled into one distribution (summing to 1); the dress is
        the bin-wise maximum over the regions (shirt and trousers may differ: each must
        cancel fully), averaged over time with the time constant ``dress_time_s``, at most
        every ``dress_interval_s``. The hands' largest circles are left out, so an object held
        in front of the body is not dress. People who are gone are forgotten."""
        cfg = self.cfg
        heads = {
            t.person: t.mean_m
            for t in targets
            if t.limb is Limb.HEAD and t.person > 0 and t.phase is not Phase.LOST
        }
        for gone in set(self._dress) - set(heads):
            del self._dress[gone]
        interval_ns = cfg.dress_interval_s * 1e9
        heads = {
            person: head_m
            for person, head_m in heads.items()
            if person not in self._dress or t_ns - self._dress[person][1] >= interval_ns
        }
        if not heads:
            return
        views = [
            (images[name], observations[name], self._cams[name])
            for name in images
            if name in observations and name in self._cams
        ]
        circles = [self._hand_circles(cam, hands_m) for _, _, cam in views]
        for person, head_m in heads.items():
            regions = []
            for drop in cfg.dress_drops_m:
                centre = head_m - np.array([0.0, 0.0, drop])
                total, n_px = np.zeros(cfg.hue_bins), 0
                for (img, obs, cam), excl in zip(views, circles, strict=True):
                    hist, n = dress_view_hist(img, obs, cam, centre, cfg.dress_radius_m, cfg, excl)
                    total += hist
                    n_px += n
                if n_px >= cfg.dress_min_pixels:
                    regions.append(total / n_px)
            if not regions:
                continue
            now = np.max(regions, axis=0)
            prev = self._dress.get(person)
            if prev is not None and cfg.dress_time_s > 0:
                gain = 1.0 - float(np.exp(-(t_ns - prev[1]) * 1e-9 / cfg.dress_time_s))
                now = prev[0] + gain * (now - prev[0])
            self._dress[person] = (now, t_ns)

    def _estimate(
        self,
        target: TargetSnapshot,
        t_ns: int,
        pdf: np.ndarray,
        total_rho: float,
        since_ns: int | None,
    ) -> CarryEstimate:
        cfg = self.cfg
        decision = decide_carrying(
            pdf,
            total_rho,
            carry_mass=cfg.carry_mass,
            halfwidth_deg=cfg.mode_mass_halfwidth_deg,
            evidence_rho=cfg.evidence_rho,
        )
        mass = pdf.sum()
        hue_pdf = pdf / mass if mass > 0 else np.zeros(cfg.hue_bins)
        return CarryEstimate(
            target_id=target.target_id,
            label=target.label,
            t_ns=t_ns,
            carrying=decision.carrying,
            hue_deg=decision.hue_deg if decision.carrying else None,
            confidence=float(np.clip(decision.confidence, 0.0, 1.0)),
            hue_pdf=hue_pdf,
            since_ns=since_ns,
        )


def _unambiguous_views(
    views: Mapping[int, HandSpot], obstacles: np.ndarray | None = None
) -> list[int]:
    """Keys of the views that may feed their hand's window.

    A blob claimed by several hands belongs to the nearest one (the others are behind it);
    two hands whose circles intersect in the image both give nothing (one object must not be
    counted in both hands, paper 004 section 7.3), nor does a hand whose circle intersects one
    of the ``obstacles`` ((K, 3) ``(u, v, r)`` circles of hands not analysed, e.g. frozen).
    """
    obstacles = np.zeros((0, 3)) if obstacles is None else obstacles
    owner: dict[int, int] = {}
    for j, v in views.items():
        if v.blob_label not in owner or v.depth_m < views[owner[v.blob_label]].depth_m:
            owner[v.blob_label] = j
    keep = sorted(owner.values())
    if not keep:
        return []
    centres = np.array([views[j].centre_px for j in keep])
    radii = np.array([views[j].radius_px for j in keep])
    gaps = np.hypot(*(centres[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    clash = gaps < radii[:, None] + radii[None, :]
    np.fill_diagonal(clash, False)
    gaps = np.hypot(*(centres[:, None, :] - obstacles[None, :, :2]).transpose(2, 0, 1))
    blocked = (gaps < radii[:, None] + obstacles[None, :, 2]).any(axis=1)
    return [j for j, bad in zip(keep, clash.any(axis=1) | blocked, strict=True) if not bad]


def _siblings(hands: Sequence[TargetSnapshot]) -> dict[int, int]:
    """Tracker id -> the tracker of the same person's other hand (labelled hands only)."""
    by_person: dict[tuple[int, Limb], int] = {
        (t.person, t.limb): t.target_id for t in hands if t.person > 0 and t.limb.is_hand
    }
    out = {}
    for (person, limb), tid in by_person.items():
        other = Limb.RIGHT_HAND if limb is Limb.LEFT_HAND else Limb.LEFT_HAND
        if (person, other) in by_person:
            out[tid] = by_person[(person, other)]
    return out
