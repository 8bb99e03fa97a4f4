"""Labelling cues: head / hand, person, left / right, angle rule (section 7.1)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from surveil.datatypes import BlobSet, CameraObservation, Limb, Silhouettes
from surveil.tracking import LabellingConfig
from surveil.tracking import labelling as lab

CFG = LabellingConfig()


def test_head_log_odds_orders_head_above_hands():
    pos = np.array([[0.0, 0.0, 1.7], [0.05, 0.25, 0.8], [0.05, -0.25, 0.8]])
    below = lab.below_another(pos, CFG)
    llr = lab.head_log_odds(pos[:, 2], np.zeros(3), below, np.full(3, np.nan), CFG)
    assert below.tolist() == [False, True, True]
    assert llr[0] > CFG.decide_llr and np.all(llr[1:] < -CFG.decide_llr)


def test_silhouette_and_speed_cues():
    z = np.full(3, CFG.head_z_mid_m)  # height neutral
    llr = lab.head_log_odds(
        z, np.array([0.0, 0.0, 2.0]), np.zeros(3, bool), np.array([0.02, 0.4, np.nan]), CFG
    )
    assert llr[0] > 0 > llr[1] and llr[2] == pytest.approx(-CFG.speed_llr)


def test_hand_joins_the_clearly_nearest_person_with_a_free_slot():
    heads = np.array([[0.0, 0, 1.7], [1.2, 0, 1.7]])
    hand = np.array([0.3, 0.2, 1.0])
    assert lab.nearest_person(hand, heads, np.array([0, 0]), CFG) == 0
    assert lab.nearest_person(hand, heads, np.array([2, 0]), CFG) == -1  # both hands taken
    assert lab.nearest_person(np.array([0.6, 0, 1.0]), heads, np.array([0, 0]), CFG) == -1
    assert lab.nearest_person(np.array([5.0, 0, 1.0]), heads, np.array([0, 0]), CFG) == -1


@pytest.mark.parametrize("facing_deg", [0, 90, 200, 300])
def test_left_right_follows_facing(facing_deg):
    f = np.radians(facing_deg)
    facing = np.array([np.cos(f), np.sin(f)])
    left = np.array([-facing[1], facing[0]])
    head = np.array([1.0, 2.0, 1.7])
    hands = np.array([[*(head[:2] - 0.25 * left), 0.8], [*(head[:2] + 0.25 * left), 0.8]])
    assert lab.decide_left_right(hands, head, facing) == (Limb.RIGHT_HAND, Limb.LEFT_HAND)
    assert lab.decide_left_right(hands[1:], head, facing) == (Limb.LEFT_HAND,)


def test_facing_cues_walking_and_social():
    head = np.array([0.0, 0.0, 1.7])
    walk = lab.facing_cues(head, np.array([0.0, 1.0, 0]), np.zeros((0, 3)), np.zeros((0, 3)), CFG)
    assert walk[1] > 0 and walk[0] == 0
    social = lab.facing_cues(head, np.zeros(3), np.zeros((0, 3)), np.array([[-1.0, 0, 1.6]]), CFG)
    assert social[0] < 0 and social[1] == 0
    # a standing head's filter speed passes 0.3 m/s in 1-3 % of frames (docs/tracking.md):
    # that is not walking, or a person facing the other way gets their hands swapped
    jitter = lab.facing_cues(
        head, np.array([0.4, 0.1, 0]), np.zeros((0, 3)), np.zeros((0, 3)), CFG
    )
    assert np.allclose(jitter, 0)
    slow_walk = lab.facing_cues(
        head, np.array([0.7, 0, 0]), np.zeros((0, 3)), np.zeros((0, 3)), CFG
    )
    assert slow_walk[0] > 0
    # hands hanging at the sides give no evidence
    rest = np.array([[0.0, 0.25, 0.8], [0.0, -0.25, 0.8]])
    assert np.allclose(lab.facing_cues(head, np.zeros(3), rest, np.zeros((0, 3)), CFG), 0)


def test_angle_rule_keeps_or_swaps():
    before = np.array([0.4, 0.0, 0.0])  # B was 40 cm to the +x of A
    back = lab.angle_rule(before, np.array([-0.2, 0, 0]), np.array([0.2, 0, 0]))
    crossed = lab.angle_rule(before, np.array([0.2, 0, 0]), np.array([-0.2, 0, 0]))
    assert back[0] == (0, 1) and back[1] == pytest.approx(0.0)
    assert crossed[0] == (1, 0) and crossed[1] == pytest.approx(np.pi)
    # 60 degrees off is still "the same side"
    tilted = lab.angle_rule(before, np.zeros(3), np.array([0.1, 0.17, 0]))
    assert tilted[0] == (0, 1)


def _observations_of_a_person(rig, centre_xy, *, scale: int = 1):
    """Silhouettes (at 1/scale resolution) of one person, a 0.2 m radius column 1.8 m high."""
    ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    z = np.linspace(0.0, 1.8, 19)
    body = np.array(
        [
            [centre_xy[0] + 0.2 * np.cos(a), centre_xy[1] + 0.2 * np.sin(a), h]
            for a in ang
            for h in z
        ]
    )
    out = {}
    for cam in rig.cameras:
        h, w = cam.height // scale, cam.width // scale
        mask = np.zeros((h, w), np.uint8)
        px, depth = cam.project(body)
        ok = cam.in_image(px, depth)
        hull = cv2.convexHull((px[ok] / scale).astype(np.int32))
        cv2.fillConvexPoly(mask, hull, 1)
        dist = cv2.distanceTransform((1 - mask).astype(np.uint8), cv2.DIST_L2, 3)
        sil = Silhouettes(mask.astype(np.int32), np.zeros(1), np.ones(1), dist.astype(np.float32))
        blobs = BlobSet.empty((h, w))
        out[cam.name] = CameraObservation(cam.name, sil, np.zeros((h, w), bool), blobs)
    return out


@pytest.mark.parametrize("scale", [1, 2])
def test_a_head_has_a_body_under_it_and_a_ghost_does_not(rig, scale):
    obs = _observations_of_a_person(rig, (2.0, 2.0), scale=scale)
    cfg = LabellingConfig()
    assert lab.body_support(np.array([2.0, 2.0, 1.75]), rig, obs, cfg) == 1.0
    # a ghost 60 cm beside the person at head height: some camera sees floor under it
    assert lab.body_support(np.array([2.6, 2.0, 1.5]), rig, obs, cfg) < cfg.body_support_min
    # too few cameras: no verdict
    one = {"cam0": obs["cam0"]}
    assert lab.body_support(np.array([2.0, 2.0, 1.75]), rig, one, cfg) is None


def test_owner_rule_gives_each_hand_the_mode_by_its_head_or_abstains():
    heads = np.array([[2.0, 2.0, 1.7], [3.0, 2.0, 1.7]])
    home_a, home_b = np.array([2.0, 1.75, 0.8]), np.array([3.0, 2.25, 0.8])
    assert lab.owner_rule(np.array([home_a, home_b]), heads, 0.2)[0] == (0, 1)
    assert lab.owner_rule(np.array([home_b, home_a]), heads, 0.2)[0] == (1, 0)
    # both modes still in the middle: no clear owner, the angle rule decides
    middle = np.array([[2.5, 2.0, 1.05], [2.52, 2.0, 0.8]])
    assert lab.owner_rule(middle, heads, 0.2) is None


def test_astray_needs_out_of_own_reach_and_within_anothers():
    cfg = LabellingConfig()
    own, other = np.array([2.0, 2.0, 1.7]), np.array([[3.0, 2.0, 1.7]])
    assert lab.astray(np.array([3.0, 2.25, 0.8]), own, other, cfg)  # at the other's side
    assert not lab.astray(np.array([2.5, 2.0, 1.05]), own, other, cfg)  # handshake: in reach
    # far from its head but nobody else's either (a tall person's hand hanging, a long reach)
    assert not lab.astray(np.array([3.0, 2.0, 0.8]), own, np.array([[4.5, 2.0, 1.7]]), cfg)
    assert not lab.astray(np.array([3.0, 2.25, 0.8]), own, np.empty((0, 3)), cfg)


def test_owned_elsewhere_tells_a_ghost_on_another_body_from_a_hand_held_out():
    cfg = LabellingConfig()
    heads = np.array([[0.0, 0.0, 1.7], [1.2, 0.0, 1.7]])
    hanging = np.array([0.0, -0.25, 0.8])  # person 0's own hand, 0.93 m from its head
    ghost = np.array([0.85, 0.0, 0.95])  # in front of person 1's body
    midway = np.array([0.6, 0.1, 1.1])  # held out to shake person 1's hand
    assert lab.owned_elsewhere(ghost, hanging, heads, 0, cfg)
    assert not lab.owned_elsewhere(midway, hanging, heads, 0, cfg)
    # the challenger must be clearly more person 0's than the holder
    assert not lab.owned_elsewhere(ghost, ghost + [0.05, 0, 0], heads, 0, cfg)
    # one person alone: nothing to compare with
    assert not lab.owned_elsewhere(ghost, hanging, heads[:1], 0, cfg)


@pytest.mark.parametrize(
    ("challenger_y", "side_m", "expected"),
    [
        (-0.3, 0.1, [True, False, False]),  # on the right: only the clearly-left hand is across
        (0.3, 0.1, [False, True, False]),  # on the left: only the clearly-right hand
        (0.05, 0.1, [False, False, False]),  # in front of the body: no side to be on
        (-0.3, 0.0, [False, False, False]),  # the check off
    ],
)
def test_across_body_needs_both_hands_clearly_on_their_sides(challenger_y, side_m, expected):
    # a person at the origin facing +x: left is +y; hands at +0.25, -0.2 and +0.05 m
    hands = np.array([[0.2, 0.25, 1.0], [0.0, -0.2, 0.8], [0.3, 0.05, 1.1]])
    head, facing = np.array([0.0, 0.0, 1.7]), np.array([2.0, 0.0])
    got = lab.across_body(hands, np.array([0.1, challenger_y, 1.0]), head, facing, side_m)
    assert got.tolist() == expected
    # turning the person round swaps its sides
    flipped = lab.across_body(hands, np.array([0.1, challenger_y, 1.0]), head, -facing, side_m)
    assert flipped.tolist() == expected


def test_head_skin_share_counts_skin_around_the_head_and_abstains_where_it_cannot(rig):
    obs = _observations_of_a_person(rig, (2.5, 2.0))
    cam = rig["cam0"]
    head = np.array([2.5, 2.0, 1.7])
    (u, v), depth = (x[0] for x in cam.project(head[None]))
    r = 0.1 * cam.K[0, 0] / depth
    skin = np.zeros_like(obs["cam0"].skin)
    skin[round(v) : round(v + r) + 1, round(u - r) : round(u + r) + 1] = True  # lower half
    seen = CameraObservation("cam0", obs["cam0"].silhouettes, skin, obs["cam0"].blobs)
    assert lab.head_skin_share(head, seen, cam, 0.1) == pytest.approx(0.5, abs=0.1)
    assert lab.head_skin_share(head, obs["cam0"], cam, 0.1) == 0.0  # hair only
    # a skin-coloured board on the wall behind the head is not face: only the person's
    # pixels count (three_people, cam0: the cork board behind p3)
    board = obs["cam0"].silhouettes.labels == 0
    behind = CameraObservation("cam0", obs["cam0"].silhouettes, board, obs["cam0"].blobs)
    wide = 2.5 * r  # a square of half-side 0.25 m reaches above the head
    square = board[round(v - wide) : round(v + wide) + 1, round(u - wide) : round(u + wide) + 1]
    assert square.mean() > 0.2  # the board fills a good part of the square
    assert lab.head_skin_share(head, behind, cam, 0.25) == 0.0
    # nobody there (off every silhouette), behind the camera, or cut by the image border
    assert np.isnan(lab.head_skin_share(np.array([4.5, 3.5, 1.7]), seen, cam, 0.1))
    assert np.isnan(lab.head_skin_share(cam.centre_m - [1.0, 1.0, 0.0], seen, cam, 0.1))
    assert np.isnan(lab.head_skin_share(head, seen, cam, 3.0))


@pytest.mark.parametrize("facing_deg", [0.0, 60.0, 135.0, -100.0])
def test_face_cue_points_where_the_face_is_seen(rig, facing_deg):
    cams = np.array([c.centre_m for c in rig.cameras])
    f = np.radians(facing_deg)
    fwd = np.array([np.cos(f), np.sin(f)])
    for head in (np.array([2.5, 2.0, 1.7]), np.array([4.5, 1.0, 1.7])):  # middle, by a wall
        to_cam = cams[:, :2] - head[:2]
        to_cam /= np.linalg.norm(to_cam, axis=1, keepdims=True)
        shares = 0.35 + 0.25 * to_cam @ fwd  # face ~0.6 from the front, hair ~0.1 behind
        ev = lab.face_cue(head, cams, shares, 1.0)
        assert np.degrees(abs(np.angle(complex(*ev) / complex(*fwd)))) < 1.0
        assert np.linalg.norm(ev) == pytest.approx(0.25, abs=0.01)
        assert np.linalg.norm(lab.face_cue(head, cams, shares, 2.0)) == pytest.approx(0.5, 0.05)
        # a head alike from everywhere, or seen by one camera only, says nothing
        assert np.allclose(lab.face_cue(head, cams, np.full(4, 0.6), 1.0), 0.0)
        one = np.array([shares[0], np.nan, np.nan, np.nan])
        assert np.allclose(lab.face_cue(head, cams, one, 1.0), 0.0)
    # two cameras facing each other across the person: along the line between them
    two = lab.face_cue(np.zeros(3), np.array([[3.0, 0, 2], [-3.0, 0, 2]]), np.array([0.6, 0.1]), 1)
    assert two.tolist() == pytest.approx([0.25, 0.0])


DROPS = np.outer(lab.BODY_AXIS_DROPS_M, (0.0, 0.0, 1.0))


def _axis_error_deg(ev: np.ndarray, facing_deg: float) -> float:
    """Angle between the axis of doubled-angle evidence ``ev`` and a facing, 0-90."""
    phi = np.degrees(0.5 * np.arctan2(ev[1], ev[0]))
    return abs((phi - facing_deg + 90.0) % 180.0 - 90.0)


def _widths(rig, obs, head, others=None):
    return np.array(
        [
            lab.silhouette_width_m(
                obs[c.name].silhouettes.labels, c, head - DROPS, 0.8, others_m=others
            )
            for c in rig.cameras
        ]
    )


@pytest.mark.parametrize("facing_deg", [0.0, 35.0, 100.0, -60.0])
def test_body_axis_from_silhouette_widths(rig, draw_bodies, facing_deg):
    cams = np.array([c.centre_m for c in rig.cameras])
    for centre in ((3.6, 1.3), (1.2, 2.8), (3.0, 2.2)):  # off the middle of the rig
        head = np.array([*centre, 1.65])
        widths = _widths(rig, draw_bodies((centre, facing_deg, 0.25, 0.12)), head)
        # every camera measures a body between its depth and its width across
        assert np.all((widths > 2 * 0.12 * 0.9) & (widths < 2 * 0.25 * 1.2))
        ev = lab.body_axis_cue(head, cams, widths, 0.3)
        assert np.linalg.norm(ev) == pytest.approx(1.0)  # a clear contrast: full weight
        assert _axis_error_deg(ev, facing_deg) < 10.0
        # a round body says less (its widths differ by a few pixels at 320 x 240: rounding,
        # and rows cut a body that the perspective tilts obliquely), too few views nothing
        round_widths = _widths(rig, draw_bodies((centre, facing_deg, 0.2, 0.2)), head)
        assert np.linalg.norm(lab.body_axis_cue(head, cams, round_widths, 0.3)) < 0.5
        two = np.where(np.arange(4) < 2, widths, np.nan)
        assert np.allclose(lab.body_axis_cue(head, cams, two, 0.3), 0.0)


def test_body_axis_between_four_corner_cameras_is_sided_but_coarse(rig, draw_bodies):
    # in the middle of the rig the cameras are two pairs of opposite views: their doubled
    # angles lie on one line, and only which diagonal the front is nearer is known
    cams = np.array([c.centre_m for c in rig.cameras])
    head = np.array([2.5, 2.0, 1.65])
    for facing_deg in (35.0, -60.0, 100.0):
        ev = lab.body_axis_cue(
            head, cams, _widths(rig, draw_bodies(((2.5, 2.0), facing_deg, 0.25, 0.12)), head), 0.3
        )
        assert _axis_error_deg(ev, facing_deg) < 40.0
    # facing a wall square on: every view sees the same width, so there is no evidence
    flat = _widths(rig, draw_bodies(((2.5, 2.0), 0.0, 0.25, 0.12)), head)
    assert np.linalg.norm(lab.body_axis_cue(head, cams, flat, 0.3)) < 0.05


def test_silhouette_width_of_a_person_merged_with_another(rig, draw_bodies):
    # two people side by side 0.45 m apart: their silhouettes merge in the cameras that see
    # them one beside the other; the free side of the run, doubled, still measures the body
    a, b = (2.8, 1.6), (2.8, 2.05)
    head_a = np.array([*a, 1.65])
    alone = _widths(rig, draw_bodies((a, 0.0, 0.22, 0.12)), head_a)
    both = draw_bodies((a, 0.0, 0.22, 0.12), (b, 0.0, 0.22, 0.12))
    merged = _widths(rig, both, head_a)
    fair = _widths(rig, both, head_a, others=np.array([[*b, 1.35]]))
    assert np.nanmax(merged / alone) > 1.5  # without knowing of b, some run holds both
    ok = np.isfinite(fair)
    assert ok.sum() >= 3
    assert np.allclose(fair[ok], alone[ok], rtol=0.15)


def test_facing_takes_the_axis_angle_and_the_evidence_sign():
    axis_ev = 1.5 * np.array([np.cos(np.radians(60)), np.sin(np.radians(60))])  # phi = 30
    for evidence_deg, expected_deg in ((70.0, 30.0), (-10.0, 30.0), (150.0, 210.0)):
        ev = 0.8 * np.array([np.cos(np.radians(evidence_deg)), np.sin(np.radians(evidence_deg))])
        out = lab.facing_on_axis(ev, axis_ev, 1.0)
        assert np.linalg.norm(out) == pytest.approx(0.8)  # the evidence's strength stays
        got = np.degrees(np.arctan2(out[1], out[0])) % 360
        assert got == pytest.approx(expected_deg % 360)
    ev = np.array([0.3, 0.5])
    assert lab.facing_on_axis(ev, 0.5 * axis_ev, 1.0).tolist() == ev.tolist()  # weak axis
    square = np.array([-np.sin(np.radians(30)), np.cos(np.radians(30))])  # along no side
    assert lab.facing_on_axis(square, axis_ev, 1.0) == pytest.approx(square)
