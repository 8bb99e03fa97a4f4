"""Hue histograms and their modes (paper 004 section 7.2.2).

Pure, vectorised functions on small image regions. Hue is in degrees ``[0, 360)`` wherever it
leaves this module (modes, histogram bins). Inside, images hold *hue codes*: OpenCV's 8-bit hue
(0-179, half the hue in degrees) as uint8, with :data:`NO_HUE` for pixels without a reliable
hue or outside the pixels of interest (:func:`pixel_hue_codes`). With only 180 possible hues,
a per-pixel test against a mode becomes a 256-entry table lookup (:func:`codes_near_hues`)
instead of float arithmetic on every pixel. Histograms are circular: bin ``i`` of ``B`` is
centred on ``i * 360 / B`` degrees and covers half a bin either side, so bin 0 straddles 0/360.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np
from scipy.ndimage import gaussian_filter1d

from surveil.validate import readonly, require_shape

NO_HUE = 255
"""Hue code of a pixel that has no reliable hue (grey, dark) or is not to be analysed."""

HUE_CODE_DEG = np.arange(180, dtype=np.float32) * np.float32(2.0)
"""(180,) float32: the hue in degrees of each hue code (OpenCV 8-bit hue x 2)."""
readonly(HUE_CODE_DEG)


def pixel_hue_codes(
    bgr: np.ndarray, min_saturation: float, min_value: float, mask: np.ndarray | None = None
) -> np.ndarray:
    """Hue code of every pixel: OpenCV 8-bit hue, or :data:`NO_HUE`.

    Parameters
    ----------
    bgr : (H, W, 3) uint8
        BGR image (normally a small region of interest).
    min_saturation, min_value : float
        HSV saturation and value thresholds in [0, 1]; pixels below either get ``NO_HUE``
        (too grey or too dark to have a hue).
    mask : (H, W) bool, optional
        The pixels of interest; the others get ``NO_HUE``. Default: all.

    Returns
    -------
    (H, W) uint8
        Hue in degrees / 2, in ``0..179`` (:data:`HUE_CODE_DEG` maps it to degrees), or
        ``NO_HUE``.

    Examples
    --------
    >>> img = np.array([[[0, 255, 0], [128, 128, 128], [0, 0, 200]]], np.uint8)  # BGR
    >>> codes = pixel_hue_codes(img, 0.3, 0.1)
    >>> codes.tolist(), HUE_CODE_DEG[codes[0, 0]]  # green, grey, red
    ([[60, 255, 0]], np.float32(120.0))
    >>> pixel_hue_codes(img, 0.3, 0.1, mask=np.array([[False, True, True]])).tolist()
    [[255, 255, 0]]
    """
    require_shape("bgr", bgr, (None, None, 3), np.uint8)
    if mask is not None:
        require_shape("mask", mask, bgr.shape[:2], np.bool_)
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    # integer bounds: inRange rounds a fractional bound to the nearest integer, which could
    # admit pixels just below the threshold
    s_min = int(np.ceil(min_saturation * 255.0))
    v_min = int(np.ceil(min_value * 255.0))
    has_hue = cv2.inRange(hsv, (0, s_min, v_min), (255, 255, 255))  # 255 = has a hue
    if mask is not None:
        has_hue = cv2.bitwise_and(has_hue, has_hue, mask=mask.view(np.uint8))
    # hue | 0 = hue where it has one, hue | 255 = NO_HUE elsewhere (OpenCV: ~4x numpy's where)
    return cv2.bitwise_or(cv2.extractChannel(hsv, 0), cv2.bitwise_not(has_hue))


def codes_near_hues(hues_deg: np.ndarray, halfwidth_deg: float) -> np.ndarray:
    """Which hue codes lie within ``+-halfwidth_deg`` of each of some hues (circularly).

    Parameters
    ----------
    hues_deg : (M,) float
        Hues, degrees.
    halfwidth_deg : float

    Returns
    -------
    (M, 256) bool
        Row m indexed by hue code: ``codes_near_hues(h, d)[m][codes]`` is the mask of the
        pixels whose hue is near ``h[m]``. ``NO_HUE`` (and every code above 179) is False.

    >>> np.flatnonzero(codes_near_hues(np.array([1.0]), 3.0)[0]).tolist()  # 358, 0, 2, 4 deg
    [0, 1, 2, 179]
    """
    hues = np.asarray(hues_deg, np.float64).reshape(-1, 1)
    tables = np.zeros((len(hues), 256), bool)
    tables[:, : len(HUE_CODE_DEG)] = circular_distance_deg(HUE_CODE_DEG, hues) <= halfwidth_deg
    return tables


def hue_to_bins(hues_deg: np.ndarray, n_bins: int) -> np.ndarray:
    """Bin index of each hue: bin ``i`` is centred on ``i * 360 / n_bins`` degrees.

    >>> hue_to_bins(np.array([0.0, 0.9, 1.1, 359.0, 120.0]), 180).tolist()
    [0, 0, 1, 0, 60]
    """
    width = 360.0 / n_bins
    return np.floor(np.asarray(hues_deg, np.float64) / width + 0.5).astype(np.int64) % n_bins


def bin_centres_deg(n_bins: int) -> np.ndarray:
    """(n_bins,) float64 hue at each bin centre, degrees.

    >>> bin_centres_deg(4).tolist()
    [0.0, 90.0, 180.0, 270.0]
    """
    return np.arange(n_bins) * (360.0 / n_bins)


def circular_distance_deg(a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray:
    """Smallest absolute angle between hues, degrees in ``[0, 180]`` (NaN propagates).

    >>> circular_distance_deg(np.array([350.0, 10.0, 90.0]), 5.0).tolist()
    [15.0, 5.0, 85.0]
    """
    # float32 images stay float32 (no copy to float64 on the hot path)
    d = np.abs(np.subtract(a, b, dtype=np.result_type(a, np.float32))) % 360.0
    return np.minimum(d, 360.0 - d)


def hue_histogram(
    hues_deg: np.ndarray,
    n_bins: int,
    n_total: int | None = None,
    *,
    weights: np.ndarray | None = None,
) -> np.ndarray:
    """Circular hue histogram normalised by a pixel count.

    Parameters
    ----------
    hues_deg : (N,) float
        Hues in degrees (NaN entries are ignored, but still count in the default total).
    n_bins : int
        Number of bins B over ``[0, 360)``.
    n_total : int, optional
        Divide the counts by this (e.g. all pixels of the region, including those without a
        reliable hue, so that the histogram is a share of the region). Default: the number of
        pixels, ``N`` or ``weights.sum()``.
    weights : (N,) int or float, optional
        Pixels per hue (e.g. a count per hue code with ``hues_deg`` = :data:`HUE_CODE_DEG`).
        Default: one pixel each.

    Returns
    -------
    (B,) float64
        Counts / ``n_total``; sums to 1 when every hue is finite and ``n_total`` is the default.
        All zeros for an empty input.

    >>> hue_histogram(np.array([0.0, 359.5, 120.0, np.nan]), 4).tolist()
    [0.5, 0.25, 0.0, 0.0]
    >>> hue_histogram(np.array([0.0, 120.0]), 4, weights=np.array([3, 1])).tolist()
    [0.75, 0.25, 0.0, 0.0]
    """
    hues = np.asarray(hues_deg, np.float64).reshape(-1)
    if n_bins < 1:
        raise ValueError(f"n_bins must be >= 1, got {n_bins}")
    if weights is not None:
        require_shape("weights", weights, hues.shape, np.number)
    if n_total is not None:
        total = int(n_total)
    else:
        total = len(hues) if weights is None else weights.sum()
    finite = np.isfinite(hues)
    if total <= 0 or not finite.any():
        return np.zeros(n_bins)
    bins = hue_to_bins(hues[finite], n_bins)
    # bincount sums weights in float64; sums of pixel counts stay exact integers
    counts = np.bincount(
        bins, weights=None if weights is None else weights[finite], minlength=n_bins
    )
    return counts / float(total)


def code_density(
    hue_codes: np.ndarray, n_bins: int, sigma_deg: float, n_total: int | None = None
) -> np.ndarray:
    """Smoothed hue histogram of an image of hue codes (:data:`NO_HUE` pixels ignored).

    Parameters
    ----------
    hue_codes : (H, W) uint8
    n_bins, sigma_deg : see :func:`hue_histogram` and :func:`smooth_circular`
    n_total : int, optional
        Divide the counts by this (default 1: plain pixel counts).

    Returns
    -------
    (B,) float64

    >>> codes = np.array([[0, 0, 60, NO_HUE]], np.uint8)  # 0 deg twice, 120 deg (bin 1) once
    >>> d = code_density(codes, 4, 0.0)
    >>> d.tolist()
    [2.0, 1.0, 0.0, 0.0]
    """
    counts = np.bincount(hue_codes.reshape(-1), minlength=256)[: len(HUE_CODE_DEG)]
    # binning and smoothing are linear: one (180, B) table does both (a few microseconds,
    # against ~60 for the histogram and scipy's filter; it runs ~15 times per frame set)
    density = counts @ _code_density_table(n_bins, float(sigma_deg))
    return density if n_total is None else density / float(n_total)


@functools.cache
def _code_density_table(n_bins: int, sigma_deg: float) -> np.ndarray:
    """(180, n_bins) read-only: row c is the smoothed histogram of one pixel of hue code c,
    so that ``counts @ table`` is :func:`smooth_circular` of :func:`hue_histogram` of the
    pixels counted per code (the same numbers up to rounding)."""
    table = np.stack(
        [
            smooth_circular(hue_histogram(HUE_CODE_DEG[c : c + 1], n_bins, n_total=1), sigma_deg)
            for c in range(len(HUE_CODE_DEG))
        ]
    )
    readonly(table)
    return table


def smooth_circular(hist: np.ndarray, sigma_deg: float) -> np.ndarray:
    """Kernel density estimate: the histogram convolved with a wrapped Gaussian.

    Parameters
    ----------
    hist : (B,) float
    sigma_deg : float
        Kernel standard deviation in degrees (0 = no smoothing).

    Returns
    -------
    (B,) float64
        Same total mass as ``hist`` (the kernel wraps around 0/360).

    >>> h = np.zeros(36); h[0] = 1.0
    >>> s = smooth_circular(h, 10.0)
    >>> round(float(s.sum()), 6), bool(s[1] == s[-1])
    (1.0, True)
    """
    h = np.asarray(hist, np.float64)
    require_shape("hist", h, (None,), np.floating)
    if sigma_deg <= 0 or len(h) == 0:
        return h.copy()
    sigma_bins = sigma_deg * len(h) / 360.0
    # keep the kernel shorter than the circle so that it does not wrap onto itself
    truncate = min(4.0, 0.5 * (len(h) - 1) / sigma_bins)
    return gaussian_filter1d(h, sigma_bins, mode="wrap", truncate=truncate)


def find_modes(density: np.ndarray, min_peak: float = 0.0) -> np.ndarray:
    """Local maxima of a circular density, strongest first.

    A bin is a maximum when it is higher than its left neighbour and not lower than its right
    one (a plateau counts once, at its first bin). A constant density has no mode.

    Parameters
    ----------
    density : (B,) float
    min_peak : float
        Maxima lower than this are dropped.

    Returns
    -------
    (M,) int64
        Bin indices, by decreasing density.

    >>> d = np.array([3.0, 1.0, 0.0, 2.0, 0.5, 1.0])  # bin 0 wraps against bin 5
    >>> find_modes(d).tolist()
    [0, 3]
    """
    d = np.asarray(density, np.float64)
    left, right = _circular_neighbours(d)
    idx = np.flatnonzero((d > left) & (d >= right) & (d >= min_peak))
    return idx[np.argsort(-d[idx], kind="stable")]


def mode_basins(density: np.ndarray) -> np.ndarray:
    """The local maximum that each bin of a circular density climbs to.

    Every bin steps to its highest neighbour (itself included) until it stops; the steps are
    followed by pointer doubling, so the cost is O(B log B) without a Python loop over bins.

    Returns
    -------
    (B,) int64
        Bin index of the maximum reached from each bin.

    >>> mode_basins(np.array([3.0, 1.0, 0.0, 2.0, 0.5, 1.0])).tolist()
    [0, 0, 3, 3, 3, 0]
    """
    d = np.asarray(density, np.float64)
    n = len(d)
    left, right = _circular_neighbours(d)
    # self first: ties stay put
    move = np.array([0, -1, 1])[np.argmax(np.stack([d, left, right]), axis=0)]
    step = (np.arange(n) + move) % max(n, 1)
    for _ in range(max(int(np.ceil(np.log2(max(n, 2)))) + 1, 1)):
        step = step[step]
    return step


def _circular_neighbours(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(d[i - 1], d[i + 1])`` for every bin of a circular array (cheaper than two np.roll)."""
    ring = np.concatenate((d[-1:], d, d[:1]))
    return ring[:-2], ring[2:]


