"""A hand's reported point pulled onto the blobs at its projection (surveil.tracking.blob_pull)."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.datatypes import (
    BlobSet,
    CameraObservation,
    CandidateSet,
    Limb,
    Phase,
    Silhouettes,
    TargetSnapshot,
)
from surveil.tracking.blob_pull import one_view_hand_points, pull_hands_onto_blobs

HAND = np.array([2.4, 1.9, 1.1])
SIGMA_PX, GATE_PX, FLOOR_M = 2.0, 25.0, 0.05


def observe(
    rig, blobs_m: dict[str, list[np.ndarray]], hands_m: np.ndarray | None = None, ends_in=None
) -> dict[str, CameraObservation]:
    """Observations whose only blobs sit at the projections of ``blobs_m[camera]``; with
    ``hands_m`` every blob's ``hand_px`` (in the cameras named in ``ends_in``, default all)
    is that point's projection (a bare forearm whose hand end is there)."""
    out = {}
    for cam in rig.cameras:
        h, w = cam.height, cam.width
        pts = blobs_m.get(cam.name, [])
        px = cam.project(np.array(pts).reshape(-1, 3))[0]
        n = len(px)
        hand_px = None
        if hands_m is not None and (ends_in is None or cam.name in ends_in):
            hand_px = np.repeat(cam.project(hands_m[None])[0], n, axis=0).astype(np.float64)
        blobs = BlobSet(
            px.astype(np.float64),
            np.full(n, 40, np.int64),
            np.zeros((n, 4), np.int32),
            np.ones(n, np.int32),
            np.full(n, 0.5),
            np.zeros((h, w), np.int32),
            hand_px=hand_px,
        )
        sil = Silhouettes(
            np.zeros((h, w), np.int32),
            np.zeros(1),
            np.full(1, h - 1.0),
            np.zeros((h, w), np.float32),
        )
        out[cam.name] = CameraObservation(cam.name, sil, np.zeros((h, w), bool), blobs)
    return out


def target(tid, mean_m, limb=Limb.RIGHT_HAND, phase=Phase.NORMAL, person=1) -> TargetSnapshot:
    return TargetSnapshot(tid, person, limb, phase, np.asarray(mean_m, float), np.eye(3) * 1e-4)


def line_distance_m(cam, point_m, through_m) -> float:
    origin, d = cam.backproject(cam.project(through_m[None])[0])
    v = point_m - origin
    return float(np.linalg.norm(v - (v @ d[0]) * d[0]))


def sideways(cam, along_m: float) -> np.ndarray:
    """A unit world vector perpendicular to ``cam``'s line of sight to HAND."""
    look = HAND - cam.centre_m
    side = np.cross(look, [0.0, 0.0, 1.0])
    return along_m * side / np.linalg.norm(side)


def test_one_view_moves_the_point_onto_its_line_of_sight_and_keeps_its_depth(rig):
    cam = rig.cameras[0]
    estimate = HAND + sideways(cam, 0.08)
    out = pull_hands_onto_blobs(
        (target(1, estimate),), observe(rig, {cam.name: [HAND]}), rig, SIGMA_PX, GATE_PX, FLOOR_M
    )
    pulled = out[0].mean_m
    depth = lambda p: float(cam.to_cam(p[None])[0, 2])  # noqa: E731
    # the offset across the line shrinks as two Gaussians' product says: line variance
    # over the sum of both
    line_var = (SIGMA_PX * depth(estimate) / cam.K[0, 0]) ** 2
    prior_var = 1e-4 + FLOOR_M**2
    expected = 0.08 * line_var / (line_var + prior_var)
    assert line_distance_m(cam, estimate, HAND) == pytest.approx(0.08, rel=0.02)
    assert line_distance_m(cam, pulled, HAND) == pytest.approx(expected, rel=0.05)
    assert depth(pulled) == pytest.approx(depth(estimate), abs=0.005)


