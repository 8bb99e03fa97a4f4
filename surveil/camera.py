"""Calibrated cameras and rigs: the geometry every stage shares.

A world point ``X`` (metres, world frame: right-handed, Z up, floor at Z = 0) maps to camera
coordinates by ``x_cam = R @ X + t`` (OpenCV camera frame: x right, y down, z forward), then
to pixels by the intrinsics ``K`` and the OpenCV distortion model ``dist``. This is exactly the
rig file's convention (docs/formats.md) and ``cv2.projectPoints``'.

This module lives at the package top level, beside ``datatypes``, because the I/O, synthesis,
reconstruction and visualisation stages all need the same camera model (one place per concept).
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import cv2
import numpy as np

from surveil.validate import readonly, require_finite, require_shape

CAMERA_NAME_RE = re.compile(r"^[A-Za-z0-9_.-]+$")
DIST_LENGTHS = (4, 5, 8, 12, 14)
UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-14)


def _undistort_points(px: np.ndarray, K: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """cv2.undistortPoints iterated to ``UNDISTORT_CRITERIA``: OpenCV 4 takes criteria only in
    ``undistortPointsIter``, OpenCV 5 dropped that function and takes them in
    ``undistortPoints``."""
    if hasattr(cv2, "undistortPointsIter"):
        return cv2.undistortPointsIter(px, K, dist, None, None, UNDISTORT_CRITERIA)
    return cv2.undistortPoints(px, K, dist, criteria=UNDISTORT_CRITERIA)


@dataclass(frozen=True, slots=True)
class Camera:
    """One calibrated camera.

    Attributes
    ----------
    name : str
        Unique name matching ``[A-Za-z0-9_.-]+`` (used in MCAP topics and Rerun paths).
    width, height : int
        Image size in pixels.
    K : (3, 3) float64
        Intrinsic matrix, pixels.
    dist : (N,) float64
        OpenCV distortion coefficients, N in {4, 5, 8, 12, 14}.
    R : (3, 3) float64
        Rotation world -> camera.
    t : (3,) float64
        Translation world -> camera, metres.
    """

    name: str
    width: int
    height: int
    K: np.ndarray
    dist: np.ndarray
    R: np.ndarray
    t: np.ndarray
    _rvec: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not CAMERA_NAME_RE.match(self.name):
            raise ValueError(f"camera name must match [A-Za-z0-9_.-]+, got {self.name!r}")
        if int(self.width) <= 0 or int(self.height) <= 0:
            raise ValueError(
                f"camera {self.name}: image size must be positive, got {self.width}x{self.height}"
            )
        K = np.array(self.K, dtype=np.float64)
        dist = np.array(self.dist, dtype=np.float64).reshape(-1)
        R = np.array(self.R, dtype=np.float64)
        t = np.array(self.t, dtype=np.float64).reshape(-1)
        require_shape(f"camera {self.name}: K", K, (3, 3), np.floating)
        require_shape(f"camera {self.name}: R", R, (3, 3), np.floating)
        require_shape(f"camera {self.name}: t", t, (3,), np.floating)
        if dist.shape[0] not in DIST_LENGTHS:
            raise ValueError(
                f"camera {self.name}: dist must have 4, 5, 8, 12 or 14 "
                f"coefficients, got {dist.shape[0]}"
            )
        for arr_name, arr in (("K", K), ("dist", dist), ("R", R), ("t", t)):
            require_finite(f"camera {self.name}: {arr_name}", arr)
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError(
                f"camera {self.name}: R must be a rotation matrix "
                f"(orthonormal, det +1), got det {np.linalg.det(R):.6f}"
            )
        if K[0, 0] <= 0 or K[1, 1] <= 0:
            raise ValueError(
                f"camera {self.name}: K must have positive focal lengths, "
                f"got fx={K[0, 0]}, fy={K[1, 1]}"
            )
        rvec = cv2.Rodrigues(R)[0].reshape(3)
        for attr, value in (("K", K), ("dist", dist), ("R", R), ("t", t), ("_rvec", rvec)):
            readonly(value)
            object.__setattr__(self, attr, value)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    @property
    def centre_m(self) -> np.ndarray:
        """(3,) camera centre in the world frame, metres: ``-R.T @ t``."""
        return -self.R.T @ self.t

    @property
    def world_from_cam(self) -> np.ndarray:
        """(4, 4) homogeneous transform mapping camera coordinates into the world frame."""
        T = np.eye(4)
        T[:3, :3] = self.R.T
        T[:3, 3] = self.centre_m
        return T

    @property
    def rvec(self) -> np.ndarray:
        """(3,) Rodrigues vector of R (world -> camera)."""
        return self._rvec

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.width, self.height

    def to_cam(self, points_m: np.ndarray) -> np.ndarray:
        """World points (N, 3) -> camera-frame points (N, 3), metres."""
        require_shape("points_m", points_m, (None, 3), np.number)
        return points_m @ self.R.T + self.t

    def project(self, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project world points into the image, with distortion.

        Parameters
        ----------
        points_m : (N, 3) float
            World points, metres.

        Returns
        -------
        pixels_px : (N, 2) float64
            ``(u, v)`` pixel coordinates (column, row). Meaningless where ``depth_m <= 0``.
        depth_m : (N,) float64
            z in the camera frame; points with ``depth_m <= 0`` are behind the camera.

        Examples
        --------
        >>> cam = Camera("c", 640, 480, [[500, 0, 320], [0, 500, 240], [0, 0, 1]],
        ...              np.zeros(5), np.eye(3), np.zeros(3))
        >>> px, z = cam.project(np.array([[0.0, 0.0, 2.0], [0.2, -0.1, 2.0]]))
        >>> px.round(1).tolist(), z.tolist()
        ([[320.0, 240.0], [370.0, 215.0]], [2.0, 2.0])
        """
        pts = np.ascontiguousarray(points_m, dtype=np.float64)
        require_shape("points_m", pts, (None, 3), np.floating)
        if len(pts) == 0:
            return np.zeros((0, 2)), np.zeros(0)
        px, _ = cv2.projectPoints(pts, self._rvec, self.t, self.K, self.dist)
        depth = pts @ self.R[2] + self.t[2]
        return px.reshape(-1, 2), depth

    def project_many(self, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`project` for many points of any leading shape (..., 3), in numpy.

        Returns pixels (..., 2) and depths (...,). Same model as OpenCV's for 4, 5 or 8
        distortion coefficients (radial k1-k6, tangential p1 p2), about 10x faster than
        ``cv2.projectPoints`` on tens of thousands of points (the arm trackers project every
        particle's joints every frame set); other models fall back to :meth:`project`.
        """
        pts = np.asarray(points_m, dtype=np.float64)
        lead = pts.shape[:-1]
        if self.dist.shape[0] not in (4, 5, 8):
            px, depth = self.project(pts.reshape(-1, 3))
            return px.reshape(*lead, 2), depth.reshape(lead)
        cam = pts @ self.R.T + self.t
        depth = cam[..., 2]
        z = np.where(np.abs(depth) > 1e-9, depth, 1e-9)
        x, y = cam[..., 0] / z, cam[..., 1] / z
        d = np.zeros(8)
        d[: self.dist.shape[0]] = self.dist
        k1, k2, p1, p2, k3, k4, k5, k6 = d
        r2 = x * x + y * y
        radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        K = self.K
        u = K[0, 0] * xd + K[0, 1] * yd + K[0, 2]
        v = K[1, 1] * yd + K[1, 2]
        return np.stack([u, v], axis=-1), depth

    def undistort_pixels(self, pixels_px: np.ndarray) -> np.ndarray:
        """Distorted pixels (N, 2) -> normalised image coordinates (N, 2) (x/z, y/z)."""
        px = np.ascontiguousarray(pixels_px, dtype=np.float64)
        require_shape("pixels_px", px, (None, 2), np.floating)
        if len(px) == 0:
            return np.zeros((0, 2))
        # OpenCV's default iteration limit leaves ~1e-6 m errors at room scale; iterate to
        # convergence so back-projection inverts projection to float precision
        return _undistort_points(px.reshape(-1, 1, 2), self.K, self.dist).reshape(-1, 2)

    def backproject(self, pixels_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lines of sight through pixels (undistorting first).

        Parameters
        ----------
        pixels_px : (N, 2) float
            ``(u, v)`` pixel coordinates.

        Returns
        -------
        origin_m : (3,) float64
            The camera centre, world frame (every line passes through it).
        directions : (N, 3) float64
            Unit direction of each line of sight, world frame, pointing away from the camera.
        """
        norm = self.undistort_pixels(pixels_px)
        rays_cam = np.column_stack([norm, np.ones(len(norm))])
        rays_world = rays_cam @ self.R  # (R.T @ d).T == d.T @ R
        rays_world /= np.linalg.norm(rays_world, axis=1, keepdims=True)
        return self.centre_m, rays_world

    def in_image(self, pixels_px: np.ndarray, depth_m: np.ndarray) -> np.ndarray:
        """(N,) bool: in front of the camera and inside the image bounds."""
        u, v = pixels_px[:, 0], pixels_px[:, 1]
        return (depth_m > 0) & (u >= 0) & (v >= 0) & (u <= self.width - 1) & (v <= self.height - 1)


@dataclass(frozen=True, slots=True)
class Rig:
    """An ordered set of cameras with unique names. Index by name: ``rig["cam0"]``."""

    cameras: tuple[Camera, ...]

    def __post_init__(self) -> None:
        cams = tuple(self.cameras)
        if not cams:
            raise ValueError("a rig needs at least one camera, got none")
        names = [c.name for c in cams]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"camera names must be unique, repeated: {', '.join(dupes)}")
        object.__setattr__(self, "cameras", cams)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.cameras)

    def __getitem__(self, name: str) -> Camera:
        for cam in self.cameras:
            if cam.name == name:
                return cam
        raise KeyError(f"no camera named {name!r} in the rig (cameras: {', '.join(self.names)})")

    def __contains__(self, name: object) -> bool:
        return name in self.names

    def __iter__(self) -> Iterator[Camera]:
        return iter(self.cameras)

    def __len__(self) -> int:
        return len(self.cameras)

    def subset(self, names: list[str] | tuple[str, ...]) -> Rig:
        """The rig restricted to ``names``, in that order."""
        return Rig(tuple(self[n] for n in names))

    def as_mapping(self) -> Mapping[str, Camera]:
        return {c.name: c for c in self.cameras}


