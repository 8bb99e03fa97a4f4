"""A hand's reported point pulled onto the blobs that show it (not in the paper).

The particle filter's estimate of a hand lags a moving hand (the motion model smooths) and
coasts where fewer than two cameras see it, because the filter only weighs 3-D candidates,
and a candidate needs two views. Every view in which a blob lies at the hand's projection
still says where the hand is, up to its depth along that view's line of sight. This module
combines the two: the tracker's estimate as a Gaussian prior (its particles' covariance,
floored), and each such blob as a Gaussian in the distance of the point from the blob's line
of sight (``sigma_px`` at the point's depth). Both terms are quadratic in the point, so the
most probable point is one 3 x 3 linear solve per hand.

Only the reported point changes; the filter's particles do not (measured in session 25: a
filter weighted by one view's line of sight drifts in depth and misleads the tracker's
decisions). Pure functions; :class:`surveil.pipeline.Pipeline` applies
:func:`pull_hands_onto_blobs` to the tracker's output.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np
from scipy.spatial.distance import cdist

from surveil.camera import Rig
from surveil.datatypes import CameraObservation, Limb, Phase, TargetSnapshot


def blob_evidence(
    points_m: np.ndarray,
    pulled: np.ndarray,
    observations: Mapping[str, CameraObservation],
    rig: Rig,
    sigma_px: float,
    gate_px: float,
    hand_end_sigma_px: tuple[float, float] | None = None,
    ends_only: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lines of sight of the blobs at each pulled point's projection, as quadratic terms.

    A view contributes to point i when the blob centroid nearest i's projection lies within
    ``gate_px`` of it and i's projection is, of all ``points_m``, the nearest to that blob
    (mutual nearest: a blob between two targets, a hand at the face, serves neither). The
    line of sight goes through the blob's centroid, or, given ``hand_end_sigma_px``, through
    its ``BlobSet.hand_px`` where the blob stage kept them: a bare forearm is matched by its
    centroid, which the tracker follows, and its hand end's line pulls towards the hand.

    Parameters
    ----------
    points_m : (A, 3) float -- every active target's point (heads too: they claim their blobs)
    pulled : (A,) bool -- the points to collect evidence for
    sigma_px : the blob centroid's error in pixels; at depth z it is sigma_px * z / f metres
    hand_end_sigma_px : (agreed, lone) -- the error of a hand end away from its blob's
        centroid, pixels, where two or more of the point's views have one (their lines meet
        at the hand) and where only one has (a blob taken for a forearm by mistake, two
        hands joined, would pull the point far across its line); None: every line goes
        through the centroid
    ends_only : (A,) bool, optional -- points that take evidence only when a hand end is
        among their views (an unlabelled tracker: a bare forearm says it is at a hand)

    Returns
    -------
    info : (A, 3, 3) -- sum over views of (I - d d^T) / sigma^2, m^-2
    rhs : (A, 3) -- sum over views of (I - d d^T) o / sigma^2 (o the camera centre)
    n_views : (A,) int -- views that contributed
    """
    n = len(points_m)
    info = np.zeros((n, 3, 3))
    rhs = np.zeros((n, 3))
    n_views = np.zeros(n, np.int64)
    if n == 0 or not pulled.any():
        return info, rhs, n_views
    lines = []  # per view: (camera, points, pixels the lines go through, depths, hand end?)
    n_ends = np.zeros(n, np.int64)
    for cam in rig:
        obs = observations.get(cam.name)
        if obs is None or len(obs.blobs) == 0:
            continue
        px, depth = cam.project(points_m)
        seen = cam.in_image(px, depth)
        if not (seen & pulled).any():
            continue
        d = cdist(px, obs.blobs.centroids_px)
        d[~seen] = np.inf
        best = d.argmin(axis=1)
        owner = d.argmin(axis=0)
        rows = np.arange(n)
        ok = pulled & seen & (d[rows, best] <= gate_px) & (owner[best] == rows)
        if not ok.any():
            continue
        idx = np.flatnonzero(ok)
        through = obs.blobs.centroids_px[best[idx]]
        moved = np.zeros(len(idx), bool)
        if hand_end_sigma_px is not None and obs.blobs.hand_px is not None:
            ends = obs.blobs.hand_px[best[idx]]
            moved = (ends != through).any(axis=1)
            through = np.where(moved[:, None], ends, through)
            n_ends[idx[moved]] += 1
        lines.append((cam, idx, through, depth[idx], moved))
    for cam, idx, through, depth_m, moved in lines:
        if ends_only is not None:
            keep = ~ends_only[idx] | (n_ends[idx] > 0)
            idx, through, depth_m, moved = idx[keep], through[keep], depth_m[keep], moved[keep]
            if not len(idx):
                continue
        sigma = np.full(len(idx), float(sigma_px))
        if hand_end_sigma_px is not None:
            agreed, lone = hand_end_sigma_px
            sigma[moved] = np.where(n_ends[idx[moved]] >= 2, agreed, lone)
        origin, dirs = cam.backproject(through)
        sigma_m = sigma * depth_m / cam.K[0, 0]
        proj = np.eye(3)[None] - dirs[:, :, None] * dirs[:, None, :]
        w = 1.0 / sigma_m**2
        info[idx] += proj * w[:, None, None]
        rhs[idx] += (proj @ origin) * w[:, None]
        n_views[idx] += 1
    return info, rhs, n_views