def refine_peaks_deg(density: np.ndarray, peak_bins: np.ndarray) -> np.ndarray:
    """Sub-bin hues of maxima by a parabola through each and its two neighbours, degrees.

    Parameters
    ----------
    density : (B,) float
        A circular density.
    peak_bins : (M,) int
        Its maxima (e.g. :func:`find_modes`).

    Returns
    -------
    (M,) float64
        Hues in ``[0, 360)``; a peak moves at most half a bin.

    >>> d = np.array([0.0, 1.0, 3.0, 3.0, 1.0, 0.0])
    >>> refine_peaks_deg(d, np.array([2])).tolist()  # between bins 2 and 3 (120 and 180 deg)
    [150.0]
    """
    d = np.asarray(density, np.float64)
    peaks = np.asarray(peak_bins, np.int64).reshape(-1)
    n = len(d)
    y0, y1, y2 = d[(peaks - 1) % n], d[peaks], d[(peaks + 1) % n]
    denom = y0 - 2.0 * y1 + y2
    is_peaked = denom < 0  # else flat or not a maximum: no parabola vertex, no offset
    vertex = np.clip(0.5 * (y0 - y2) / np.where(is_peaked, denom, -1.0), -0.5, 0.5)
    offset = np.where(is_peaked, vertex, 0.0)
    return ((peaks + offset) * 360.0 / n) % 360.0


