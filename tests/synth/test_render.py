import numpy as np
import pytest

from surveil.synth.render import _ray_box, _ray_ellipsoid


def grid(n=41, half=0.2):
    xn, yn = np.meshgrid(
        np.linspace(-half, half, n, dtype=np.float32),
        np.linspace(-half, half, n, dtype=np.float32),
    )
    return xn, yn


def test_ray_ellipsoid_matches_the_analytic_sphere():
    xn, yn = grid()
    c, r = np.array([0.0, 0.0, 3.0]), 0.3
    t, n0, n1, n2, hit = _ray_ellipsoid(xn, yn, c, np.eye(3), np.full(3, r))
    d = np.stack([xn, yn, np.ones_like(xn)], -1).astype(np.float64)
    d_unit = d / np.linalg.norm(d, axis=-1, keepdims=True)
    # |s d_unit - c|^2 = r^2, nearest root; depth = s * d_unit_z
    b = d_unit @ c
    disc = b**2 - (c @ c - r**2)
    expect_hit = disc > 0
    s = b - np.sqrt(np.maximum(disc, 0))
    np.testing.assert_array_equal(hit, expect_hit)
    np.testing.assert_allclose(t[hit], (s * d_unit[..., 2])[hit], rtol=1e-5)
    # normals point back towards the camera and are unit length
    normals = np.stack([n0, n1, n2], -1)[hit]
    np.testing.assert_allclose(np.linalg.norm(normals, axis=-1), 1, atol=1e-5)
    assert (normals[:, 2] < 0).all()


def test_ray_box_hits_the_front_face_at_its_depth():
    xn, yn = grid()
    t, n0, n1, n2, hit = _ray_box(
        xn, yn, np.array([0.0, 0, 2.0]), np.eye(3), np.array([0.1, 0.1, 0.2])
    )
    # front face at z = 1.8, half width 0.1 -> |x/z| < 0.1/1.8
    inside = (np.abs(xn) < 0.1 / 1.8 - 1e-3) & (np.abs(yn) < 0.1 / 1.8 - 1e-3)
    assert hit[inside].all()
    np.testing.assert_allclose(t[inside], 1.8, rtol=1e-5)
    np.testing.assert_allclose(n2[inside], -1.0)
    assert not hit[(np.abs(xn) > 0.1 / 1.8 + 1e-3)].any()


@pytest.mark.parametrize("kind", ["ellipsoid", "box"])
def test_nearer_primitive_wins_the_z_test(kind):
    xn, yn = grid(11, 0.01)
    fn = _ray_ellipsoid if kind == "ellipsoid" else _ray_box
    t_near, *_ = fn(xn, yn, np.array([0.0, 0, 2.0]), np.eye(3), np.full(3, 0.1))
    t_far, *_ = fn(xn, yn, np.array([0.0, 0, 3.0]), np.eye(3), np.full(3, 0.1))
    assert (t_near < t_far).all()
