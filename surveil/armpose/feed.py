"""The arm model's hands as 3D candidates for the 3D tracker (not in the papers).

Paper 004's candidates need a hand in two views. A hand seen by one camera only (hidden from
the others by the body or by what it holds) has none, and its tracker is lost, although the
arm model of that person still places it on its blob in the one view that sees it
(docs/armpose.md, "Feeding the 3D tracker"). Such hands join the frame set's candidates with
a fixed prior, so that the tracker, its state machine, the carry stage and the activity
rules treat them like any other hand.

An arm hand is added only where it explains what the candidates do not: a blob that no
candidate projects onto. An arm that settled on another hand's blobs (both arms of a person
can explain the same blob) adds nothing, and neither does a hand that two views already
triangulate.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from surveil.armpose.settings import ArmPoseConfig
from surveil.camera import Rig
from surveil.datatypes import ArmPose, CameraObservation, CandidateSet
from surveil.recon.candidates import view_support


def arm_hand_points(
    candidates: CandidateSet,
    poses: Sequence[ArmPose],
    observations: Mapping[str, CameraObservation],
    rig: Rig,
    cfg: ArmPoseConfig,
    support_radius_px: float,
) -> np.ndarray:
    """(H, 3) the hands of ``poses`` to add as candidates, m.

    A hand qualifies when, in at least ``cfg.feed_min_views`` cameras, its projection is
    within ``support_radius_px`` of a blob that no candidate's projection is (the candidate
    stage's own radius for explaining away), and no candidate lies within
    ``cfg.feed_radius_m`` of it. Hands are visited in order (persons as given, left before
    right); a blob taken by one hand does not qualify another.
    """
    if not poses:
        return np.zeros((0, 3))
    index = {name: m for m, name in enumerate(rig.names)}
    by_cam = {index[name]: obs for name, obs in observations.items()}
    hands = np.concatenate([p.hands_m for p in poses])
    cand = view_support(
        candidates.points_m,
        candidates.cam_pairs,
        candidates.blob_pairs,
        rig,
        by_cam,
        support_radius_px,
    )
    taken = {(m, int(b)) for m, col in enumerate(cand.T) for b in col if b >= 0}
    own = view_support(hands, None, None, rig, by_cam, support_radius_px)
    near = np.zeros(len(hands), dtype=bool)
    if len(candidates.points_m):
        d = np.linalg.norm(hands[:, None] - candidates.points_m[None], axis=2)
        near = d.min(axis=1) <= cfg.feed_radius_m
    keep = []
    for h in np.flatnonzero(~near):
        fresh = {(m, int(b)) for m, b in enumerate(own[h]) if b >= 0} - taken
        if len(fresh) >= cfg.feed_min_views:
            keep.append(h)
            taken |= fresh
    return hands[keep]


def with_arm_hands(
    candidates: CandidateSet,
    poses: Sequence[ArmPose],
    observations: Mapping[str, CameraObservation],
    rig: Rig,
    cfg: ArmPoseConfig,
    support_radius_px: float,
) -> CandidateSet:
    """``candidates`` followed by :func:`arm_hand_points` with prior ``cfg.feed_prior``;
    their ``cam_pairs`` and ``blob_pairs`` rows are -1, ``half_gap_m`` NaN (no camera
    pair made them), ``rescued`` and ``head_only`` false, ``views`` 1."""
    extra = arm_hand_points(candidates, poses, observations, rig, cfg, support_radius_px)
    return candidates.with_points(extra, cfg.feed_prior, np.ones(len(extra), np.int64))
