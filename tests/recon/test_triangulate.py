"""closest_points and least_squares_points against OpenCV's DLT triangulation and hand-built
lines."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from surveil.camera import look_at
from surveil.recon.triangulate import closest_points, least_squares_points


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


def _four_cameras():
    target = np.array([3.0, 2, 1])
    corners = {"a": [0.0, 0, 2.8], "b": [6.0, 0, 2.8], "c": [6.0, 4, 2.8], "d": [0.0, 4, 2.8]}
    return [
        look_at(n, np.array(c), target, width=320, height=240, hfov_deg=70)
        for n, c in corners.items()
    ]


def _bundles(cams, world, px_noise=0.0, rng=None):
    origins, dirs = [], []
    for cam in cams:
        px, _ = cam.project(world)
        if px_noise:
            px = px + rng.normal(scale=px_noise, size=px.shape)
        o, d = cam.backproject(px)
        origins.append(np.broadcast_to(o, (len(world), 3)))
        dirs.append(d)
    return np.stack(origins, axis=1), np.stack(dirs, axis=1)


def test_least_squares_point_of_noiseless_views_is_the_point_and_cv2s(rng):
    cams = _four_cameras()
    world = rng.uniform([2.0, 1.0, 0.2], [4.0, 3.0, 2.0], size=(40, 3))
    origins, dirs = _bundles(cams, world)
    use = np.ones((len(world), 4), bool)
    use[::3, 1] = False  # some bundles of three lines
    points, dist = least_squares_points(origins, dirs, use)
    np.testing.assert_allclose(points, world, atol=1e-6)
    assert dist.shape == (len(world), 4) and np.all(dist < 1e-6)
    # two lines: OpenCV's DLT and the common perpendicular's midpoint
    two = np.zeros_like(use)
    two[:, [0, 2]] = True
    pair, _ = least_squares_points(origins, dirs, two)
    P = [c.K @ np.column_stack([c.R, c.t]) for c in (cams[0], cams[2])]
    px = [c.project(world)[0].T.copy() for c in (cams[0], cams[2])]
    hom = cv2.triangulatePoints(P[0], P[1], px[0], px[1])
    np.testing.assert_allclose(pair, (hom[:3] / hom[3]).T, atol=1e-6)


def test_two_skew_lines_give_the_midpoint_and_half_gaps(rng):
    o1, o2 = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    d1, d2 = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    mid, half_gap = closest_points(o1, d1, o2, d2)
    points, dist = least_squares_points(
        np.stack([o1, o2], axis=1), np.stack([d1, d2], axis=1), np.ones((5, 2), bool)
    )
    np.testing.assert_allclose(points, mid, atol=1e-9)
    np.testing.assert_allclose(dist, np.column_stack([half_gap, half_gap]), atol=1e-9)


def test_more_views_put_noisy_blob_centres_nearer_the_point(rng):
    """With one pixel of noise on every blob centre, four views' point lies nearer the true
    point than a pair's midpoint: the reason candidates may be refined from all views."""
    cams = _four_cameras()
    world = rng.uniform([2.5, 1.5, 0.5], [3.5, 2.5, 1.8], size=(400, 3))
    origins, dirs = _bundles(cams, world, px_noise=1.0, rng=rng)
    pair = np.zeros((len(world), 4), bool)
    pair[:, :2] = True
    err_pair = np.linalg.norm(least_squares_points(origins, dirs, pair)[0] - world, axis=1)
    err_all = np.linalg.norm(
        least_squares_points(origins, dirs, np.ones_like(pair))[0] - world, axis=1
    )
    assert np.median(err_all) < 0.7 * np.median(err_pair)


def test_bundles_of_fewer_than_two_or_parallel_lines_have_no_point():
    origins = np.zeros((3, 2, 3))
    origins[:, 1] = [0.0, 1, 0]
    dirs = np.tile(np.array([1.0, 0, 0]), (3, 2, 1))
    dirs[0, 1] = [0.0, 0, 1]  # bundle 0: two crossing lines, but only one used
    use = np.array([[True, False], [True, True], [False, False]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        points, dist = least_squares_points(origins, dirs, use)
    assert np.all(np.isnan(points)) and np.all(np.isnan(dist))


def test_least_squares_bad_shape_names_the_argument():
    with pytest.raises(ValueError, match="use"):
        least_squares_points(np.zeros((2, 3, 3)), np.ones((2, 3, 3)), np.ones((2, 2), bool))
