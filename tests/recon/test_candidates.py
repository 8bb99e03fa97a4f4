"""make_candidates on small hand-built observations (320x240 cameras high in a 6 x 4 m room)."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from surveil.camera import Camera, Rig, look_at
from surveil.config import from_table
from surveil.datatypes import BlobSet, CameraObservation, CandidateSet, Silhouettes
from surveil.errors import ConfigError
from surveil.recon.candidates import (
    _merge,
    blob_rows,
    explain_away,
    floor_relative_v,
    make_candidates,
    project_into,
    refine_from_views,
    rescue_expected,
    silhouette_prior,
    view_support,
)
from surveil.recon.settings import CandidateConfig

W, H = 320, 240
CFG = CandidateConfig()
PAPER = CandidateConfig(silhouette_drop_worst=False)  # p_b over every camera (eq. 27)
SIL_BOTTOM = CandidateConfig(rel_v_to_floor=False)  # the paper's D_v: down to the silhouette


def _rig(n: int = 4) -> Rig:
    corners = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)][:n]
    return Rig(
        tuple(
            look_at(
                f"cam{i}",
                np.array([x, y, 2.8]),
                np.array([3.0, 2.0, 1.0]),
                width=W,
                height=H,
                hfov_deg=80,
            )
            for i, (x, y) in enumerate(corners)
        )
    )


def _silhouettes(centres_px: np.ndarray, radius_px: int = 20) -> Silhouettes:
    mask = np.zeros((H, W), np.uint8)
    for u, v in np.rint(centres_px).astype(int):
        cv2.circle(mask, (int(u), int(v)), radius_px, 255, -1)
    n, labels = cv2.connectedComponents(mask)
    rows = np.arange(H)
    top = np.array([rows[(labels == s).any(axis=1)].min() for s in range(1, n)], np.float64)
    bottom = np.array([rows[(labels == s).any(axis=1)].max() for s in range(1, n)], np.float64)
    dist = cv2.distanceTransform((mask == 0).astype(np.uint8), cv2.DIST_L2, 5)
    if n == 1:
        dist = np.full((H, W), 1e4, np.float32)
    return Silhouettes(labels.astype(np.int32), top, bottom, dist)


def _observation(
    cam: Camera,
    points_m: np.ndarray,
    *,
    rel_v: np.ndarray | None = None,
    silhouette_at_m: np.ndarray | None = None,
    foreground_share: np.ndarray | None = None,
    restored: np.ndarray | None = None,
) -> CameraObservation:
    """Blobs at the projections of ``points_m``; silhouettes are disks around the projections
    of ``silhouette_at_m`` (default: the blob points). rel_v defaults to a function of height,
    so the same 3-D point has the same rel_v in every camera."""
    points_m = np.asarray(points_m, np.float64).reshape(-1, 3)
    px, _ = cam.project(points_m)
    sil_px = cam.project(points_m if silhouette_at_m is None else silhouette_at_m)[0]
    n = len(points_m)
    rel = (2.0 - points_m[:, 2]) / 2.0 if rel_v is None else np.asarray(rel_v, np.float64)
    blobs = BlobSet(
        centroids_px=px,
        areas_px=np.full(n, 50, np.int64),
        bboxes_px=np.zeros((n, 4), np.int32),
        silhouette=np.ones(n, np.int32),
        rel_v=rel,
        labels=np.zeros((H, W), np.int32),
        foreground_share=foreground_share,
        restored=restored,
    )
    return CameraObservation(cam.name, _silhouettes(sil_px), np.zeros((H, W), bool), blobs)


HEAD = np.array([[3.0, 2.0, 1.7]])


def test_three_targets_seen_by_four_cameras_are_the_strongest_candidates():
    rig = _rig()
    targets = np.array([[2.5, 1.5, 1.6], [3.6, 2.5, 1.1], [3.0, 1.2, 1.3]])
    obs = [_observation(cam, targets) for cam in rig]
    cs = make_candidates(obs, rig, CFG)
    assert isinstance(cs, CandidateSet)
    assert np.all(np.diff(cs.prior) <= 0)  # strongest first
    best = cs.points_m[:3]
    order = np.argsort(best[:, 0])
    np.testing.assert_allclose(best[order], targets[np.argsort(targets[:, 0])], atol=1e-6)
    np.testing.assert_allclose(cs.prior[:3], 1.0)
    assert np.all(cs.half_gap_m[:3] < 1e-6)
    np.testing.assert_array_equal(cs.views[:3], 4)  # every camera has a blob on each target
    assert np.all(cs.blob_pairs[:3, 0] == cs.blob_pairs[:3, 1])  # true correspondences
    assert np.all(cs.cam_pairs[:, 0] < cs.cam_pairs[:, 1])
    # ghosts of two nearly coplanar views (cam0, cam3) may survive, but weakly
    ghosts = cs.blob_pairs[3:]
    assert np.all(ghosts[:, 0] != ghosts[:, 1]) and np.all(cs.prior[3:] < 0.5)


def _exact_ghost(rig: Rig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two limbs A, B and the point G where cam0's line of sight to A crosses cam1's to B."""
    a = np.array([2.6, 1.8, 1.0])
    g = a + 0.5 * (a - rig.cameras[0].centre_m) / np.linalg.norm(a - rig.cameras[0].centre_m)
    to_g = g - rig.cameras[1].centre_m
    b = g - 0.6 * to_g / np.linalg.norm(to_g)
    return a, b, g


