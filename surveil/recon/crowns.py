"""Head candidates from the silhouettes' crowns, not skin (not in the paper; docs/candidates.md,
"Crowns").

A head's skin candidate needs a face or neck blob in two views that pair. A person whose
skin-coloured shirt joins his face and neck into one blob, whose face is seen from one side
only, or whose hair is camouflaged against a dark wall gets none (three_people's p3, in every
take). His silhouettes still show his head: a bump on the silhouette's top edge, in every
view where no one taller stands in front of him.

Per view, the crowns are the local peaks of each silhouette's top edge that rise far enough
above their neighbourhood and are about a head wide, measured in metres at the depth where the
peak's line of sight meets an adult's crown height. A peak's line of sight passes over the head,
tangent to it; moved down (perpendicular to it, in its vertical plane) by the head's extent in
that direction, it passes through the head's centre. Every pair of moved lines from two views
that (nearly) meet gives a point; points within ``merge_radius_m`` are one head, kept when at
least ``min_views`` views agree (a pair of two views is too often two people's crowns that
happen to cross; on the bundled takes every false crown point had two views and every true one
but 0.5 % three or four).

Pure functions, vectorised over views and pairs; the loops run over silhouettes and peaks
(a few per frame).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from scipy.signal import find_peaks, peak_prominences, peak_widths

from surveil.camera import Camera, Rig
from surveil.datatypes import Silhouettes
from surveil.recon.settings import CrownConfig
from surveil.recon.triangulate import closest_points

# below every silhouette's top edge (as minus image rows): the walls between the edges of a
# view's silhouettes, laid end to end, so that no peak's neighbourhood spans two of them
WALL = -1e6

# every this many image columns are read for the top edges: a head is at least 10 columns
# wide where a crown can be told at all, and the edges cost half as much
COLUMN_STEP = 2

# a crown lies in this upper share of its silhouette's box (a seated person's head beside a
# standing one's lies 30 % down); the edge is not read below it
TOP_SHARE = 0.6


def people_from_crowns(crowns_per_view: Sequence[int]) -> int:
    """How many people a frame set's views show by their crowns: the median of the views'
    crown counts, rounded down (0 without views).

    A view's silhouettes undercount people who stand close (they merge into one silhouette);
    its crowns do not, as long as each head rises above the others' shoulders. A view where
    a raised hand or a bag also makes a crown, or where one person hides behind another, is
    outvoted by the other views (docs/blobs.md, "How many people").

    >>> people_from_crowns([3, 2, 3, 4])
    3
    >>> people_from_crowns([1, 2])
    1
    >>> people_from_crowns([])
    0
    """
    if len(crowns_per_view) == 0:
        return 0
    return int(np.floor(np.median(np.asarray(crowns_per_view, dtype=np.float64))))


def _px_per_m(
    camera: Camera, uv_px: np.ndarray, height_m: float, fallback: np.ndarray
) -> np.ndarray:
    """(N,) pixels per metre at the depth where each pixel's line of sight reaches
    ``height_m``; ``fallback`` where it never does (looking up or level). A scale, not a
    measurement: the pinhole model, without the lens distortion."""
    K = camera.K
    y = (uv_px[:, 1] - K[1, 2]) / K[1, 1]
    x = (uv_px[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    # world directions with unit depth: the parameter reaching height_m is the depth
    rays = np.column_stack([x, y, np.ones(len(uv_px))]) @ camera.R
    down = rays[:, 2]
    level = np.abs(down) <= 1e-9
    depth = np.where(level, -1.0, (height_m - camera.centre_m[2]) / np.where(level, 1.0, down))
    return np.where(depth > 0.3, K[0, 0] / np.maximum(depth, 0.3), fallback)


def silhouette_crowns(silhouettes: Silhouettes, camera: Camera, cfg: CrownConfig) -> np.ndarray:
    """(C, 2) float64: the crowns (u, v) of one view's silhouettes, v the top edge of the
    crown's row (half a pixel above its centre).

    A crown is a local peak of a silhouette's top edge (its first row in each column) that
    rises ``cfg.min_rise_m`` above the edge on either side (its prominence) and is
    ``cfg.min_width_m``..``cfg.max_width_m`` wide ``cfg.width_depth_m`` below its top, in
    metres at the depth where its line of sight meets ``cfg.crown_height_m`` (elsewhere, at
    the silhouette's height taken as an adult's). Peaks on the image's top row are not crowns
    (the head may go on above the frame). u is the middle of the crown's width.

    Examples
    --------
    A camera 4 m from a 1.75 m tall box with a 0.16 m wide, 0.25 m high head on top:

    >>> from surveil.camera import look_at
    >>> cam = look_at("c", np.array([-4.0, 0, 2.5]), np.array([0.0, 0, 1.2]),
    ...               width=640, height=480, hfov_deg=60)
    >>> def px(y, z): return cam.project(np.array([[0.0, y, z]]))[0][0]
    >>> labels = np.zeros((480, 640), np.int32)
    >>> (u0, v0), (u1, v1) = px(0.25, 1.5), px(-0.25, 0.0)
    >>> labels[int(v0):int(v1), int(u0):int(u1)] = 1  # the body, 0.5 m wide
    >>> (u0, v0), (u1, _) = px(0.08, 1.75), px(-0.08, 1.75)
    >>> labels[int(v0):int(v1), int(u0):int(u1)] = 1  # the head
    >>> sil = Silhouettes(labels, np.array([float(int(v0))]), np.array([float(int(v1) - 1)]),
    ...                   np.zeros((480, 640), np.float32))
    >>> crowns = silhouette_crowns(sil, cam, CrownConfig())
    >>> bool(np.allclose(crowns, [[0.5 * (u0 + u1) - 0.5, int(v0) - 0.5]], atol=1.0))
    True
    """
    labels = silhouettes.labels
    if silhouettes.n == 0:
        return np.zeros((0, 2))
    if silhouettes.boxes_px is not None:
        boxes = np.asarray(silhouettes.boxes_px, dtype=np.int64)
    else:
        x0, y0, x1, y1 = silhouettes.boxes(0)[0]
        boxes = np.tile([x0, y0, x1 - x0, y1 - y0], (silhouettes.n, 1))
    # every silhouette's top edge (minus its first row in each column), end to end
    edges, columns, fallback = [], [], []
    for s in range(1, silhouettes.n + 1):
        x, y, w, h = (int(a) for a in boxes[s - 1])
        inside = labels[y : y + int(TOP_SHARE * h) + 1, x : x + w][:, ::COLUMN_STEP] == s
        has = inside.any(axis=0)
        edges.append(np.where(has, -(y + inside.argmax(axis=0)), WALL))
        edges.append([WALL])
        columns.append(np.arange(x, x + w, COLUMN_STEP))
        columns.append([-1])
        height_px = silhouettes.bottom_v_px[s - 1] - silhouettes.top_v_px[s - 1] + 1
        fallback.append(np.full(len(has) + 1, height_px / cfg.crown_height_m))
    edge = np.concatenate([[WALL], *edges]).astype(np.float64)
    column = np.concatenate([[-1], *columns]).astype(np.float64)
    peaks = find_peaks(edge, plateau_size=1)[0]
    peaks = peaks[edge[peaks] < 0]  # on the image's top row: cut off
    if len(peaks) == 0:
        return np.zeros((0, 2))
    scale = _px_per_m(
        camera,
        np.column_stack([column[peaks], -edge[peaks]]),
        cfg.crown_height_m,
        np.concatenate(fallback)[peaks - 1],
    )
    rise, left_base, right_base = peak_prominences(edge, peaks)
    ok = (rise >= cfg.min_rise_m * scale) & (rise > 0)
    peaks, scale, rise = peaks[ok], scale[ok], rise[ok]
    if len(peaks) == 0:
        return np.zeros((0, 2))
    # the width cfg.width_depth_m below the top (or at the lower side, if it rises less)
    depth = np.minimum(cfg.width_depth_m * scale, rise)
    width, _, left, right = peak_widths(edge, peaks, 1.0, (depth, left_base[ok], right_base[ok]))
    width *= COLUMN_STEP
    ok = (width >= cfg.min_width_m * scale) & (width <= cfg.max_width_m * scale)
    # u: the middle of the width (fractional indices into the edge, COLUMN_STEP apart)
    middle = 0.5 * (left[ok] + right[ok])
    u = column[peaks[ok]] + (middle - peaks[ok]) * COLUMN_STEP
    return np.column_stack([u, -edge[peaks[ok]] - 0.5])


def centre_lines(
    camera: Camera, crowns_px: np.ndarray, top_to_centre_m: float, half_width_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Lines of sight over crowns moved down to the heads' centres.

    A line of sight tangent to the top of a head (an ellipsoid of revolution with vertical
    semi-axis ``top_to_centre_m`` and horizontal ``half_width_m``) passes its centre at the
    head's extent along the line's downward normal n (in its vertical plane): sqrt(a^2 cos^2 b
    + c^2 sin^2 b), b the angle of n from straight down.

    Returns (N, 3) points on the moved lines and (N, 3) their unit directions; NaN rows for
    lines looking straight down or up (no vertical plane).

    >>> from surveil.camera import look_at
    >>> cam = look_at("c", np.array([-4.0, 0, 1.7]), np.array([0.0, 0, 1.7]),
    ...               width=640, height=480, hfov_deg=60)
    >>> o, d = centre_lines(cam, np.array([[319.5, 239.5]]), 0.125, 0.09)
    >>> np.round(o, 3).tolist(), np.round(d + 0.0, 3).tolist()  # level: 0.125 m down
    ([[-4.0, 0.0, 1.575]], [[1.0, 0.0, 0.0]])
    """
    origin, d = camera.backproject(crowns_px)
    n = np.array([0.0, 0.0, -1.0]) + d[:, 2:3] * d  # straight down minus its part along d
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(norm > 1e-6, n / np.where(norm > 1e-6, norm, 1.0), np.nan)
    cos_b = -n[:, 2]
    extent = np.sqrt(top_to_centre_m**2 * cos_b**2 + half_width_m**2 * (1.0 - cos_b**2))
    return origin + extent[:, None] * n, d


