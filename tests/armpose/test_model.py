"""The arm model: anthropometry, shoulders under the head, forward kinematics, limits."""

from __future__ import annotations

import numpy as np

from surveil.armpose.model import (
    JOINT_LIMITS,
    ArmShape,
    arm_joints_m,
    clip_to_limits,
    shoulders_m,
)

SHAPE = ArmShape.from_head_height(1.60)
LEFT, RIGHT = 1.0, -1.0


def joints(angles_deg, phi_deg=0.0, side=LEFT):
    a = np.deg2rad(np.asarray(angles_deg, dtype=np.float64))
    return arm_joints_m(np.zeros(3), a, np.deg2rad(np.float64(phi_deg)), np.float64(side), SHAPE)


def unit(v):
    return v / np.linalg.norm(v)


def test_bones_keep_their_lengths_for_any_angles(rng):
    angles = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], (500, 4))
    phi = rng.uniform(-np.pi, np.pi, 500)
    side = rng.choice([LEFT, RIGHT], 500)
    shoulder = rng.normal(0, 1, (500, 3))
    elbow, hand = arm_joints_m(shoulder, angles, phi, side, SHAPE)
    assert np.allclose(np.linalg.norm(elbow - shoulder, axis=1), SHAPE.upper_arm_m)
    assert np.allclose(np.linalg.norm(hand - elbow, axis=1), SHAPE.forearm_to_hand_m)


def test_elbow_angle_is_the_angle_between_the_bones(rng):
    angles = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], (200, 4))
    elbow, hand = arm_joints_m(np.zeros(3), angles, np.zeros(200), np.ones(200), SHAPE)
    cos = np.sum(elbow / SHAPE.upper_arm_m * (hand - elbow) / SHAPE.forearm_to_hand_m, axis=1)
    assert np.allclose(np.arccos(np.clip(cos, -1, 1)), angles[:, 3], atol=1e-9)


def test_rest_pose_hangs_straight_down():
    elbow, hand = joints([0, 0, 0, 0])
    assert np.allclose(hand, [0, 0, -SHAPE.reach_m])


def test_flexion_raises_the_arm_forward_of_a_turned_body():
    # a body facing +Y (phi 90 deg): flexion 90 deg points the arm along +Y
    _, hand = joints([90, 0, 0, 0], phi_deg=90)
    assert np.allclose(unit(hand), [0, 1, 0], atol=1e-9)


def test_abduction_raises_either_arm_outward():
    _, left = joints([0, 90, 0, 0], side=LEFT)
    _, right = joints([0, 90, 0, 0], side=RIGHT)
    assert np.allclose(unit(left), [0, 1, 0], atol=1e-9)  # facing +X: left is +Y
    assert np.allclose(unit(right), [0, -1, 0], atol=1e-9)


def test_elbow_bends_forward_and_twist_turns_it_to_the_midline():
    elbow, hand = joints([0, 0, 0, 90])
    assert np.allclose(unit(hand - elbow), [1, 0, 0], atol=1e-9)
    for side, midline in ((LEFT, [0, -1, 0]), (RIGHT, [0, 1, 0])):
        elbow, hand = joints([0, 0, 90, 90], side=side)
        assert np.allclose(unit(hand - elbow), midline, atol=1e-9)


def test_shoulders_sit_below_and_beside_the_head_across_the_facing():
    head = np.array([2.0, 1.0, 1.60])
    sh = shoulders_m(head, np.deg2rad(np.array([0.0, 90.0])), SHAPE)
    assert sh.shape == (2, 2, 3)
    assert np.allclose(sh[..., 2], head[2] - SHAPE.shoulder_drop_m)
    width = np.linalg.norm(sh[:, 0] - sh[:, 1], axis=1)
    assert np.allclose(width, 2 * SHAPE.shoulder_half_width_m)
    # facing +X, the left shoulder is at +Y; facing +Y, it is at -X
    assert sh[0, 0, 1] > head[1] > sh[0, 1, 1]
    assert sh[1, 0, 0] < head[0] < sh[1, 1, 0]


def test_stature_and_lengths_follow_the_head_height():
    small, tall = ArmShape.from_head_height(1.4), ArmShape.from_head_height(1.8)
    assert np.isclose(tall.reach_m / small.reach_m, 1.8 / 1.4)
    assert 0.6 < ArmShape.from_head_height(1.64).reach_m < 0.75  # an adult arm


def test_clip_reflects_steps_over_a_limit_back_inside():
    lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    a = np.array([lo - 0.1, hi + 0.2, (lo + hi) / 2])
    out = clip_to_limits(a)
    assert np.allclose(out[0], lo + 0.1)
    assert np.allclose(out[1], hi - 0.2)
    assert np.allclose(out[2], (lo + hi) / 2)
