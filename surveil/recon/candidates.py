"""3-D candidate points from pairs of views and their prior p(Z) (paper 004 sections 5.1, 6.3).

Every blob of camera m is paired with every blob of camera m' > m; each pair's lines of sight
give a point Z (the midpoint of their common perpendicular) and an error d (half its length).
The prior p(Z) = p_o * p_t * p_b (eq. 19) scores how consistent the pair is; weak candidates
are dropped and close ones merged. See docs/candidates.md.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from surveil.camera import Rig
from surveil.datatypes import BlobSet, CameraObservation, CandidateSet
from surveil.recon.crowns import crown_heads, silhouette_crowns
from surveil.recon.settings import CandidateConfig, CrownConfig
from surveil.recon.triangulate import closest_points, least_squares_points

log = logging.getLogger(__name__)


def _empty() -> CandidateSet:
    return CandidateSet(
        np.zeros((0, 3)),
        np.zeros(0),
        half_gap_m=np.zeros(0),
        cam_pairs=np.zeros((0, 2), dtype=np.int64),
        blob_pairs=np.zeros((0, 2), dtype=np.int64),
        head_only=np.zeros(0, dtype=bool),
        views=np.zeros(0, dtype=np.int64),
    )


def gauss_term(x: np.ndarray, sigma: float) -> np.ndarray:
    """exp(-x^2 / (2 sigma^2)); 0 where x is not finite."""
    with np.errstate(invalid="ignore", over="ignore"):
        g = np.exp(-0.5 * np.square(x / sigma))
    return np.where(np.isfinite(x), g, 0.0)


def floor_relative_v(
    points_m: np.ndarray, cams: np.ndarray, v_px: np.ndarray, top_px: np.ndarray, rig: Rig
) -> np.ndarray:
    """D_v of eq. 25 measured down to the floor: (v - top) / (v_floor - top).

    The paper's D_v (``BlobSet.rel_v``) divides by the silhouette's height; where legs are
    hidden (behind a table, by a person in front, in a camera whose background model lost
    them) the silhouette's bottom row is not the feet. Here the bottom is the image row of
    the floor point under Z, which the calibration gives (docs/candidates.md, "p_o").

    Parameters
    ----------
    points_m : (N, 3) float -- the candidate Z each blob takes part in, m
    cams : (N,) int -- rig index of the blob's camera
    v_px, top_px : (N,) float -- the blob centroid's row and its silhouette's top row, px
    rig : Rig

    Returns
    -------
    (N,) float64, 0 at the silhouette's top and 1 on the floor under Z; the denominator is
    at least 1 px.
    """
    floor = np.array(points_m, dtype=np.float64)
    floor[:, 2] = 0.0
    bottom = np.empty(len(floor))
    for m in np.unique(cams):
        sel = cams == m
        bottom[sel] = rig.cameras[int(m)].project(floor[sel])[0][:, 1]
    return (v_px - top_px) / np.maximum(bottom - top_px, 1.0)


def merged_tops(
    points_m: np.ndarray,
    cams: np.ndarray,
    silhouettes: np.ndarray,
    top_px: np.ndarray,
    crowns_m: np.ndarray,
    rig: Rig,
    by_cam: Mapping[int, CameraObservation],
    head_drop_m: float = 0.12,
    headless_m: float = 0.0,
) -> np.ndarray:
    """(N,) the silhouette top row for p_o of each blob: where its silhouette holds two or
    more tracked heads (people merged in that view), the row of the crown of the one
    nearest to Z horizontally; with ``headless_m`` > 0, where it holds none but a tracked
    head's centre projects above its top row, between its box's columns, and that head is
    within ``headless_m`` of Z horizontally, the row of the nearest such head's crown (the
    background model lost the head: dark hair against a dark door); elsewhere ``top_px``.

    A head is in a silhouette when the point ``head_drop_m`` under its crown (its centre)
    projects onto it. Headless silhouettes need ``Silhouettes.boxes_px`` (a run's have them).

    Parameters
    ----------
    points_m : (N, 3) float -- the candidate Z each blob takes part in, m
    cams : (N,) int -- rig index of the blob's camera
    silhouettes : (N,) int -- the blob's silhouette label (0 none)
    top_px : (N,) float -- its silhouette's top row, px
    crowns_m : (H, 3) float -- the tracked heads' crowns, m
    rig : Rig
    by_cam : rig index -> that camera's observation
    """
    out = np.array(top_px, dtype=np.float64)
    centres = np.asarray(crowns_m, dtype=np.float64) - [0.0, 0.0, head_drop_m]
    horiz = np.linalg.norm(points_m[:, None, :2] - centres[None, :, :2], axis=2)  # (N, H)
    for m in np.unique(cams).tolist():
        cam = rig.cameras[m]
        labels = by_cam[m].silhouettes.labels
        px, depth = cam.project(centres)
        crown_v = cam.project(np.asarray(crowns_m, dtype=np.float64))[0][:, 1]
        seen = cam.in_image(px, depth)
        head_sil = np.zeros(len(centres), dtype=np.int64)
        uv = np.rint(px[seen]).astype(np.int64)
        head_sil[seen] = labels[uv[:, 1], uv[:, 0]]
        sel = np.flatnonzero(cams == m)
        inside = (head_sil[None, :] == silhouettes[sel, None]) & (silhouettes[sel, None] > 0)
        merged = inside.sum(axis=1) >= 2
        if merged.any():
            d = np.where(inside, horiz[sel], np.inf)
            nearest = d.argmin(axis=1)
            out[sel[merged]] = crown_v[nearest[merged]]
        boxes = by_cam[m].silhouettes.boxes_px
        headless = sel[(inside.sum(axis=1) == 0) & (silhouettes[sel] > 0)]
        if headless_m <= 0 or boxes is None or not len(headless):
            continue
        x0, _, width, _ = boxes[silhouettes[headless] - 1].T[..., None]  # (R, 1) each
        u, v = px[:, 0], px[:, 1]
        above = (
            seen
            & (u >= x0)
            & (u < x0 + width)
            & (v < out[headless, None])
            & (horiz[headless] <= headless_m)
        )  # (R, H)
        has = above.any(axis=1)
        nearest = np.where(above, horiz[headless], np.inf).argmin(axis=1)
        out[headless[has]] = crown_v[nearest[has]]
    return out


def blob_rows(obs: CameraObservation) -> tuple[np.ndarray, np.ndarray]:
    """(B,) row of every blob's centroid and (B,) top row of its silhouette, px (0, the
    frame's top, for a blob outside every silhouette)."""
    tops = np.concatenate([[0.0], np.asarray(obs.silhouettes.top_v_px, dtype=np.float64)])
    return obs.blobs.centroids_px[:, 1], tops[obs.blobs.silhouette]


def silhouette_prior(
    points_m: np.ndarray,
    rig: Rig,
    by_cam: dict[int, CameraObservation],
    sigma_px: float,
    drop_worst: bool = True,
    projected: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None,
) -> np.ndarray:
    """p_b (eq. 27): product over observed cameras Z projects into of a Gaussian in the
    distance (px) of Z's projection to the nearest silhouette pixel.

    With ``drop_worst`` (a deviation from the paper, for robustness) the single lowest term
    is left out wherever three or more cameras see Z: one camera whose background model
    failed (started late with people in view, a sudden light change) would otherwise veto
    every candidate in the room.

    ``projected``: ``Camera.project(points_m)`` per rig camera index of ``by_cam``, when the
    caller has it already (:func:`project_into`).
    """
    log_pb = np.zeros(len(points_m))
    worst = np.zeros(len(points_m))  # the lowest log term
    n_seen = np.zeros(len(points_m), np.int64)
    for m, obs in by_cam.items():
        cam = rig.cameras[m]
        px, depth = cam.project(points_m) if projected is None else projected[m]
        inside = cam.in_image(px, depth)
        if not inside.any():
            continue
        dist_img = obs.silhouettes.dist_outside_px
        h, w = dist_img.shape
        if obs.silhouettes.n == 0:
            # no silhouette at all: every point is far outside one
            dist = np.full(int(inside.sum()), float(max(h, w)))
        else:
            uv = np.rint(px[inside]).astype(np.intp)
            dist = dist_img[np.clip(uv[:, 1], 0, h - 1), np.clip(uv[:, 0], 0, w - 1)]
        term = -0.5 * (dist.astype(np.float64) / sigma_px) ** 2
        log_pb[inside] += term
        worst[inside] = np.minimum(worst[inside], term)
        n_seen[inside] += 1
    if drop_worst:
        robust = n_seen >= 3
        log_pb[robust] -= worst[robust]
    return np.exp(log_pb)


def project_into(
    points_m: np.ndarray, rig: Rig, cameras: Iterable[int]
) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """``Camera.project(points_m)`` for each rig camera index in ``cameras``. OpenCV projects
    each point on its own, so a subset's projections are rows of these: the candidate stage
    projects its points once for p_b and takes the merged ones' rows for their support."""
    return {m: rig.cameras[m].project(points_m) for m in cameras}


def _merge(
    points_m: np.ndarray, prior: np.ndarray, radius_m: float, boost: float
) -> tuple[np.ndarray, np.ndarray]:
    """Greedy merge, strongest first: each kept candidate absorbs the not yet absorbed ones
    within ``radius_m`` and gains ``boost`` times their priors (clipped to 1).

    Returns indices of the kept candidates (strongest first) and their boosted priors."""
    order = np.argsort(-prior, kind="stable")
    pts = points_m[order]
    pri = prior[order]
    close = np.einsum("ijk,ijk->ij", pts[:, None] - pts[None], pts[:, None] - pts[None])
    rows, cols = np.nonzero(close < radius_m * radius_m)
    # each candidate's close neighbours, ascending; the greedy loop runs on Python lists
    near = np.split(cols, np.searchsorted(rows, np.arange(1, len(pts)))) if len(pts) else []
    alive = [True] * len(pts)
    kept, kept_prior = [], []
    for i, neighbours in enumerate(near):
        if not alive[i]:
            continue
        alive[i] = False
        absorbed = [j for j in neighbours.tolist() if alive[j]]
        for j in absorbed:
            alive[j] = False
        gain = boost * pri[absorbed].sum() if absorbed else 0.0
        kept.append(i)
        kept_prior.append(min(1.0, pri[i] + gain))
    return order[np.array(kept, dtype=np.intp)], np.array(kept_prior)


def _per_blob(blob_sets: Sequence[BlobSet], field: str, default: float | bool) -> np.ndarray:
    """One optional per-blob field (``foreground_share``, ``restored``) of several blob sets,
    concatenated; ``default`` for every blob of a set that does not have it.

    >>> one = np.zeros((1, 2)), np.ones(1, np.int64), np.zeros((1, 4), np.int32)
    >>> one += np.ones(1, np.int32), np.zeros(1), np.zeros((4, 4), np.int32)
    >>> flagged = BlobSet(*one, restored=np.array([True]))
    >>> _per_blob([BlobSet(*one), flagged], "restored", False).tolist()
    [False, True]
    """
    return np.concatenate(
        [
            np.full(len(b), default) if getattr(b, field) is None else getattr(b, field)
            for b in blob_sets
        ]
    )


def view_support(
    points_m: np.ndarray,
    cam_pairs: np.ndarray | None,
    blob_pairs: np.ndarray | None,
    rig: Rig,
    by_cam: Mapping[int, CameraObservation],
    radius_px: float,
    projected: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None,
) -> np.ndarray:
    """(K, M) int: per point and rig camera, the blob whose centroid is nearest to the
    point's projection if within ``radius_px`` (-1: none, or the camera did not see it).
    A candidate's own two blobs (``cam_pairs``, ``blob_pairs``; rows of -1 for points no
    camera pair made) always support it. ``projected`` as in :func:`silhouette_prior`."""
    k = len(points_m)
    support = np.full((k, len(rig.cameras)), -1, dtype=np.int64)
    for m, obs in by_cam.items():
        if len(obs.blobs) == 0:
            continue
        px, depth = rig.cameras[m].project(points_m) if projected is None else projected[m]
        inside = rig.cameras[m].in_image(px, depth)
        dist = np.linalg.norm(px[:, None] - obs.blobs.centroids_px[None], axis=2)
        nearest = dist.argmin(axis=1)
        ok = inside & (dist[np.arange(k), nearest] <= radius_px)
        support[ok, m] = nearest[ok]
    if cam_pairs is not None and blob_pairs is not None:
        rows = np.flatnonzero(cam_pairs[:, 0] >= 0)
        for col in (0, 1):
            support[rows, cam_pairs[rows, col]] = blob_pairs[rows, col]
    return support


def refine_from_views(
    points_m: np.ndarray,
    support: np.ndarray,
    first_blob: np.ndarray,
    origins: np.ndarray,
    dirs: np.ndarray,
    min_views: int,
    outlier_m: float,
) -> np.ndarray:
    """Candidates that ``min_views`` or more cameras support, moved to the least-squares
    point of those views' lines of sight (:func:`least_squares_points`); the others as they
    are.

    A pair's midpoint uses two of the views that see a limb; calibration error and each
    blob centroid's own error then fall on those two alone. A second solve leaves out the
    lines farther than ``outlier_m`` from the first point (a supporting blob of another
    limb within ``support_radius_px``); a candidate left with fewer than two lines keeps
    its midpoint.

    Parameters
    ----------
    points_m : (K, 3) float -- the candidates, m
    support : (K, M) int -- per rig camera, the supporting blob (-1 none; :func:`view_support`)
    first_blob : (M,) int -- per rig camera, the global index of its blob 0 in ``origins``
        (-1: a camera without blobs)
    origins, dirs : (B, 3) float -- every blob's line of sight, all cameras' blobs in turn
    min_views, outlier_m : ``CandidateConfig.refine_min_views``, ``refine_outlier_m``

    Returns
    -------
    (K, 3) float64
    """
    out = np.array(points_m, dtype=np.float64)
    rows = np.flatnonzero((support >= 0).sum(axis=1) >= min_views)
    if len(rows) == 0:
        return out
    sup = support[rows]
    use = sup >= 0
    idx = np.where(use, first_blob[None, :] + sup, 0)
    o, d = origins[idx], dirs[idx]
    refined, dist = least_squares_points(o, d, use)
    far = use & (dist > outlier_m)
    again = far.any(axis=1)
    if again.any():
        refined[again] = least_squares_points(o[again], d[again], use[again] & ~far[again])[0]
    ok = np.isfinite(refined).all(axis=1)
    out[rows[ok]] = refined[ok]
    return out


def explain_away(support: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """(K,) bool: the candidates kept when each blob may explain one 3-D point.

    Candidates are visited best first (most supporting views, then highest prior). One that
    reuses a blob already claimed by a better candidate and has fewer than two unclaimed
    supporting blobs is a *ghost*: two lines of sight of different limbs that happen to
    cross (or a second, weaker copy of a kept point); the others are kept and claim their
    blobs. A limb hidden behind another in one view still has its own blobs in two others.

    Parameters
    ----------
    support : (K, M) int -- blob index per camera supporting each candidate, -1 none
        (:func:`_view_support`)
    prior : (K,) float

    Examples
    --------
    Two true points seen by three cameras, and a ghost pairing camera 0's blob 0 with
    camera 1's blob 1:

    >>> support = np.array([[0, 0, 0], [1, 1, 1], [0, 1, -1]])
    >>> explain_away(support, np.array([0.9, 0.8, 0.95])).tolist()
    [True, True, False]
    """
    n_views = (support >= 0).sum(axis=1)
    order = np.lexsort((-prior, -n_views))
    claimed: set[tuple[int, int]] = set()
    keep = np.zeros(len(prior), dtype=bool)
    rows = support.tolist()  # Python ints: the loop reads every row, cell by cell
    for k in order.tolist():
        views = [(m, b) for m, b in enumerate(rows[k]) if b >= 0]
        fresh = [v for v in views if v not in claimed]
        if len(fresh) < 2 and len(fresh) < len(views):
            continue
        keep[k] = True
        claimed.update(views)
    return keep


def rescue_expected(
    points_m: np.ndarray,
    prior: np.ndarray,
    keep: np.ndarray,
    expected_m: np.ndarray,
    radius_m: float,
    pair_radius_m: float = np.inf,
    alone: np.ndarray | None = None,
    alone_radius_m: float | None = None,
) -> np.ndarray:
    """(K,) bool: ``keep`` plus, for every expected position that explaining away left with
    no candidate within ``radius_m`` and that has another expected position within
    ``pair_radius_m`` (or is marked in ``alone``), the strongest still-dropped candidate
    within ``radius_m`` of it (two targets expected side by side each get their own).

    Explaining away lets each blob explain one point, but two hands whose blobs merged in all
    views but one are two points sharing blobs: the second hand's candidate is dropped as a
    ghost although a tracker expects a hand right there. Rescuing only next to an expected
    position that would otherwise go without a candidate keeps the ghosts out elsewhere, and
    only where two targets are close enough for their blobs to merge: a lone tracker left on
    a ghost would otherwise rescue that ghost in every frame set and never be lost (demo:
    a hand tracker stayed 2.5 s, until the end, where the clap had been).

    Parameters
    ----------
    points_m : (K, 3) float
    prior : (K,) float
    keep : (K,) bool -- :func:`explain_away`'s verdict
    expected_m : (E, 3) float -- where tracked targets are expected in this frame set, m
    radius_m : float
    pair_radius_m : float -- only expected positions this close to another are helped
        (inf: all)
    alone : (E,) bool or None -- expected positions helped without a neighbour (the
        tracker's hands that had a candidate of their own in the previous frame set)
    alone_radius_m : float or None -- the radius for those helped only because of
        ``alone`` (None: ``radius_m``)

    Examples
    --------
    >>> pts = np.array([[0.0, 0, 1], [0.25, 0, 1], [0.3, 0, 1]])
    >>> keep = np.array([True, False, False])
    >>> rescue_expected(pts, np.array([0.9, 0.5, 0.7]), keep, np.array([[0.28, 0, 1]]),
    ...                 0.1).tolist()
    [True, False, True]
    """
    keep = keep.copy()
    if len(expected_m) == 0 or len(points_m) == 0 or radius_m <= 0:
        return keep
    dist = np.linalg.norm(points_m[:, None] - expected_m[None], axis=2)  # (K, E)
    apart = np.linalg.norm(expected_m[:, None] - expected_m[None], axis=2)
    np.fill_diagonal(apart, np.inf)
    paired = (apart.min(axis=1) < pair_radius_m) | np.isinf(pair_radius_m)
    radius = np.full(len(expected_m), radius_m)
    if alone is not None:
        only_alone = alone & ~paired
        if alone_radius_m is not None:
            radius[only_alone] = alone_radius_m
        paired |= alone
    near = dist < radius
    for e in np.flatnonzero(~(near & keep[:, None]).any(axis=0) & paired):
        dropped = np.flatnonzero(near[:, e] & ~keep)
        if len(dropped):
            keep[dropped[np.argmax(prior[dropped])]] = True
    return keep


def make_candidates(
    observations: Sequence[CameraObservation],
    rig: Rig,
    cfg: CandidateConfig,
    *,
    expected_m: np.ndarray | None = None,
    crowns_m: np.ndarray | None = None,
    expected_alone: np.ndarray | None = None,
) -> CandidateSet:
    """3-D candidate points of one frame set with their priors p(Z): the skin blobs' pairs
    (paper 004) and, with ``cfg.crowns.enabled``, the silhouettes' crowns where a head has no
    skin candidate (:func:`surveil.recon.crowns.crown_heads`; their ``cam_pairs`` and
    ``blob_pairs`` rows are -1, strongest-first order is kept within each kind).

    Parameters
    ----------
    observations : sequence of CameraObservation
        One per camera with a frame in this set (at most one per camera); cameras of the rig
        with no observation take no part (neither in pairs nor in p_b).
    rig : Rig
        The calibrated cameras; every ``observation.camera`` must be one of them.
    cfg : CandidateConfig
        Widths, thresholds and merging.
    expected_m : (E, 3) float or None
        Where tracked targets are predicted to be in this frame set, m (the tracker's
        feedback): explaining away spares the strongest candidate near each of them that
        would otherwise have none (:func:`rescue_expected`, ``cfg.expected_radius_m``), and
        a candidate within ``cfg.expected_gate_m`` of one needs only
        ``cfg.expected_prior_threshold`` on its product.
    expected_alone : (E,) bool or None
        Which of ``expected_m`` may be spared a candidate with no other target expected
        beside them (``rescue_expected``'s ``alone``; None: none).
    crowns_m : (H, 3) float or None
        The tracked heads' crowns (tops), m (the tracker's feedback): with
        ``cfg.tops_from_heads``, the top of a silhouette holding two or more of them is, for
        p_o, the crown of the one nearest to Z (:func:`merged_tops`).

    Returns
    -------
    CandidateSet
        ``points_m (K, 3)``, ``prior (K,)`` in (0, 1], ``half_gap_m (K,)``, ``cam_pairs (K, 2)``
        (rig camera indices, m < m'), ``blob_pairs (K, 2)`` (blob indices in those cameras),
        strongest first. Empty (``(0, 3)``) when fewer than two cameras see blobs.

    Raises
    ------
    ValueError
        If an observation names a camera missing from the rig, or a camera twice.

    Notes
    -----
    A candidate survives if it lies in front of both cameras, at ``z >= cfg.min_z_m``, has
    ``d <= cfg.max_gap_m``, each of p_o (eq. 25), p_t (eq. 26), p_b (eq. 27) reaches
    ``cfg.term_threshold`` and their product (eq. 19) reaches ``cfg.prior_threshold``
    (``cfg.expected_prior_threshold`` next to an expected position).
    p_o assumes that higher points have smaller v in every camera (cameras high up, looking
    down). Survivors closer than ``cfg.merge_radius_m`` are merged, strongest first.

    References
    ----------
    Paper 004, section 5.1 (eq. 18-19), section 6.3 (eq. 22-24), section 6.4 (eq. 25-27).
    """
    index = {name: m for m, name in enumerate(rig.names)}
    by_cam: dict[int, CameraObservation] = {}
    for i, obs in enumerate(observations):
        if obs.camera not in index:
            raise ValueError(
                f"observations[{i}].camera {obs.camera!r} is not in the rig "
                f"(cameras: {', '.join(rig.names)})"
            )
        m = index[obs.camera]
        if m in by_cam:
            raise ValueError(f"observations[{i}]: camera {obs.camera!r} appears twice")
        by_cam[m] = obs
    skin = _skin_candidates(by_cam, rig, cfg, expected_m, crowns_m, expected_alone)
    if not cfg.crowns.enabled:
        return skin
    return with_crowns(skin, by_cam, rig, cfg.crowns)


def with_crowns(
    skin: CandidateSet, by_cam: Mapping[int, CameraObservation], rig: Rig, cfg: CrownConfig
) -> CandidateSet:
    """``skin`` and after it the crowns' heads (:func:`crown_heads`) farther than
    ``cfg.skin_clear_m`` from every skin candidate, with prior ``cfg.prior`` and marked
    ``head_only`` (the skin candidates are not). Each view's
    crowns are its observation's (``crowns_px``), or found here when it has none."""
    crowns = {
        m: silhouette_crowns(o.silhouettes, rig.cameras[m], cfg)
        if o.crowns_px is None
        else o.crowns_px
        for m, o in by_cam.items()
    }
    points, half_gap, _ = crown_heads(
        {m: o.silhouettes for m, o in by_cam.items()}, crowns, rig, cfg
    )
    if len(skin.points_m) and len(points):
        d = np.linalg.norm(points[:, None] - skin.points_m[None], axis=2).min(axis=1)
        points, half_gap = points[d > cfg.skin_clear_m], half_gap[d > cfg.skin_clear_m]
    if len(points) == 0:
        return skin
    n, k = len(skin.points_m), len(points)

    def column(values: np.ndarray | None, missing: float | bool, crowns: np.ndarray) -> np.ndarray:
        base = np.full((n, *crowns.shape[1:]), missing, crowns.dtype) if values is None else values
        return np.concatenate([base, crowns])

    return CandidateSet(
        np.concatenate([skin.points_m, points]),
        np.concatenate([skin.prior, np.full(k, cfg.prior)]),
        half_gap_m=column(skin.half_gap_m, np.nan, half_gap),
        cam_pairs=column(skin.cam_pairs, -1, np.full((k, 2), -1, np.int64)),
        blob_pairs=column(skin.blob_pairs, -1, np.full((k, 2), -1, np.int64)),
        rescued=column(skin.rescued, False, np.zeros(k, bool)),
        head_only=column(skin.head_only, False, np.ones(k, bool)),
        # a crown head is where two views' crowns meet
        views=None if skin.views is None else column(skin.views, 0, np.full(k, 2, np.int64)),
    )


def _skin_candidates(
    by_cam: dict[int, CameraObservation],
    rig: Rig,
    cfg: CandidateConfig,
    expected_m: np.ndarray | None,
    crowns_m: np.ndarray | None,
    expected_alone: np.ndarray | None = None,
) -> CandidateSet:
    """:func:`make_candidates`' blob pairs (paper 004)."""
    # one back-projection per camera for all its blobs
    seen = sorted(m for m, obs in by_cam.items() if len(obs.blobs) > 0)
    if len(seen) < 2:
        return _empty()
    origins, dirs, rel_v, rows, cam_of, blob_of = [], [], [], [], [], []
    for m in seen:
        blobs = by_cam[m].blobs
        origin, d = rig.cameras[m].backproject(blobs.centroids_px)
        n = len(blobs)
        origins.append(np.broadcast_to(origin, (n, 3)))
        dirs.append(d)
        rel_v.append(blobs.rel_v)
        rows.append(np.column_stack(blob_rows(by_cam[m])))
        cam_of.append(np.full(n, m, dtype=np.int64))
        blob_of.append(np.arange(n, dtype=np.int64))
    origins_all = np.concatenate(origins)
    dirs_all = np.concatenate(dirs)
    rel_v_all = np.concatenate(rel_v)
    rows_all = np.concatenate(rows)
    cam_all = np.concatenate(cam_of)
    blob_all = np.concatenate(blob_of)
    starts = np.cumsum([0] + [len(d) for d in dirs])

    # eq. 18: every blob pair of every camera pair m < m' (global blob indices ia, ib)
    ia_parts, ib_parts = [], []
    for a in range(len(seen)):
        for b in range(a + 1, len(seen)):
            ga = np.arange(starts[a], starts[a + 1])
            gb = np.arange(starts[b], starts[b + 1])
            ia_parts.append(np.repeat(ga, len(gb)))
            ib_parts.append(np.tile(gb, len(ga)))
    ia = np.concatenate(ia_parts)
    ib = np.concatenate(ib_parts)

    # eq. 22-24
    o1, d1, o2, d2 = origins_all[ia], dirs_all[ia], origins_all[ib], dirs_all[ib]
    points, half_gap = closest_points(o1, d1, o2, d2)
    # in front of both cameras: the midpoint's position along each (unit) line of sight
    with np.errstate(invalid="ignore"):
        ahead1 = np.einsum("ij,ij->i", points - o1, d1) > 0
        ahead2 = np.einsum("ij,ij->i", points - o2, d2) > 0
        geometric = ahead1 & ahead2 & (half_gap <= cfg.max_gap_m) & (points[:, 2] >= cfg.min_z_m)
    # eq. 26 (reconstruction error), then eq. 25 (relative v consistency) on its survivors:
    # the floor rows of D_v take a projection per candidate
    p_t = gauss_term(half_gap, cfg.sigma_gap_m)
    # p_o and p_b are at most 1: a pair whose p_t misses the prior threshold is lost already
    keep = geometric & (p_t >= max(cfg.term_threshold, cfg.prior_threshold))
    if cfg.min_pair_foreground_share > 0:
        # two lines of sight through skin-coloured scenery (a wooden table's edge that the
        # silhouettes took in, seen from two sides) cross somewhere near the person; a real
        # limb is foreground in at least one of the two views. A blob whose share was not
        # measured counts as foreground.
        share_all = _per_blob([by_cam[m].blobs for m in seen], "foreground_share", 1.0)
        keep &= np.maximum(share_all[ia], share_all[ib]) >= cfg.min_pair_foreground_share
    if any(by_cam[m].blobs.restored is not None for m in seen):
        # a blob the opening would have erased (BlobConfig.open_keeps_isolated) is a hand
        # seen edge-on or a fringe of colour along a fold: it may pair with a plain blob of
        # another view, but two of them are too often two fringes
        restored_all = _per_blob([by_cam[m].blobs for m in seen], "restored", False)
        keep &= ~(restored_all[ia] & restored_all[ib])
    ia, ib, points, half_gap, p_t = ia[keep], ib[keep], points[keep], half_gap[keep], p_t[keep]
    if cfg.rel_v_to_floor:
        # both blobs' rows at once: one floor projection per camera
        both = np.concatenate([ia, ib])
        twice = np.concatenate([points, points])
        v_px, top_px = rows_all[both].T
        if (
            cfg.tops_from_heads
            and crowns_m is not None
            and (len(crowns_m) >= 2 or (cfg.headless_top_m > 0 and len(crowns_m)))
        ):
            sil_all = np.concatenate([by_cam[m].blobs.silhouette for m in seen])
            top_px = merged_tops(
                twice,
                cam_all[both],
                sil_all[both],
                top_px,
                crowns_m,
                rig,
                by_cam,
                headless_m=cfg.headless_top_m,
            )
        d_v = np.split(floor_relative_v(twice, cam_all[both], v_px, top_px, rig), 2)
    else:
        d_v = [rel_v_all[ia], rel_v_all[ib]]
    p_o = gauss_term(d_v[0] - d_v[1], cfg.sigma_rel_v)
    threshold = np.full(len(points), cfg.prior_threshold)
    if (
        expected_m is not None
        and len(expected_m)
        and cfg.expected_prior_threshold < cfg.prior_threshold
    ):
        near = np.linalg.norm(points[:, None] - expected_m[None], axis=2).min(axis=1)
        threshold[near <= cfg.expected_gate_m] = cfg.expected_prior_threshold
    keep = (p_o >= cfg.term_threshold) & (p_o * p_t >= threshold)
    if not keep.any():
        return _empty()
    ia, ib, points, half_gap = ia[keep], ib[keep], points[keep], half_gap[keep]
    p_o, p_t, threshold = p_o[keep], p_t[keep], threshold[keep]
    # eq. 27 (silhouette consistency) on the survivors only
    projected = project_into(points, rig, by_cam)
    p_b = silhouette_prior(
        points, rig, by_cam, cfg.sigma_silhouette_px, cfg.silhouette_drop_worst, projected
    )
    prior = p_o * p_t * p_b  # eq. 19
    ok = (p_b >= cfg.term_threshold) & (prior >= threshold)
    ia, ib, points, half_gap, prior = ia[ok], ib[ok], points[ok], half_gap[ok], prior[ok]
    if len(points) == 0:
        return _empty()

    kept, prior = _merge(points, prior, cfg.merge_radius_m, cfg.merge_boost)
    n_merged = len(kept)
    ia, ib = ia[kept], ib[kept]
    points, half_gap = points[kept], half_gap[kept]
    cam_pairs = np.column_stack([cam_all[ia], cam_all[ib]])
    blob_pairs = np.column_stack([blob_all[ia], blob_all[ib]])
    rescued = views = None
    if cfg.explain_away:
        merged = np.flatnonzero(ok)[kept]
        support = view_support(
            points,
            cam_pairs,
            blob_pairs,
            rig,
            by_cam,
            cfg.support_radius_px,
            {m: (px[merged], depth[merged]) for m, (px, depth) in projected.items()},
        )
        real = explain_away(support, prior)
        explained = real
        if expected_m is not None:
            real = rescue_expected(
                points,
                prior,
                real,
                expected_m,
                cfg.expected_radius_m,
                cfg.rescue_pair_m,
                expected_alone,
                cfg.rescue_alone_radius_m,
            )
        rescued = (real & ~explained)[real]
        views = (support[real] >= 0).sum(axis=1)
        points, prior, half_gap = points[real], prior[real], half_gap[real]
        if cfg.refine_min_views >= 2:
            first_blob = np.full(len(rig.cameras), -1, dtype=np.int64)
            first_blob[seen] = starts[:-1]
            points = refine_from_views(
                points,
                support[real],
                first_blob,
                origins_all,
                dirs_all,
                cfg.refine_min_views,
                cfg.refine_outlier_m,
            )
        cam_pairs, blob_pairs = cam_pairs[real], blob_pairs[real]
    log.debug(
        "candidates: %d pairs, %d pass the prior, %d after merging, %d after explaining away",
        len(keep),
        int(ok.sum()),
        n_merged,
        len(points),
    )
    return CandidateSet(
        points,
        prior,
        half_gap_m=half_gap,
        cam_pairs=cam_pairs,
        blob_pairs=blob_pairs,
        rescued=rescued,
        head_only=np.zeros(len(points), dtype=bool),
        views=views,
    )