@pytest.mark.parametrize("enabled", [True, False])
def test_crossing_lines_of_sight_of_two_limbs_are_explained_away(enabled):
    rig = _rig()
    a, b, g = _exact_ghost(rig)
    limbs = np.stack([a, b])
    # equal rel_v and silhouettes over A, B and G: only the other views can tell G is a ghost
    obs = [
        _observation(cam, limbs, rel_v=np.full(2, 0.5), silhouette_at_m=np.stack([a, b, g]))
        for cam in rig
    ]
    cs = make_candidates(obs, rig, dataclasses.replace(CFG, explain_away=enabled))
    to_limb = np.linalg.norm(cs.points_m[:, None] - limbs[None], axis=2).min(axis=1)
    to_ghost = np.linalg.norm(cs.points_m - g, axis=1)
    assert (to_limb < 1e-3).sum() >= 2  # both limbs found either way
    assert (to_ghost < 0.01).any() != enabled
    if enabled:  # A and B: cam2 and cam3 see them too
        np.testing.assert_array_equal(cs.views[to_limb < 1e-3], 4)
    else:
        assert cs.views is None


@pytest.mark.parametrize("threshold", [0.2, 0.0])
@pytest.mark.parametrize("measured", [True, False])
def test_a_pair_of_scenery_blobs_is_dropped_a_camouflaged_hand_is_not(threshold, measured):
    rig = _rig()
    hand = np.array([3.2, 1.8, 0.95])  # on a wooden table: mostly background to cam0
    scenery = np.array([2.7, 2.3, 0.7])  # a table edge inside the silhouette, cams 0 and 1
    shares = {"cam0": [0.1, 0.05], "cam1": [0.8, 0.1], "cam2": [0.9], "cam3": [0.7]}
    obs = []
    for m, cam in enumerate(rig):
        points = np.stack([hand, scenery]) if m < 2 else hand[None]
        share = np.array(shares[cam.name]) if measured else None
        obs.append(
            _observation(
                cam,
                points,
                silhouette_at_m=np.stack([hand, scenery]),  # one person around both
                foreground_share=share,
            )
        )
    cfg = dataclasses.replace(CFG, min_pair_foreground_share=threshold)
    cs = make_candidates(obs, rig, cfg)
    assert np.linalg.norm(cs.points_m - hand, axis=1).min() < 1e-6
    scenery_kept = np.linalg.norm(cs.points_m - scenery, axis=1).min() < 1e-6
    # an unmeasured share counts as foreground
    assert scenery_kept == (threshold == 0 or not measured)


