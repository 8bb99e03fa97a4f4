"""Hue histograms, modes and the connectivity check (paper 004 section 7.2.2)."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.carry.hue import (
    circular_distance_deg,
    connected_modes,
    find_modes,
    hue_histogram,
    mode_basins,
    pixel_hues,
    region_mode_pdf,
    smooth_circular,
)

PDF_ARGS = dict(n_bins=180, sigma_deg=5.0, min_peak=0.0, halfwidth_deg=3.0, min_pixels=10)


def test_pixel_hues_doubles_opencv_hue_and_masks_grey_and_dark():
    bgr = np.array([[[255, 0, 0], [0, 255, 255], [90, 90, 90], [0, 0, 20]]], np.uint8)
    hue = pixel_hues(bgr, min_saturation=0.3, min_value=0.15)
    assert hue.dtype == np.float32 and hue.shape == (1, 4)
    assert hue[0, 0] == 240.0 and hue[0, 1] == 60.0  # blue, yellow
    assert np.isnan(hue[0, 2]) and np.isnan(hue[0, 3])  # grey, too dark


def test_pixel_hues_rejects_non_uint8():
    with pytest.raises(TypeError, match="bgr"):
        pixel_hues(np.zeros((2, 2, 3)), 0.3, 0.1)


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


def test_smoothing_wraps_and_keeps_mass():
    hist = np.zeros(180)
    hist[0] = 1.0
    s = smooth_circular(hist, 6.0)
    assert s.sum() == pytest.approx(1.0)
    assert s[1] == pytest.approx(s[179]) and s[1] > 0  # symmetric across 0/360
    assert find_modes(s).tolist() == [0]


def test_modes_on_both_sides_of_zero_merge_into_one_mode_at_zero():
    hues = np.concatenate([np.full(50, 356.0), np.full(50, 4.0)])
    s = smooth_circular(hue_histogram(hues, 180), 6.0)
    modes = find_modes(s)
    assert len(modes) == 1 and circular_distance_deg(modes[0] * 2.0, 0.0) <= 2.0


def test_basins_cover_every_bin_of_a_two_peak_density():
    s = smooth_circular(hue_histogram(np.array([60.0] * 10 + [240.0] * 5), 180), 10.0)
    basins = mode_basins(s)
    assert set(basins[s > 1e-9].tolist()) == {30, 120}


def test_compact_patch_is_a_mode_scattered_pixels_are_not():
    hue = np.full((40, 40), np.nan, np.float32)
    hue[5:9, 5:9] = 120.0  # 16 connected pixels
    hue[20::2, ::2] = 240.0  # 200 pixels, none touching another (8-connectivity)
    keep = connected_modes(hue, np.array([120.0, 240.0]), 3.0, 10)
    assert keep.tolist() == [True, False]


def test_connectivity_check_wraps_around_zero():
    hue = np.full((20, 20), np.nan, np.float32)
    hue[2:6, 2:6] = 358.0
    hue[2:6, 6:8] = 2.0  # the same red patch, hue on both sides of 0
    assert connected_modes(hue, np.array([0.0]), 3.0, 20).tolist() == [True]
    assert connected_modes(hue, np.array([0.0]), 1.0, 20).tolist() == [False]


def test_region_mode_pdf_drops_scattered_mode_and_keeps_patch():
    hue = np.full((40, 40), 0.0, np.float32)
    hue[:] = np.nan
    hue[10:16, 10:16] = 120.0  # 36 compact green pixels
    hue[20::2, ::2] = 240.0  # 200 scattered blue pixels: the histogram's biggest peak
    region = np.ones((40, 40), bool)
    pdf, modes = region_mode_pdf(hue, region, **PDF_ARGS)
    assert modes.round().tolist() == [120.0]
    assert pdf.shape == (180,)
    assert pdf.sum() == pytest.approx(36 / 1600, rel=1e-6)  # share of the region's pixels
    assert pdf[50:71].sum() == pytest.approx(pdf.sum())  # bins of 2 deg: 100-140 deg


def test_region_mode_pdf_empty_region():
    pdf, modes = region_mode_pdf(np.zeros((5, 5), np.float32), np.zeros((5, 5), bool), **PDF_ARGS)
    assert pdf.shape == (180,) and not pdf.any() and modes.shape == (0,)


def test_extent_test_drops_a_colour_that_continues_outside_the_region():
    hue = np.full((30, 30), 220.0, np.float32)  # trousers everywhere
    region = np.zeros((30, 30), bool)
    region[10:20, 10:20] = True
    outer = hue.copy()
    inner = np.where(region, hue, np.nan).astype(np.float32)
    args = dict(outer_hue_img=outer, max_extent=2.5)
    assert connected_modes(inner, np.array([220.0]), 3.0, 10).tolist() == [True]
    assert connected_modes(inner, np.array([220.0]), 3.0, 10, **args).tolist() == [False]
    # a compact object entirely inside the region passes
    obj = np.full((30, 30), np.nan, np.float32)
    obj[12:17, 12:17] = 120.0
    assert connected_modes(obj, np.array([120.0]), 3.0, 10, outer_hue_img=obj, max_extent=2.5)[0]
