"""Eq. 29 fusion, the ring buffer and the decision."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.carry.fusion import (
    HueWindow,
    decide_carrying,
    fuse_distributions,
    subtract_distribution,
)


def test_fusion_is_the_reliability_weighted_average():
    rng = np.random.default_rng(0)
    pdfs = rng.random((5, 36))
    rho = np.array([0.1, 0.5, 1.1, 0.3, 0.0])
    expected = sum(r * p for r, p in zip(rho, pdfs, strict=True)) / rho.sum()
    np.testing.assert_allclose(fuse_distributions(pdfs, rho), expected)


def test_fusion_all_weight_on_one_camera_and_degenerate_inputs():
    pdfs = np.eye(3)
    np.testing.assert_array_equal(fuse_distributions(pdfs, np.array([0.0, 2.0, 0.0])), pdfs[1])
    assert not fuse_distributions(np.zeros((0, 3)), np.zeros(0)).any()
    assert not fuse_distributions(pdfs, np.zeros(3)).any()
    with pytest.raises(ValueError, match="rho"):
        fuse_distributions(pdfs, np.ones(2))
    with pytest.raises(ValueError, match="rho must be non-negative"):
        fuse_distributions(pdfs, np.array([1.0, -1.0, 0.0]))


def test_subtraction_removes_negative_parts():
    out = subtract_distribution(np.array([0.3, 0.1, 0.0]), np.array([0.1, 0.3, 0.2]))
    np.testing.assert_allclose(out, [0.2, 0.0, 0.0])


def test_window_keeps_only_recent_samples_and_bounded_memory():
    win = HueWindow(capacity=4, n_bins=3)
    for k in range(10):
        win.push(k * 100, 1.0 + k, np.eye(3)[k % 3])
    assert len(win) == 4  # the ring buffer never grows
    pdf, total = win.fused(900, window_ns=250)  # samples at 700, 800, 900
    assert total == pytest.approx(8.0 + 9.0 + 10.0)
    expected = (8.0 * np.eye(3)[1] + 9.0 * np.eye(3)[2] + 10.0 * np.eye(3)[0]) / 27.0
    np.testing.assert_allclose(pdf, expected)
    win.clear()
    assert len(win) == 0 and win.fused(900, 10**9)[1] == 0.0


def test_a_paused_window_keeps_its_samples_for_the_pause_and_their_capture_times():
    win = HueWindow(capacity=8, n_bins=3)
    win.push(100, 1.0, np.eye(3)[0])
    win.push(200, 1.0, np.eye(3)[1])
    assert win.fused(1150, window_ns=1000)[1] == 1.0  # 100 has aged out, 200 not yet
    win.pause(900)  # 900 ns in which the hand was not looked at
    pdf, total = win.fused(1150, window_ns=1000)
    assert total == 2.0
    np.testing.assert_allclose(pdf, [0.5, 0.5, 0.0])
    assert win.oldest_ns(1150, window_ns=1000) == 100  # when it was taken, not its age
    win.push(1300, 1.0, np.eye(3)[2])  # the clock resumes: 100 (now at 1000) ages out
    assert win.fused(2001, window_ns=1000)[1] == 2.0
    assert win.oldest_ns(2001, window_ns=1000) == 200


def test_decision_threshold_hue_and_wrap():
    pdf = np.zeros(180)
    pdf[[179, 0, 1]] = 0.03  # a red object on both sides of 0
    d = decide_carrying(pdf, 4.0, carry_mass=0.06, halfwidth_deg=15.0, evidence_rho=2.0)
    assert d.carrying and d.mass == pytest.approx(0.09)
    assert min(d.hue_deg, 360 - d.hue_deg) < 0.5
    weak = decide_carrying(pdf / 3, 4.0, carry_mass=0.06, halfwidth_deg=15.0, evidence_rho=2.0)
    assert not weak.carrying and 0.0 <= weak.confidence <= 1.0
    empty = decide_carrying(np.zeros(180), 0.0, carry_mass=0.06, halfwidth_deg=15, evidence_rho=2)
    assert not empty.carrying and empty.hue_deg is None and empty.confidence == 0.0