def _cluster(points_m: np.ndarray, order: np.ndarray, radius_m: float) -> np.ndarray:
    """(N,) cluster index of each point: greedily, in ``order``, each point not yet taken
    takes those not yet taken within ``radius_m``."""
    cluster = np.full(len(points_m), -1)
    close = np.linalg.norm(points_m[:, None] - points_m[None], axis=2) < radius_m
    n = 0
    for i in order.tolist():
        if cluster[i] >= 0:
            continue
        cluster[close[i] & (cluster < 0)] = n
        n += 1
    return cluster


def crown_heads(
    silhouettes: Mapping[int, Silhouettes],
    crowns_px: Mapping[int, np.ndarray],
    rig: Rig,
    cfg: CrownConfig,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Head centres where the crowns of at least ``cfg.min_views`` views meet.

    Parameters
    ----------
    silhouettes : rig camera index -> that view's silhouettes (views of this frame set)
    crowns_px : rig camera index -> that view's crowns (C, 2) (:func:`silhouette_crowns`)
    rig : Rig
    cfg : CrownConfig

    Returns
    -------
    points_m : (K, 3) float64 -- each head's centre: the mean of its pairs' points
    half_gap_m : (K,) float64 -- the mean half gap of those pairs
    n_views : (K,) int64 -- how many views' crowns made it
    """
    rows_o, rows_d, rows_cam = [], [], []
    for m, crowns in crowns_px.items():
        if len(crowns) == 0:
            continue
        o, d = centre_lines(rig.cameras[m], crowns, cfg.top_to_centre_m, cfg.half_width_m)
        ok = np.isfinite(o).all(axis=1)
        rows_o.append(o[ok])
        rows_d.append(d[ok])
        rows_cam.append(np.full(int(ok.sum()), m))
    none = np.zeros((0, 3)), np.zeros(0), np.zeros(0, np.int64)
    if len(rows_o) < 2:
        return none
    o, d, cam_of = np.concatenate(rows_o), np.concatenate(rows_d), np.concatenate(rows_cam)
    ia, ib = np.triu_indices(len(o), k=1)
    pair = cam_of[ia] != cam_of[ib]
    ia, ib = ia[pair], ib[pair]
    points, gap = closest_points(o[ia], d[ia], o[ib], d[ib])
    with np.errstate(invalid="ignore"):
        ok = (
            (gap <= cfg.max_gap_m)
            & (points[:, 2] >= cfg.min_z_m)
            & (points[:, 2] <= cfg.max_z_m)
            & (np.einsum("ij,ij->i", points - o[ia], d[ia]) > 0)
            & (np.einsum("ij,ij->i", points - o[ib], d[ib]) > 0)
        )
    ia, ib, points, gap = ia[ok], ib[ok], points[ok], gap[ok]
    if len(points) == 0:
        return none
    outside = np.zeros(len(points), np.int64)
    for m, sil in silhouettes.items():
        cam = rig.cameras[m]
        px, depth = cam.project(points)
        seen = cam.in_image(px, depth)
        uv = np.rint(px[seen]).astype(np.intp)
        dist = sil.dist_outside_px[uv[:, 1], uv[:, 0]]
        outside[np.flatnonzero(seen)[dist >= cfg.outside_px]] += 1
    ok = outside <= cfg.max_outside_views
    ia, ib, points, gap = ia[ok], ib[ok], points[ok], gap[ok]
    if len(points) == 0:
        return none
    cluster = _cluster(points, np.argsort(gap, kind="stable"), cfg.merge_radius_m)
    n = int(cluster.max()) + 1
    count = np.bincount(cluster, minlength=n)
    centres = np.stack([np.bincount(cluster, points[:, k], n) for k in range(3)], 1)
    centres /= count[:, None]
    mean_gap = np.bincount(cluster, gap, n) / count
    # views per cluster: a (cluster, camera) table of the pairs' two cameras
    seen_by = np.zeros((n, len(rig)), bool)
    seen_by[cluster, cam_of[ia]] = True
    seen_by[cluster, cam_of[ib]] = True
    n_views = seen_by.sum(axis=1)
    keep = n_views >= cfg.min_views
    return centres[keep], mean_gap[keep], n_views[keep].astype(np.int64)