def test_two_views_move_the_point_onto_the_hand(rig):
    a, b = rig.cameras[0], rig.cameras[1]
    estimate = HAND + np.array([0.06, -0.05, 0.07])
    seen = observe(rig, {a.name: [HAND], b.name: [HAND]})
    sharp_px = 0.3  # blobs far surer than the estimate: the point goes to where they meet
    out = pull_hands_onto_blobs((target(1, estimate),), seen, rig, sharp_px, GATE_PX, FLOOR_M)
    assert np.linalg.norm(estimate - HAND) > 0.1
    assert np.linalg.norm(out[0].mean_m - HAND) < 0.01


def test_a_bare_forearms_hand_end_pulls_the_reported_hand_its_centroid_the_tracker(rig):
    """The blob stage's ``arm_hand_end = 'report'``: the tracker follows a bare forearm's
    centre of mass; the reported hand is pulled along the lines through its hand end (given
    their error), and a blob without hand ends, a pull not given that error and the
    one-view points the tracker is fed keep the centroids."""
    a, b = rig.cameras[0], rig.cameras[1]
    forearm = HAND + np.array([0.0, 0.05, 0.12])  # its centre of mass, towards the elbow
    end_px = (0.3, 0.3)
    with_ends = observe(rig, {a.name: [forearm], b.name: [forearm]}, hands_m=HAND)
    pull = (rig, SIGMA_PX, GATE_PX, FLOOR_M)
    out = pull_hands_onto_blobs((target(1, forearm),), with_ends, *pull, end_px)
    assert np.linalg.norm(out[0].mean_m - HAND) < 0.01
    out = pull_hands_onto_blobs((target(1, forearm),), with_ends, *pull)
    assert np.linalg.norm(out[0].mean_m - forearm) < 0.01
    # one view's hand end alone pulls less: it may be a blob taken for a forearm by mistake
    lone = observe(rig, {a.name: [forearm], b.name: [forearm]}, hands_m=HAND, ends_in={a.name})
    sure = pull_hands_onto_blobs((target(1, forearm),), lone, *pull, (0.3, 0.3))[0].mean_m
    wary = pull_hands_onto_blobs((target(1, forearm),), lone, *pull, (0.3, 3.0))[0].mean_m
    assert line_distance_m(a, sure, HAND) < 0.005
    assert line_distance_m(a, wary, HAND) > 3 * line_distance_m(a, sure, HAND)
    plain = observe(rig, {a.name: [forearm], b.name: [forearm]})
    out = pull_hands_onto_blobs((target(1, forearm),), plain, *pull, end_px)
    assert np.linalg.norm(out[0].mean_m - forearm) < 0.01
    one_view = observe(rig, {a.name: [forearm]}, hands_m=HAND)
    estimate = forearm + sideways(a, 0.05)
    points, _ = one_view_hand_points(
        (target(1, estimate),), np.zeros((0, 3)), one_view, *pull, 0.15
    )
    to_forearm = line_distance_m(a, points[0], forearm)
    assert to_forearm < 0.5 * line_distance_m(a, estimate, forearm)
    assert to_forearm < 0.5 * line_distance_m(a, points[0], HAND)


@pytest.mark.parametrize("limb", [Limb.UNKNOWN, Limb.LEFT_HAND])
def test_an_unlabelled_tracker_on_a_bare_forearm_is_pulled_to_its_hand_end(rig, limb):
    """An unlabelled tracker (labels pending, not a head) is pulled where one of its views is
    a bare forearm, through the hand end; on plain blobs, or as a head, it keeps the
    filter's estimate."""
    a, b = rig.cameras[0], rig.cameras[1]
    forearm = HAND + np.array([0.0, 0.05, 0.12])
    pull = (rig, SIGMA_PX, GATE_PX, FLOOR_M, (0.3, 0.3))
    unlabelled = target(1, forearm, limb=limb, phase=Phase.UNLABELLED, person=0)
    with_ends = observe(rig, {a.name: [forearm], b.name: [forearm]}, hands_m=HAND)
    (out,) = pull_hands_onto_blobs((unlabelled,), with_ends, *pull)
    assert np.linalg.norm(out.mean_m - HAND) < 0.01
    plain = observe(rig, {a.name: [forearm], b.name: [forearm]})
    assert pull_hands_onto_blobs((unlabelled,), plain, *pull)[0] is unlabelled
    head = target(1, forearm, limb=Limb.HEAD, phase=Phase.UNLABELLED, person=0)
    assert pull_hands_onto_blobs((head,), with_ends, *pull)[0] is head