def connected_modes(
    hue_codes: np.ndarray,
    modes_deg: np.ndarray,
    halfwidth_deg: float,
    min_pixels: int,
    *,
    outer_hue_codes: np.ndarray | None = None,
    region_box: tuple[slice, slice] | None = None,
    max_extent: float = 0.0,
) -> np.ndarray:
    """Connectivity check of section 7.2.2: is each mode a compact patch in the image?

    A mode is kept when the pixels whose hue lies within ``+-halfwidth_deg`` of it contain a
    connected region (8-connectivity) of at least ``min_pixels`` pixels. Scattered noise with
    the same hue forms no such region.

    Parameters
    ----------
    hue_codes : (H, W) uint8
        Hue code per pixel (:func:`pixel_hue_codes`); ``NO_HUE`` outside the region and for
        pixels without a hue.
    modes_deg : (M,) float
        Mode hues, degrees.
    halfwidth_deg : float
        delta (paper: about 3 degrees).
    min_pixels : int
        n (paper: 10).
    outer_hue_codes : (H', W') uint8, optional
        Hue codes of a larger neighbourhood (``NO_HUE`` outside it) that contains the region.
        With ``max_extent > 0``, a mode is also dropped when its patches, followed into this
        neighbourhood, are more than ``max_extent`` times larger than inside the region: the
        colour belongs to something that extends beyond the hand's circle (dress, trousers,
        furniture) rather than to a compact carried object. (An addition to the paper, which
        removes the sleeve where it crosses the bounding circle.)
    region_box : (slice, slice), optional
        Rows and columns of ``outer_hue_codes`` that ``hue_codes`` covers; default: all (the
        two images have the same shape). The connectivity check then runs on the small
        region image, and only the extent test on the neighbourhood.
    max_extent : float
        0 disables the extent test.

    Returns
    -------
    (M,) bool

    Examples
    --------
    >>> img = np.full((20, 20), NO_HUE, np.uint8)
    >>> img[2:6, 2:6] = 60              # a compact 16-pixel patch, 120 deg
    >>> img[10::3, 0::3] = 120          # 21 isolated pixels, 240 deg
    >>> connected_modes(img, np.array([120.0, 240.0]), 3.0, 10).tolist()
    [True, False]
    >>> outer = np.full((30, 30), 60, np.uint8)  # the patch continues far outside
    >>> connected_modes(img, np.array([120.0]), 3.0, 10, outer_hue_codes=outer,
    ...                 region_box=np.s_[5:25, 5:25], max_extent=3.0).tolist()
    [False]
    """
    require_shape("hue_codes", hue_codes, (None, None), np.uint8)
    modes = np.asarray(modes_deg, np.float64).reshape(-1)
    keep = np.zeros(len(modes), bool)
    if hue_codes.size == 0:
        return keep
    extent_test = outer_hue_codes is not None and max_extent > 0
    if extent_test:
        require_shape("outer_hue_codes", outer_hue_codes, (None, None), np.uint8)
        if region_box is None:
            region_box = (slice(None), slice(None))
        if outer_hue_codes[region_box].shape != hue_codes.shape:
            raise ValueError(
                f"region_box must select a {hue_codes.shape} part of outer_hue_codes "
                f"{outer_hue_codes.shape}, got {region_box}"
            )
    # a handful of modes; each test is one OpenCV call (two with the extent test)
    # the per-pixel table lookups go through OpenCV (~4x numpy's fancy indexing)
    for k, is_near in enumerate(codes_near_hues(modes, halfwidth_deg).view(np.uint8)):
        near = cv2.LUT(hue_codes, is_near).view(bool)
        n_near = np.count_nonzero(near)
        if n_near < min_pixels:
            continue
        n_patches, patches = cv2.connectedComponents(near.view(np.uint8), connectivity=8)
        patch_px = np.bincount(patches.reshape(-1), minlength=n_patches)
        keep[k] = patch_px[1:].max() >= min_pixels
        if keep[k] and extent_test:
            far = cv2.LUT(outer_hue_codes, is_near).view(bool)
            far[region_box] |= near
            n_far, far_patches, stats, _ = cv2.connectedComponentsWithStats(
                far.view(np.uint8), connectivity=8
            )
            reached = np.zeros(n_far, bool)
            reached[far_patches[region_box][near]] = True
            reached[0] = False
            keep[k] = stats[reached, cv2.CC_STAT_AREA].sum() <= max_extent * n_near
    return keep