@pytest.mark.parametrize(
    ("restored_in", "found"),
    [
        ((), True),
        (("cam0",), True),  # a restored blob pairs with a plain one
        (("cam0", "cam1"), False),  # two restored blobs do not pair
    ],
)
def test_two_restored_blobs_do_not_pair(restored_in, found):
    """Blobs the opening would have erased (``BlobConfig.open_keeps_isolated``) may be a
    hand seen edge-on or a fringe of colour along a fold: a point seen only as restored
    blobs is dropped; a third view's plain blob brings it back."""
    rig = _rig()
    hand = np.array([3.2, 1.8, 0.95])
    obs = [
        _observation(cam, hand[None], restored=np.array([cam.name in restored_in]))
        for cam in rig.cameras[:2]
    ]

    def found_hand(cs: CandidateSet) -> bool:
        return bool(np.any(np.linalg.norm(cs.points_m - hand, axis=1) < 1e-6))

    assert found_hand(make_candidates(obs, rig, CFG)) == found
    third = _observation(rig.cameras[2], hand[None])
    assert found_hand(make_candidates([*obs, third], rig, CFG))


def test_expected_position_spares_the_dropped_candidate_next_to_it():
    """Explaining away drops G; a tracker that expects a target 5 cm from G, with another
    target expected 25 cm away (hands about to meet), gets it back. One that expects a target
    there alone (a tracker left on a ghost), at limb A (which has its candidate) or far from
    everything adds nothing. The candidate set marks the candidate it got back as rescued
    (the tracker limits how long a target may live on rescued candidates)."""
    rig = _rig()
    a, b, g = _exact_ghost(rig)
    obs = [
        _observation(
            cam, np.stack([a, b]), rel_v=np.full(2, 0.5), silhouette_at_m=np.stack([a, b, g])
        )
        for cam in rig
    ]
    plain = make_candidates(obs, rig, CFG)
    for expected, ghost_back in (
        ([g + [0.05, 0, 0], g + [0.0, 0, 0.25]], True),
        ([g + [0.05, 0, 0]], False),
        ([a], False),
        ([[0.5, 0.5, 1]], False),
    ):
        cs = make_candidates(obs, rig, CFG, expected_m=np.array(expected))
        at_g = np.linalg.norm(cs.points_m - g, axis=1) < 0.01
        assert at_g.any() == ghost_back
        assert len(cs.points_m) == len(plain.points_m) + ghost_back
        assert cs.rescued.tolist() == at_g.tolist()
    assert not plain.rescued.any()


def test_rescue_gives_each_expected_position_its_own_strongest_dropped_candidate():
    pts = np.array([[0.0, 0, 1], [0.1, 0, 1], [0.12, 0, 1], [1.0, 0, 1]])
    prior = np.array([0.9, 0.4, 0.6, 0.8])
    keep = np.array([False, False, False, True])
    # two hands expected side by side: the stronger nearby candidate, then the other one
    out = rescue_expected(pts, prior, keep, np.array([[0.1, 0, 1], [0.11, 0, 1]]), 0.05)
    assert out.tolist() == [False, True, True, True]
    # ... but not one expected alone, when a partner is required within 0.3 m
    out = rescue_expected(pts, prior, keep, np.array([[0.1, 0, 1], [0.6, 0, 1]]), 0.05, 0.3)
    assert out.tolist() == keep.tolist()
    assert keep.tolist() == [False, False, False, True]  # the input is not modified
    # ... unless that one is marked as helped alone (a hand with a candidate of its own
    # in the previous frame set); the far one, unmarked, still is not
    alone = rescue_expected(
        pts, prior, keep, np.array([[0.1, 0, 1], [0.6, 0, 1]]), 0.05, 0.3, np.array([True, False])
    )
    assert alone.tolist() == [False, False, True, True]
    # ... within its own radius: 1 cm takes the candidate at 0.1 m, not the stronger one
    # 2 cm away
    alone_near = rescue_expected(
        pts, prior, keep, np.array([[0.1, 0, 1]]), 0.05, 0.3, np.array([True]), 0.01
    )
    assert alone_near.tolist() == [False, True, False, True]
    one = rescue_expected(pts, prior, keep, np.array([[0.1, 0, 1]]), 0.05)
    assert one.tolist() == [False, False, True, True]
    assert rescue_expected(pts, prior, keep, np.zeros((0, 3)), 0.05).tolist() == keep.tolist()


