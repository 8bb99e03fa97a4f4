import numpy as np
import pytest

from surveil.synth.actors import (
    BodyShape,
    min_jerk,
    rest_hand_targets,
    solve_pose,
    two_bone_ik,
)


def test_two_bone_ik_reaches_a_reachable_target_with_exact_segment_lengths():
    root, target = np.array([0.0, 0, 1.4]), np.array([0.3, 0.2, 1.0])
    joint, end = two_bone_ik(root, target, 0.33, 0.35, np.array([0.0, 0, -1]))
    np.testing.assert_allclose(end, target, atol=1e-12)
    assert np.linalg.norm(joint - root) == pytest.approx(0.33)
    assert np.linalg.norm(end - joint) == pytest.approx(0.35)


def test_two_bone_ik_bends_towards_the_pole():
    root, target = np.zeros(3), np.array([0.0, 0, -0.4])
    for pole in (np.array([1.0, 0, 0]), np.array([0.0, -1, 0])):
        joint, _ = two_bone_ik(root, target, 0.3, 0.3, pole)
        assert np.dot(joint, pole) > 0.1


def test_two_bone_ik_clamps_an_unreachable_target_onto_the_reach_shell():
    root, target = np.zeros(3), np.array([2.0, 0, 0])
    joint, end = two_bone_ik(root, target, 0.3, 0.3, np.array([0.0, 0, -1]))
    assert np.linalg.norm(end) == pytest.approx(0.6, abs=1e-3)
    np.testing.assert_allclose(end / np.linalg.norm(end), [1, 0, 0], atol=1e-9)


def test_min_jerk_starts_and_ends_at_rest_and_is_symmetric():
    tau = np.linspace(0, 1, 101)
    s = min_jerk(tau)
    assert s[0] == 0 and s[-1] == 1
    np.testing.assert_allclose(s + s[::-1], 1.0, atol=1e-12)
    v = np.gradient(s, tau)
    assert abs(v[0]) < 1e-3 and abs(v[-1]) < 1e-3 and v[50] == pytest.approx(1.875, abs=1e-3)


def test_adult_hand_has_realistic_size():
    shape = BodyShape.from_height(1.75)
    assert 0.17 <= shape.hand_length_m <= 0.19
    assert 0.08 <= shape.hand_width_m <= 0.09


def test_hands_at_rest_hang_beside_the_hips_and_the_pose_reaches_them():
    shape = BodyShape.from_height(1.75)
    root = np.array([1.0, 2.0, 0.0])
    targets = rest_hand_targets(shape, root, 0.0)
    pose = solve_pose(shape, root, 0.0, targets)
    np.testing.assert_allclose(pose.hands_m, targets, atol=1e-9)
    assert (0.6 < pose.hands_m[:, 2]).all() and (pose.hands_m[:, 2] < 0.95).all()
    # facing +X: the left hand is on the +Y side
    assert pose.hands_m[0, 1] > root[1] > pose.hands_m[1, 1]
    assert pose.head_m[2] == pytest.approx(1.75 - 0.112, abs=0.01)
