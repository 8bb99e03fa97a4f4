"""closest_points against OpenCV's DLT triangulation and hand-built skew lines."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from surveil.camera import look_at
from surveil.recon.triangulate import closest_points


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_matches_cv2_triangulate_points_on_noiseless_projections(rng):
    cam1 = look_at(
        "a", np.array([0.0, 0, 2.8]), np.array([3.0, 2, 1]), width=320, height=240, hfov_deg=70
    )
    cam2 = look_at(
        "b", np.array([6.0, 0, 2.8]), np.array([3.0, 2, 1]), width=320, height=240, hfov_deg=70
    )
    world = rng.uniform([2.0, 1.0, 0.2], [4.0, 3.0, 2.0], size=(50, 3))
    px1, _ = cam1.project(world)
    px2, _ = cam2.project(world)
    o1, dir1 = cam1.backproject(px1)
    o2, dir2 = cam2.backproject(px2)
    n = len(world)
    mid, half_gap = closest_points(np.tile(o1, (n, 1)), dir1, np.tile(o2, (n, 1)), dir2)
    P1 = cam1.K @ np.column_stack([cam1.R, cam1.t])
    P2 = cam2.K @ np.column_stack([cam2.R, cam2.t])
    hom = cv2.triangulatePoints(P1, P2, px1.T.copy(), px2.T.copy())
    ref = (hom[:3] / hom[3]).T
    assert mid.shape == (n, 3) and mid.dtype == np.float64
    assert half_gap.shape == (n,) and half_gap.dtype == np.float64
    np.testing.assert_allclose(mid, ref, atol=1e-6)
    np.testing.assert_allclose(mid, world, atol=1e-6)
    assert np.all(half_gap < 1e-9)


def test_skew_lines_give_known_midpoint_and_half_gap(rng):
    half = np.array([0.05, 0.3, 1.7])
    # line 1 along x through the origin, line 2 along y through (0, 0, 2h): the common
    # perpendicular is the z axis from 0 to 2h; then move everything rigidly
    R = _rotation(rng)
    shift = rng.normal(size=3)
    o1 = np.tile(shift, (3, 1)) + np.array([2.0, 0, 0]) @ R.T
    d1 = np.tile(np.array([3.0, 0, 0]) @ R.T, (3, 1))
    o2 = (np.column_stack([np.zeros(3), 2 * np.ones(3), 2 * half]) @ R.T) + shift
    d2 = np.tile(np.array([0.0, -0.5, 0]) @ R.T, (3, 1))
    mid, half_gap = closest_points(o1, d1, o2, d2)
    np.testing.assert_allclose(half_gap, half, rtol=1e-9)
    expected = np.column_stack([np.zeros(3), np.zeros(3), half]) @ R.T + shift
    np.testing.assert_allclose(mid, expected, atol=1e-9)


def test_parallel_lines_are_invalid_without_warnings():
    o1 = np.array([[0.0, 0, 0], [0.0, 0, 0]])
    d1 = np.array([[1.0, 0, 0], [1.0, 0, 0]])
    o2 = np.array([[0.0, 1, 0], [0.0, 1, 0]])
    d2 = np.array([[-2.0, 0, 0], [1.0, 1e-9, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mid, half_gap = closest_points(o1, d1, o2, d2)
    assert np.all(np.isinf(half_gap))
    assert np.all(np.isnan(mid))


def test_empty_input_gives_empty_output():
    z = np.zeros((0, 3))
    mid, half_gap = closest_points(z, z, z, z)
    assert mid.shape == (0, 3) and half_gap.shape == (0,)


def test_bad_shape_names_the_argument():
    good = np.ones((2, 3))
    with pytest.raises(ValueError, match="d2"):
        closest_points(good, good, good, np.ones((2, 2)))