def test_explain_away_keeps_a_limb_hidden_in_one_view():
    # limb 1 shares camera 0's blob with limb 0 (one behind the other) but has its own in 1, 2
    support = np.array([[0, 0, 0, -1], [0, 1, 1, -1]])
    assert explain_away(support, np.array([0.9, 0.8])).tolist() == [True, True]


def test_mismatched_relative_v_makes_p_o_small():
    rig = _rig(2)
    obs = [
        _observation(rig.cameras[0], HEAD, rel_v=np.array([0.2])),
        _observation(rig.cameras[1], HEAD, rel_v=np.array([0.8])),
    ]
    assert len(make_candidates(obs, rig, SIL_BOTTOM).points_m) == 0
    # a small mismatch passes with p(Z) = p_o = exp(-dv^2 / (2 sigma^2))
    obs[1] = _observation(rig.cameras[1], HEAD, rel_v=np.array([0.35]))
    cs = make_candidates(obs, rig, SIL_BOTTOM)
    np.testing.assert_allclose(cs.prior, [np.exp(-0.5 * (0.15 / CFG.sigma_rel_v) ** 2)])


def test_a_weak_candidate_is_kept_only_next_to_a_tracked_hand():
    """p_o = 0.20 (D_v 0.2 against 0.38, as where one view's silhouette top is another
    person's head): under the product threshold 0.2, dropped; kept at the lower
    ``expected_prior_threshold`` where a tracked hand is predicted within
    ``expected_gate_m``, and only there."""
    rig = _rig(2)
    obs = [
        _observation(rig.cameras[0], HEAD, rel_v=np.array([0.2])),
        _observation(rig.cameras[1], HEAD, rel_v=np.array([0.38])),
    ]
    weak_near_hands = SIL_BOTTOM  # expected_prior_threshold 0.1 by default
    off = dataclasses.replace(SIL_BOTTOM, expected_prior_threshold=SIL_BOTTOM.prior_threshold)
    assert len(make_candidates(obs, rig, off, expected_m=HEAD).points_m) == 0
    assert len(make_candidates(obs, rig, weak_near_hands).points_m) == 0
    far = HEAD + np.array([[0.0, 0.0, 0.15]])
    assert len(make_candidates(obs, rig, weak_near_hands, expected_m=far).points_m) == 0
    near = HEAD + np.array([[0.0, 0.05, 0.0]])
    cs = make_candidates(obs, rig, weak_near_hands, expected_m=near)
    np.testing.assert_allclose(cs.points_m, HEAD, atol=1e-6)
    np.testing.assert_allclose(cs.prior, [np.exp(-0.5 * (0.18 / CFG.sigma_rel_v) ** 2)])


def _standing(cam: Camera, at_m, blobs_m: np.ndarray, hidden_below_m: float = 0.0):
    """A person 1.8 m tall standing at ``at_m`` (x, y), seen by ``cam`` down to
    ``hidden_below_m`` (a table in front hides the rest), with skin blobs at ``blobs_m``;
    rel_v as the blob stage measures it, down to the silhouette's bottom row."""
    return _people(cam, np.array([[*at_m, 1.8]]), blobs_m, hidden_below_m)


def _people(
    cam: Camera, crowns_m: np.ndarray, blobs_m: np.ndarray, hidden_below_m: float = 0.0
) -> CameraObservation:
    """People standing under ``crowns_m`` (x, y, crown height), seen down to
    ``hidden_below_m``, all in one silhouette (as where they overlap in a view), with skin
    blobs at ``blobs_m``; rel_v down to the silhouette's bottom row."""
    mask = np.zeros((H, W), np.uint8)
    for x, y, z in crowns_m:
        ends = cam.project(np.array([[x, y, z], [x, y, hidden_below_m]]))[0]
        cv2.line(mask, *(tuple(int(c) for c in np.rint(p)) for p in ends), 255, 16)
    rows = np.flatnonzero(mask.any(axis=1))
    top, bottom = float(rows.min()), float(rows.max())
    dist = cv2.distanceTransform((mask == 0).astype(np.uint8), cv2.DIST_L2, 5)
    sil = Silhouettes((mask > 0).astype(np.int32), np.array([top]), np.array([bottom]), dist)
    px = cam.project(blobs_m)[0]
    n = len(blobs_m)
    blobs = BlobSet(
        centroids_px=px,
        areas_px=np.full(n, 50, np.int64),
        bboxes_px=np.zeros((n, 4), np.int32),
        silhouette=np.ones(n, np.int32),
        rel_v=(px[:, 1] - top) / (bottom - top),
        labels=np.zeros((H, W), np.int32),
    )
    return CameraObservation(cam.name, sil, np.zeros((H, W), bool), blobs)


