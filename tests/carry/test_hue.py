"""Hue histograms, modes and the connectivity check (paper 004 section 7.2.2)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from surveil.carry.hue import (
    HUE_CODE_DEG,
    NO_HUE,
    circular_distance_deg,
    code_density,
    codes_near_hues,
    connected_modes,
    find_modes,
    hue_histogram,
    mode_basins,
    pixel_hue_codes,
    refine_peaks_deg,
    region_mode_pdf,
    smooth_circular,
)

PDF_ARGS = dict(n_bins=180, sigma_deg=5.0, min_peak=0.0, halfwidth_deg=3.0, min_pixels=10)


def codes_from_degrees(hue_deg: np.ndarray) -> np.ndarray:
    """Hue codes of a float image of even-degree hues, NaN -> NO_HUE."""
    return np.where(np.isnan(hue_deg), NO_HUE, np.nan_to_num(hue_deg) / 2).astype(np.uint8)


def test_pixel_hue_codes_halve_the_hue_and_mask_grey_dark_and_unwanted_pixels():
    bgr = np.array([[[255, 0, 0], [0, 255, 255], [90, 90, 90], [0, 0, 20]]], np.uint8)
    codes = pixel_hue_codes(bgr, min_saturation=0.3, min_value=0.15)
    assert codes.dtype == np.uint8 and codes.shape == (1, 4)
    assert HUE_CODE_DEG[codes[0, 0]] == 240.0 and HUE_CODE_DEG[codes[0, 1]] == 60.0
    assert codes[0, 2] == NO_HUE and codes[0, 3] == NO_HUE  # grey, too dark
    mask = np.array([[False, True, True, True]])
    assert pixel_hue_codes(bgr, 0.3, 0.15, mask=mask).tolist() == [[NO_HUE, 30, NO_HUE, NO_HUE]]


def test_pixel_hue_codes_equal_the_straightforward_hsv_thresholds():
    rng = np.random.default_rng(1)
    bgr = rng.integers(0, 256, (40, 50, 3), dtype=np.uint8)
    mask = rng.random((40, 50)) < 0.7
    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    for min_sat, min_val in [(0.3, 0.12), (0.0, 0.0), (1.0, 1.0), (0.301, 0.5)]:
        has_hue = (hsv[..., 1] >= np.ceil(min_sat * 255)) & (hsv[..., 2] >= np.ceil(min_val * 255))
        expected = np.where(has_hue & mask, hsv[..., 0], NO_HUE)
        np.testing.assert_array_equal(pixel_hue_codes(bgr, min_sat, min_val, mask=mask), expected)


def test_pixel_hue_codes_reject_bad_input():
    with pytest.raises(TypeError, match="bgr"):
        pixel_hue_codes(np.zeros((2, 2, 3)), 0.3, 0.1)
    with pytest.raises(ValueError, match="mask"):
        pixel_hue_codes(np.zeros((2, 2, 3), np.uint8), 0.3, 0.1, mask=np.ones((3, 2), bool))


def test_codes_near_hue_is_the_per_pixel_circular_distance_test():
    rng = np.random.default_rng(2)
    codes = rng.integers(0, 180, (30, 30)).astype(np.uint8)
    codes[::7] = NO_HUE
    hue_deg = np.where(codes == NO_HUE, np.nan, codes * np.float32(2.0)).astype(np.float32)
    modes = np.array([0.0, 1.3, 119.7, 359.0, 181.25])
    for mode, is_near in zip(modes, codes_near_hues(modes, 6.0), strict=True):
        expected = circular_distance_deg(hue_deg, mode) <= 6.0  # NaN -> False
        np.testing.assert_array_equal(is_near[codes], expected)


def test_histogram_is_normalised_and_wraps_at_360():
    hues = np.array([359.2, 0.4, 0.8, 180.0])
    hist = hue_histogram(hues, 180)
    assert hist.shape == (180,) and hist.dtype == np.float64
    assert hist.sum() == pytest.approx(1.0)
    assert hist[0] == pytest.approx(0.75)  # 359.2 lands in the bin centred on 0
    assert hist[90] == pytest.approx(0.25)


def test_histogram_share_of_region_and_empty_input():
    assert hue_histogram(np.array([10.0]), 36, n_total=4).sum() == pytest.approx(0.25)
    assert not hue_histogram(np.zeros(0), 36).any()
    with pytest.raises(ValueError, match="n_bins"):
        hue_histogram(np.zeros(3), 0)


def test_weighted_histogram_equals_the_histogram_of_repeated_hues():
    rng = np.random.default_rng(3)
    counts = rng.integers(0, 5, 180)
    repeated = np.repeat(HUE_CODE_DEG, counts)
    for n_bins in (180, 36, 7):
        weighted = hue_histogram(HUE_CODE_DEG, n_bins, n_total=1000, weights=counts)
        np.testing.assert_array_equal(weighted, hue_histogram(repeated, n_bins, n_total=1000))
    assert hue_histogram(HUE_CODE_DEG, 180, weights=counts).sum() == pytest.approx(1.0)
    with pytest.raises(ValueError, match="weights"):
        hue_histogram(HUE_CODE_DEG, 180, weights=counts[:3])


def test_smoothing_wraps_and_keeps_mass():
    hist = np.zeros(180)
    hist[0] = 1.0
    s = smooth_circular(hist, 6.0)
    assert s.sum() == pytest.approx(1.0)
    assert s[1] == pytest.approx(s[179]) and s[1] > 0  # symmetric across 0/360
    assert find_modes(s).tolist() == [0]


@pytest.mark.parametrize("n_bins", [180, 90, 36])
@pytest.mark.parametrize("sigma_deg", [0.0, 4.0, 6.0])
def test_code_density_is_the_smoothed_histogram_of_the_codes(n_bins, sigma_deg):
    """The one-table shortcut gives the histogram of the pixels' hues, smoothed."""
    rng = np.random.default_rng(3)
    codes = rng.integers(0, 180, (40, 30)).astype(np.uint8)
    codes[rng.random(codes.shape) < 0.3] = NO_HUE
    codes[5:15, 5:15] = 7  # a patch of one hue: a peak for the smoothing to spread
    has_hue = codes != NO_HUE
    expected = smooth_circular(
        hue_histogram(HUE_CODE_DEG[codes[has_hue]], n_bins, n_total=codes.size), sigma_deg
    )
    got = code_density(codes, n_bins, sigma_deg, n_total=codes.size)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)
    assert got.sum() == pytest.approx(has_hue.mean())
    counts = code_density(codes, n_bins, sigma_deg)  # no total: pixel counts
    np.testing.assert_allclose(counts, expected * codes.size, rtol=1e-12, atol=1e-12)


