"""Hue histograms and their modes (paper 004 section 7.2.2).

Pure, vectorised functions on small image regions. Hue is in degrees ``[0, 360)``; OpenCV's
8-bit hue (0-179) is doubled at the edge (:func:`pixel_hues`). Histograms are circular: bin
``i`` of ``B`` is centred on ``i * 360 / B`` degrees and covers half a bin either side, so
bin 0 straddles 0/360.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.ndimage import gaussian_filter1d

from surveil.validate import require_shape


def pixel_hues(bgr: np.ndarray, min_saturation: float, min_value: float) -> np.ndarray:
    """Hue of every pixel, NaN where the colour is too grey or too dark to have one.

    Parameters
    ----------
    bgr : (H, W, 3) uint8
        BGR image (normally a small region of interest).
    min_saturation, min_value : float
        HSV saturation and value thresholds in [0, 1]; pixels below either get NaN.

    Returns
    -------
    (H, W) float32
        Hue in degrees, ``[0, 360)`` in steps of 2 (OpenCV 8-bit hue x 2), or NaN.

    Examples
    --------
    >>> img = np.array([[[0, 255, 0], [128, 128, 128], [0, 0, 200]]], np.uint8)  # BGR
    >>> pixel_hues(img, 0.3, 0.1).tolist()
    [[120.0, nan, 0.0]]
    """
    require_shape("bgr", bgr, (None, None, 3), np.uint8)
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    hue = hsv[..., 0].astype(np.float32) * 2.0
    s_min = np.ceil(min_saturation * 255.0)
    v_min = np.ceil(min_value * 255.0)
    unreliable = (hsv[..., 1] < s_min) | (hsv[..., 2] < v_min)
    hue[unreliable] = np.nan
    return hue


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


def hue_histogram(hues_deg: np.ndarray, n_bins: int, n_total: int | None = None) -> np.ndarray:
    """Circular hue histogram normalised by a pixel count.

    Parameters
    ----------
    hues_deg : (N,) float
        Hues in degrees (NaN entries are ignored, but still count in the default total).
    n_bins : int
        Number of bins B over ``[0, 360)``.
    n_total : int, optional
        Divide the counts by this (e.g. all pixels of the region, including those without a
        reliable hue, so that the histogram is a share of the region). Default ``N``.

    Returns
    -------
    (B,) float64
        Counts / ``n_total``; sums to 1 when every hue is finite and ``n_total`` is N.
        All zeros for an empty input.

    >>> hue_histogram(np.array([0.0, 359.5, 120.0, np.nan]), 4).tolist()
    [0.5, 0.25, 0.0, 0.0]
    """
    hues = np.asarray(hues_deg, np.float64).reshape(-1)
    if n_bins < 1:
        raise ValueError(f"n_bins must be >= 1, got {n_bins}")
    total = len(hues) if n_total is None else int(n_total)
    finite = hues[np.isfinite(hues)]
    if total <= 0 or len(finite) == 0:
        return np.zeros(n_bins)
    counts = np.bincount(hue_to_bins(finite, n_bins), minlength=n_bins)
    return counts / float(total)


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
    left, right = np.roll(d, 1), np.roll(d, -1)
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
    i = np.arange(n)
    cand = np.stack([i, (i - 1) % n, (i + 1) % n])  # self first: ties stay put
    step = cand[np.argmax(d[cand], axis=0), i]
    for _ in range(max(int(np.ceil(np.log2(max(n, 2)))) + 1, 1)):
        step = step[step]
    return step


def refine_peak_deg(density: np.ndarray, peak_bin: int) -> float:
    """Sub-bin hue of a maximum by a parabola through it and its two neighbours, degrees.

    >>> d = np.array([0.0, 1.0, 3.0, 3.0, 1.0, 0.0])
    >>> refine_peak_deg(d, 2)  # the true peak lies between bins 2 and 3 (120 and 180 deg)
    150.0
    """
    d = np.asarray(density, np.float64)
    n = len(d)
    y0, y1, y2 = d[(peak_bin - 1) % n], d[peak_bin], d[(peak_bin + 1) % n]
    denom = y0 - 2.0 * y1 + y2
    offset = 0.0 if denom >= 0 else float(np.clip(0.5 * (y0 - y2) / denom, -0.5, 0.5))
    return float(((peak_bin + offset) * 360.0 / n) % 360.0)


def connected_modes(
    hue_img: np.ndarray,
    modes_deg: np.ndarray,
    halfwidth_deg: float,
    min_pixels: int,
    *,
    outer_hue_img: np.ndarray | None = None,
    max_extent: float = 0.0,
) -> np.ndarray:
    """Connectivity check of section 7.2.2: is each mode a compact patch in the image?

    A mode is kept when the pixels whose hue lies within ``+-halfwidth_deg`` of it contain a
    connected region (8-connectivity) of at least ``min_pixels`` pixels. Scattered noise with
    the same hue forms no such region.

    Parameters
    ----------
    hue_img : (H, W) float
        Hue per pixel in degrees; NaN for pixels outside the region or without a hue.
    modes_deg : (M,) float
        Mode hues, degrees.
    halfwidth_deg : float
        delta (paper: about 3 degrees).
    min_pixels : int
        n (paper: 10).
    outer_hue_img : (H, W) float, optional
        Hues of a larger neighbourhood (NaN outside it) that contains ``hue_img``'s pixels.
        With ``max_extent > 0``, a mode is also dropped when its patches, followed into this
        neighbourhood, are more than ``max_extent`` times larger than inside the region: the
        colour belongs to something that extends beyond the hand's circle (dress, trousers,
        furniture) rather than to a compact carried object. (An addition to the paper, which
        removes the sleeve where it crosses the bounding circle.)
    max_extent : float
        0 disables the extent test.

    Returns
    -------
    (M,) bool

    Examples
    --------
    >>> img = np.full((20, 20), np.nan, np.float32)
    >>> img[2:6, 2:6] = 120.0           # a compact 16-pixel patch
    >>> img[10::3, 0::3] = 240.0        # 21 isolated pixels
    >>> connected_modes(img, np.array([120.0, 240.0]), 3.0, 10).tolist()
    [True, False]
    >>> outer = np.full((20, 20), 120.0, np.float32)  # the patch continues far outside
    >>> connected_modes(img, np.array([120.0]), 3.0, 10, outer_hue_img=outer,
    ...                 max_extent=3.0).tolist()
    [False]
    """
    require_shape("hue_img", hue_img, (None, None), np.floating)
    modes = np.asarray(modes_deg, np.float64).reshape(-1)
    keep = np.zeros(len(modes), bool)
    if hue_img.size == 0:
        return keep
    for k, mode in enumerate(modes):  # a handful of modes; each test is one OpenCV call
        near = circular_distance_deg(hue_img, mode) <= halfwidth_deg  # NaN -> False
        if np.count_nonzero(near) < min_pixels:
            continue
        _, _, stats, _ = cv2.connectedComponentsWithStats(near.view(np.uint8), connectivity=8)
        keep[k] = stats[1:, cv2.CC_STAT_AREA].max() >= min_pixels
        if keep[k] and outer_hue_img is not None and max_extent > 0:
            far = (circular_distance_deg(outer_hue_img, mode) <= halfwidth_deg) | near
            _, labels = cv2.connectedComponents(far.view(np.uint8), connectivity=8)
            hit = np.zeros(int(labels.max()) + 1, bool)
            hit[labels[near]] = True
            hit[0] = False
            keep[k] = np.count_nonzero(hit[labels]) <= max_extent * np.count_nonzero(near)
    return keep


def region_mode_pdf(
    hue_img: np.ndarray,
    region: np.ndarray,
    *,
    n_bins: int,
    sigma_deg: float,
    min_peak: float,
    halfwidth_deg: float,
    min_pixels: int,
    outer_hue_img: np.ndarray | None = None,
    max_extent: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The hue distribution of a region, restricted to its connected modes.

    Histogram of the region's hues as a share of *all* its pixels (so a small object in a large
    region has a small mass), smoothed with a wrapped Gaussian; each bin then belongs to the
    mode it climbs to (:func:`mode_basins`), and the bins of modes that fail
    :func:`connected_modes` are zeroed. This is p_jmk(c) of eq. 29, "the pdf of the modes".

    Parameters
    ----------
    hue_img : (H, W) float
        Hue per pixel in degrees, NaN where unreliable (see :func:`pixel_hues`).
    region : (H, W) bool
        The pixels to analyse.
    n_bins, sigma_deg, min_peak, halfwidth_deg, min_pixels, max_extent
        See :class:`surveil.carry.settings.CarryConfig` (``hue_bins``, ``kde_sigma_deg``,
        ``mode_min_peak``, ``mode_halfwidth_deg``, ``mode_min_pixels``, ``max_mode_extent``).
    outer_hue_img : (H, W) float, optional
        Hues around the region for the extent test of :func:`connected_modes`.

    Returns
    -------
    pdf : (B,) float64
        Non-negative, total mass <= 1 (the share of region pixels explained by kept modes).
    modes_deg : (K,) float64
        Hue of the kept modes, strongest first.

    Examples
    --------
    >>> hue = np.full((12, 12), 30.0, np.float32); hue[3:8, 3:8] = 120.0
    >>> pdf, modes = region_mode_pdf(hue, np.ones((12, 12), bool), n_bins=180, sigma_deg=4,
    ...                              min_peak=0.0, halfwidth_deg=3, min_pixels=10)
    >>> modes.round().tolist(), round(float(pdf.sum()), 3)
    ([30.0, 120.0], 1.0)
    """
    require_shape("region", region, hue_img.shape, np.bool_)
    n_region = int(np.count_nonzero(region))
    if n_region == 0:
        return np.zeros(n_bins), np.zeros(0)
    hues = hue_img[region]
    hist = hue_histogram(hues, n_bins, n_total=n_region)
    density = smooth_circular(hist, sigma_deg)
    modes = find_modes(density, min_peak)
    if len(modes) == 0:
        return np.zeros(n_bins), np.zeros(0)
    modes_deg = np.array([refine_peak_deg(density, m) for m in modes])
    masked = np.where(region, hue_img, np.float32(np.nan))
    keep = connected_modes(
        masked,
        modes_deg,
        halfwidth_deg,
        min_pixels,
        outer_hue_img=outer_hue_img,
        max_extent=max_extent,
    )
    kept_bins = np.zeros(n_bins, bool)
    kept_bins[modes[keep]] = True
    pdf = np.where(kept_bins[mode_basins(density)], density, 0.0)
    return pdf, modes_deg[keep]