def test_relative_v_down_to_the_floor_keeps_a_hand_whose_legs_are_hidden_in_one_view():
    """A table hides the legs below 0.9 m from cam1: the silhouette's bottom row is the
    table's edge, so the hand sits far lower in cam1's silhouette than in cam0's and the
    paper's p_o rejects the pair. Measured down to the floor under Z, the two agree, and a
    head still differs from a hand of the same silhouette by more than 3 sigma."""
    rig = _rig(2)
    hand = np.array([[3.0, 2.0, 1.1]])
    head = np.array([[3.0, 2.0, 1.65]])
    obs = [
        _standing(rig.cameras[0], (3.0, 2.0), hand),
        _standing(rig.cameras[1], (3.0, 2.0), hand, hidden_below_m=0.9),
    ]
    assert obs[1].blobs.rel_v[0] - obs[0].blobs.rel_v[0] > 0.2
    assert len(make_candidates(obs, rig, SIL_BOTTOM).points_m) == 0
    cs = make_candidates(obs, rig, CFG)
    np.testing.assert_allclose(cs.points_m, hand, atol=1e-6)
    assert cs.prior[0] > 0.8
    # the floor-based D_v still tells a head from a hand of the same (truncated) silhouette
    both = np.concatenate([hand, head])
    cam1 = _standing(rig.cameras[1], (3.0, 2.0), both, hidden_below_m=0.9)
    v, top = blob_rows(cam1)
    d_v = floor_relative_v(both, np.array([1, 1]), v, top, rig)
    d_v0 = floor_relative_v(hand, np.array([0]), *blob_rows(obs[0]), rig)
    assert abs(d_v[0] - d_v0[0]) < 0.05
    assert d_v[0] - d_v[1] > 3 * CFG.sigma_rel_v


def test_blobs_of_different_points_have_a_large_gap_and_are_dropped():
    rig = _rig(2)
    other = HEAD + np.array([[0.0, 0.6, 0.0]])  # same height: p_o cannot reject the pair
    obs = [_observation(rig.cameras[0], HEAD), _observation(rig.cameras[1], other)]
    assert len(make_candidates(obs, rig, CFG).points_m) == 0
    lenient = CandidateConfig(term_threshold=0.0, prior_threshold=0.0, max_gap_m=10.0)
    cs = make_candidates(obs, rig, lenient)
    assert cs.half_gap_m[0] > CFG.max_gap_m
    p_t = np.exp(-0.5 * (cs.half_gap_m[0] / CFG.sigma_gap_m) ** 2)
    assert cs.prior[0] <= p_t < 1e-3


def test_point_projecting_outside_a_silhouette_makes_p_b_small():
    rig = _rig(3)
    cam2 = rig.cameras[2]
    elsewhere = HEAD + np.array([[0.0, 0.0, -0.8]])  # cam2's silhouette is 0.8 m lower
    obs = [
        _observation(rig.cameras[0], HEAD),
        _observation(rig.cameras[1], HEAD),
        _observation(cam2, np.zeros((0, 3)), silhouette_at_m=elsewhere),
    ]
    assert len(make_candidates(obs, rig, PAPER).points_m) == 0
    lenient = CandidateConfig(term_threshold=0.0, prior_threshold=0.0, silhouette_drop_worst=False)
    cs = make_candidates(obs, rig, lenient)
    u, v = np.rint(cam2.project(HEAD)[0][0]).astype(int)
    dist = float(obs[2].silhouettes.dist_outside_px[v, u])
    assert dist > 10
    np.testing.assert_allclose(
        cs.prior, [np.exp(-0.5 * (dist / CFG.sigma_silhouette_px) ** 2)], rtol=1e-9
    )
    # without cam2's observation it is not consulted and the candidate is perfect
    np.testing.assert_allclose(make_candidates(obs[:2], rig, PAPER).prior, [1.0])

    # the robust default leaves out the one camera that disagrees when three see the point
    robust = CandidateConfig(silhouette_drop_worst=True)
    assert len(make_candidates(obs, rig, robust).points_m) == 1