def test_modes_on_both_sides_of_zero_merge_into_one_mode_at_zero():
    hues = np.concatenate([np.full(50, 356.0), np.full(50, 4.0)])
    s = smooth_circular(hue_histogram(hues, 180), 6.0)
    modes = find_modes(s)
    assert len(modes) == 1 and circular_distance_deg(modes[0] * 2.0, 0.0) <= 2.0


def test_refined_peaks_equal_the_vertex_of_the_parabola_through_three_bins():
    rng = np.random.default_rng(4)
    density = smooth_circular(rng.random(180), 4.0)
    peaks = find_modes(density)
    refined = refine_peaks_deg(density, peaks)
    for peak, hue in zip(peaks, refined, strict=True):
        y0, y1, y2 = density[(peak - 1) % 180], density[peak], density[(peak + 1) % 180]
        offset = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)  # vertex of the parabola, in bins
        assert hue == pytest.approx((peak + offset) * 2.0 % 360.0, abs=1e-9)
    flat = np.ones(8)  # no curvature: the peak stays on its bin
    assert refine_peaks_deg(flat, np.array([0, 3])).tolist() == [0.0, 135.0]
    assert refine_peaks_deg(flat, np.zeros(0, int)).shape == (0,)


def test_basins_cover_every_bin_of_a_two_peak_density():
    s = smooth_circular(hue_histogram(np.array([60.0] * 10 + [240.0] * 5), 180), 10.0)
    basins = mode_basins(s)
    assert set(basins[s > 1e-9].tolist()) == {30, 120}


def test_compact_patch_is_a_mode_scattered_pixels_are_not():
    codes = np.full((40, 40), NO_HUE, np.uint8)
    codes[5:9, 5:9] = 60  # 16 connected pixels, 120 deg
    codes[20::2, ::2] = 120  # 200 pixels, 240 deg, none touching another (8-connectivity)
    keep = connected_modes(codes, np.array([120.0, 240.0]), 3.0, 10)
    assert keep.tolist() == [True, False]


def test_connectivity_check_wraps_around_zero():
    codes = np.full((20, 20), NO_HUE, np.uint8)
    codes[2:6, 2:6] = 179  # 358 deg
    codes[2:6, 6:8] = 1  # 2 deg: the same red patch, hue on both sides of 0
    assert connected_modes(codes, np.array([0.0]), 3.0, 20).tolist() == [True]
    assert connected_modes(codes, np.array([0.0]), 1.0, 20).tolist() == [False]


