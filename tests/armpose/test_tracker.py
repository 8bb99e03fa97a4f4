"""Arm trackers on constructed views: a rendered body with known facing and arm angles."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from surveil.armpose import ArmPoseConfig, ArmTracker
from surveil.armpose.model import ArmShape, arm_joints_m, shoulders_m
from surveil.armpose.tracker import facing_transition, resample_blocks
from surveil.datatypes import (
    BlobSet,
    CameraObservation,
    Limb,
    Phase,
    Silhouettes,
    TargetSnapshot,
)
from surveil.rigs import lab4_rig

RIG = lab4_rig()
HEAD = np.array([3.2, 2.6, 1.60])
PHI = np.deg2rad(-150.0)  # facing cam0, at the room's (0, 0) corner
ANGLES = np.deg2rad(np.array([[45.0, 25.0, 10.0, 70.0], [5.0, 10.0, 0.0, 20.0]]))
SHAPE = ArmShape.from_head_height(HEAD[2])
NS = 1_000_000_000 // 15


def true_pose():
    sh = shoulders_m(HEAD, np.float64(PHI), SHAPE)
    elbow, hand = arm_joints_m(sh, ANGLES, np.full(2, PHI), np.array([1.0, -1.0]), SHAPE)
    return sh, elbow, hand


def body_points(rng):
    """3D points filling the head, the torso and both arms."""
    sh, elbow, hand = true_pose()
    fwd = np.array([np.cos(PHI), np.sin(PHI), 0.0])
    left = np.array([-np.sin(PHI), np.cos(PHI), 0.0])
    u = rng.uniform(-1, 1, (4000, 3))
    centre = sh.mean(axis=0) - np.array([0, 0, 0.35]) + 0.02 * fwd
    torso = centre + u[:, :1] * 0.2 * left + u[:, 1:2] * 0.11 * fwd + u[:, 2:] * [0, 0, 0.45]
    legs = centre - [0, 0, 0.8] + u[:, :1] * 0.15 * left + u[:, 2:] * [0, 0, 0.4]
    head = HEAD + rng.normal(0, 0.06, (1000, 3))
    arms = []
    for a, b in ((sh, elbow), (elbow, hand)):
        t = rng.random((1500, 1, 1))
        arms.append((a + t * (b - a) + rng.normal(0, 0.025, (1500, 2, 3))).reshape(-1, 3))
    return np.concatenate([torso, legs, head, *arms])


def observe(cams, rng):
    """CameraObservations of the constructed body in ``cams``."""
    pts = body_points(rng)
    _, _, hand = true_pose()
    out = {}
    for name in cams:
        cam = RIG[name]
        px, depth = cam.project(pts)
        keep = cam.in_image(px, depth)
        mask = np.zeros((cam.height, cam.width), np.uint8)
        uv = np.rint(px[keep]).astype(int)
        mask[uv[:, 1], uv[:, 0]] = 1
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((7, 7), np.uint8))
        dist = cv2.distanceTransform((mask == 0).astype(np.uint8), cv2.DIST_L2, 3)
        rows = np.flatnonzero(mask.any(axis=1))
        sil = Silhouettes(
            mask.astype(np.int32),
            np.array([float(rows[0])]),
            np.array([float(rows[-1])]),
            dist.astype(np.float32),
        )
        blob_px = np.vstack([cam.project(hand)[0], cam.project(HEAD[None])[0]])
        n = len(blob_px)
        blobs = BlobSet(
            blob_px,
            np.full(n, 40, np.int64),
            np.zeros((n, 4), np.int32),
            np.ones(n, np.int32),
            np.zeros(n),
            np.zeros_like(sil.labels),
        )
        out[name] = CameraObservation(name, sil, np.zeros(mask.shape, bool), blobs)
    return out


def head_target(phase=Phase.NORMAL):
    return TargetSnapshot(1, 1, Limb.HEAD, phase, HEAD)


def run(tracker, observations, steps=40, extra=()):
    poses = ()
    for k in range(steps):
        poses = tracker.step(k * NS, (head_target(), *extra), observations)
    return poses


def hand_targets(hand, phase=Phase.NORMAL):
    return (
        TargetSnapshot(2, 1, Limb.LEFT_HAND, phase, hand[0]),
        TargetSnapshot(3, 1, Limb.RIGHT_HAND, phase, hand[1]),
    )


@pytest.mark.parametrize("cams", [("cam0", "cam1"), ("cam1", "cam3"), ("cam0",)])
def test_arms_carry_on_in_the_views_left_when_the_3d_hands_are_lost(cams, rng):
    """Tracked hands first (as while two views see them), then only the views ``cams``
    and no 3D hand: the arms keep the hands and elbows. (A single view from behind, cam2,
    is not asserted: there the hands are often lost; docs/armpose.md.)"""
    _, elbow, hand = true_pose()
    obs = observe(cams, rng)
    tracker = ArmTracker(ArmPoseConfig(enabled=True), RIG, seed=3)
    run(tracker, obs, steps=15, extra=hand_targets(hand))
    poses = [
        tracker.step((15 + k) * NS, (head_target(), *hand_targets(hand, Phase.LOST)), obs)[0]
        for k in range(20)
    ]
    hand_err = np.array([np.linalg.norm(p.hands_m - hand, axis=1) for p in poses])
    elbow_err = np.array([np.linalg.norm(p.elbows_m - elbow, axis=1) for p in poses])
    assert poses[-1].n_views == len(cams)
    # one view leaves depth along its line of sight to the arm's length and the foreground
    # (one view's median over tracker seeds 0-7: 0.09-0.17 m, and 0.46 m once)
    assert np.median(hand_err) < (0.06 if len(cams) == 2 else 0.15), hand_err.round(2)
    assert np.median(elbow_err) < (0.10 if len(cams) == 2 else 0.15), elbow_err.round(2)
    cam = RIG[cams[0]]
    px_err = np.linalg.norm(cam.project(poses[-1].hands_m)[0] - cam.project(hand)[0], axis=1)
    assert px_err.max() < 8.0, px_err


def test_a_tracked_hand_pulls_its_arm_without_any_view(rng):
    _, _, hand = true_pose()
    left = TargetSnapshot(2, 1, Limb.LEFT_HAND, Phase.NORMAL, hand[0])
    right = TargetSnapshot(3, 1, Limb.RIGHT_HAND, Phase.NORMAL, hand[1])
    (pose,) = run(ArmTracker(ArmPoseConfig(enabled=True), RIG, seed=1), {}, extra=(left, right))
    assert np.linalg.norm(pose.hands_m - hand, axis=1).max() < 0.05
    assert pose.n_views == 0


def test_arms_take_the_tracked_hands_by_side_not_by_label(rng):
    """The 3D tracker calls the left hand right and the right hand left (its facing cues
    failed): each arm still takes the hand on its own side of the body."""
    _, _, hand = true_pose()
    swapped = (
        TargetSnapshot(2, 1, Limb.LEFT_HAND, Phase.NORMAL, hand[1]),
        TargetSnapshot(3, 1, Limb.RIGHT_HAND, Phase.NORMAL, hand[0]),
    )
    tracker = ArmTracker(ArmPoseConfig(enabled=True), RIG, seed=2)
    (pose,) = run(tracker, observe(("cam0", "cam1"), rng), steps=20, extra=swapped)
    assert np.linalg.norm(pose.hands_m - hand, axis=1).max() < 0.06


def test_a_lost_hand_does_not_pull(rng):
    _, _, hand = true_pose()
    far = hand[0] + np.array([0.0, 0.0, 0.5])  # out of reach anyway: the lost one is ignored
    lost = TargetSnapshot(2, 1, Limb.LEFT_HAND, Phase.LOST, far)
    (pose,) = run(ArmTracker(ArmPoseConfig(enabled=True), RIG, seed=1), {}, extra=(lost,))
    assert np.linalg.norm(pose.hands_m[0] - far) > 0.3


def test_same_seed_same_poses_and_people_retire(rng):
    obs = observe(("cam0", "cam2"), rng)
    cfg = ArmPoseConfig(enabled=True, retire_after_s=0.5)
    a, b = ArmTracker(cfg, RIG, seed=7), ArmTracker(cfg, RIG, seed=7)
    pa, pb = run(a, obs, steps=5), run(b, obs, steps=5)
    assert np.array_equal(pa[0].hands_m, pb[0].hands_m)
    assert pa[0].facing_rad == pb[0].facing_rad
    # the head is gone: no pose, and after retire_after_s the person's filters are dropped
    assert a.step(6 * NS, (), obs) == ()
    assert 1 in a.persons
    a.step(6 * NS + NS * 15, (), obs)
    assert 1 not in a.persons


def test_facing_transition_is_a_wrapped_gaussian():
    T = facing_transition(12, np.deg2rad(20))
    assert np.allclose(T.sum(axis=1), 1)
    assert np.allclose(T, np.roll(np.roll(T, 1, axis=0), 1, axis=1))  # circulant
    assert T[0, 1] == pytest.approx(T[0, 11])


def test_resample_blocks_keeps_each_block_to_itself(rng):
    w = rng.random((3, 5, 40))
    w[1, 2] = 0.0
    w[1, 2, 7] = 1.0
    idx = resample_blocks(w, rng)
    assert idx.shape == w.shape and idx.min() >= 0 and idx.max() < 40
    assert np.all(idx[1, 2] == 7)
    counts = np.apply_along_axis(np.bincount, -1, idx, minlength=40)
    expected = 40 * w / w.sum(axis=-1, keepdims=True)
    assert np.all(np.abs(counts - expected) < 1 + 1e-9)