def test_pairs_of_one_point_merge_into_the_strongest_with_a_boosted_prior():
    rig = _rig(3)
    obs = [
        _observation(cam, HEAD, rel_v=np.array([rv]))
        for cam, rv in zip(rig, (0.5, 0.6, 0.7), strict=True)
    ]
    cfg = dataclasses.replace(SIL_BOTTOM, prior_threshold=0.1)  # keep the weak pair (0, 2)
    cs = make_candidates(obs, rig, cfg)
    strong = np.exp(-0.5)  # |dv| = 0.1 = sigma for pairs (0, 1) and (1, 2)
    weak = np.exp(-2.0)  # |dv| = 0.2 for pair (0, 2)
    assert cs.points_m.shape == (1, 3)
    np.testing.assert_allclose(cs.prior, [strong + cfg.merge_boost * (strong + weak)])
    np.testing.assert_array_equal(cs.cam_pairs, [[0, 1]])  # first of the tied strongest
    np.testing.assert_array_equal(cs.blob_pairs, [[0, 0]])


def test_merge_keeps_the_stronger_of_close_candidates_and_clips_to_one():
    pts = np.array([[0.0, 0, 1], [0.01, 0, 1], [1.0, 0, 1], [1.0, 0.005, 1]])
    kept, prior = _merge(pts, np.array([0.3, 0.6, 0.9, 0.8]), radius_m=0.05, boost=0.5)
    np.testing.assert_array_equal(kept, [2, 1])
    np.testing.assert_allclose(prior, [1.0, 0.75])
    kept, prior = _merge(pts[[0, 2]], np.array([0.3, 0.6]), radius_m=0.05, boost=0.5)
    np.testing.assert_array_equal(kept, [1, 0])
    np.testing.assert_allclose(prior, [0.6, 0.3])


@pytest.mark.parametrize("n_cams, n_blobs", [(0, 1), (1, 3), (4, 0), (2, 0)])
def test_empty_inputs_give_an_empty_candidate_set(n_cams, n_blobs):
    rig = _rig(4)
    pts = np.tile(HEAD, (n_blobs, 1)) + np.arange(n_blobs)[:, None] * 0.3
    cs = make_candidates([_observation(cam, pts) for cam in rig.cameras[:n_cams]], rig, CFG)
    assert cs.points_m.shape == (0, 3) and cs.prior.shape == (0,)
    assert cs.cam_pairs.shape == (0, 2) and cs.blob_pairs.shape == (0, 2)


def test_points_behind_or_below_are_dropped():
    rig = _rig(2)
    below = np.array([[3.0, 2.0, -0.3]])
    obs = [_observation(cam, below) for cam in rig]
    assert len(make_candidates(obs, rig, CFG).points_m) == 0


def test_projections_shared_by_p_b_and_support_are_those_of_projecting_again(rng):
    # the candidate stage projects once and takes rows of the result for a subset
    rig = _rig()
    targets = rng.uniform([2.0, 1.0, 0.8], [4.0, 3.0, 1.8], size=(5, 3))
    by_cam = {m: _observation(cam, targets) for m, cam in enumerate(rig.cameras)}
    points = rng.uniform([1.5, 0.5, 0.3], [4.5, 3.5, 2.0], size=(40, 3))
    projected = project_into(points, rig, by_cam)
    np.testing.assert_array_equal(
        silhouette_prior(points, rig, by_cam, 4.0, True, projected),
        silhouette_prior(points, rig, by_cam, 4.0, True),
    )
    subset = np.array([3, 7, 8, 21, 39])
    rows = {m: (px[subset], depth[subset]) for m, (px, depth) in projected.items()}
    np.testing.assert_array_equal(
        view_support(points[subset], None, None, rig, by_cam, 6.0, rows),
        view_support(points[subset], None, None, rig, by_cam, 6.0),
    )


