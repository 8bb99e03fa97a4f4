"""Closest points of pairs of 3-D lines (paper 004 section 5.1, eq. 22-24). Pure, vectorised."""

from __future__ import annotations

import numpy as np

from surveil.validate import require_shape


def closest_points(
    o1: np.ndarray,
    d1: np.ndarray,
    o2: np.ndarray,
    d2: np.ndarray,
    *,
    min_sin_angle: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint and half length of the common perpendicular of N pairs of lines.

    Line 1 is ``o1 + c1 * d1``, line 2 is ``o2 + c2 * d2``. The common perpendicular joins
    the closest points ``o1 + c1 d1`` and ``o2 + c2 d2``; its midpoint is the reconstructed
    point Z (eq. 22) and half its length is the reconstruction error d (eq. 24).

    Parameters
    ----------
    o1, o2 : (N, 3) float
        Points on the lines (e.g. camera centres), world frame, metres.
    d1, d2 : (N, 3) float
        Line directions (any non-zero length), world frame.
    min_sin_angle : float
        Lines whose angle has a sine below this are treated as parallel.

    Returns
    -------
    midpoints_m : (N, 3) float64
        Z, midpoint of the common perpendicular; NaN for (near-)parallel lines.
    half_gap_m : (N,) float64
        d, half the shortest distance between the lines; ``inf`` for (near-)parallel lines.

    References
    ----------
    Paper 004 (shared/papers/004_*), section 5.1, eq. 22-24.

    Examples
    --------
    >>> o1, d1 = np.array([[0.0, 0, 0]]), np.array([[1.0, 0, 0]])
    >>> o2, d2 = np.array([[0.0, 0, 2]]), np.array([[0.0, 1, 0]])
    >>> z, d = closest_points(o1, d1, o2, d2)
    >>> z.tolist(), d.tolist()
    ([[0.0, 0.0, 1.0]], [1.0])
    >>> closest_points(o1, d1, o2, d1)[1].tolist()  # parallel
    [inf]
    """
    arrays = {}
    for name, arr in (("o1", o1), ("d1", d1), ("o2", o2), ("d2", d2)):
        arr = np.asarray(arr, dtype=np.float64)
        require_shape(name, arr, (len(np.atleast_1d(o1)), 3), np.floating)
        arrays[name] = arr
    o1, d1, o2, d2 = arrays["o1"], arrays["d1"], arrays["o2"], arrays["d2"]
    # eq. 23, solved in closed form: (p1 + c1 v1) - (p2 + c2 v2) is orthogonal to v1 and v2
    w = o1 - o2
    a = np.einsum("ij,ij->i", d1, d1)
    b = np.einsum("ij,ij->i", d1, d2)
    c = np.einsum("ij,ij->i", d2, d2)
    d = np.einsum("ij,ij->i", d1, w)
    e = np.einsum("ij,ij->i", d2, w)
    den = a * c - b * b  # = |d1|^2 |d2|^2 sin^2(angle)
    valid = den > (min_sin_angle**2) * a * c
    safe = np.where(valid, den, 1.0)
    c1 = np.where(valid, (b * e - c * d) / safe, np.nan)
    c2 = np.where(valid, (a * e - b * d) / safe, np.nan)
    p1 = o1 + c1[:, None] * d1
    p2 = o2 + c2[:, None] * d2
    # eq. 22 and 24
    midpoints = 0.5 * (p1 + p2)
    half_gap = np.where(valid, 0.5 * np.linalg.norm(p1 - p2, axis=1), np.inf)
    return midpoints, half_gap


def least_squares_points(
    origins: np.ndarray, dirs: np.ndarray, use: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The point nearest, in summed squared distance, to each of K bundles of 3-D lines.

    Bundle k holds the lines ``origins[k, m] + c * dirs[k, m]`` with ``use[k, m]``. The point
    solves sum_m P_m x = sum_m P_m o_m, P_m = I - d_m d_m^T (d_m unit): the N-view
    generalisation of the common perpendicular's midpoint (:func:`closest_points`), to which
    it reduces for two lines.

    Parameters
    ----------
    origins, dirs : (K, M, 3) float -- points on the lines and their directions (any
        non-zero length), metres
    use : (K, M) bool -- which lines take part

    Returns
    -------
    points_m : (K, 3) float64 -- NaN where fewer than two lines take part or they are
        (near-)parallel
    distances_m : (K, M) float64 -- each line's distance from its bundle's point (NaN where
        the point is)

    Examples
    --------
    >>> o = np.array([[[0.0, 0, 0], [0.0, 0, 2], [5.0, 5, 1]]])
    >>> d = np.array([[[1.0, 0, 0], [0.0, 1, 0], [-1.0, -1, 0]]])
    >>> x, dist = least_squares_points(o, d, np.array([[True, True, False]]))
    >>> x.round(6).tolist(), dist.round(6).tolist()
    ([[0.0, 0.0, 1.0]], [[1.0, 1.0, 0.0]])
    """
    origins = np.asarray(origins, dtype=np.float64)
    dirs = np.asarray(dirs, dtype=np.float64)
    require_shape("origins", origins, (None, None, 3), np.floating)
    require_shape("dirs", dirs, origins.shape, np.floating)
    require_shape("use", use, origins.shape[:2], np.bool_)
    unit = dirs / np.linalg.norm(dirs, axis=2, keepdims=True)
    proj = np.eye(3) - unit[..., :, None] * unit[..., None, :]  # (K, M, 3, 3)
    used = np.where(use[..., None, None], proj, 0.0)
    a = used.sum(axis=1)
    b = np.einsum("kmij,kmj->ki", used, origins)
    solvable = (use.sum(axis=1) >= 2) & (np.abs(np.linalg.det(a)) > 1e-12)
    points = np.full((len(a), 3), np.nan)
    if solvable.any():
        points[solvable] = np.linalg.solve(a[solvable], b[solvable][..., None])[..., 0]
    off = np.einsum("kmij,kmj->kmi", proj, points[:, None] - origins)
    return points, np.linalg.norm(off, axis=2)
