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
        sil = Silhouettes(
            mask.astype(np.int32), np.zeros(1), np.full(1, h - 1.0), distance_outside_px(mask)
        )
        out[cam.name] = CameraObservation(
            cam.name, sil, np.zeros((h, w), bool), BlobSet.empty((h, w))
        )
    return out


@pytest.fixture(scope="session")
def draw_bodies(rig):
    """:func:`render_bodies` on the session's rig."""
    return lambda *bodies: render_bodies(rig, bodies)


def person_labels(
    cam, centre_xy, crown_m: float, head_radius_m: float, label: int = 1, labels=None
) -> np.ndarray:
    """A person's silhouette in ``cam`` (drawn into ``labels`` if given): a vertical column of
    radius 0.2 m from the floor to the shoulders under a ball of radius ``head_radius_m``
    whose top is ``crown_m`` high."""
    import cv2

    h, w = cam.height, cam.width
    out = np.zeros((h, w), np.int32) if labels is None else labels
    mask = np.zeros((h, w), np.uint8)
    ang = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    ring = 0.2 * np.column_stack([np.cos(ang), np.sin(ang)]) + np.asarray(centre_xy)
    shoulders = crown_m - 2 * head_radius_m
    column = np.array([[x, y, z] for z in (0.0, shoulders) for x, y in ring])
    px, depth = cam.project(column)
    cv2.fillConvexPoly(mask, cv2.convexHull(np.rint(px[depth > 0]).astype(np.int32)), 1)
    c_px, c_depth = cam.project(np.array([[*centre_xy, crown_m - head_radius_m]]))
    radius_px = head_radius_m * float(cam.K[1, 1]) / float(c_depth[0])
    cv2.circle(mask, tuple(np.rint(c_px[0]).astype(int)), round(radius_px), 1, -1)
    out[mask > 0] = label
    return out


@pytest.fixture(scope="session")
def draw_person_labels():
    """:func:`person_labels`."""
    return person_labels


@pytest.fixture(scope="session")
def draw_person(rig):
    """Observations (no skin, no blobs) of one person drawn by :func:`person_labels`."""
    from surveil.datatypes import BlobSet, CameraObservation, Silhouettes

    def draw(centre_xy, crown_m: float, head_radius_m: float) -> dict:
        out = {}
        for cam in rig.cameras:
            labels = person_labels(cam, centre_xy, crown_m, head_radius_m)
            sil = Silhouettes(
                labels, np.zeros(1), np.full(1, cam.height - 1.0), distance_outside_px(labels)
            )
            out[cam.name] = CameraObservation(
                cam.name, sil, np.zeros(labels.shape, bool), BlobSet.empty(labels.shape)
            )
        return out

    return draw


def distance_outside_px(labels: np.ndarray) -> np.ndarray:
    """(H, W) float32 distance of every pixel to the nearest silhouette pixel, px
    (``Silhouettes.dist_outside_px``)."""
    import cv2

    return cv2.distanceTransform((labels == 0).astype(np.uint8), cv2.DIST_L2, 3)
