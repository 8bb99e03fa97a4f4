"""A combined pair's two reported points, each on its own side of the pair's estimate."""

from __future__ import annotations

import numpy as np

from surveil.datatypes import Limb, Phase, TargetSnapshot
from surveil.tracking.contact import side_direction, spread_combined


def snap(tid: int, phase: Phase, at, limb=Limb.RIGHT_HAND) -> TargetSnapshot:
    return TargetSnapshot(tid, 1, limb, phase, np.asarray(at, float))


def test_each_target_of_a_pair_moves_half_the_gap_away_from_its_partner():
    at = [2.0, 1.0, 1.1]
    targets = (snap(1, Phase.COMBINED, at), snap(2, Phase.COMBINED, at), snap(3, Phase.NORMAL, at))
    # before joining, 2 was 0.3 m from 1 along +x and 0.1 m higher
    sides = {1: np.array([0.3, 0.0, 0.1]), 2: np.array([-0.3, 0.0, -0.1])}
    out = spread_combined(targets, sides, 0.05)
    np.testing.assert_allclose(out[0].mean_m, [1.975, 1.0, 1.1])  # horizontal only
    np.testing.assert_allclose(out[1].mean_m, [2.025, 1.0, 1.1])
    assert abs(np.linalg.norm(out[1].mean_m - out[0].mean_m) - 0.05) < 1e-12
    np.testing.assert_array_equal(out[2].mean_m, at)  # not combined: unchanged
    assert [t.target_id for t in out] == [1, 2, 3]
    np.testing.assert_array_equal(out[0].cov_m2, targets[0].cov_m2)


def test_no_gap_no_side_or_a_vertical_side_leave_the_targets_as_they_are():
    at = [2.0, 1.0, 1.1]
    targets = (snap(1, Phase.COMBINED, at), snap(2, Phase.COMBINED, at))
    sides = {1: np.array([0.3, 0.0, 0.0]), 2: np.array([-0.3, 0.0, 0.0])}
    assert spread_combined(targets, sides, 0.0) is targets
    assert spread_combined(targets, {}, 0.05) is targets
    vertical = {1: np.array([0.0, 0.0, 0.3]), 2: np.array([0.0, 0.0, -0.3])}
    for a, b in zip(spread_combined(targets, vertical, 0.05), targets, strict=True):
        np.testing.assert_array_equal(a.mean_m, b.mean_m)
    assert side_direction(np.array([0.0, 0.0, 1.0])) is None
    np.testing.assert_allclose(side_direction(np.array([0.0, -2.0, 5.0])), [0.0, -1.0, 0.0])