def test_merge_with_no_radius_keeps_every_candidate_strongest_first():
    pts = np.array([[0.0, 0, 1], [0.0, 0, 1], [1.0, 0, 1]])
    kept, prior = _merge(pts, np.array([0.3, 0.6, 0.9]), radius_m=0.0, boost=0.5)
    np.testing.assert_array_equal(kept, [2, 1, 0])
    np.testing.assert_allclose(prior, [0.9, 0.6, 0.3])


def test_is_deterministic(rng):
    rig = _rig()
    targets = rng.uniform([2.0, 1.0, 0.8], [4.0, 3.0, 1.8], size=(6, 3))
    obs = [_observation(cam, targets) for cam in rig]
    a, b = make_candidates(obs, rig, CFG), make_candidates(obs, rig, CFG)
    for name in ("points_m", "prior", "half_gap_m", "cam_pairs", "blob_pairs"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_unknown_camera_is_named():
    rig = _rig(2)
    obs = [_observation(rig.cameras[0], HEAD)]
    stray = CameraObservation("nope", obs[0].silhouettes, obs[0].skin, obs[0].blobs)
    with pytest.raises(ValueError, match="'nope'"):
        make_candidates([*obs, stray], rig, CFG)
    with pytest.raises(ValueError, match="twice"):
        make_candidates([obs[0], obs[0]], rig, CFG)


def test_config_rejects_out_of_range_values_by_key():
    with pytest.raises(ConfigError, match="recon.sigma_gap_m must be >= "):
        from_table(CandidateConfig, {"sigma_gap_m": 0.0}, "run.toml: recon")
    assert from_table(CandidateConfig, {"merge_boost": 0.2}, "x").merge_boost == 0.2
    with pytest.raises(ConfigError, match="recon: refine_min_views must be 0 .off. or 2"):
        from_table(CandidateConfig, {"refine_min_views": 1}, "run.toml: recon")


def test_a_hand_in_a_silhouette_merged_with_a_taller_person_takes_its_own_heads_top():
    """cam1 sees a 1.6 m person's hand in one silhouette with a 1.95 m person farther away
    behind him: the silhouette's top row is the farther head's, the hand sits much lower in
    it than in cam0, where the short person stands alone, and p_o rejects the pair. With the
    tracked heads' crowns (tops_from_heads, the default) the top is the crown of the head
    nearest to the hand, and the pair is kept; with no crowns, or one in the silhouette,
    nothing changes."""
    rig = _rig(2)
    short, tall = np.array([3.0, 2.0, 1.6]), np.array([1.0, 3.4, 1.95])
    hand = np.array([[3.0, 2.05, 1.1]])
    obs = [
        _people(rig.cameras[0], short[None], hand),
        _people(rig.cameras[1], np.array([short, tall]), hand),
    ]
    on = dataclasses.replace(CFG, tops_from_heads=True)
    off = dataclasses.replace(CFG, tops_from_heads=False)
    crowns = np.array([short, tall])
    assert len(make_candidates(obs, rig, off, crowns_m=crowns).points_m) == 0
    assert len(make_candidates(obs, rig, on).points_m) == 0  # no tracked heads yet
    assert len(make_candidates(obs, rig, on, crowns_m=crowns[:1]).points_m) == 0
    cs = make_candidates(obs, rig, on, crowns_m=crowns)
    np.testing.assert_allclose(cs.points_m, hand, atol=1e-6)
    assert cs.prior[0] > 0.7


def _with_boxes(obs: CameraObservation) -> CameraObservation:
    """``obs`` whose silhouettes know their bounding boxes, as a run's do."""
    sil = obs.silhouettes
    box = np.array([cv2.boundingRect((sil.labels == 1).view(np.uint8))], np.int32)
    return dataclasses.replace(obs, silhouettes=dataclasses.replace(sil, boxes_px=box))


def test_a_silhouette_that_lost_its_head_takes_the_tracked_heads_top():
    """cam0's background model lost the person's head (dark hair against a dark door): the
    silhouette ends at the shoulders, the hand sits lower in it than in cam1, and p_o
    rejects the pair. With ``headless_top_m`` the top is the crown of the tracked head
    just above the silhouette; a head farther from Z than that, or no tracked head,
    changes nothing, and so does the setting off (0)."""
    rig = _rig(2)
    crown = np.array([3.0, 2.0, 1.85])
    hand = np.array([[3.0, 2.15, 1.3]])  # raised
    shoulders = np.array([[3.0, 2.0, 1.4]])
    obs = [
        _with_boxes(_people(rig.cameras[0], shoulders, hand)),
        _with_boxes(_people(rig.cameras[1], crown[None], hand)),
    ]
    off = dataclasses.replace(CFG, headless_top_m=0.0)
    on = CFG
    assert on.headless_top_m == 0.5  # on by default
    assert len(make_candidates(obs, rig, off, crowns_m=crown[None]).points_m) == 0
    assert len(make_candidates(obs, rig, on).points_m) == 0
    far = crown + [0.0, 0.6, 0.0]  # above the silhouette in cam0, but 0.6 m from the hand
    assert len(make_candidates(obs, rig, on, crowns_m=far[None]).points_m) == 0
    cs = make_candidates(obs, rig, on, crowns_m=crown[None])
    np.testing.assert_allclose(cs.points_m, hand, atol=1e-6)
    assert cs.prior[0] > 0.7


def _noisy(obs: CameraObservation, rng: np.random.Generator, px: float) -> CameraObservation:
    blobs = obs.blobs
    moved = blobs.centroids_px + rng.normal(scale=px, size=blobs.centroids_px.shape)
    return dataclasses.replace(obs, blobs=dataclasses.replace(blobs, centroids_px=moved))


@pytest.mark.parametrize("min_views", [3, 0])
def test_candidates_seen_by_four_views_are_refined_from_all_of_them(rng, min_views):
    """Blob centres one pixel off: a candidate four views support moves from its best
    pair's midpoint to the least-squares point of its four lines of sight, nearer the
    target (``refine_min_views``); with the refinement off it stays at the midpoint."""
    rig = _rig()
    targets = np.array([[2.5, 1.5, 1.6], [3.6, 2.5, 1.1], [3.0, 1.2, 1.3]])
    cfg = CandidateConfig(refine_min_views=min_views)
    err = {}
    for refine in (cfg, CandidateConfig(refine_min_views=0)):
        found = []
        for trial in range(30):
            noise = np.random.default_rng(trial)
            obs = [_noisy(_observation(cam, targets), noise, 1.0) for cam in rig]
            cs = make_candidates(obs, rig, refine)
            d = np.linalg.norm(cs.points_m[:, None] - targets[None], axis=2)
            found.append(d.min(axis=0))
        err[refine is cfg] = np.median(np.concatenate(found))
    if min_views:
        assert err[True] < 0.9 * err[False]
    else:
        assert err[True] == err[False]


def test_refinement_leaves_out_a_supporting_blob_of_another_limb():
    """Three views see a hand; a fourth view's blob of the other hand, 6 px from the
    projection, supports it too. The first least-squares point leans towards that line of
    sight; the second solve leaves it out and finds the hand. A candidate two views
    support keeps its midpoint."""
    rig = _rig()
    hand = np.array([3.0, 2.0, 1.0])
    lines = [cam.backproject(cam.project(hand[None])[0]) for cam in rig]
    origins = np.array([o for o, _ in lines])
    dirs = np.array([d[0] for _, d in lines])
    cam3 = rig.cameras[3]
    px = cam3.project(hand[None])[0] + [6.0, 0.0]
    o3, d3 = cam3.backproject(px)
    origins = np.vstack([origins, o3])  # global blob 4: cam3's blob 1
    dirs = np.vstack([dirs, d3])
    first_blob = np.array([0, 1, 2, 3])
    support = np.array([[0, 0, 0, 1], [0, 0, -1, -1]])
    start = np.array([hand + [0.02, 0.0, 0.0], hand + [0.01, 0.01, 0.0]])
    out = refine_from_views(start, support, first_blob, origins, dirs, 3, 0.03)
    np.testing.assert_allclose(out[0], hand, atol=1e-6)
    np.testing.assert_array_equal(out[1], start[1])
    kept = refine_from_views(start, support, first_blob, origins, dirs, 3, 1.0)
    assert np.linalg.norm(kept[0] - hand) > 0.005  # with the far line in, it leans
