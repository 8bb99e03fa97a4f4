"""Shared fixtures of the tracking tests."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.camera import Rig, look_at


@pytest.fixture(scope="session")
def rig() -> Rig:
    """Four 320x240 cameras at the corners of a 5 x 4 m room, 2.5 m up."""
    corners = [(0.0, 0.0), (5.0, 0.0), (5.0, 4.0), (0.0, 4.0)]
    return Rig(
        tuple(
            look_at(
                f"cam{i}",
                np.array([x, y, 2.5]),
                np.array([2.5, 2.0, 1.0]),
                width=320,
                height=240,
                hfov_deg=80,
            )
            for i, (x, y) in enumerate(corners)
        )
    )


def render_bodies(rig: Rig, bodies) -> dict:
    """Observations of people drawn as elliptic columns 1.8 m high, all in silhouette 1
    (touching columns merge, as real silhouettes do); no skin, no blobs.

    ``bodies``: (centre_xy, facing_deg, half_across_m, half_depth_m) per person.
    """
    import cv2

    from surveil.datatypes import BlobSet, CameraObservation, Silhouettes

    ang = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    out = {}
    for cam in rig.cameras:
        h, w = cam.height, cam.width
        mask = np.zeros((h, w), np.uint8)
        for centre_xy, facing_deg, across, depth in bodies:
            f = np.radians(facing_deg)
            fwd, left = np.array([np.cos(f), np.sin(f)]), np.array([-np.sin(f), np.cos(f)])
            ring = np.outer(depth * np.cos(ang), fwd) + np.outer(across * np.sin(ang), left)
            pts = np.array([[*(np.asarray(centre_xy) + xy), z] for z in (0.0, 1.8) for xy in ring])
            px, dist = cam.project(pts)
            hull = cv2.convexHull(np.rint(px[dist > 0]).astype(np.int32))
            cv2.fillConvexPoly(mask, hull, 1)
        free = cv2.distanceTransform((1 - mask).astype(np.uint8), cv2.DIST_L2, 3)
        sil = Silhouettes(
            mask.astype(np.int32), np.zeros(1), np.full(1, h - 1.0), free.astype(np.float32)
        )
        out[cam.name] = CameraObservation(
            cam.name, sil, np.zeros((h, w), bool), BlobSet.empty((h, w))
        )
    return out


@pytest.fixture(scope="session")
def draw_bodies(rig):
    """:func:`render_bodies` on the session's rig."""
    return lambda *bodies: render_bodies(rig, bodies)