def region_mode_pdf(
    hue_codes: np.ndarray,
    region: np.ndarray,
    *,
    n_bins: int,
    sigma_deg: float,
    min_peak: float,
    halfwidth_deg: float,
    min_pixels: int,
    outer_hue_codes: np.ndarray | None = None,
    region_box: tuple[slice, slice] | None = None,
    max_extent: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The hue distribution of a region, restricted to its connected modes.

    Histogram of the region's hues as a share of *all* its pixels (so a small object in a large
    region has a small mass), smoothed with a wrapped Gaussian; each bin then belongs to the
    mode it climbs to (:func:`mode_basins`), and the bins of modes that fail
    :func:`connected_modes` are zeroed. This is p_jmk(c) of eq. 29, "the pdf of the modes".

    Parameters
    ----------
    hue_codes : (H, W) uint8
        Hue code per pixel, ``NO_HUE`` where unreliable (see :func:`pixel_hue_codes`).
    region : (H, W) bool
        The pixels to analyse.
    n_bins, sigma_deg, min_peak, halfwidth_deg, min_pixels, max_extent
        See :class:`surveil.carry.settings.CarryConfig` (``hue_bins``, ``kde_sigma_deg``,
        ``mode_min_peak``, ``mode_halfwidth_deg``, ``mode_min_pixels``, ``max_mode_extent``).
    outer_hue_codes : (H', W') uint8, optional
        Hue codes around the region for the extent test of :func:`connected_modes`.
    region_box : (slice, slice), optional
        Where ``hue_codes`` lies in ``outer_hue_codes`` (default: the same shape).

    Returns
    -------
    pdf : (B,) float64
        Non-negative, total mass <= 1 (the share of region pixels explained by kept modes).
    modes_deg : (K,) float64
        Hue of the kept modes, strongest first.

    Examples
    --------
    >>> codes = np.full((12, 12), 15, np.uint8); codes[3:8, 3:8] = 60  # 30 and 120 deg
    >>> pdf, modes = region_mode_pdf(codes, np.ones((12, 12), bool), n_bins=180, sigma_deg=4,
    ...                              min_peak=0.0, halfwidth_deg=3, min_pixels=10)
    >>> modes.round().tolist(), round(float(pdf.sum()), 3)
    ([30.0, 120.0], 1.0)
    """
    require_shape("hue_codes", hue_codes, (None, None), np.uint8)
    require_shape("region", region, hue_codes.shape, np.bool_)
    n_region = int(np.count_nonzero(region))
    if n_region == 0:
        return np.zeros(n_bins), np.zeros(0)
    region_codes = np.where(region, hue_codes, np.uint8(NO_HUE))
    density = code_density(region_codes, n_bins, sigma_deg, n_total=n_region)
    modes = find_modes(density, min_peak)
    if len(modes) == 0:
        return np.zeros(n_bins), np.zeros(0)
    modes_deg = refine_peaks_deg(density, modes)
    keep = connected_modes(
        region_codes,
        modes_deg,
        halfwidth_deg,
        min_pixels,
        outer_hue_codes=outer_hue_codes,
        region_box=region_box,
        max_extent=max_extent,
    )
    if not keep.any():  # common (a bare hand beside clothing): no basins to follow
        return np.zeros(n_bins), np.zeros(0)
    kept_bins = np.zeros(n_bins, bool)
    kept_bins[modes[keep]] = True
    pdf = np.where(kept_bins[mode_basins(density)], density, 0.0)
    return pdf, modes_deg[keep]
