"""Camera model: projection against OpenCV, back-projection, look_at, Rig and validation."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from surveil.camera import Camera, Rig, look_at

DIST5 = np.array([-0.12, 0.03, 0.0005, -0.0003, 0.001])
DIST8 = np.array([-0.12, 0.03, 0.0005, -0.0003, 0.001, 0.02, -0.01, 0.003])


def make_camera(dist: np.ndarray, name: str = "cam0") -> Camera:
    """A camera at (0.5, -3, 1.8) looking at (0, 0, 1): a generic, non-axis-aligned pose."""
    return look_at(
        name,
        np.array([0.5, -3.0, 1.8]),
        np.array([0.0, 0.0, 1.0]),
        width=640,
        height=480,
        hfov_deg=70,
        dist=dist,
    )


def points_in_view(cam: Camera, rng: np.random.Generator, n: int = 200) -> np.ndarray:
    """(n, 3) world points in front of ``cam``, inside about 30 deg of its axis."""
    norm = rng.uniform(-0.5, 0.5, size=(n, 2))
    depth = rng.uniform(0.5, 8.0, size=n)
    pts_cam = np.column_stack([norm * depth[:, None], depth])
    return (pts_cam - cam.t) @ cam.R  # R.T @ (x - t), row-wise


@pytest.mark.parametrize("dist", [DIST5, DIST8], ids=["5 coefficients", "8 coefficients"])
def test_project_agrees_with_cv2_projectpoints(dist, rng):
    cam = make_camera(dist)
    pts = points_in_view(cam, rng)
    rvec = cv2.Rodrigues(cam.R)[0]
    expected, _ = cv2.projectPoints(pts, rvec, cam.t, cam.K, dist)
    px, depth = cam.project(pts)
    assert px.shape == (len(pts), 2) and px.dtype == np.float64
    np.testing.assert_allclose(px, expected.reshape(-1, 2), atol=1e-9)
    np.testing.assert_allclose(depth, (pts @ cam.R.T + cam.t)[:, 2])


def test_project_empty_input_gives_empty_arrays_of_the_right_shape():
    px, depth = make_camera(DIST5).project(np.zeros((0, 3)))
    assert px.shape == (0, 2) and depth.shape == (0,)


def distance_to_lines_of_sight(cam: Camera, pts: np.ndarray) -> np.ndarray:
    """(N,) distance (m) from each world point to the back-projection of its projection."""
    px, _ = cam.project(pts)
    origin, directions = cam.backproject(px)
    np.testing.assert_allclose(origin, cam.centre_m)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)
    to_pts = pts - origin
    along = np.einsum("ij,ij->i", to_pts, directions)
    assert (along > 0).all(), "lines of sight must point away from the camera, towards X"
    return np.linalg.norm(to_pts - along[:, None] * directions, axis=1)


@pytest.mark.parametrize("dist", [DIST5, DIST8], ids=["5 coefficients", "8 coefficients"])
def test_backproject_of_projection_passes_through_the_point(dist, rng):
    cam = make_camera(dist)
    assert distance_to_lines_of_sight(cam, points_in_view(cam, rng)).max() < 1e-6


def test_depth_is_negative_behind_the_camera_and_in_image_is_false():
    cam = make_camera(np.zeros(5))
    forward = cam.R[2]  # camera z axis in world coordinates
    pts = np.array([cam.centre_m + 2.0 * forward, cam.centre_m - 2.0 * forward])
    px, depth = cam.project(pts)
    np.testing.assert_allclose(depth, [2.0, -2.0])
    assert cam.in_image(px, depth).tolist() == [True, False]


def test_world_from_cam_inverts_to_cam(rng):
    cam = make_camera(DIST5)
    pts = rng.uniform(-2, 2, size=(10, 3))
    pts_cam_h = np.column_stack([cam.to_cam(pts), np.ones(10)])
    np.testing.assert_allclose((pts_cam_h @ cam.world_from_cam.T)[:, :3], pts, atol=1e-12)


def test_look_at_puts_target_at_principal_point_and_up_above():
    target = np.array([3.0, 2.5, 0.9])
    cam = look_at("c", np.array([0.25, 0.25, 2.6]), target, width=640, height=480, hfov_deg=78)
    px, depth = cam.project(np.array([target, target + [0, 0, 0.5]]))
    np.testing.assert_allclose(px[0], cam.K[:2, 2], atol=1e-9)
    np.testing.assert_allclose(px[0], [319.5, 239.5], atol=1e-9)
    assert (depth > 0).all()
    assert px[1, 1] < px[0, 1], "a point higher in the world must be higher (smaller v)"
    assert abs(px[1, 0] - px[0, 0]) < 1e-6, "vertical in the world stays vertical at the centre"
    np.testing.assert_allclose(cam.centre_m, [0.25, 0.25, 2.6], atol=1e-12)
    np.testing.assert_allclose(cam.K[0, 0], 320 / np.tan(np.radians(39)))


def test_look_at_straight_down_is_refused():
    with pytest.raises(ValueError, match="camera top: viewing direction is parallel to up"):
        look_at("top", np.array([0, 0, 3.0]), np.zeros(3), width=64, height=48, hfov_deg=60)


def test_rig_lookup_by_name_and_order():
    cams = [make_camera(DIST5, f"cam{i}") for i in range(3)]
    rig = Rig(tuple(cams))
    assert rig.names == ("cam0", "cam1", "cam2") and len(rig) == 3
    assert rig["cam1"] is cams[1] and "cam2" in rig and "cam9" not in rig
    assert rig.subset(["cam2", "cam0"]).names == ("cam2", "cam0")
    assert list(rig.as_mapping()) == ["cam0", "cam1", "cam2"]


def test_rig_unknown_name_lists_the_cameras():
    rig = Rig((make_camera(DIST5, "cam0"), make_camera(DIST5, "cam1")))
    with pytest.raises(KeyError, match="'cam7'.*cam0, cam1"):
        rig["cam7"]


def test_rig_duplicate_names_are_refused():
    with pytest.raises(ValueError, match="unique, repeated: cam0"):
        Rig((make_camera(DIST5, "cam0"), make_camera(DIST5, "cam0")))


def test_rig_needs_a_camera():
    with pytest.raises(ValueError, match="at least one camera"):
        Rig(())


def _camera_kwargs(**overrides):
    kw = dict(
        name="cam0",
        width=640,
        height=480,
        K=np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]]),
        dist=np.zeros(5),
        R=np.eye(3),
        t=np.zeros(3),
    )
    kw.update(overrides)
    return kw


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"name": "cam 0"}, r"camera name must match.*'cam 0'"),
        ({"name": "cam/0"}, r"camera name must match.*'cam/0'"),
        ({"R": np.diag([1.0, 1.0, 1.1])}, r"camera cam0: R must be a rotation"),
        ({"R": np.diag([1.0, 1.0, -1.0])}, r"camera cam0: R must be a rotation.*det -1"),
        ({"dist": np.zeros(6)}, r"camera cam0: dist must have 4, 5, 8, 12 or 14.*got 6"),
        ({"K": np.eye(2)}, r"camera cam0: K must have shape"),
        ({"t": np.zeros(2)}, r"camera cam0: t must have shape"),
        ({"t": np.array([0.0, np.nan, 0.0])}, r"camera cam0: t must be finite"),
        ({"width": 0}, r"camera cam0: image size must be positive"),
        ({"K": np.diag([-500.0, 500.0, 1.0])}, r"camera cam0: K must have positive focal"),
    ],
)
def test_camera_validation_names_the_field(overrides, match):
    with pytest.raises(ValueError, match=match):
        Camera(**_camera_kwargs(**overrides))


def test_camera_arrays_are_read_only_copies():
    K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
    cam = Camera(**_camera_kwargs(K=K))
    K[0, 0] = 1.0
    assert cam.K[0, 0] == 500.0
    with pytest.raises(ValueError, match="read-only"):
        cam.t[0] = 1.0


def test_project_many_agrees_with_opencv_for_any_leading_shape(rng):
    from surveil.rigs import lab4_rig

    pts = rng.uniform([0.0, 0.0, 0.0], [6.0, 5.0, 2.0], (7, 50, 3))
    for cam in lab4_rig():
        px, depth = cam.project_many(pts)
        ref_px, ref_depth = cam.project(pts.reshape(-1, 3))
        front = ref_depth > 0.2
        assert px.shape == (7, 50, 2) and depth.shape == (7, 50)
        assert np.allclose(px.reshape(-1, 2)[front], ref_px[front], atol=1e-6)
        assert np.allclose(depth.reshape(-1), ref_depth)