def look_at(
    name: str,
    centre_m: np.ndarray,
    target_m: np.ndarray,
    *,
    width: int,
    height: int,
    hfov_deg: float,
    dist: np.ndarray | None = None,
    up: tuple[float, float, float] = (0.0, 0.0, 1.0),
) -> Camera:
    """A camera at ``centre_m`` looking at ``target_m`` with world ``up`` towards image top.

    The principal point is the image centre and pixels are square; ``hfov_deg`` is the
    horizontal field of view of the undistorted pinhole.

    >>> cam = look_at("c", np.array([0.0, -3, 1]), np.array([0.0, 0, 1]),
    ...               width=640, height=480, hfov_deg=60)
    >>> px, z = cam.project(np.array([[0.0, 0, 1], [0.0, 0, 1.5]]))
    >>> px.round(1).tolist(), bool(px[1, 1] < px[0, 1])  # higher Z is higher in the image
    ([[319.5, 239.5], [319.5, 147.1]], True)
    """
    centre = np.asarray(centre_m, dtype=np.float64)
    forward = np.asarray(target_m, dtype=np.float64) - centre
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(up, dtype=np.float64))
    if np.linalg.norm(right) < 1e-9:
        raise ValueError(f"camera {name}: viewing direction is parallel to up; pick another up")
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    R = np.stack([right, down, forward])  # rows: camera axes in world coordinates
    f = 0.5 * width / np.tan(np.radians(hfov_deg) / 2)
    K = np.array([[f, 0, (width - 1) / 2], [0, f, (height - 1) / 2], [0, 0, 1]])
    return Camera(name, width, height, K, np.zeros(5) if dist is None else dist, R, -R @ centre)