def pull_hands_onto_blobs(
    targets: tuple[TargetSnapshot, ...],
    observations: Mapping[str, CameraObservation],
    rig: Rig,
    sigma_px: float,
    gate_px: float,
    prior_floor_m: float,
    hand_end_sigma_px: tuple[float, float] | None = None,
) -> tuple[TargetSnapshot, ...]:
    """``targets`` with each labelled hand in the normal phase moved to the most probable
    point given its estimate (prior: ``cov_m2`` + ``prior_floor_m``^2 I) and the blobs at its
    projection (:func:`blob_evidence`). Given ``hand_end_sigma_px``, (agreed, lone) pixels, a
    bare forearm's line goes through its hand end, and an unlabelled tracker that is not a
    head is pulled too where one of its views is such a forearm (its labels are pending, the
    hand end says where a hand is). Other targets, and hands no blob shows, unchanged."""
    active = [i for i, t in enumerate(targets) if t.phase is not Phase.LOST]
    if not active:
        return targets
    pts = np.array([targets[i].mean_m for i in active])
    hands = np.array(
        [targets[i].limb.is_hand and targets[i].phase is Phase.NORMAL for i in active]
    )
    unlabelled = np.array(
        [
            hand_end_sigma_px is not None
            and targets[i].phase is Phase.UNLABELLED
            and targets[i].limb is not Limb.HEAD
            for i in active
        ]
    )
    info, rhs, n_views = blob_evidence(
        pts,
        hands | unlabelled,
        observations,
        rig,
        sigma_px,
        gate_px,
        hand_end_sigma_px,
        unlabelled,
    )
    out = list(targets)
    for k in np.flatnonzero(n_views):
        t = targets[active[k]]
        point = most_probable_point(t, prior_floor_m, info[k], rhs[k])
        out[active[k]] = dataclasses.replace(t, mean_m=point)
    return tuple(out)


def most_probable_point(
    target: TargetSnapshot, prior_floor_m: float, info: np.ndarray, rhs: np.ndarray
) -> np.ndarray:
    """(3,) the point maximising the target's Gaussian (``mean_m``, ``cov_m2`` +
    ``prior_floor_m``^2 I) times the blob terms ``info`` (3, 3) and ``rhs`` (3,) of
    :func:`blob_evidence`: one 3 x 3 solve."""
    prec = np.linalg.inv(target.cov_m2 + prior_floor_m**2 * np.eye(3))
    return np.linalg.solve(prec + info, prec @ target.mean_m + rhs)


def one_view_hand_points(
    predicted: tuple[TargetSnapshot, ...],
    candidates_m: np.ndarray,
    observations: Mapping[str, CameraObservation],
    rig: Rig,
    sigma_px: float,
    gate_px: float,
    prior_floor_m: float,
    explained_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Points for labelled hands that no candidate explains but a blob still shows.

    A hand seen by one camera has no candidate (a candidate needs two views), so its
    tracker coasts and is lost ``lost_frames`` later, although that view says where it is
    across its line of sight (three_people: p3's left hand at the box, one view for 0.6 s).
    For each labelled hand in the normal phase, predicted to this frame set, with no
    candidate within ``explained_m``: the most probable point given its prediction and the
    blobs at its projection (as :func:`pull_hands_onto_blobs`; mutual nearest among every
    active target, heads too).

    Returns
    -------
    points_m : (E, 3) -- one per such hand that a blob shows
    n_views : (E,) int -- views whose blob contributed
    """
    active = [t for t in predicted if t.phase is not Phase.LOST]
    if not active:
        return np.zeros((0, 3)), np.zeros(0, np.int64)
    pts = np.array([t.mean_m for t in active])
    wanted = np.array([t.limb.is_hand and t.phase is Phase.NORMAL for t in active])
    if len(candidates_m) and wanted.any():
        wanted &= cdist(pts, candidates_m).min(axis=1) > explained_m
    info, rhs, n_views = blob_evidence(pts, wanted, observations, rig, sigma_px, gate_px)
    seen = np.flatnonzero(n_views)
    out = [most_probable_point(active[k], prior_floor_m, info[k], rhs[k]) for k in seen]
    return np.array(out).reshape(-1, 3), n_views[seen].astype(np.int64)