def test_a_blob_nearer_another_target_pulls_nothing(rig):
    """A hand at the face: the face's blob belongs to the head, whose projection is nearer."""
    cam = rig.cameras[0]
    face = HAND + sideways(cam, 0.05)
    hand = HAND + sideways(cam, 0.09)
    head = target(2, face, limb=Limb.HEAD)
    out = pull_hands_onto_blobs(
        (target(1, hand), head), observe(rig, {cam.name: [face]}), rig, SIGMA_PX, GATE_PX, FLOOR_M
    )
    np.testing.assert_array_equal(out[0].mean_m, hand)
    np.testing.assert_array_equal(out[1].mean_m, face)


@pytest.mark.parametrize(
    "limb, phase, person",
    [
        (Limb.HEAD, Phase.NORMAL, 1),
        (Limb.RIGHT_HAND, Phase.COMBINED, 1),
        (Limb.RIGHT_HAND, Phase.LOST, 1),
        (Limb.UNKNOWN, Phase.UNLABELLED, 0),
    ],
)
def test_only_labelled_hands_in_the_normal_phase_move(rig, limb, phase, person):
    cam = rig.cameras[0]
    estimate = HAND + sideways(cam, 0.08)
    one = target(1, estimate, limb=limb, phase=phase, person=person)
    out = pull_hands_onto_blobs(
        (one,), observe(rig, {cam.name: [HAND]}), rig, SIGMA_PX, GATE_PX, FLOOR_M
    )
    assert out[0] is one


def test_a_blob_beyond_the_gate_pulls_nothing(rig):
    cam = rig.cameras[0]
    estimate = HAND + sideways(cam, 0.8)
    one = target(1, estimate)
    out = pull_hands_onto_blobs(
        (one,), observe(rig, {cam.name: [HAND]}), rig, SIGMA_PX, GATE_PX, FLOOR_M
    )
    assert out[0] is one


def test_a_hand_no_candidate_explains_gets_a_point_from_the_one_view_that_shows_it(rig):
    """``one_view_hand_points``: a labelled hand seen by one camera has no candidate; the
    blob at its projection gives it a point on that blob's line of sight, from its
    prediction. A hand with a candidate near it, a hand no blob shows and a head get none."""
    cam = rig.cameras[0]
    estimate = HAND + sideways(cam, 0.05)
    other_hand = HAND + np.array([0.0, 0.8, 0.0])
    head = HAND + np.array([0.3, 0.0, 0.6])
    predicted = (
        target(1, estimate),
        target(2, other_hand, limb=Limb.LEFT_HAND),
        target(3, head, limb=Limb.HEAD),
    )
    seen = observe(rig, {cam.name: [HAND, head]})
    points, n_views = one_view_hand_points(
        predicted, np.zeros((0, 3)), seen, rig, SIGMA_PX, GATE_PX, FLOOR_M, 0.15
    )
    assert points.shape == (1, 3) and n_views.tolist() == [1]
    assert line_distance_m(cam, points[0], HAND) < 0.5 * line_distance_m(cam, estimate, HAND)
    explained = one_view_hand_points(
        predicted, estimate[None] + 0.03, seen, rig, SIGMA_PX, GATE_PX, FLOOR_M, 0.15
    )
    assert len(explained[0]) == 0


def test_points_added_to_a_candidate_set_say_that_no_camera_pair_made_them():
    base = CandidateSet(
        np.array([[1.0, 1.0, 1.0]]),
        np.array([0.9]),
        cam_pairs=np.array([[0, 1]]),
        blob_pairs=np.array([[2, 3]]),
    )
    out = base.with_points(np.array([[2.0, 1.0, 1.0]]), 0.5, np.array([1]))
    assert out.prior.tolist() == [0.9, 0.5]
    assert out.cam_pairs.tolist() == [[0, 1], [-1, -1]]
    assert out.blob_pairs.tolist() == [[2, 3], [-1, -1]]
    assert out.views.tolist() == [2, 1]
    assert base.with_points(np.zeros((0, 3)), 0.5, np.zeros(0, np.int64)) is base