def test_region_mode_pdf_drops_scattered_mode_and_keeps_patch():
    codes = np.full((40, 40), NO_HUE, np.uint8)
    codes[10:16, 10:16] = 60  # 36 compact green pixels
    codes[20::2, ::2] = 120  # 200 scattered blue pixels: the histogram's biggest peak
    region = np.ones((40, 40), bool)
    pdf, modes = region_mode_pdf(codes, region, **PDF_ARGS)
    assert modes.round().tolist() == [120.0]
    assert pdf.shape == (180,)
    assert pdf.sum() == pytest.approx(36 / 1600, rel=1e-6)  # share of the region's pixels
    assert pdf[50:71].sum() == pytest.approx(pdf.sum())  # bins of 2 deg: 100-140 deg


def test_region_mode_pdf_empty_region():
    pdf, modes = region_mode_pdf(np.zeros((5, 5), np.uint8), np.zeros((5, 5), bool), **PDF_ARGS)
    assert pdf.shape == (180,) and not pdf.any() and modes.shape == (0,)


def test_region_mode_pdf_rejects_float_hues():
    with pytest.raises(TypeError, match="hue_codes"):
        region_mode_pdf(np.zeros((5, 5), np.float32), np.ones((5, 5), bool), **PDF_ARGS)


def test_extent_test_drops_a_colour_that_continues_outside_the_region():
    codes = np.full((30, 30), 110, np.uint8)  # trousers everywhere, 220 deg
    region = np.zeros((30, 30), bool)
    region[10:20, 10:20] = True
    inner = np.where(region, codes, NO_HUE).astype(np.uint8)
    args = dict(outer_hue_codes=codes, max_extent=2.5)
    assert connected_modes(inner, np.array([220.0]), 3.0, 10).tolist() == [True]
    assert connected_modes(inner, np.array([220.0]), 3.0, 10, **args).tolist() == [False]
    # a compact object entirely inside the region passes
    obj = np.full((30, 30), NO_HUE, np.uint8)
    obj[12:17, 12:17] = 60
    assert connected_modes(obj, np.array([120.0]), 3.0, 10, outer_hue_codes=obj, max_extent=2.5)[0]


def test_region_box_gives_the_same_result_as_the_region_embedded_in_the_neighbourhood():
    """The fast path (connectivity on the region's box, extent test on the neighbourhood)
    equals the straightforward one (the region as a full-size image)."""
    rng = np.random.default_rng(5)
    outer = rng.choice(np.array([10, 11, NO_HUE], np.uint8), size=(60, 70), p=[0.2, 0.2, 0.6])
    outer[24:34, 28:38] = 60  # a compact patch inside the box
    outer[20:24, 30:70] = 110  # a patch that continues far outside it
    box = np.s_[18:42, 23:47]
    region = rng.random((24, 24)) < 0.9
    inner = np.where(region, outer[box], NO_HUE).astype(np.uint8)
    embedded = np.full_like(outer, NO_HUE)
    embedded[box] = inner
    modes = np.array([120.0, 220.0, 20.0])
    expected = {0.0: [True, True, True], 2.5: [True, False, False], 50.0: [True, True, True]}
    for max_extent, keep in expected.items():
        args = dict(outer_hue_codes=outer, max_extent=max_extent)
        fast = connected_modes(inner, modes, 6.0, 10, region_box=box, **args)
        assert fast.tolist() == keep
        np.testing.assert_array_equal(fast, connected_modes(embedded, modes, 6.0, 10, **args))
    pdf_fast = region_mode_pdf(
        outer[box], region, outer_hue_codes=outer, region_box=box, max_extent=2.5, **PDF_ARGS
    )
    full_region = np.zeros(outer.shape, bool)
    full_region[box] = region
    pdf_full = region_mode_pdf(
        outer, full_region, outer_hue_codes=outer, max_extent=2.5, **PDF_ARGS
    )
    for fast_part, full_part in zip(pdf_fast, pdf_full, strict=True):
        np.testing.assert_array_equal(fast_part, full_part)
    wrong_box = dict(outer_hue_codes=outer, region_box=np.s_[0:5, 0:5], max_extent=2.5)
    with pytest.raises(ValueError, match="region_box"):
        connected_modes(inner, modes, 6.0, 10, **wrong_box)
