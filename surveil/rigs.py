"""Standard camera rigs built from room geometry (no I/O).

:func:`make_corner_rig` places cameras high up round a rectangular room, all looking at one
point: the four upper corners first, then the middles of the four walls. The synthetic
scene generator (``surveil.synth``) uses it for scenario rigs made on the fly, and the
bundled ``calibration/lab4.yaml`` is :func:`lab4_rig` saved with
``surveil.io.calibration.save_rig``::

    from pathlib import Path
    from surveil.io.calibration import save_rig
    from surveil.rigs import lab4_rig

    save_rig(lab4_rig(), Path("calibration/lab4.yaml"))

World frame as everywhere in surveil: right-handed, Z up, metres, floor at Z = 0; the room's
floor spans ``[0, room_x] x [0, room_y]``.
"""

from __future__ import annotations

import numpy as np

from surveil.camera import Rig, look_at

#: Distortion of the four lab4 cameras: mild barrel distortion, varied slightly per camera
#: as real lenses are. OpenCV order (k1, k2, p1, p2, k3).
LAB4_DIST = np.array(
    [
        [-0.120, 0.030, 0.0005, -0.0003, 0.0],
        [-0.115, 0.027, -0.0004, 0.0002, 0.0],
        [-0.125, 0.033, 0.0003, 0.0004, 0.0],
        [-0.118, 0.029, -0.0002, -0.0005, 0.0],
    ]
)

MAX_CORNER_RIG_CAMERAS = 8


def corner_rig_positions(
    n_cameras: int,
    room_m: tuple[float, float] = (6.0, 5.0),
    height_m: float = 2.6,
    inset_m: float = 0.25,
) -> np.ndarray:
    """Camera centres of :func:`make_corner_rig`: corners first, then mid-walls.

    Parameters
    ----------
    n_cameras : int
        1 to 8.
    room_m : (float, float)
        Floor size along world x and y, metres; the floor spans ``[0, x] x [0, y]``.
    height_m : float
        Height of every camera above the floor, metres.
    inset_m : float
        Distance of every camera from the wall(s) it is mounted on, metres.

    Returns
    -------
    centres_m : (n_cameras, 3) float64
        World frame, metres. Order: corners (0, 0), (x, 0), (x, y), (0, y) (anticlockwise
        seen from above), then the walls y = 0, x = room_x, y = room_y, x = 0 at their middles.

    Examples
    --------
    >>> corner_rig_positions(5).tolist()[::4]
    [[0.25, 0.25, 2.6], [3.0, 0.25, 2.6]]
    """
    if not 1 <= n_cameras <= MAX_CORNER_RIG_CAMERAS:
        raise ValueError(
            f"n_cameras must be in 1..{MAX_CORNER_RIG_CAMERAS} (corners, then mid-walls), "
            f"got {n_cameras}"
        )
    x, y = float(room_m[0]), float(room_m[1])
    if x <= 2 * inset_m or y <= 2 * inset_m:
        raise ValueError(f"room_m must exceed 2 * inset_m = {2 * inset_m} m, got {room_m}")
    lo_x, hi_x, lo_y, hi_y = inset_m, x - inset_m, inset_m, y - inset_m
    xy = [
        (lo_x, lo_y),
        (hi_x, lo_y),
        (hi_x, hi_y),
        (lo_x, hi_y),
        (x / 2, lo_y),
        (hi_x, y / 2),
        (x / 2, hi_y),
        (lo_x, y / 2),
    ][:n_cameras]
    return np.array([(px, py, height_m) for px, py in xy], dtype=np.float64)


def make_corner_rig(
    n_cameras: int,
    room_m: tuple[float, float] = (6.0, 5.0),
    height_m: float = 2.6,
    size: tuple[int, int] = (640, 480),
    hfov_deg: float = 78.0,
    inset_m: float = 0.25,
    look_at_m: np.ndarray | None = None,
    dist: np.ndarray | None = None,
) -> Rig:
    """Cameras ``cam0 .. cam{n-1}`` high in a room, all looking at one point.

    Parameters
    ----------
    n_cameras : int
        1 to 8: the four upper corners first, then the middles of the walls (see
        :func:`corner_rig_positions`).
    room_m : (float, float)
        Floor size along world x and y, metres.
    height_m : float
        Camera height above the floor, metres.
    size : (int, int)
        Image (width, height), pixels.
    hfov_deg : float
        Horizontal field of view of the undistorted pinhole, degrees.
    inset_m : float
        Distance of the cameras from the walls, metres.
    look_at_m : (3,) float, optional
        World point every camera looks at (it lands on the principal point), metres.
        Default: the room centre at 0.9 m height (hand height of a standing person).
    dist : (N,) or (n_cameras, N) float, optional
        OpenCV distortion coefficients (N in 4, 5, 8, 12, 14), shared or one row per camera.
        Default: no distortion.

    Returns
    -------
    Rig
        World up (+Z) is up in every image.

    Examples
    --------
    >>> rig = make_corner_rig(4)
    >>> rig.names
    ('cam0', 'cam1', 'cam2', 'cam3')
    >>> px, depth = rig["cam2"].project(np.array([[3.0, 2.5, 0.9]]))
    >>> px.round(3).tolist(), bool(depth[0] > 0)
    ([[319.5, 239.5]], True)
    """
    centres = corner_rig_positions(n_cameras, room_m, height_m, inset_m)
    target = (
        np.array([room_m[0] / 2, room_m[1] / 2, 0.9])
        if look_at_m is None
        else np.asarray(look_at_m, dtype=np.float64).reshape(3)
    )
    if dist is None:
        dists = np.zeros((n_cameras, 5))
    else:
        d = np.asarray(dist, dtype=np.float64)
        dists = np.broadcast_to(d, (n_cameras, d.shape[-1])) if d.ndim == 1 else d
        if dists.shape[0] != n_cameras:
            raise ValueError(
                f"dist must have shape (N,) or ({n_cameras}, N), got {np.shape(dist)}"
            )
    width, height = size
    cams = tuple(
        look_at(
            f"cam{i}",
            centres[i],
            target,
            width=width,
            height=height,
            hfov_deg=hfov_deg,
            dist=dists[i].copy(),
        )
        for i in range(n_cameras)
    )
    return Rig(cams)


def lab4_rig() -> Rig:
    """The bundled ``calibration/lab4.yaml``: a 6 m x 5 m room, four 640x480 cameras.

    Cameras at the four upper corners (0.25 m from the walls, 2.6 m high), horizontal field
    of view 78 deg, looking at the room centre at 0.9 m height, mild per-camera distortion
    (:data:`LAB4_DIST`).

    >>> [c.centre_m.round(2).tolist() for c in lab4_rig()][1]
    [5.75, 0.25, 2.6]
    """
    return make_corner_rig(4, dist=LAB4_DIST)
