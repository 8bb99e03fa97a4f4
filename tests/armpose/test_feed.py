"""The arm model's hands as 3D candidates: only where they explain blobs nothing else does."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.armpose import ArmPoseConfig
from surveil.armpose.feed import arm_hand_points, with_arm_hands
from surveil.datatypes import ArmPose, BlobSet, CameraObservation, CandidateSet, Silhouettes
from surveil.rigs import lab4_rig

RIG = lab4_rig()
CFG = ArmPoseConfig(enabled=True, feed_candidates=True)
RADIUS_PX = 12.0
HEAD = np.array([3.2, 2.6, 1.6])
LEFT = np.array([3.0, 2.9, 1.1])
RIGHT = np.array([3.4, 2.3, 1.1])


def observe(points_by_cam: dict[str, np.ndarray]) -> dict[str, CameraObservation]:
    """Observations whose blobs lie exactly at the projections of the given points."""
    out = {}
    for name, pts in points_by_cam.items():
        cam = RIG[name]
        shape = (cam.height, cam.width)
        sil = Silhouettes(
            np.zeros(shape, np.int32), np.zeros(0), np.zeros(0), np.zeros(shape, np.float32)
        )
        px = cam.project(np.asarray(pts, dtype=np.float64).reshape(-1, 3))[0]
        n = len(px)
        blobs = BlobSet(
            px,
            np.full(n, 40, np.int64),
            np.zeros((n, 4), np.int32),
            np.ones(n, np.int32),
            np.zeros(n),
            np.zeros(shape, np.int32),
        )
        out[name] = CameraObservation(name, sil, np.zeros(shape, bool), blobs)
    return out


def pose(left_m: np.ndarray, right_m: np.ndarray) -> ArmPose:
    z = np.zeros((2, 3))
    return ArmPose(0, 1, 0.0, 1.0, z, z, np.stack([left_m, right_m]), 4)


def candidates(*points: np.ndarray) -> CandidateSet:
    """Candidates that two camera pairs made, without their blob indices."""
    pts = np.array(points, dtype=np.float64).reshape(-1, 3)
    return CandidateSet(pts, np.full(len(pts), 0.9))


def test_a_hand_seen_in_one_view_only_becomes_a_candidate():
    # the head in every view (its own candidate explains it); the right hand in two (a
    # candidate); the left hand only in cam0
    obs = observe({"cam0": [HEAD, LEFT, RIGHT], "cam1": [HEAD, RIGHT], "cam2": [HEAD]})
    out = arm_hand_points(candidates(HEAD, RIGHT), [pose(LEFT, RIGHT)], obs, RIG, CFG, RADIUS_PX)
    assert out.tolist() == [LEFT.tolist()]


def test_an_arm_on_another_hands_blob_adds_nothing():
    # the left arm settled on the right hand's blob in cam0 (on its line of sight, 0.3 m
    # nearer the camera: beyond feed_radius_m), the left hand being hidden; that blob is the
    # right hand's, whose candidate two views give
    obs = observe({"cam0": [HEAD, RIGHT], "cam1": [HEAD, RIGHT]})
    towards_cam0 = RIGHT + 0.3 * (RIG["cam0"].centre_m - RIGHT) / np.linalg.norm(
        RIG["cam0"].centre_m - RIGHT
    )
    arms = [pose(towards_cam0, RIGHT)]
    assert len(arm_hand_points(candidates(HEAD, RIGHT), arms, obs, RIG, CFG, RADIUS_PX)) == 0
    # the same arm is a candidate once no candidate explains that blob
    fed = arm_hand_points(candidates(HEAD), arms, obs, RIG, CFG, RADIUS_PX)
    np.testing.assert_allclose(fed[0], towards_cam0)


def test_a_hand_next_to_a_candidate_adds_nothing():
    obs = observe({"cam0": [HEAD, LEFT]})
    beside = LEFT + np.array([0.1, 0.0, 0.0])  # within feed_radius_m 0.15
    out = arm_hand_points(candidates(beside), [pose(LEFT, RIGHT)], obs, RIG, CFG, RADIUS_PX)
    assert len(out) == 0


def test_one_blob_feeds_one_hand():
    # both arms on the left hand's lone blob: the left arm (first) takes it
    obs = observe({"cam0": [LEFT]})
    out = arm_hand_points(CandidateSet.empty(), [pose(LEFT, LEFT)], obs, RIG, CFG, RADIUS_PX)
    assert len(out) == 1


@pytest.mark.parametrize("with_pairs", [True, False])
def test_fed_candidates_follow_the_camera_candidates(with_pairs):
    obs = observe({"cam0": [HEAD, LEFT, RIGHT], "cam1": [HEAD, RIGHT]})
    base = candidates(HEAD, RIGHT)
    if with_pairs:
        base = CandidateSet(
            base.points_m,
            base.prior,
            half_gap_m=np.zeros(2),
            cam_pairs=np.array([[0, 1], [0, 1]]),
            blob_pairs=np.array([[0, 0], [2, 1]]),
            head_only=np.array([False, True]),
            views=np.array([3, 2]),
        )
    out = with_arm_hands(base, [pose(LEFT, RIGHT)], obs, RIG, CFG, RADIUS_PX)
    assert len(out.points_m) == 3
    np.testing.assert_array_equal(out.points_m[:2], base.points_m)
    assert out.prior[2] == CFG.feed_prior
    if with_pairs:
        assert out.cam_pairs[2].tolist() == [-1, -1]
        assert out.blob_pairs[2].tolist() == [-1, -1]
        assert np.isnan(out.half_gap_m[2])
        assert out.head_only.tolist() == [False, True, False]  # an arm's hand is a hand
        assert out.views.tolist() == [3, 2, 1]  # one view's arm model
    else:
        assert out.cam_pairs is None


def test_no_poses_leave_the_candidates_as_they_are():
    base = candidates(HEAD)
    assert with_arm_hands(base, [], {}, RIG, CFG, RADIUS_PX) is base


def test_feeding_without_the_arm_trackers_is_a_config_error(tmp_path):
    from surveil.errors import ConfigError
    from surveil.pipeline import load_pipeline_config

    path = tmp_path / "feed.toml"
    path.write_text("[arms]\nfeed_candidates = true\n")
    with pytest.raises(ConfigError, match="arms: feed_candidates needs .*enabled = true"):
        load_pipeline_config(path)
    path.write_text("[arms]\nenabled = true\nfeed_candidates = true\nfeed_min_views = 0\n")
    with pytest.raises(ConfigError, match="arms.feed_min_views"):
        load_pipeline_config(path)
