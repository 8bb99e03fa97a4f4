"""MultiTargetTracker on constructed candidate sequences: every transition, labels, speed."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from surveil.datatypes import (
    BlobSet,
    CameraObservation,
    CandidateSet,
    Phase,
    Silhouettes,
    TrackFrame,
)
from surveil.tracking import (
    FilterConfig,
    LabellingConfig,
    LifecycleConfig,
    MultiTargetTracker,
    TrackingConfig,
)

DT_NS = 66_666_667  # 15 fps


# these tests follow lone points (no person around them): never retire them as unclaimed
LONE = TrackingConfig(lifecycle=LifecycleConfig(retire_unclaimed_s=0.0))


def body(centre_xy, facing_deg: float) -> dict[str, np.ndarray]:
    """Head and hands at rest of a person standing at centre_xy facing facing_deg."""
    f = np.radians(facing_deg)
    fwd = np.array([np.cos(f), np.sin(f), 0.0])
    left = np.array([-fwd[1], fwd[0], 0.0])
    c = np.array([*centre_xy, 0.0])
    return {
        "head": c + [0, 0, 1.7],
        "left_hand": c + 0.25 * left + [0, 0, 0.8],
        "right_hand": c - 0.25 * left + [0, 0, 0.8],
        "fwd": fwd,
        "left": left,
    }


def candidates(points, rng, *, noise_m=0.005, clutter=0) -> CandidateSet:
    pts = [np.asarray(p, dtype=float) + rng.normal(0, noise_m, 3) for p in points]
    pri = [0.9] * len(pts)
    for _ in range(clutter):
        pts.append(rng.uniform([0, 0, 0], [5, 4, 2]))
        pri.append(0.1)
    if not pts:
        return CandidateSet.empty()
    return CandidateSet(np.array(pts), np.array(pri))


def merged(points, radius_m=0.08):
    """Like the candidate stage: points closer than radius_m merge into their midpoint."""
    out: list[np.ndarray] = []
    for p in points:
        for i, q in enumerate(out):
            if np.linalg.norm(p - q) < radius_m:
                out[i] = (p + q) / 2
                break
        else:
            out.append(np.asarray(p, dtype=float))
    return out


def by_label(frame: TrackFrame) -> dict[str, np.ndarray]:
    return {s.label: s.mean_m for s in frame.targets}


def run(trk, frames, rng, **kw) -> list[TrackFrame]:
    return [trk.step(i * DT_NS, candidates(pts, rng, **kw)) for i, pts in enumerate(frames)]


def test_filter_converges_on_a_moving_point_with_clutter(rig, rng):
    trk = MultiTargetTracker(LONE, rig, seed=1)
    truth = [np.array([1.0 + 1.0 * i / 15, 2.0, 1.0 + 0.3 * np.sin(i / 5)]) for i in range(45)]
    out = run(trk, [[p] for p in truth], rng, noise_m=0.01, clutter=5)
    assert all(len(f.targets) == 1 for f in out[2:])  # weak clutter starts no tracker
    err = [
        np.linalg.norm(f.targets[0].mean_m - p) for f, p in zip(out[25:], truth[25:], strict=True)
    ]
    assert np.mean(err) < 0.03 and max(err) < 0.06
    assert out[-1].particles_m.shape == (200, 3) and out[-1].particles_m.dtype == np.float32
    assert set(out[-1].particle_owner.tolist()) == {out[-1].targets[0].target_id}


def test_a_one_frame_ghost_starts_no_tracker(rig, rng):
    trk = MultiTargetTracker(LONE, rig, seed=0)
    frames = [[], [np.array([2.0, 2.0, 1.0])], [], []]
    assert all(not f.targets and not f.transitions for f in run(trk, frames, rng))


def two_people_frames(n: int, b_from: int):
    a, b = body((2.0, 2.0), 0.0), body((3.2, 2.0), 180.0)
    limbs = ("head", "left_hand", "right_hand")
    return [
        [a[k] for k in limbs] + ([b[k] for k in limbs] if i >= b_from else []) for i in range(n)
    ]


def test_two_people_are_labelled_and_grouped(rig, rng):
    trk = MultiTargetTracker(LONE, rig, seed=3)
    out = run(trk, two_people_frames(75, b_from=20), rng)
    a, b = body((2.0, 2.0), 0.0), body((3.2, 2.0), 180.0)
    labels = by_label(out[-1])
    # the candidates are skin points: a head's face lies below its centre, so a head is
    # reported raised by head_centre_rise_m and a hand where its skin is
    rise = np.array([0.0, 0.0, LONE.head_centre_rise_m])
    expected = {f"p1/{k}": a[k] for k in ("left_hand", "right_hand")}
    expected |= {f"p2/{k}": b[k] for k in ("left_hand", "right_hand")}
    expected |= {"p1/head": a["head"] + rise, "p2/head": b["head"] + rise}
    assert LONE.head_centre_rise_m > 0
    assert set(labels) == set(expected)
    for lbl, pos in expected.items():
        assert np.linalg.norm(labels[lbl] - pos) < 0.03, lbl
    assert all(s.phase is Phase.NORMAL for s in out[-1].targets)
    # the first person was grouped before the second one entered (left / right wait for
    # facing evidence, which the second person provides)
    assert [s.person for s in out[19].targets] == [1, 1, 1]
    assert "p1/head" in {s.label for s in out[19].targets}
    # every tracker went uninitialised -> unlabelled -> normal exactly once
    changes = [(t.old, t.new) for f in out for t in f.transitions]
    assert changes.count((Phase.UNINITIALISED, Phase.UNLABELLED)) == 6
    assert changes.count((Phase.UNLABELLED, Phase.NORMAL)) == 6


def test_disappear_reappear_keeps_id_and_label(rig, rng):
    frames = two_people_frames(80, b_from=0)
    for i in range(45, 53):  # p1's left hand hidden for 8 frames
        frames[i] = [p for k, p in enumerate(frames[i]) if k != 1]
    trk = MultiTargetTracker(LONE, rig, seed=4)
    out = run(trk, frames, rng)
    hand = next(s for s in out[44].targets if s.label == "p1/left_hand")
    mine = [
        (i, t) for i, f in enumerate(out) for t in f.transitions if t.target_id == hand.target_id
    ]
    phases = [(t.old.value, t.new.value) for i, t in mine if i >= 45]
    assert phases == [("normal", "lost"), ("lost", "unlabelled"), ("unlabelled", "normal")]
    lost_at = next(i for i, t in mine if t.new is Phase.LOST)
    back_at = next(i for i, t in mine if t.old is Phase.LOST)
    assert 46 <= lost_at <= 49 and 53 <= back_at <= 56
    assert all(t.label == "p1/left_hand" for _, t in mine if _ >= 45)
    assert by_label(out[-1])["p1/left_hand"] is not None


@pytest.mark.parametrize("typed", [True, False])
def test_a_crown_head_supports_a_head_and_no_hand(rig, rng, typed):
    """A candidate marked head_only (a crown head) keeps a head's tracker; in place of a
    hand's candidate it does not keep the hand's: the hand goes lost."""
    frames = two_people_frames(70, b_from=0)
    cfg = dataclasses.replace(LONE, filter=FilterConfig(heads_only_for_heads=typed))
    trk = MultiTargetTracker(cfg, rig, seed=4)
    out = run(trk, frames[:40], rng)
    ids = {s.label: s.target_id for s in out[-1].targets}
    head_only = np.array([True, False, True, False, False, False])  # p1's head, right hand
    for i, pts in enumerate(frames[40:], start=40):
        c = candidates(pts, rng)
        out.append(trk.step(i * DT_NS, dataclasses.replace(c, head_only=head_only)))
    phases = {s.target_id: s.phase for s in out[-1].targets}
    assert phases[ids["p1/head"]] is Phase.NORMAL
    assert phases[ids["p1/left_hand"]] is Phase.NORMAL
    assert phases[ids["p1/right_hand"]] is (Phase.LOST if typed else Phase.NORMAL)
    if typed:  # nor is the tracker that the crown head starts typed as a hand
        labels = {s.label for s in out[-1].targets if s.phase is not Phase.LOST}
        assert "p1/right_hand" not in labels


def test_a_person_who_leaves_is_retired(rig, rng):
    frames = two_people_frames(40, b_from=0)[:30] + [[]] * 25
    cfg = TrackingConfig(lifecycle=LifecycleConfig(retire_s=1.0))
    out = run(MultiTargetTracker(cfg, rig, seed=5), frames, rng)
    changes = [(t.old, t.new) for f in out for t in f.transitions]
    assert changes.count((Phase.NORMAL, Phase.LOST)) == 6
    assert changes.count((Phase.LOST, Phase.UNINITIALISED)) == 6
    assert all(s.phase is Phase.LOST for s in out[40].targets)
    assert out[-1].targets == () and len(out[-1].particles_m) == 0


def test_sides_guessed_wrong_are_swapped_once_the_person_reaches_forward(rig, rng):
    # a lone person standing still facing away from the middle of the rig: left / right are
    # guessed (facing the middle), wrongly; then both hands reach forward and stay apart
    a = body((3.5, 2.0), 0.0)
    rest = [a["left_hand"], a["right_hand"]]
    ahead = [a["head"] + 0.35 * a["fwd"] + s * 0.15 * a["left"] - [0, 0, 0.6] for s in (1, -1)]
    frames = [[a["head"], *rest]] * 40 + [
        [a["head"], *(r + min(i / 10, 1.0) * (h - r) for r, h in zip(rest, ahead, strict=True))]
        for i in range(1, 41)
    ]
    out = run(MultiTargetTracker(LONE, rig, seed=2), frames, rng)
    guessed = by_label(out[39])
    assert guessed["p1/left_hand"][1] < a["head"][1]  # the guess put the left hand on the right
    final = by_label(out[-1])
    assert np.linalg.norm(final["p1/left_hand"] - ahead[0]) < 0.03
    assert np.linalg.norm(final["p1/right_hand"] - ahead[1]) < 0.03
    swapped_at = next(
        i for i, f in enumerate(out) if i > 40 and by_label(f)["p1/left_hand"][1] > a["head"][1]
    )
    assert swapped_at <= 40 + 30  # about lr_revise_s (15 frame sets) after the reach
    # with revision off the guess stands
    cfg = TrackingConfig(
        lifecycle=LONE.lifecycle, labelling=LabellingConfig(lr_revise_evidence=0.0)
    )
    kept = by_label(run(MultiTargetTracker(cfg, rig, seed=2), frames, rng)[-1])
    assert np.linalg.norm(kept["p1/right_hand"] - ahead[0]) < 0.03


def face_views(rig, head_m, fwd, radius_m=0.1) -> dict[str, CameraObservation]:
    """Every camera's frame all silhouette, with skin over the head's square in the cameras
    the face looks towards (within 90 degrees of ``fwd``) and none in the others (hair)."""
    out = {}
    for cam in rig.cameras:
        h, w = cam.height, cam.width
        skin = np.zeros((h, w), bool)
        to_cam = cam.centre_m[:2] - head_m[:2]
        if to_cam @ fwd[:2] > 0:
            (u, v), depth = (x[0] for x in cam.project(head_m[None]))
            r = radius_m * cam.K[0, 0] / depth
            skin[round(v - r) : round(v + r) + 1, round(u - r) : round(u + r) + 1] = True
        sil = Silhouettes(
            np.ones((h, w), np.int32),
            np.zeros(1),
            np.full(1, h - 1.0),
            np.zeros((h, w), np.float32),
        )
        blobs = BlobSet.empty((h, w))
        out[cam.name] = CameraObservation(cam.name, sil, skin, blobs)
    return out


def test_a_still_person_seen_face_on_is_sided_by_the_face(rig, rng):
    # a lone person standing still facing away from the middle of the rig, hands at rest:
    # no motion or hand cue says where they face; the cameras in front see the face
    a = body((3.5, 2.0), 0.0)
    frames = [[a["head"], a["left_hand"], a["right_hand"]]] * 40
    obs = face_views(rig, a["head"], a["fwd"])
    cfg = TrackingConfig(lifecycle=LONE.lifecycle, labelling=LabellingConfig(face_weight=1.0))
    trk = MultiTargetTracker(cfg, rig, seed=2)
    out = [trk.step(i * DT_NS, candidates(pts, rng), obs) for i, pts in enumerate(frames)]
    sided = by_label(out[-1])
    assert sided["p1/left_hand"][1] > a["head"][1] > sided["p1/right_hand"][1]
    facing = trk.person_facing(1)
    assert np.degrees(abs(np.arctan2(facing[1], facing[0]))) < 10
    # without the face cue the sides are guessed (facing the middle of the rig): wrong
    guessed = run(MultiTargetTracker(LONE, rig, seed=2), frames, rng)
    assert by_label(guessed[-1])["p1/left_hand"][1] < a["head"][1]


@pytest.mark.parametrize("top_to_centre_m", [0.11, 0.0])
def test_a_head_is_reported_below_the_crown_its_silhouettes_show(
    rig, draw_person, rng, top_to_centre_m
):
    # the head's skin point is a neck seen from behind, 12 cm below the head's centre (not
    # the 4 cm of a face that head_centre_rise_m assumes): the silhouettes' crown, 11 cm
    # above the centre, tells; with the measure off the fixed rise stands
    a = body((2.5, 2.0), 0.0)
    centre_z = a["head"][2] + 0.12
    obs = draw_person(a["head"][:2], centre_z + 0.11, 0.11)
    cfg = TrackingConfig(lifecycle=LONE.lifecycle, head_top_to_centre_m=top_to_centre_m)
    trk = MultiTargetTracker(cfg, rig, seed=4)
    frames = [[a["head"], a["left_hand"], a["right_hand"]]] * 40
    out = [trk.step(i * DT_NS, candidates(pts, rng), obs) for i, pts in enumerate(frames)]
    head = by_label(out[-1])["p1/head"]
    want = centre_z if top_to_centre_m > 0 else a["head"][2] + cfg.head_centre_rise_m
    assert abs(head[2] - want) < 0.02
    # the candidate stage's feedback: the crown, head_top_to_centre_m above the centre
    crowns = trk.expected_crowns(40 * DT_NS)
    assert crowns.shape == (1, 3)
    assert abs(crowns[0, 2] - (head[2] + (top_to_centre_m or 0.125))) < 0.01
    # the hands are where their skin is
    assert np.linalg.norm(by_label(out[-1])["p1/left_hand"] - a["left_hand"]) < 0.03


@pytest.mark.parametrize("facing_deg", [120.0, 40.0, -70.0])
def test_a_reaching_person_is_faced_along_the_silhouettes_body_axis(
    rig, draw_bodies, rng, facing_deg
):
    # a lone person standing still reaches forward with the right hand: the hands' forward
    # excursion says where the front is, but along the normal of the hand-to-hand line,
    # tens of degrees off; the silhouettes' widths across the shoulders give the angle
    a = body((3.3, 1.5), facing_deg)
    reach = a["head"] + 0.45 * a["fwd"] - 0.05 * a["left"] - [0, 0, 0.6]
    frames = [[a["head"], a["left_hand"], reach]] * 45
    obs = draw_bodies(((3.3, 1.5), facing_deg, 0.25, 0.12))
    truth = complex(*a["fwd"][:2])
    errors = []
    for axis_weight in (1.0, 0.0):
        cfg = TrackingConfig(
            lifecycle=LONE.lifecycle, labelling=LabellingConfig(axis_weight=axis_weight)
        )
        trk = MultiTargetTracker(cfg, rig, seed=2)
        out = [trk.step(i * DT_NS, candidates(pts, rng), obs) for i, pts in enumerate(frames)]
        errors.append(abs(np.degrees(np.angle(complex(*trk.person_facing(1)) / truth))))
        sided = by_label(out[-1])
        assert np.linalg.norm(sided["p1/right_hand"] - reach) < 0.05
    assert errors[0] < 5.0 < 30.0 < errors[1]


@pytest.mark.parametrize("lone_m", [0.15, 0.0])
def test_a_lone_tracked_hand_on_the_wrong_side_is_swapped(rig, rng, lone_m):
    # sides guessed wrong (a still person facing away from the middle of the rig); then the
    # face is seen, and the left hand's candidates stop (its tracker is lost): the right
    # hand, labelled left, is 25 cm to the right of the head, and with lr_revise_lone_m the
    # two slots swap (the lost one too); with 0 the guess stands, as the pair rule needs two
    # tracked hands
    a = body((3.5, 2.0), 0.0)
    cfg = TrackingConfig(
        lifecycle=LONE.lifecycle, labelling=LabellingConfig(lr_revise_lone_m=lone_m)
    )
    trk = MultiTargetTracker(cfg, rig, seed=2)
    obs = face_views(rig, a["head"], a["fwd"])
    both, one = [a["head"], a["left_hand"], a["right_hand"]], [a["head"], a["right_hand"]]
    out = [trk.step(i * DT_NS, candidates(both, rng)) for i in range(40)]
    out += [trk.step(i * DT_NS, candidates(one, rng), obs) for i in range(40, 100)]
    assert np.linalg.norm(by_label(out[39])["p1/left_hand"] - a["right_hand"]) < 0.05
    final = {s.label: s for s in out[-1].targets}
    right = min(final.values(), key=lambda s: np.linalg.norm(s.mean_m - a["right_hand"]))
    assert right.label == ("p1/right_hand" if lone_m > 0 else "p1/left_hand")
    assert right.phase is Phase.NORMAL


def test_a_person_who_turns_round_keeps_the_sides_of_their_hands(rig, rng):
    # a still person faces +x, seen face on, for 80 frame sets, then turns round in 0.4 s
    # and stands facing -x: the hands turn with the body, so their labels stay right. The
    # accumulated facing evidence points backwards for more than lr_revise_s after the turn;
    # the last frames' cues already point the new way, so no swap is counted meanwhile
    centre = (3.5, 2.0)
    cfg = TrackingConfig(lifecycle=LONE.lifecycle, labelling=LabellingConfig(axis_weight=0.0))
    trk = MultiTargetTracker(cfg, rig, seed=3)
    out = []
    for i in range(160):
        a = body(centre, 180.0 * min(max(i - 80, 0) / 6, 1.0))
        pts = [a["head"], a["left_hand"], a["right_hand"]]
        out.append(trk.step(i * DT_NS, candidates(pts, rng), face_views(rig, a["head"], a["fwd"])))
        if i in (79, 100, 120, 159):
            sided = by_label(out[-1])
            assert np.linalg.norm(sided["p1/left_hand"] - a["left_hand"]) < 0.05, i
            assert np.linalg.norm(sided["p1/right_hand"] - a["right_hand"]) < 0.05, i


def clap_frames(cross: bool):
    """One person facing the middle of the rig; from frame 35 (after left / right were
    decided) the hands move to a point 35 cm in front of the chest,
    stay 5 frames, then go back to their sides (or, crossing, each to the other side)."""
    p = body((2.5, 1.2), 90.0)
    meet = p["head"] + 0.35 * p["fwd"] - [0, 0, 0.5]
    frames, sides = [], []
    path = [0.0] * 35 + list(np.linspace(0, 1, 9)[1:]) + [1.0] * 5 + list(np.linspace(1, 0, 9)[1:])
    path += [0.0] * 12
    for i, u in enumerate(path):
        back = i >= 35 + 8 + 5
        lh0, rh0 = (
            (p["right_hand"], p["left_hand"])
            if (cross and back)
            else (p["left_hand"], p["right_hand"])
        )
        lh = lh0 + u * (meet + 0.015 * p["left"] - lh0)
        rh = rh0 + u * (meet - 0.015 * p["left"] - rh0)
        frames.append([p["head"], *merged([lh, rh])])
        sides.append((lh, rh))
    return frames, sides, p


@pytest.mark.parametrize("cross", [False, True])
def test_join_and_separate_follow_the_angle_rule(rig, rng, cross):
    frames, sides, p = clap_frames(cross)
    out = run(MultiTargetTracker(LONE, rig, seed=6), frames, rng)
    before = {s.label: s.target_id for s in out[34].targets}
    assert {"p1/left_hand", "p1/right_hand"} <= set(before)
    joins = [t for f in out for t in f.transitions if t.new is Phase.COMBINED]
    splits = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    left_id, right_id = before["p1/left_hand"], before["p1/right_hand"]
    assert sorted((t.target_id, t.partner_id) for t in joins) == sorted(
        [(left_id, right_id), (right_id, left_id)]
    )
    assert sorted(t.new.value for t in splits) == ["unlabelled", "unlabelled"]
    assert {t.label for t in splits} == {"p1/left_hand", "p1/right_hand"}
    final = by_label(out[-1])
    # the rule puts each label on the side its hand came from: right for a clap, wrong
    # (by design of the paper's rule) for hands that cross over
    assert np.linalg.norm(final["p1/left_hand"] - p["left_hand"]) < 0.04
    assert np.linalg.norm(final["p1/right_hand"] - p["right_hand"]) < 0.04
    true_left_final = sides[-1][0]
    assert bool(np.linalg.norm(final["p1/left_hand"] - true_left_final) < 0.04) is (not cross)


@pytest.mark.parametrize("by_sides", [False, True])
def test_a_persons_own_hands_part_by_the_persons_sides_not_a_stale_before_vector(
    rig, rng, by_sides
):
    """The clap's pair, its angle rule's "before" vector reversed while it is combined (as
    when it was last measured with the hands crossed): the paper's angle rule then parts the
    labels onto the wrong sides; with ``own_hands_by_sides`` the person's facing decides, and
    each label ends on its own side."""
    frames, _, p = clap_frames(cross=False)
    labelling = dataclasses.replace(LONE.labelling, own_hands_by_sides=by_sides)
    trk = MultiTargetTracker(dataclasses.replace(LONE, labelling=labelling), rig, seed=6)
    reversed_once: set[int] = set()
    for i, pts in enumerate(frames):
        out = trk.step(i * DT_NS, candidates(pts, rng))
        for tr in trk._tracks.values():
            if tr.phase is Phase.COMBINED and tr.id not in reversed_once:
                tr.before_vec_m = -tr.before_vec_m
                reversed_once.add(tr.id)
    assert len(reversed_once) == 2
    final = by_label(out)
    left_home = bool(np.linalg.norm(final["p1/left_hand"] - p["left_hand"]) < 0.04)
    right_home = bool(np.linalg.norm(final["p1/right_hand"] - p["right_hand"]) < 0.04)
    assert left_home is by_sides and right_home is by_sides


def test_joined_hands_stay_combined_through_missing_candidates(rig, rng):
    """Hands that met head-on keep opposite velocities in their particles; frames without any
    candidate while they are together must not split the pair (the split comes only when two
    candidates part)."""
    frames, _, _ = clap_frames(cross=False)
    joined = range(35 + 8, 35 + 8 + 5)  # the five frames the hands rest together
    frames = [[f[0]] if i in joined and i % 2 else f for i, f in enumerate(frames)]
    out = run(MultiTargetTracker(LONE, rig, seed=7), frames, rng)
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    joins = [i for i, f in enumerate(out) for t in f.transitions if t.new is Phase.COMBINED]
    assert len(joins) == 2 and len(splits) == 2  # one pair, joined once, parted once
    assert min(splits) > max(joined)  # not before the hands move apart
    final = by_label(out[-1])
    assert {"p1/left_hand", "p1/right_hand"} <= set(final)


def test_stray_candidates_beside_joined_hands_do_not_part_them(rig, rng):
    """A candidate that flickers 25-35 cm from joined hands, somewhere new each frame, is two
    modes for a frame but not two targets moving apart: the pair stays combined until the
    hands themselves part."""
    frames, _, p = clap_frames(cross=False)
    joined = range(35 + 8, 35 + 8 + 5)
    offsets = [p["left"], -p["fwd"], [0.0, 0.0, 1.0], -p["left"], p["fwd"]]
    for k, i in enumerate(joined):
        direction = np.asarray(offsets[k], dtype=float)
        stray = frames[i][1] + (0.25 + 0.02 * k) * direction / np.linalg.norm(direction)
        frames[i] = [*frames[i], stray]
    out = run(MultiTargetTracker(LONE, rig, seed=7), frames, rng)
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    assert len(splits) == 2 and min(splits) > max(joined)


def test_expected_hands_extrapolates_moving_targets_for_the_candidate_stage(rig, rng):
    trk = MultiTargetTracker(LONE, rig, seed=1)
    truth = [np.array([1.0 + i / 15, 2.0, 1.0]) for i in range(31)]  # 1 m/s along x
    run(trk, [[p] for p in truth[:30]], rng)
    expected = trk.expected_hands(30 * DT_NS)
    assert expected.shape == (1, 3)
    assert np.linalg.norm(expected[0] - truth[30]) < 0.03  # where it will be, not where it was
    assert MultiTargetTracker(LONE, rig, seed=1).expected_hands(0).shape == (0, 3)


@pytest.mark.parametrize("limit", [2, 0])
def test_a_pair_held_only_by_rescued_candidates_is_no_longer_expected(rig, rng, limit):
    """The candidate stage rescues a dropped candidate where hands are expected; a combined
    pair whose nearest candidate was such a rescued one for rescue_max_frames frame sets in a
    row (a pair left on the ghost where two hands' lines of sight cross) is not expected any
    more, so the ghost is not rescued again, until a candidate of its own supports it. A
    lone hand is always expected (approaching hands, whose blobs merge, are what rescuing is
    for); with no limit (0) so is the pair."""
    frames, _, p = clap_frames(cross=False)
    rest = 35 + 8 + 5  # the hands have joined and rest together
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, rescue_max_frames=limit)
    )
    trk = MultiTargetTracker(cfg, rig, seed=1)
    out = run(trk, frames[:rest], rng)
    assert sum(s.phase is Phase.COMBINED for s in out[-1].targets) == 2
    meet = frames[rest - 1][1]

    def step(i: int, rescued: bool) -> int:
        cands = CandidateSet(
            np.array([p["head"], meet]), np.array([0.9, 0.9]), rescued=np.array([False, rescued])
        )
        trk.step(i * DT_NS, cands)
        return len(trk.expected_hands((i + 1) * DT_NS))

    seen = [step(rest + k, rescued) for k, rescued in enumerate([True, True, True, False])]
    assert seen == ([2, 0, 0, 2] if limit else [2, 2, 2, 2])

    lone = MultiTargetTracker(cfg, rig, seed=1)
    point = np.array([2.0, 2.0, 1.0])
    run(lone, [[point]] * 10, rng)
    for k in range(3):
        rescued = CandidateSet(point[None].copy(), np.array([0.9]), rescued=np.array([True]))
        lone.step((10 + k) * DT_NS, rescued)
    assert len(lone.expected_hands(13 * DT_NS)) == 1


def test_a_lone_hand_is_helped_alone_only_just_after_a_candidate_of_its_own(rig, rng):
    """With lone_rescue_frames = 1 a labelled hand in the normal state may be spared a
    candidate with no other hand beside it in the frame set right after its nearest
    candidate was one of its own; after a rescued one (a tracker left on a ghost that only
    rescuing keeps) or none it is not, and with 0 (off) never. Heads never are."""
    frames, _, p = clap_frames(cross=False)
    start = 30  # both hands labelled and apart
    for frames_on, expect in [(1, [True, False, False, True]), (0, [False] * 4)]:
        cfg = TrackingConfig(
            lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, lone_rescue_frames=frames_on)
        )
        trk = MultiTargetTracker(cfg, rig, seed=1)
        out = run(trk, frames[:start], rng)
        hands = [s for s in out[-1].targets if s.phase is Phase.NORMAL and "hand" in s.label]
        assert len(hands) == 2
        assert trk.expected_alone().tolist() == [frames_on == 1] * 2
        hand = frames[start - 1][1]
        seen = []
        for k, rescued in enumerate([False, True, None, False]):
            points = [p["head"], hand] if rescued is not None else [p["head"]]
            flags = [False, rescued] if rescued is not None else [False]
            cands = CandidateSet(
                np.array(points), np.full(len(points), 0.9), rescued=np.array(flags)
            )
            trk.step((start + k) * DT_NS, cands)
            alone = trk.expected_alone()
            near = np.linalg.norm(trk.expected_hands((start + k + 1) * DT_NS) - hand, axis=1)
            seen.append(bool(alone[near.argmin()]))
        assert seen == expect


def test_predicted_targets_are_the_last_frame_moved_on_to_the_next_time(rig, rng):
    trk = MultiTargetTracker(LONE, rig, seed=1)
    truth = [np.array([1.0 + i / 15, 2.0, 1.0]) for i in range(31)]  # 1 m/s along x
    frames = run(trk, [[p] for p in truth[:30]], rng)
    (now,) = frames[-1].targets
    (ahead,) = trk.predicted_targets(30 * DT_NS)
    assert (ahead.target_id, ahead.label, ahead.phase) == (now.target_id, now.label, now.phase)
    assert np.linalg.norm(ahead.mean_m - truth[30]) < 0.03
    assert np.allclose(trk.predicted_targets(29 * DT_NS)[0].mean_m, now.mean_m)


def test_same_seed_same_output_and_skipped_frames(rig):
    frames = two_people_frames(30, b_from=5)

    def go(seed: int):
        rng = np.random.default_rng(9)
        trk = MultiTargetTracker(LONE, rig, seed=seed)
        # frames 10-14 are skipped: the time step comes from t_ns
        return [
            trk.step(i * DT_NS, candidates(f, rng))
            for i, f in enumerate(frames)
            if not 10 <= i < 15
        ]

    a, b, c = go(1), go(1), go(2)
    for fa, fb in zip(a, b, strict=True):
        assert np.array_equal(fa.particles_m, fb.particles_m)
        assert np.array_equal(fa.particle_owner, fb.particle_owner)
        assert [s.label for s in fa.targets] == [s.label for s in fb.targets]
        assert [(t.target_id, t.new) for t in fa.transitions] == [
            (t.target_id, t.new) for t in fb.transitions
        ]
    assert not np.array_equal(a[-1].particles_m, c[-1].particles_m)
    trk = MultiTargetTracker(LONE, rig, seed=1)
    first = [
        trk.step(i * DT_NS, candidates(f, np.random.default_rng(i)))
        for i, f in enumerate(frames[:5])
    ]
    trk.reset()
    again = [
        trk.step(i * DT_NS, candidates(f, np.random.default_rng(i)))
        for i, f in enumerate(frames[:5])
    ]
    assert np.array_equal(first[-1].particles_m, again[-1].particles_m)


def test_bad_input_is_named(rig):
    trk = MultiTargetTracker(LONE, rig, seed=0)
    with pytest.raises(TypeError, match="candidates"):
        trk.step(0, np.zeros((3, 3)))
    trk.step(DT_NS, CandidateSet.empty())
    with pytest.raises(ValueError, match="t_ns"):
        trk.step(0, CandidateSet.empty())
    with pytest.raises(TypeError, match="cfg"):
        MultiTargetTracker(object(), rig, seed=0)


def fake_observation(name: str, rel_v: list[float]) -> CameraObservation:
    n = len(rel_v)
    sil = Silhouettes(
        np.zeros((4, 4), np.int32), np.zeros(0), np.zeros(0), np.zeros((4, 4), np.float32)
    )
    blobs = BlobSet(
        np.zeros((n, 2)),
        np.ones(n, np.int64),
        np.zeros((n, 4), np.int32),
        np.ones(n, np.int32),
        np.array(rel_v, dtype=float),
        np.zeros((4, 4), np.int32),
    )
    return CameraObservation(name, sil, np.zeros((4, 4), bool), blobs)


def test_blob_rel_v_of_candidates(rig):
    trk = MultiTargetTracker(LONE, rig, seed=0)
    cands = CandidateSet(
        np.zeros((3, 3)),
        np.full(3, 0.9),
        cam_pairs=np.array([[0, 1], [0, 2], [1, 2]]),
        blob_pairs=np.array([[0, 1], [1, 0], [0, 9]]),
    )
    obs = {
        "cam0": fake_observation("cam0", [0.1, 0.5]),
        "cam1": fake_observation("cam1", [0.3, 0.2]),
    }
    rel = trk._candidate_rel_v(cands, obs)
    assert rel[0] == pytest.approx(0.15) and rel[1] == pytest.approx(0.5)
    assert rel[2] == pytest.approx(0.3)  # cam2 missing, blob 9 absent: one blob known
    assert np.isnan(trk._candidate_rel_v(cands, None)).all()
    out = trk.step(0, cands, obs)  # observations are accepted by step
    assert out.targets == ()


def test_step_is_fast_with_six_targets(rig, rng):
    import time

    frames = two_people_frames(40, b_from=0)
    trk = MultiTargetTracker(LONE, rig, seed=0)
    times = []
    for i, f in enumerate(frames):
        c = candidates(f, rng, clutter=6)
        t0 = time.perf_counter()
        trk.step(i * DT_NS, c)
        times.append(time.perf_counter() - t0)
    assert np.median(times[10:]) < 0.010  # generous: shared, slow CI machines


def test_a_tracker_never_labelled_is_retired_as_unclaimed(rig, rng):
    """A lone point that never becomes a head or a person's hand is a ghost: retired after
    retire_unclaimed_s, with an unlabelled -> uninitialised transition."""
    cfg = TrackingConfig(lifecycle=LifecycleConfig(retire_unclaimed_s=1.0))
    trk = MultiTargetTracker(cfg, rig, seed=2)
    frames = [[np.array([2.0, 2.0, 0.9])]] * 30  # a still point at hand height, no head
    out = run(trk, frames, rng, noise_m=0.005)
    alive = [len(f.targets) for f in out]
    retired = [tr for f in out for tr in f.transitions if tr.new is Phase.UNINITIALISED]
    assert alive[5] == 1 and retired
    assert (retired[0].t_ns - out[0].t_ns) * 1e-9 > 1.0


@pytest.mark.parametrize("exclusion", [True, False])
def test_a_target_whose_candidates_vanish_is_not_pulled_onto_its_neighbour(rig, exclusion):
    """Exclusion: a head's candidate belongs to the head's tracker; a hand 20 cm away whose
    own candidates vanish stays put (and goes lost) instead of sliding onto the head."""
    cfg = TrackingConfig(
        filter=FilterConfig(exclusion=exclusion),
        lifecycle=LifecycleConfig(retire_unclaimed_s=0.0),
    )
    trk = MultiTargetTracker(cfg, rig, seed=3)
    rng = np.random.default_rng(0)
    head = np.array([2.5, 2.0, 1.6])
    hand = head + [0.2, 0.0, 0.0]
    t = 0
    for _ in range(12):  # both seen: two trackers
        frame = trk.step(t, candidates([head, hand], rng))
        t += DT_NS
    assert len(frame.targets) == 2
    hand_id = min(frame.targets, key=lambda s: np.linalg.norm(s.mean_m - hand)).target_id
    for _ in range(6):  # the hand hides; the head stays
        frame = trk.step(t, candidates([head], rng))
        t += DT_NS
    snap = {s.target_id: s for s in frame.targets}[hand_id]
    assert (np.linalg.norm(snap.mean_m - head) < 0.05) != exclusion


def meeting_hands(half_gap_m: float, rest: int, hidden_from: float):
    """A person's two hands move in 8 frame sets from rest to meet in front (``half_gap_m``
    either side of the meeting point) after 35 still frame sets, then stay ``rest`` frame
    sets; the left hand's candidate is missing from path fraction ``hidden_from`` on.
    Returns (frames, path fractions, body, meeting point)."""
    p = body((2.5, 1.2), 90.0)
    meet = p["head"] + 0.35 * p["fwd"] - [0, 0, 0.5]
    path = [0.0] * 35 + list(np.linspace(0, 1, 9)[1:]) + [1.0] * rest
    frames = []
    for u in path:
        lh = p["left_hand"] + u * (meet + half_gap_m * p["left"] - p["left_hand"])
        rh = p["right_hand"] + u * (meet - half_gap_m * p["left"] - p["right_hand"])
        frames.append([p["head"], rh] if u >= hidden_from else [p["head"], lh, rh])
    return frames, path, p, meet


def hands_join_frame(rig, rng, frames, **lifecycle) -> int | None:
    """The frame set in which p1's two hands (labelled by frame set 34) combine, or None."""
    lc = LifecycleConfig(retire_unclaimed_s=0.0, **lifecycle)
    out = run(MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=6), frames, rng)
    ids = {s.label: s.target_id for s in out[34].targets}
    pair = {ids["p1/left_hand"], ids["p1/right_hand"]}
    for i, f in enumerate(out):
        for t in f.transitions:
            if t.new is Phase.COMBINED and {t.target_id, t.partner_id} == pair:
                return i
    return None


def test_a_hand_that_vanishes_beside_the_other_hand_joins_it_at_once(rig, rng):
    """Meeting hands 15 cm apart whose blobs merge leave one candidate: with
    hand_merge_distance_m the hand that lost it combines with the other within the frames a
    loss takes to declare; without, it joins only once its cloud drifts within the combine
    distance (with the stop-and-go motion component that can happen as early)."""
    frames, path, _, _ = meeting_hands(0.075, rest=8, hidden_from=1.0)
    vanish = path.index(1.0)
    with_rule = hands_join_frame(rig, rng, frames, hand_merge_distance_m=0.2)
    without = hands_join_frame(rig, rng, frames, hand_merge_distance_m=0.0)
    assert with_rule is not None and with_rule <= vanish + 2
    assert without is None or without >= with_rule


def test_a_hand_hidden_26_cm_from_the_hand_it_approached_joins_it(rig, rng):
    """A hand going behind the other as they meet (handshake, seed 0: the taker's hand hidden
    in three of four views) leaves its tracker where it was last seen, 23-27 cm short of the
    other. With the default hand_merge_distance_m (0.3 m) the two combine as soon as the
    hand is hidden; at the old 0.2 m only later, once the hidden hand's tracker has coasted
    within 0.2 m of the other (the lost-hand path is off here; in the recordings the hidden
    hand's tracker stopped and was lost instead)."""
    frames, path, _, _ = meeting_hands(0.13, rest=8, hidden_from=1.0)
    vanish = path.index(1.0)
    default = LifecycleConfig().hand_merge_distance_m
    joined = hands_join_frame(rig, rng, frames, hand_merge_distance_m=default, merge_lost_s=0.0)
    assert joined is not None and joined <= vanish + 1
    old = hands_join_frame(rig, rng, frames, hand_merge_distance_m=0.2, merge_lost_s=0.0)
    assert old is None or old > joined


def test_a_hand_hidden_before_the_other_comes_to_it_combines_with_it(rig, rng):
    """The taker's hand is held out, still, and goes out of view (behind the giver's hand,
    which is coming); the giver's hand reaches where it was last seen (exchange, seed 0).
    The two were not closing in before the hidden hand's miss began; with met_by_other the
    other's approach counts and the two combine, without it the hidden hand is lost and
    the meeting has no combined state."""
    p = body((2.5, 1.2), 90.0)
    held = p["head"] + 0.35 * p["fwd"] - [0, 0, 0.5] + 0.05 * p["left"]
    frames = [[p["head"], p["left_hand"], p["right_hand"]]] * 30
    frames += [
        [p["head"], p["left_hand"] + u * (held - p["left_hand"]), p["right_hand"]]
        for u in np.linspace(0, 1, 9)[1:]
    ]
    frames += [[p["head"], held, p["right_hand"]]] * 8
    near, goal = held - 0.32 * p["left"], held - 0.06 * p["left"]
    path = [p["right_hand"] + u * (near - p["right_hand"]) for u in np.linspace(0, 1, 9)[1:]]
    frames += [[p["head"], held, r] for r in path] + [[p["head"], held, near]] * 8
    # the left hand hides as the right sets off again, at 1.3 m/s
    path = [near + u * (goal - near) for u in np.linspace(0, 1, 4)[1:]]
    frames += [[p["head"], r] for r in path] + [[p["head"], goal]] * 6

    def left_story(met_by_other: bool) -> list:
        lc = LifecycleConfig(retire_unclaimed_s=0.0, met_by_other=met_by_other)
        out = run(MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=6), frames, rng)
        left = {s.label: s.target_id for s in out[29].targets}["p1/left_hand"]
        return [(t.old, t.new) for f in out[30:] for t in f.transitions if t.target_id == left]

    with_rule, without = left_story(True), left_story(False)
    assert (Phase.NORMAL, Phase.COMBINED) in with_rule, with_rule
    assert not any(new is Phase.COMBINED for _, new in without), without


def test_a_hand_lost_just_before_it_meets_the_other_is_reacquired_onto_it(rig, rng):
    """Hands closing at ~1 m/s: the left hand's candidate vanishes 28 cm before contact (its
    blob merged with the other's) and its tracker is lost. When the right hand reaches the
    left one's coasted position, the lost tracker is re-acquired onto it, keeping its label,
    and the two combine; they part when both candidates are back. With merge_lost_s = 0 the
    lost hand never joins."""
    frames, _, p, meet = meeting_hands(0.04, rest=6, hidden_from=0.5)
    for k in range(1, 9):  # they part again, both seen
        off = 0.04 + 0.05 * k
        frames.append([p["head"], meet + off * p["left"], meet - off * p["left"]])

    def left_hand_story(merge_lost_s: float) -> tuple[list, list]:
        # the paths that combine a hand as it loses its support beside the other are off:
        # only the lost-hand path can join them
        lc = LifecycleConfig(
            retire_unclaimed_s=0.0,
            merge_lost_s=merge_lost_s,
            hand_merge_distance_m=0.0,
            met_by_other=False,
        )
        out = run(MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=6), frames, rng)
        ids = {s.label: s.target_id for s in out[34].targets}
        left = ids["p1/left_hand"]
        mine = [t for f in out[35:] for t in f.transitions if t.target_id == left]
        return [(t.old, t.new) for t in mine], [t.label for t in mine]

    story, labels = left_hand_story(0.6)
    assert story[:4] == [
        (Phase.NORMAL, Phase.LOST),
        (Phase.LOST, Phase.UNLABELLED),
        (Phase.UNLABELLED, Phase.COMBINED),
        (Phase.COMBINED, Phase.UNLABELLED),
    ], story
    assert set(labels) == {"p1/left_hand"}
    without, _ = left_hand_story(0.0)
    assert (Phase.UNLABELLED, Phase.COMBINED) not in without
    assert (Phase.NORMAL, Phase.COMBINED) not in without


def test_a_resting_hand_lost_beside_the_other_is_not_merged_onto_it(rig, rng):
    """The right hand has come to rest 25 cm from the resting left hand, and then the left
    hand's candidate vanishes (pick_place: the left hand beside the table, the right picking
    the box). Neither is moving towards the other, so the lost hand is not re-acquired onto
    the right hand; with the closing-speed guard off it is, and the two combine although
    they never met."""
    p = body((2.5, 1.2), 90.0)
    target = p["left_hand"] - 0.25 * p["left"]
    frames = [[p["head"], p["left_hand"], p["right_hand"]]] * 35
    for u in np.linspace(0, 1, 9)[1:]:
        frames.append(
            [p["head"], p["left_hand"], p["right_hand"] + u * (target - p["right_hand"])]
        )
    frames += [[p["head"], p["left_hand"], target]] * 6 + [[p["head"], target]] * 8

    def left_story(closing_mps: float) -> list:
        lc = LifecycleConfig(retire_unclaimed_s=0.0, merge_closing_mps=closing_mps)
        out = run(MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=6), frames, rng)
        left = {s.label: s.target_id for s in out[34].targets}["p1/left_hand"]
        return [(t.old, t.new) for f in out[35:] for t in f.transitions if t.target_id == left]

    guarded, unguarded = left_story(0.3), left_story(-1e9)
    assert (Phase.NORMAL, Phase.LOST) in guarded
    assert not any(new is Phase.COMBINED for _, new in guarded), guarded
    assert any(new is Phase.COMBINED for _, new in unguarded), unguarded


def test_a_candidate_that_stays_beside_joined_hands_does_not_part_them(rig, rng):
    """A stray candidate that appears 28 cm from joined hands and stays (a bare forearm, a
    mismatched blob pair) is a second mode, but the modes do not move apart: the pair stays
    combined until the hands themselves part."""
    frames, _, p = clap_frames(cross=False)
    joined = range(35 + 8, 35 + 8 + 5)
    stray = frames[joined[0]][1] + 0.28 * p["fwd"]
    for i in joined:
        frames[i] = [*frames[i], stray]
    out = run(MultiTargetTracker(LONE, rig, seed=7), frames, rng)
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    assert len(splits) == 2 and min(splits) > max(joined)


@pytest.mark.parametrize(
    ("speed_m_per_frame", "pair_m_per_frame"), [(0.01, 0.0), (0.08, 0.0), (0.01, 0.06)]
)
def test_a_hand_that_leaves_a_pair_unseen_parts_it_instead_of_starting_a_tracker(
    rig, rng, speed_m_per_frame, pair_m_per_frame
):
    """The left hand leaves the joined hands while hidden for a frame and reappears 50 cm
    away, beyond the pair's mode gate: its candidate is the pair's second mode, so the pair
    separates onto it (angle rule) and no new tracker starts. Also when it goes on moving
    away fast (1.2 m/s: 66 cm away when its seed is confirmed, beyond pair_seed_gate_m), and
    when the right hand, which the pair follows, withdraws the other way (0.9 m/s: the seed
    is 62 cm from the pair when confirmed)."""
    frames, _, p = clap_frames(cross=False)
    rest = 35 + 8 + 5  # first frame after the hands rested together
    meet = frames[rest - 1][1]
    frames = frames[:rest]
    frames.append([p["head"], meet])  # the left hand hidden
    for k in range(8):
        left = meet + (0.5 + speed_m_per_frame * min(k, 4)) * p["left"]
        right = meet - pair_m_per_frame * min(k + 1, 4) * p["left"]
        frames.append([p["head"], right, left])
    out = run(MultiTargetTracker(LONE, rig, seed=8), frames, rng)
    ids = {s.label: s.target_id for s in out[34].targets}
    starts = [t for f in out[35:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    splits = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    assert not starts
    assert {t.target_id for t in splits} == {ids["p1/left_hand"], ids["p1/right_hand"]}
    final = by_label(out[-1])
    gone = 0.5 + 4 * speed_m_per_frame
    assert np.linalg.norm(final["p1/left_hand"] - (meet + gone * p["left"])) < 0.05
    right = meet - 4 * pair_m_per_frame * p["left"]
    assert np.linalg.norm(final["p1/right_hand"] - right) < 0.05


@pytest.mark.parametrize("within_reach", [True, False])
def test_joined_hands_do_not_part_on_a_ghost_out_of_every_heads_reach(rig, rng, within_reach):
    """handshake take 102, seed 1: a pair of one person's hands parted on a ghost 15 cm
    above the floor, 1.3 m from the head, and one hand's label went there. Here the hands
    stay clasped in front of the chest while a ghost shows 0.56 m below them, 1.14 m from
    the head: beyond any hand's reach, so the pair does not part on it."""
    frames, _, p = clap_frames(cross=False)
    rest = 35 + 8  # the hands have met
    meet = frames[rest][1]
    ghost = p["head"] + 0.45 * p["fwd"] - [0, 0, 1.05]
    assert np.linalg.norm(ghost - p["head"]) > 1.1 and np.linalg.norm(ghost - meet) < 0.6
    frames = frames[: rest + 3] + [[p["head"], meet, ghost]] * 12
    lc = dataclasses.replace(LONE.lifecycle, seed_within_reach=within_reach)
    cfg = dataclasses.replace(LONE, lifecycle=lc)
    out = run(MultiTargetTracker(cfg, rig, seed=8), frames, rng)
    splits = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    if within_reach:
        assert not splits
        assert all(s.phase is Phase.COMBINED for s in out[-1].targets if s.limb.is_hand)
    else:
        assert splits  # the old behaviour: the ghost took a hand


def test_a_new_tracker_that_meets_a_persons_hand_is_lost_not_combined(rig, rng):
    """A ghost candidate (here 40 cm in front of a labelled hand) starts a tracker that never
    joins a person; when it slides onto the hand it is a duplicate: it goes lost and the hand
    keeps its label and stays out of the combined state."""
    p = body((2.5, 1.2), 90.0)
    frames = [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(35)]
    ghost = p["right_hand"] + 0.4 * p["fwd"]
    for k in range(12):
        u = min(k / 6, 1.0)  # the ghost drifts onto the hand over six frames
        frames.append(
            [
                p["head"],
                p["left_hand"],
                *merged([p["right_hand"], ghost * (1 - u) + p["right_hand"] * u]),
            ]
        )
    out = run(MultiTargetTracker(LONE, rig, seed=9), frames, rng)
    hand_id = {s.label: s.target_id for s in out[34].targets}["p1/right_hand"]
    new = [t.target_id for f in out[35:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    assert len(new) == 1
    combined = [t for f in out for t in f.transitions if t.new is Phase.COMBINED]
    lost = [t.target_id for f in out for t in f.transitions if t.new is Phase.LOST]
    assert not combined and new[0] in lost and hand_id not in lost
    assert {s.label: s.target_id for s in out[-1].targets}["p1/right_hand"] == hand_id


def _head_and_left(p) -> list[np.ndarray]:
    return [p["head"], p["left_hand"]]


def shaking_hands(hold: int):
    """Two people 1 m apart (a at x = 2.0 facing +x, b at x = 3.0 facing -x), at rest for 45
    frames; then their right hands meet over eight frames (one candidate once they are
    close) and stay clasped for ``hold`` frames. Returns (frames, a, b, meeting point)."""
    a, b = body((2.0, 2.0), 0.0), body((3.0, 2.0), 180.0)
    meet = np.array([2.5, 2.0, 1.05])
    rest = _head_and_left
    frames = [[*rest(a), a["right_hand"], *rest(b), b["right_hand"]] for _ in range(45)]
    for u in np.linspace(0, 1, 9)[1:]:
        ra = a["right_hand"] + u * (meet - a["right_hand"])
        rb = b["right_hand"] + u * (meet - b["right_hand"])
        frames.append([*rest(a), *rest(b), *merged([ra, rb])])
    frames += [[*rest(a), *rest(b), meet] for _ in range(hold)]
    return frames, a, b, meet


def handshake_with_ghost_frames():
    """Two people 1 m apart (a at x = 2.0 facing +x, b at x = 3.0 facing -x) shake right hands
    at frame 45; their hands merge into one candidate for six frames. Then b's hand goes home
    at once, and a's hand, unseen for seven frames, reappears already back at a's side. A
    mismatched blob pair shows 35 cm above b's left hand from the fifth frame after the
    parting (the pair, following b's hand, is out of a's reach by then). Returns
    (frames, a, b)."""
    frames, a, b, meet = shaking_hands(hold=6)
    rest = _head_and_left
    home_b = [meet + u * (b["right_hand"] - meet) for u in np.linspace(0, 1, 7)[1:]]
    home_b += [b["right_hand"]] * 30
    for k, rb in enumerate(home_b):
        pts = [*rest(a), *rest(b), rb] + ([a["right_hand"]] if k >= 7 else [])
        if 4 <= k < 12:
            pts.append(b["left_hand"] + [0.0, 0.0, 0.35])
        frames.append(pts)
    return frames, a, b


def _owner_of(frame: TrackFrame, point: np.ndarray) -> str:
    """The label of the target nearest a point (which must be within 5 cm of it)."""
    near = min(frame.targets, key=lambda s: np.linalg.norm(s.mean_m - point))
    assert np.linalg.norm(near.mean_m - point) < 0.05
    return near.label


def _assert_right_hands_owned(frame: TrackFrame, a, b) -> None:
    heads = {s.person: s.mean_m for s in frame.targets if s.label.endswith("/head")}
    for p in (a, b):
        label = _owner_of(frame, p["right_hand"])
        person = min(heads, key=lambda k: np.linalg.norm(heads[k] - p["head"]))
        assert label == f"p{person}/right_hand"


def test_a_ghost_beside_shaking_hands_does_not_take_a_hand_away(rig, rng):
    """After a handshake the pair follows b's hand home; a's hand reappears at a's side, 1.2 m
    from the pair, and a ghost appears beside the pair, out of a's reach. The ghost must not
    part the pair (it would take a's label to b's side); a's hand does, although it is
    beyond pair_seed_gate_m, because the pair is out of a's reach and the hand is within it."""
    frames, a, b = handshake_with_ghost_frames()
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=11), frames, rng)
    splits = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    starts = [t for f in out[53:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    assert len(splits) == 2
    assert all(np.linalg.norm(t.position_m - b["left_hand"]) > 0.2 for t in starts)
    _assert_right_hands_owned(out[-1], a, b)


@pytest.mark.parametrize(("b_later", "both"), [(0, True), (1, True), (3, False)])
def test_two_hands_that_leave_a_pair_at_once_both_part_it(rig, rng, b_later, both):
    """After a handshake both hands go home fast, unseen for three frame sets, while a ghost
    (their lines of sight crossing) holds the pair where they met (bundled handshake scene,
    seeds 0, 2 and 5 at 10.1 s). Both hands' candidates then show 49 cm from the pair on
    opposite sides (beyond separate_gate_m: not modes of the pair). When a's seed is
    confirmed and b's shows too (``b_later`` 0: confirmed in the same frame set; 1: one
    frame set behind), the pair parts onto the two of them: each hand keeps its tracker and
    label, and no tracker starts on either hand. When b's hand shows only once a's seed has
    parted the pair (3), one tracker keeps the ghost and b's hand gets a new tracker."""
    frames, a, b, meet = shaking_hands(hold=6)
    n_before = len(frames)
    path = {"a": [], "b": []}
    for k in range(24):
        pts = [*_head_and_left(a), *_head_and_left(b)] + ([meet] if k < 12 else [])
        for name, p, shown in (("a", a, 3), ("b", b, 3 + b_later)):
            u = min(1.0, 0.8 + 0.04 * (k - 3))
            hand = meet + u * (p["right_hand"] - meet)
            if k >= shown:
                pts.append(hand)
            path[name].append(hand)
        frames.append(pts)
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=11), frames, rng)
    before = {s.label: s.target_id for s in out[n_before - 1].targets}
    starts = [t for f in out[n_before:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    on_hands = [
        t
        for t in starts
        if min(np.linalg.norm(t.position_m - path[n][i]) for n in "ab" for i in range(24)) < 0.05
    ]
    after = {s.label: s for s in out[-1].targets}
    if both:
        assert not on_hands
        _assert_right_hands_owned(out[-1], a, b)
        for label in ("p1/right_hand", "p2/right_hand"):
            assert after[label].target_id == before[label]
    else:
        assert len(on_hands) == 1


def test_a_hand_tracked_since_it_left_a_pair_parts_it_before_a_later_ghost(rig, rng):
    """After a handshake a ghost holds the pair where the hands met, and a stray point 25 cm
    below it gives the pair two modes that do not move apart. a's hand shows again 48 cm
    away while the pair counts those modes, so its seed starts a tracker instead of parting
    the pair (handshake, seeds 4 and 5 at 10.07 s). The stray goes; then b's hand and a
    ghost by a's chest, on the opposite side, become seeds in the same frame set. The pair
    must part onto b's hand and a's young tracker (retired, a duplicate), not onto the
    ghost: each hand keeps its tracker and label."""
    frames, a, b, meet = shaking_hands(hold=6)
    n_before = len(frames)
    unit = lambda v: v / np.linalg.norm(v)  # noqa: E731
    hand_a = meet + 0.48 * unit(a["right_hand"] - meet)
    hand_b = meet + 0.49 * unit(b["right_hand"] - meet)
    ghost = meet + 0.55 * unit(np.array([-0.35, 0.2, 0.35]))
    for k in range(20):
        pts = [*_head_and_left(a), *_head_and_left(b), meet]
        pts += [meet - [0.0, 0.0, 0.25]] if k < 6 else []
        pts += [hand_a] if k >= 3 else []
        pts += [hand_b, ghost] if k >= 5 else []
        frames.append(pts)
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=11), frames, rng)
    before = {s.label: s.target_id for s in out[n_before - 1].targets}
    after = {s.label: s for s in out[-1].targets}
    for label, hand in (("p1/right_hand", hand_a), ("p2/right_hand", hand_b)):
        assert after[label].target_id == before[label]
        assert np.linalg.norm(after[label].mean_m - hand) < 0.05


@pytest.mark.parametrize("held_views", [3, 0])
def test_a_pair_held_by_a_well_seen_candidate_is_not_left_by_both_hands(rig, rng, held_views):
    """Two points show 49 cm from a handshake's pair on opposite sides, each within its
    owner's reach, as both hands' do when they leave at once (above), but the clasped hands
    stay where they met, on a candidate four views support (three_people, seeds 0 and 1 at
    4.73 s: a ghost and a stray point beside a give). Both hands cannot have left: the pair
    parts on one point at most, a right hand's tracker stays on the clasped hands and none
    starts there. With the test off (``held_views`` 0) the pair parts onto both points and
    a new tracker takes the hands."""
    frames, a, b, meet = shaking_hands(hold=6)
    strays = [meet + 0.8 * (p["right_hand"] - meet) for p in (a, b)]
    cfg = TrackingConfig(lifecycle=LifecycleConfig(held_views=held_views))
    trk = MultiTargetTracker(cfg, rig, seed=11)
    out = run(trk, frames, rng)
    before = {s.label: s.target_id for s in out[-1].targets}
    for k in range(16):
        pts = [*_head_and_left(a), *_head_and_left(b), meet] + (strays if k >= 3 else [])
        views = np.full(len(pts), 2)
        views[4] = 4  # the clasped hands
        cands = dataclasses.replace(candidates(pts, rng), views=views)
        out.append(trk.step((len(frames) + k) * DT_NS, cands))
    starts = [t for f in out[len(frames) :] for t in f.transitions if t.old is Phase.UNINITIALISED]
    on_meet = [t for t in starts if np.linalg.norm(t.position_m - meet) < 0.1]
    if held_views == 0:
        assert on_meet
        return
    assert not on_meet
    at_meet = [s for s in out[-1].targets if np.linalg.norm(s.mean_m - meet) < 0.05]
    assert {s.target_id for s in at_meet} & {before["p1/right_hand"], before["p2/right_hand"]}


@pytest.mark.parametrize("frames_out", [3, 0])
def test_a_pair_that_follows_one_hand_out_of_the_others_reach_parts(rig, rng, frames_out):
    """After a handshake b's hand goes home and a's hand is never seen again: the pair has no
    second mode. Once it is beyond the reach of a's head (out_of_reach_frames), a's hand is
    not in it: the pair parts, b's hand keeps b's label at b's side and a's label stays at
    the meeting point, where a's hand was last seen; a's tracker is then lost there. With
    the test off the pair stays combined, both labels on b's hand."""
    frames, a, b, meet = shaking_hands(hold=6)
    home_b = [meet + u * (b["right_hand"] - meet) for u in np.linspace(0, 1, 7)[1:]]
    frames += [[*_head_and_left(a), *_head_and_left(b), rb] for rb in home_b + [home_b[-1]] * 20]
    cfg = TrackingConfig(lifecycle=LifecycleConfig(out_of_reach_frames=frames_out))
    out = run(MultiTargetTracker(cfg, rig, seed=11), frames, rng)
    last = out[-1]
    splits = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    if frames_out == 0:
        assert not splits
        assert all(s.phase is Phase.COMBINED for s in last.targets if "right" in s.label)
        return
    assert len(splits) == 2
    _owner_of(last, b["right_hand"])  # a live target is on b's hand ...
    heads = {s.person: s.mean_m for s in last.targets if s.label.endswith("/head")}
    pa = min(heads, key=lambda k: np.linalg.norm(heads[k] - a["head"]))
    pb = min(heads, key=lambda k: np.linalg.norm(heads[k] - b["head"]))
    hands = {s.label: s for s in last.targets if s.label.endswith("right_hand")}
    assert np.linalg.norm(hands[f"p{pb}/right_hand"].mean_m - b["right_hand"]) < 0.05
    assert hands[f"p{pb}/right_hand"].phase is Phase.NORMAL
    assert hands[f"p{pa}/right_hand"].phase is Phase.LOST
    assert np.linalg.norm(hands[f"p{pa}/right_hand"].mean_m - meet) < 0.1


def test_a_pair_out_of_one_owners_reach_gives_that_owner_the_candidate_at_its_side(rig, rng):
    """After a handshake the pair follows b's hand home while a's hand goes home unseen. a's
    hand shows at a's side only in the frame set in which the pair has been out of a's
    reach for out_of_reach_frames: too late to be a mode of the pair, too soon to be a
    confirmed seed. The pair parts there, and a's tracker takes that candidate (before,
    it was put where the hands met, where nothing is, and lost; a new tracker then took
    a's hand: an identity switch)."""
    frames, a, b, meet = shaking_hands(hold=6)
    home_b = [meet + u * (b["right_hand"] - meet) for u in np.linspace(0, 1, 7)[1:]]
    n_before = len(frames)
    frames += [
        [*_head_and_left(a), *_head_and_left(b), rb] + ([a["right_hand"]] if k >= 5 else [])
        for k, rb in enumerate(home_b + [home_b[-1]] * 20)
    ]
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=11), frames, rng)
    before = {s.label: s.target_id for s in out[n_before - 1].targets}
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    starts = [t for f in out[n_before:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    assert splits == [n_before + 5] * 2  # the frame set of the out-of-reach test
    assert not starts
    _assert_right_hands_owned(out[-1], a, b)
    after = {s.label: s for s in out[-1].targets}
    for label in ("p1/right_hand", "p2/right_hand"):
        assert after[label].target_id == before[label]
        assert after[label].phase is Phase.NORMAL


@pytest.mark.parametrize("hand_from", [4, 5])
def test_out_of_reach_the_left_hand_takes_a_seed_seen_twice_before_a_nearer_one_seen_once(
    rig, rng, hand_from
):
    """As above, but a ghost shows once, in the frame set of the out-of-reach test, a little
    nearer where the hands met than a's hand at a's side (three_people at 9.93 s, five of
    seeds 0-5: the ghost 27 cm from the meeting point, the hand, seen twice, 29 cm). Seen
    from the frame set before (``hand_from`` 4), a's hand is the stronger evidence and a's
    tracker takes it; seen once like the ghost, the nearer one is taken."""
    frames, a, b, meet = shaking_hands(hold=6)
    home_b = [meet + u * (b["right_hand"] - meet) for u in np.linspace(0, 1, 7)[1:]]
    n_before = len(frames)
    d_hand = float(np.linalg.norm(a["right_hand"] - meet))
    ghost = meet + (d_hand - 0.03) * np.array([0.0, 0.6, 0.8])  # above and beside a's side
    for k, rb in enumerate(home_b + [home_b[-1]] * 20):
        pts = [*_head_and_left(a), *_head_and_left(b), rb]
        if k >= hand_from:
            pts.append(a["right_hand"])
        if k == 5:
            pts.append(ghost)
        frames.append(pts)
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=11), frames, rng)
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    assert splits == [n_before + 5] * 2  # the frame set of the out-of-reach test
    parted = {t.target_id: t.position_m for t in out[n_before + 5].transitions}
    took_hand = [np.linalg.norm(p - a["right_hand"]) < 0.05 for p in parted.values()]
    took_ghost = [np.linalg.norm(p - ghost) < 0.05 for p in parted.values()]
    if hand_from == 4:
        assert any(took_hand) and not any(took_ghost)
    else:
        assert any(took_ghost) and not any(took_hand)


@pytest.mark.parametrize(
    "ghost",
    [
        pytest.param([2.9, 2.15, 1.3], id="within-a's-reach"),
        # out of a's reach (arm_reach_m + person_margin_m): the ghost's tracker looks like b's
        # hand gone home from the pair (bundled handshake scene, seed 0, 4.67 s)
        pytest.param([2.95, 2.15, 1.1], id="out-of-a's-reach"),
    ],
)
@pytest.mark.parametrize("leave_speed_mps", [3.0, 1e9])
def test_a_ghost_that_stood_beside_the_hands_as_they_joined_does_not_part_them(
    rig, rng, leave_speed_mps, ghost
):
    """Two people shake right hands for two seconds. From just before the hands meet a ghost
    flickers 50 cm from them, on b's chest (skin-coloured clothes), and then stays. It was
    there as the hands joined, sooner than either hand could have got there, so it is not a
    hand leaving the pair, neither as a seed nor, out of a's reach, as an unlabelled tracker
    of b's (a hand gone home): the pair stays combined until the hands part, and each hand
    keeps its owner's label. Without the rule (an unbounded leave speed) the pair parts onto
    the ghost while the hands are still joined."""
    frames, a, b, meet = shaking_hands(hold=30)
    rest = _head_and_left
    ghost = np.array(ghost)
    for u in np.linspace(0, 1, 7)[1:]:
        frames.append(
            [
                *rest(a),
                *rest(b),
                meet + u * (a["right_hand"] - meet),
                meet + u * (b["right_hand"] - meet),
            ]
        )
    frames += [[*rest(a), a["right_hand"], *rest(b), b["right_hand"]] for _ in range(20)]
    joined = (45 + 6, 45 + 8 + 30)  # the hands' candidates are one from here to there
    for k in range(joined[0] - 2, len(frames)):
        if k >= joined[0] + 10 or (k - joined[0]) % 2 == 0:
            frames[k] = [*frames[k], ghost]
    cfg = TrackingConfig(lifecycle=LifecycleConfig(leave_speed_mps=leave_speed_mps))
    out = run(MultiTargetTracker(cfg, rig, seed=14), frames, rng)
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    assert splits
    if leave_speed_mps < 1e3:
        assert min(splits) >= joined[1]
        _assert_right_hands_owned(out[-1], a, b)
    else:
        assert min(splits) < joined[1]


def test_a_seed_beside_a_pair_gets_one_verdict_from_both_of_its_trackers(rig, rng):
    """Whether a seed was there as a combined pair joined (something beside it, not a
    target leaving it) is one verdict for the pair. Its two trackers joined where each was,
    apart, so a sighting of the seed just before the joining can lie in the window of the
    farther tracker (sooner than a target could have come from there) but not of the
    nearer. Asked from the nearer alone, the pair parted onto a ghost while the hands still
    held the ball (demo take 101 with the bare-forearm option, docs/benchmarks.md, session
    98); the answer must not depend on which tracker asks."""
    frames, _, _, _ = shaking_hands(hold=10)
    trk = MultiTargetTracker(TrackingConfig(), rig, seed=14)
    run(trk, frames, rng)
    pair = [t for t in trk._tracks.values() if t.phase is Phase.COMBINED]
    assert len(pair) == 2 and pair[0].partner == pair[1].id and pair[1].partner == pair[0].id
    near, far = pair
    lc = trk.cfg.lifecycle
    axis = near.joined_m - far.joined_m
    assert np.linalg.norm(axis) > 1e-3  # they joined where each was, apart
    seed_m = near.joined_m + 0.5 * axis / np.linalg.norm(axis)  # beyond the pair, nearer `near`
    d_near, d_far = (np.linalg.norm(seed_m - t.joined_m) - lc.init_gate_m for t in pair)
    seen_ns = near.joined_ns - int(0.5 * (d_near + d_far) / lc.leave_speed_mps * 1e9)
    log = list(trk._unexplained_log)
    at = sum(t_ns <= seen_ns for t_ns, _ in log)
    trk._unexplained_log.clear()
    trk._unexplained_log.extend([*log[:at], (seen_ns, seed_m[None, :]), *log[at:]])
    first_ns = near.joined_ns + 10**9  # the seed's present run began long after
    assert trk._there_as_joined(far, seed_m, first_ns)
    assert not trk._there_as_joined(near, seed_m, first_ns)
    assert trk._there_as_pair_joined(near, seed_m, first_ns)
    assert trk._there_as_pair_joined(far, seed_m, first_ns)


def test_a_hand_whose_tracker_drifted_off_it_does_not_part_a_pair(rig, rng):
    """Two people shake right hands. While the hands are joined, b's resting left hand loses
    its candidate to one 35 cm above it (a blob pair on b's shirt) and its tracker follows it
    up; then the hand's own candidate shows again. That seed is where b's left-hand tracker
    stood as the pair joined, so it is not a hand leaving the pair: the pair stays combined
    until the hands part, each right hand keeps its owner's label, and the left hand's own
    tracker is put back on it, so no new tracker takes it; nor does the ghost it leaves part
    the pair (bundled handshake scene, seed 3, 4.33 s; without the rule the pair parts onto
    the seed there and then, and the hands' labels go wrong)."""
    frames, a, b, meet = shaking_hands(hold=30)
    rest = _head_and_left
    b["left_hand"] = b["left_hand"] + [-0.08, 0.05, 0.0]  # 53 cm from where the hands meet
    up = np.array([0.0, 0.0, 0.35])
    drift, back = 58, 66  # the slide begins; the hand's own candidate shows again
    for k in range(len(frames)):
        u = min(max(k - drift + 1, 0) / 6, 1.0)
        shown = [b["left_hand"] + u * up] + ([b["left_hand"]] if k >= back else [])
        frames[k] = [*rest(a), b["head"], *shown, *frames[k][4:]]
    for u in np.linspace(0, 1, 7)[1:]:
        frames.append(
            [
                *rest(a),
                b["head"],
                b["left_hand"] + up,
                b["left_hand"],
                meet + u * (a["right_hand"] - meet),
                meet + u * (b["right_hand"] - meet),
            ]
        )
    hands_part = len(frames) - 6
    frames += [
        [
            *rest(a),
            a["right_hand"],
            b["head"],
            b["left_hand"] + up,
            b["left_hand"],
            b["right_hand"],
        ]
        for _ in range(20)
    ]
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=15), frames, rng)
    joined = [i for i, f in enumerate(out) for t in f.transitions if t.new is Phase.COMBINED]
    splits = [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]
    assert joined and max(joined) < drift
    assert splits and min(splits) >= hands_part
    _assert_right_hands_owned(out[-1], a, b)
    # and b's left-hand tracker is put back on its hand: no new tracker takes it
    left_before = _owner_of(out[drift - 1], b["left_hand"])
    left_ids = {s.label: s.target_id for s in out[drift - 1].targets}
    near = min(out[-1].targets, key=lambda s: np.linalg.norm(s.mean_m - b["left_hand"]))
    assert near.target_id == left_ids[left_before] and near.label == left_before


@pytest.mark.parametrize("revise_s", [0.5, 0.0])
def test_a_hand_taken_for_the_wrong_person_is_relabelled(rig, rng, revise_s):
    """b's right hand shows before b's head does (b's head hidden), held out 85 cm from a's
    head while a's own right hand is hidden: a claims it. When b's head appears and the hand
    goes home, it is out of a's reach and within b's: after reach_revise_s it loses its label
    (normal -> unlabelled) and joins b, and a's right hand, shown again, takes a's free slot
    (with 0, never: b's hand keeps a's label). The ownership contest, which would also
    mend this, is off to test the reach rule alone."""
    a, b = body((2.0, 2.0), 0.0), body((3.0, 2.0), 180.0)
    held = np.array([2.6, 2.0, 1.1])
    frames = [[a["head"], a["left_hand"], held] for _ in range(45)]
    for k in range(45):
        u = min((k + 1) / 6, 1.0)
        hand_b = held + u * (b["right_hand"] - held)
        frames.append(
            [a["head"], a["left_hand"], a["right_hand"], b["head"], b["left_hand"], hand_b]
        )
    cfg = TrackingConfig(
        labelling=LabellingConfig(reach_revise_s=revise_s, contest_by_owner=False)
    )
    out = run(MultiTargetTracker(cfg, rig, seed=12), frames, rng)
    assert _owner_of(out[44], held).startswith("p1/")  # claimed by a (the only person yet)
    revoked = [
        t for f in out for t in f.transitions if (t.old, t.new) == (Phase.NORMAL, Phase.UNLABELLED)
    ]
    if revise_s > 0:
        assert len(revoked) == 1
        _assert_right_hands_owned(out[-1], a, b)
    else:
        assert not revoked
        assert _owner_of(out[-1], b["right_hand"]).startswith("p1/")


@pytest.mark.parametrize("at_join", [True, False])
def test_a_hand_that_joins_out_of_its_persons_reach_joins_without_their_label(rig, rng, at_join):
    """a claims b's right hand while b's head is hidden (as above); b shows, the hand goes
    home, out of a's reach, and b's left hand comes to it at once (a clap), before
    reach_revise_s has passed. The join is not between a's hand and b's: with
    astray_at_join the tracker that carried a's label joins unlabelled, and no event could
    read a meeting of two people's hands; without it, it joins as p1/right_hand."""
    a, b = body((2.0, 2.0), 0.0), body((3.0, 2.0), 180.0)
    held = np.array([2.6, 2.0, 1.1])
    frames = [[a["head"], a["left_hand"], held] for _ in range(20)]
    frames += [[a["head"], a["left_hand"], held, b["head"], b["left_hand"]] for _ in range(25)]
    right_b = b["right_hand"]
    for k in range(6):
        hand = held + (k + 1) / 6 * (right_b - held)
        frames.append([a["head"], a["left_hand"], b["head"], b["left_hand"], hand])
    for k in range(10):
        u = min((k + 1) / 3, 1.0)
        left = b["left_hand"] + u * (right_b + [0, -0.04, 0] - b["left_hand"])
        frames.append([a["head"], a["left_hand"], b["head"], left, right_b])
    cfg = TrackingConfig(labelling=LabellingConfig(astray_at_join=at_join, contest_by_owner=False))
    out = run(MultiTargetTracker(cfg, rig, seed=12), frames, rng)
    assert _owner_of(out[44], held).startswith("p1/")
    first = next(f for f in out[45:] if any(t.new is Phase.COMBINED for t in f.transitions))
    labels = {t.label for t in first.transitions if t.new is Phase.COMBINED}
    assert len(labels) == 2
    assert any(lab.startswith("p2/") for lab in labels)
    if at_join:
        assert not any(lab.startswith("p1/") for lab in labels)
    else:
        assert "p1/right_hand" in labels


def right_hands_held_out(held_a, held_b) -> tuple[list, list]:
    """Two people, a at x 2.0 facing b at x 3.0, stand still for 40 frame sets, then raise
    their right hands to ``held_a`` and ``held_b`` in 8. Returns (those frames, the other
    limbs at rest: heads and left hands)."""
    a, b = body((2.0, 2.0), 0.0), body((3.0, 2.0), 180.0)
    rest = [a["head"], a["left_hand"], b["head"], b["left_hand"]]
    frames = [[*rest, a["right_hand"], b["right_hand"]] for _ in range(40)]
    for u in np.linspace(0, 1, 9)[1:]:
        frames.append(
            [
                *rest,
                a["right_hand"] + u * (held_a - a["right_hand"]),
                b["right_hand"] + u * (held_b - b["right_hand"]),
            ]
        )
    return frames, rest


@pytest.mark.parametrize("closing_mps", [0.3, -1e9])
def test_a_still_hand_that_loses_its_candidate_beside_another_has_not_met_it(
    rig, rng, closing_mps
):
    """Two people hold their right hands out, 24 cm apart and still (the negative scene);
    then a's candidate vanishes for ten frame sets. a's hand was not approaching b's before
    its miss, so they have not met: a's tracker is lost, not merged onto b's hand, and no
    combined state opens (no handshake later); a's hand keeps its label when it shows again.
    With the closing-speed guard off (and in session 10's tracker) the two combine."""
    a = body((2.0, 2.0), 0.0)
    held_a, held_b = np.array([2.38, 1.95, 1.05]), np.array([2.62, 1.97, 1.05])
    frames, rest = right_hands_held_out(held_a, held_b)
    frames += [[*rest, held_a, held_b]] * 15 + [[*rest, held_b]] * 10
    frames += [[*rest, held_a, held_b]] * 10
    lc = LifecycleConfig(merge_closing_mps=closing_mps)
    out = run(MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=13), frames, rng)
    combined = [t for f in out for t in f.transitions if t.new is Phase.COMBINED]
    if closing_mps > 0:
        assert not combined
        assert _owner_of(out[-1], held_a) == "p1/right_hand"
        assert _owner_of(out[-1], held_b) == "p2/right_hand"
        assert _owner_of(out[-1], a["head"]) == "p1/head"
    else:
        assert combined


@pytest.mark.parametrize("yield_s", [0.5, 0.0])
def test_hands_lost_while_their_person_walks_away_give_their_slots_to_new_trackers(
    rig, rng, yield_s
):
    """Without ``reacquire_with_body``: a person's hands lose their candidates (carrying a
    box against the body) while the head walks 1.5 m away in 2 s; the hands show again at
    the new place, far outside the lost trackers' re-acquisition gate, so new trackers start
    there. The lost hands give their
    slots to them after yield_lost_s and are retired: the new trackers become p1's hands.
    With 0 (never), the lost hands hold the slots until they retire (retire_s, 3 s) and the
    new trackers stay unlabelled."""
    a = body((1.5, 2.0), 0.0)
    frames = [[a["head"], a["left_hand"], a["right_hand"]] for _ in range(40)]
    shift = np.array([1.5, 0.0, 0.0])
    for u in (1 - np.cos(np.pi * np.linspace(0, 1, 31)[1:])) / 2:  # 2 s, at most 1.2 m/s
        frames.append([a["head"] + u * shift])
    frames += [[a["head"] + shift, a["left_hand"] + shift, a["right_hand"] + shift]] * 12
    cfg = TrackingConfig(
        labelling=LabellingConfig(yield_lost_s=yield_s),
        lifecycle=LifecycleConfig(reacquire_with_body=False),
    )
    out = run(MultiTargetTracker(cfg, rig, seed=14), frames, rng)
    assert _owner_of(out[39], a["right_hand"]) == "p1/right_hand"
    last = out[-1]
    if yield_s > 0:
        assert _owner_of(last, a["left_hand"] + shift) == "p1/left_hand"
        assert _owner_of(last, a["right_hand"] + shift) == "p1/right_hand"
        assert len(last.targets) == 3  # the lost trackers are retired
    else:
        assert not _owner_of(last, a["right_hand"] + shift).startswith("p1/")


def _walk_hidden(a: dict, shift: np.ndarray, hidden_frames: int) -> list[list[np.ndarray]]:
    """Head and hands seen for 40 frame sets; then the head alone walks ``shift`` in 30
    (2 s) and stands ``hidden_frames - 30`` more; then all three are seen there for 12."""
    frames = [[a["head"], a["left_hand"], a["right_hand"]] for _ in range(40)]
    for u in (1 - np.cos(np.pi * np.linspace(0, 1, 31)[1:])) / 2:  # at most 1.2 m/s
        frames.append([a["head"] + u * shift])
    frames += [[a["head"] + shift]] * (hidden_frames - 30)
    frames += [[a["head"] + shift, a["left_hand"] + shift, a["right_hand"] + shift]] * 12
    return frames


@pytest.mark.parametrize("hidden_frames", [30, 75])
def test_hands_hidden_while_their_person_walks_away_are_reacquired_where_the_body_went(
    rig, rng, hidden_frames
):
    """The walk of the test above, but hands that follow their body: the lost hands are
    looked for around their last positions moved as far as the head moved, so the trackers
    that lost them re-acquire them at the new place; their ids (and with them the carry
    window and the activity history) survive. Hidden for 5 s, longer than ``retire_s``
    (3 s), they are still kept: a tracked person's hand is hidden, not gone. While lost
    they are reported where the body took them."""
    a = body((1.5, 2.0), 0.0)
    shift = np.array([1.5, 0.0, 0.0])
    out = run(
        MultiTargetTracker(TrackingConfig(), rig, seed=14),
        _walk_hidden(a, shift, hidden_frames),
        rng,
    )
    ids = {s.label: s.target_id for s in out[39].targets}
    assert set(ids) == {"p1/head", "p1/left_hand", "p1/right_hand"}
    hidden = {s.label: s for s in out[40 + hidden_frames - 1].targets}
    assert hidden["p1/right_hand"].phase is Phase.LOST
    moved = a["right_hand"] + shift
    assert np.linalg.norm(hidden["p1/right_hand"].mean_m[:2] - moved[:2]) < 0.1
    last = out[-1]
    assert {s.label: s.target_id for s in last.targets} == ids
    assert _owner_of(last, a["left_hand"] + shift) == "p1/left_hand"
    assert _owner_of(last, moved) == "p1/right_hand"


def _noisy_set(rng, points, priors) -> CandidateSet:
    """Candidates at ``points`` (5 mm noise) with the given priors."""
    pts = np.array(points) + rng.normal(0, 0.005, (len(points), 3))
    return CandidateSet(pts, np.asarray(priors, dtype=float))


def _ghost_then_hand(rng):
    """A person's head, left hand and a weak ghost (prior 0.5) 18 cm from the hidden right
    hand for 40 frame sets; then the right hand shows (0.95) for 30. Returns (body, ghost,
    the candidates seen throughout, the 70 candidate sets)."""
    a = body((2.0, 2.0), 0.0)
    ghost = a["right_hand"] + 0.15 * a["fwd"] + 0.1 * a["left"]
    seen = [a["head"], a["left_hand"], ghost]
    sets = [_noisy_set(rng, seen, [0.95, 0.95, 0.5]) for _ in range(40)]
    sets += [_noisy_set(rng, [*seen, a["right_hand"]], [0.95, 0.95, 0.5, 0.95]) for _ in range(30)]
    return a, ghost, seen, sets


@pytest.mark.parametrize("contest_s", [0.5, 0.0])
def test_a_real_hand_takes_its_slot_from_a_weaker_ghost(rig, contest_s):
    """A ghost candidate beside the right hand (two views' lines of sight crossing; prior
    0.5) holds the right hand's slot while the real right hand is hidden. When it shows
    (prior 0.95, from several camera pairs) its tracker out-supports the ghost's and takes
    the label after contest_s; with 0 (never) the ghost keeps it."""
    a, ghost, _, sets = _ghost_then_hand(np.random.default_rng(5))
    cfg = TrackingConfig(labelling=LabellingConfig(contest_s=contest_s))
    trk = MultiTargetTracker(cfg, rig, seed=15)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], ghost) == "p1/right_hand"
    if contest_s > 0:
        assert _owner_of(out[-1], a["right_hand"]) == "p1/right_hand"
        assert not _owner_of(out[-1], ghost).startswith("p1/")
    else:
        assert _owner_of(out[-1], ghost) == "p1/right_hand"


@pytest.mark.parametrize("demotes", [True, False])
def test_a_ghost_that_lost_its_slot_does_not_combine_with_a_hand_that_passes(rig, demotes):
    """The ghost of the test above loses the right hand's slot to the real hand, then the
    real hand moves through the ghost's place and stays there. A contest loser counts as a
    stray (``contest_demotes``): the hand does not combine with it, and the ghost's
    tracker is dropped as a duplicate (lost), so the hand keeps its label with no combined
    state -- which would otherwise open a hand/hand episode with an unlabelled partner.
    With the option off the two combine."""
    rng = np.random.default_rng(5)
    a, ghost, seen, sets = _ghost_then_hand(rng)
    strong = [0.95, 0.95, 0.5, 0.95]
    for u in np.linspace(0, 1, 7)[1:]:
        sets.append(
            _noisy_set(rng, [*seen, a["right_hand"] + u * (ghost - a["right_hand"])], strong)
        )
    sets += [_noisy_set(rng, [*seen, ghost], strong) for _ in range(15)]
    cfg = TrackingConfig(labelling=LabellingConfig(contest_demotes=demotes))
    trk = MultiTargetTracker(cfg, rig, seed=15)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[69], a["right_hand"]) == "p1/right_hand"
    assert not _owner_of(out[69], ghost).startswith("p1/")
    combined = [t for f in out[70:] for t in f.transitions if t.new is Phase.COMBINED]
    if demotes:
        assert not combined
        assert _owner_of(out[-1], ghost) == "p1/right_hand"
    else:
        assert combined


@pytest.mark.parametrize("side_m", [0.1, 0.0])
def test_a_strong_point_at_the_right_elbow_does_not_take_the_left_hands_slot(rig, side_m):
    """a holds a ball out in front with the left hand, which the ball half hides (prior 0.5);
    from frame set 40 a strong point (prior 0.95, a shaded shirt the skin stage calls skin)
    shows 23 cm above the right hand. It out-supports the left hand, but it is on a's right
    (b faces a, so a's facing is known): it cannot take the left hand's slot and stays
    unlabelled. With contest_side_m 0 it takes the slot (three_people's p1: the real left
    hand then stayed unlabelled through the exchange)."""
    rng = np.random.default_rng(6)
    a, b = body((2.0, 2.0), 0.0), body((3.2, 2.0), 180.0)
    held = a["head"] + 0.2 * a["left"] + 0.3 * a["fwd"] - [0, 0, 0.6]
    shirt = a["right_hand"] + [0, 0, 0.23]

    seen = [a["head"], held, a["right_hand"], b["head"], b["left_hand"], b["right_hand"]]
    strong = [0.95, 0.5, 0.95, 0.95, 0.95, 0.95]
    sets = [_noisy_set(rng, seen, strong) for _ in range(40)]
    sets += [_noisy_set(rng, [*seen, shirt], [*strong, 0.95]) for _ in range(40)]
    cfg = TrackingConfig(labelling=LabellingConfig(contest_side_m=side_m))
    trk = MultiTargetTracker(cfg, rig, seed=16)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], held) == "p1/left_hand"
    assert _owner_of(out[-1], a["right_hand"]) == "p1/right_hand"
    if side_m > 0:
        assert _owner_of(out[-1], held) == "p1/left_hand"
        assert not _owner_of(out[-1], shirt).startswith("p1/")
    else:
        assert _owner_of(out[-1], shirt) == "p1/left_hand"


@pytest.mark.parametrize("side_m", [0.1, 0.0])
def test_a_shirt_point_stacked_above_the_right_hand_gives_its_slot_to_the_left_hand(rig, side_m):
    """a's left hand is hidden for 40 frame sets while a strong point 23 cm above the right
    hand (the colour fringe where a hanging sleeve meets the wall, three_people) becomes
    a's second hand. Then the left hand shows, held out in front, as strong: the support
    contest cannot tell it from the shirt point. Both of a's hands are on its right (b
    faces a, so a's facing is known) and the newcomer is on its left: the upper of the two
    gives its slot up, and a's hands are sided afresh. With contest_side_m 0 the left hand
    stays unlabelled."""
    rng = np.random.default_rng(8)
    a, b = body((2.0, 2.0), 0.0), body((3.2, 2.0), 180.0)
    shirt = a["right_hand"] + [0, 0, 0.23]
    held = a["head"] + 0.2 * a["left"] + 0.3 * a["fwd"] - [0, 0, 0.6]
    seen = [a["head"], a["right_hand"], shirt, b["head"], b["left_hand"], b["right_hand"]]
    sets = [_noisy_set(rng, seen, [0.95] * 6) for _ in range(40)]
    sets += [_noisy_set(rng, [*seen, held], [0.95] * 7) for _ in range(40)]
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(reacquire_unsupported=False),
        labelling=LabellingConfig(contest_side_m=side_m),
    )
    trk = MultiTargetTracker(cfg, rig, seed=17)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], shirt).startswith("p1/")
    if side_m > 0:
        assert _owner_of(out[-1], held) == "p1/left_hand"
        assert _owner_of(out[-1], a["right_hand"]) == "p1/right_hand"
        assert not _owner_of(out[-1], shirt).startswith("p1/")
    else:
        assert not _owner_of(out[-1], held).startswith("p1/")


@pytest.mark.parametrize("side_m", [0.1, 0.0])
def test_a_lost_left_hand_gives_its_slot_to_a_tracker_on_the_left(rig, side_m):
    """a's left hand, held out, jumps 0.34 m further out (a reach faster than its tracker
    follows): its tracker is lost and a new one starts at the hand. A strong point by the
    right elbow (a shaded shirt) has been unlabelled since it showed, after the hands. After
    yield_lost_s the lost left hand's slot goes to the tracker on the left, not to the
    older one on the right; with contest_side_m 0 the first unlabelled tracker in line, the
    shirt's, takes it. (The jump must lose the tracker: ``reacquire_unsupported`` off, else
    the hand's seed re-acquires it before it is lost.)"""
    rng = np.random.default_rng(7)
    a, b = body((2.0, 2.0), 0.0), body((3.6, 2.0), 180.0)
    held = a["head"] + 0.2 * a["left"] + 0.25 * a["fwd"] - [0, 0, 0.6]
    reach = held + 0.3 * a["fwd"] + 0.15 * a["left"]
    shirt = a["right_hand"] + [0, 0, 0.23]

    def frame(points) -> CandidateSet:
        return _noisy_set(rng, points, np.full(len(points), 0.95))

    rest = [a["head"], a["right_hand"], b["head"], b["left_hand"], b["right_hand"]]
    sets = [frame([*rest, held]) for _ in range(20)]
    sets += [frame([*rest, held, shirt]) for _ in range(20)]
    sets += [frame([*rest, reach, shirt]) for _ in range(30)]
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(reacquire_unsupported=False),
        labelling=LabellingConfig(contest_side_m=side_m),
    )
    trk = MultiTargetTracker(cfg, rig, seed=17)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], held) == "p1/left_hand"
    assert not _owner_of(out[39], shirt).startswith("p1/")
    if side_m > 0:
        assert _owner_of(out[-1], reach) == "p1/left_hand"
        assert not _owner_of(out[-1], shirt).startswith("p1/")
    else:
        assert _owner_of(out[-1], shirt) == "p1/left_hand"


@pytest.mark.parametrize(
    ("near_m", "offset_m", "back"), [(0.0, 0.0, False), (0.1, 0.0, True), (0.1, 0.2, False)]
)
def test_a_still_hand_whose_candidate_flickers_is_reacquired_at_once_near_its_last_position(
    rig, rng, near_m, offset_m, back
):
    # p1's left hand rests; from frame 45 its candidate (offset_m away from it) is seen only
    # every fourth frame set (a small dark hand that the skin stage finds now and then), never
    # three in a row
    frames = two_people_frames(90, b_from=0)
    rest = frames[44][1]
    for i in range(45, 90):
        frames[i] = [p for k, p in enumerate(frames[i]) if k != 1]
        if i % 4 == 0:
            frames[i].append(rest + [0.0, offset_m, 0.0])
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, reacquire_near_m=near_m)
    )
    out = run(MultiTargetTracker(cfg, rig, seed=4), frames, rng)
    hand = next(s.target_id for s in out[44].targets if s.label == "p1/left_hand")
    phase = {i: {s.target_id: s.phase for s in f.targets}.get(hand) for i, f in enumerate(out)}
    assert phase[47] is Phase.LOST
    seen = [i for i in range(52, 90) if i % 4 == 0]
    if back:  # back in the very frame set its candidate shows, with its label
        assert all(phase[i] in (Phase.UNLABELLED, Phase.NORMAL) for i in seen)
        assert all(phase[i + 1] is Phase.NORMAL for i in seen)
        last = {s.target_id: s for s in out[88].targets}[hand]
        assert last.label == "p1/left_hand" and np.linalg.norm(last.mean_m - rest) < 0.03
    else:  # never three candidates in a row, or too far from where it was lost: stays lost
        assert all(phase[i] is Phase.LOST for i in seen)
    assert len({s.target_id for f in out for s in f.targets}) == 6  # no new tracker


def _left_hand_run(rig, sets, **lifecycle) -> tuple[list[TrackFrame], int]:
    """Two people's candidate sets through a tracker (tracker seed 4, lone trackers never
    retired, ``lifecycle`` settings): its frames and the id p1's left hand had at frame 44."""
    cfg = TrackingConfig(lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, **lifecycle))
    trk = MultiTargetTracker(cfg, rig, seed=4)
    out = [trk.step(i * DT_NS, cs) for i, cs in enumerate(sets)]
    return out, next(s.target_id for s in out[44].targets if s.label == "p1/left_hand")


@pytest.mark.parametrize("weak_min, back", [(0.2, True), (0.3, False)])
def test_a_lost_hand_is_reacquired_by_a_weak_candidate_near_its_last_position(
    rig, rng, weak_min, back
):
    # p1's left hand vanishes at frame set 45 and comes back 10 cm away at 60, its candidate
    # weak (prior 0.25, under init_prior_min 0.3: the hand is cut off from the silhouette in
    # one view, and that view's silhouette term pulls its prior down)
    frames = two_people_frames(90, b_from=0)
    back_at = frames[44][1] + [0.0, 0.1, 0.0]
    sets = []
    for i, pts in enumerate(frames):
        cs = candidates([p for k, p in enumerate(pts) if k != 1 or i < 45], rng)
        if i >= 60:
            weak = back_at + rng.normal(0, 0.005, 3)
            cs = CandidateSet(np.vstack([cs.points_m, weak]), np.append(cs.prior, 0.25))
        sets.append(cs)
    out, hand = _left_hand_run(rig, sets, reacquire_prior_min=weak_min)
    assert {s.target_id: s.phase for s in out[59].targets}[hand] is Phase.LOST
    last = {s.target_id: s for s in out[89].targets}[hand]
    if back:  # its last position is the prior that makes a weak candidate enough
        assert last.phase is Phase.NORMAL and last.label == "p1/left_hand"
        assert np.linalg.norm(last.mean_m - back_at) < 0.03
    else:
        assert last.phase is Phase.LOST
    assert len({s.target_id for f in out for s in f.targets}) == 6  # weak: never a new tracker


def _ghost_story(a, b, ghost, rng) -> list[CandidateSet]:
    """70 frame sets, every point strong (prior 0.95): A's head, left hand and a ghost for
    30; B (head, hands) joins for 10; A's right hand shows for the last 30."""

    def frame(points) -> CandidateSet:
        pts = np.array(points) + rng.normal(0, 0.005, (len(points), 3))
        return CandidateSet(pts, np.full(len(pts), 0.95))

    sets = [frame([a["head"], a["left_hand"], ghost]) for _ in range(30)]
    with_b = [a["head"], a["left_hand"], ghost, b["head"], b["left_hand"], b["right_hand"]]
    sets += [frame(with_b) for _ in range(10)]
    sets += [frame([*with_b, a["right_hand"]]) for _ in range(30)]
    return sets


@pytest.mark.parametrize("by_owner", [False, True])
def test_a_ghost_on_another_body_gives_its_slot_to_the_real_hand(rig, by_owner):
    """A strong ghost (prior as high as a real hand's) joins person A as a hand while A's
    right hand is hidden. Person B then stands right behind it: the ghost is nearer B's head
    than A's. When A's real right hand shows, as strong as the ghost, the support contest
    cannot tell them apart; the ownership contest gives the slot to the real hand."""
    rng = np.random.default_rng(7)
    a = body((2.0, 2.0), 0.0)
    b = body((2.95, 2.0), 180.0)
    b["head"] = b["head"] - [0, 0, 0.1]
    ghost = np.array([2.55, 2.0, 0.95])  # 0.93 m from A's head, 0.76 m from B's
    sets = _ghost_story(a, b, ghost, rng)
    cfg = TrackingConfig(labelling=LabellingConfig(contest_by_owner=by_owner))
    trk = MultiTargetTracker(cfg, rig, seed=21)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], ghost).startswith("p1/")
    assert _owner_of(out[-1], b["left_hand"]).startswith("p2/")
    assert _owner_of(out[-1], b["right_hand"]).startswith("p2/")
    if by_owner:
        assert _owner_of(out[-1], a["right_hand"]).startswith("p1/")
        assert not _owner_of(out[-1], ghost).startswith("p1/")
    else:
        assert _owner_of(out[-1], ghost).startswith("p1/")
        assert not _owner_of(out[-1], a["right_hand"]).startswith("p1/")


@pytest.mark.parametrize("redecide", [False, True])
def test_a_hand_that_wins_a_slot_by_ownership_is_sided_afresh(rig, redecide):
    """A ghost far out on A's left takes A's left slot, so A's real left hand, nearer the
    middle, is sided "right". B comes and stands by the ghost; when A's real right hand
    shows, it wins the ghost's slot by ownership. Inheriting the ghost's side would leave
    both of A's hands wrong; sided afresh from A's facing, both are right. (A's facing is
    the default guess, towards the middle of the cameras, which is A's true facing: the
    hands lie on one line through the head, and the cue towards B is off.)"""
    rng = np.random.default_rng(5)
    a = body((2.0, 2.0), 0.0)
    ghost = a["head"] + 0.5 * a["left"] - [0, 0, 0.75]
    b = body((2.35, 2.75), -120.0)
    b["head"] = b["head"] - [0, 0, 0.2]
    sets = _ghost_story(a, b, ghost, rng)
    lcfg = LabellingConfig(redecide_sides=redecide, lr_revise_evidence=0, social_weight=0)
    cfg = TrackingConfig(labelling=lcfg)
    trk = MultiTargetTracker(cfg, rig, seed=21)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], ghost) == "p1/left_hand"
    assert _owner_of(out[39], a["left_hand"]) == "p1/right_hand"
    sides = (_owner_of(out[-1], a["left_hand"]), _owner_of(out[-1], a["right_hand"]))
    if redecide:
        assert sides == ("p1/left_hand", "p1/right_hand")
    else:
        assert sides == ("p1/right_hand", "p1/left_hand")


def test_a_ghost_tracker_that_slides_into_joined_hands_is_lost_and_the_pair_parts(rig, rng):
    """A ghost candidate 25 cm in front of where the hands will meet starts a tracker that
    never joins the person; while the hands are joined it slides into them. Inside the
    pair it would claim the candidate of a hand that leaves, and the pair would keep both
    labels on the other hand: as a duplicate of the pair's targets it is lost, and the
    pair parts with each label on its own hand."""
    frames, sides, p = clap_frames(cross=False)
    meet = frames[35 + 8][1]
    ghost = meet + 0.25 * p["fwd"]
    for i in range(20, 43):
        frames[i] = [*frames[i], ghost]
    for k, i in enumerate(range(43, 47)):  # into the joined hands over four frames
        u = (k + 1) / 4
        frames[i] = [frames[i][0], *merged([frames[i][1], ghost * (1 - u) + meet * u])]
    out = run(MultiTargetTracker(LONE, rig, seed=12), frames, rng)
    ids = {s.label: s.target_id for s in out[34].targets}
    starts = [t.target_id for f in out for t in f.transitions if t.old is Phase.UNINITIALISED]
    people = {ids["p1/head"], ids["p1/left_hand"], ids["p1/right_hand"]}
    ghost_id = [t for t in starts if t not in people]
    assert len(ghost_id) == 1
    lost = {t.target_id for f in out for t in f.transitions if t.new is Phase.LOST}
    assert ghost_id[0] in lost
    splits = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    assert {t.target_id for t in splits} == {ids["p1/left_hand"], ids["p1/right_hand"]}
    final = by_label(out[-1])
    assert np.linalg.norm(final["p1/left_hand"] - sides[-1][0]) < 0.04
    assert np.linalg.norm(final["p1/right_hand"] - sides[-1][1]) < 0.04


def near_miss_frames(gap_m: float, slide_m: float, flicker: int = 0):
    """Two people (a at x 2.0 facing b at x 3.0) raise their right hands towards each other
    and hold them ``gap_m`` apart and still (the negative scene: 27 cm). One frame set after
    they stop, a's candidate is missing and one candidate lies ``slide_m`` from b's hand
    towards a's (their blobs touched in one view); a's candidate stays missing for
    ``flicker`` more frame sets (too weak to count); then both candidates are back where the
    hands are. Returns (frames, a's held hand, b's held hand)."""
    mid = np.array([2.5, 1.96, 1.05])
    held_a, held_b = mid - [gap_m / 2, 0, 0], mid + [gap_m / 2, 0, 0]
    frames, rest = right_hands_held_out(held_a, held_b)
    touched = held_b + slide_m * (held_a - held_b) / gap_m
    frames += [[*rest, held_a, held_b], [*rest, touched]] + [[*rest, held_b]] * flicker
    frames += [[*rest, held_a, held_b]] * 20
    return frames, held_a, held_b


@pytest.mark.parametrize(
    "lifecycle, flicker, parted",
    [
        ({}, 0, True),
        ({"unjoin_gate_m": 0.0}, 0, False),
        ({}, 3, True),
        ({"unjoin_within_s": 0.15}, 3, False),
    ],
)
def test_hands_held_near_each_other_that_never_met_are_parted_where_they_were(
    rig, lifecycle, flicker, parted
):
    """Two right hands stop 27 cm apart; a's candidate vanishes for one frame set beside
    b's, so the two combine (one lost its candidate within hand_merge_distance_m of the other
    while approaching it). Their candidates come back where the hands are: the pair
    separates two frame sets later with ``met`` False, each tracker on its own hand with
    its label. With unjoin_gate_m = 0 the pair stays combined while the hands stay still,
    and would part as a handshake when they leave. With ``flicker``, a's candidate stays
    missing for three more frame sets (0.27 s: on the negative scene the weaker hand's
    candidate flickers under separate_min_prior): the modes still appear within
    unjoin_within_s (0.5 s) of the join, but not within the 0.15 s it was until session 75."""
    frames, held_a, held_b = near_miss_frames(0.27, 0.05, flicker=flicker)
    lc = LifecycleConfig(**lifecycle)
    trk = MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=13)
    out = run(trk, frames, np.random.default_rng(7))
    joins = [t for f in out for t in f.transitions if t.new is Phase.COMBINED]
    parts = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    assert {t.label for t in joins} == {"p1/right_hand", "p2/right_hand"}
    if parted:
        assert len(parts) == 2 and not any(t.met for t in parts)
        assert parts[0].t_ns - joins[0].t_ns <= (3 + flicker) * DT_NS
        assert _owner_of(out[-1], held_a) == "p1/right_hand"
        assert _owner_of(out[-1], held_b) == "p2/right_hand"
    else:
        assert not parts
        assert all(s.phase is Phase.COMBINED for s in out[-1].targets if "right" in s.label)


@pytest.mark.parametrize("rejoin_s", [1.0, 0.0])
def test_hands_that_never_met_and_drift_together_again_have_still_not_met(rig, rejoin_s):
    """The near miss above, then a's candidate slides to 5 cm from b's hand and back within
    0.4 s (the negative scene with the bare-forearm option, seed 1: after the first pair
    parted as never met, a's tracker drifted onto a candidate between the hands and the
    two combined again, closer than combine_distance_m, and parted later as a handshake).
    With rejoin_never_met_s the second pair is joined apart, with the places where the
    first parted as its own, and parts as never met when the hands show there again;
    without it the second join is a meeting, and the pair parts as one when the hands go
    home."""
    frames, held_a, held_b = near_miss_frames(0.27, 0.05)
    rest, frames = frames[-1][:-2], frames[:-15]
    toward = held_b - held_a
    for u in (0.35, 0.7, 0.8, 0.8, 0.7, 0.35):
        frames.append([*rest, held_a + u * toward, held_b])
    frames += [[*rest, held_a, held_b]] * 20
    a, b = body((2.0, 2.0), 0.0), body((3.0, 2.0), 180.0)
    for u in np.linspace(0, 1, 7)[1:]:  # the hands go home
        frames.append(
            [
                *rest,
                held_a + u * (a["right_hand"] - held_a),
                held_b + u * (b["right_hand"] - held_b),
            ]
        )
    frames += [[*rest, a["right_hand"], b["right_hand"]]] * 10
    lc = LifecycleConfig(rejoin_never_met_s=rejoin_s)
    trk = MultiTargetTracker(TrackingConfig(lifecycle=lc), rig, seed=13)
    out = run(trk, frames, np.random.default_rng(7))
    joins = [t for f in out for t in f.transitions if t.new is Phase.COMBINED]
    parts = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    assert len(joins) == 4  # two pairs, one after the other
    assert len(parts) == 4 and not any(t.met for t in parts[:2])
    assert all(t.met is (rejoin_s == 0) for t in parts[2:])
    assert _owner_of(out[-1], a["right_hand"]) == "p1/right_hand"
    assert _owner_of(out[-1], b["right_hand"]) == "p2/right_hand"


@pytest.mark.parametrize("hand_speed_mps, back", [(2.0, True), (0.5, False)])
def test_a_hand_that_outran_its_tracker_is_reacquired_where_it_went(
    rig, rng, hand_speed_mps, back
):
    """p1's left hand swings 0.54 m forward and up in 0.2 s (2.7 m/s; demo, p2's left hand at
    9.7-10.0 s): its tracker cannot follow, the hand's candidate goes unexplained for three
    frame sets and the tracker is lost. The hand's new candidate is re-acquired by the lost
    tracker once the gate has grown at a hand's speed since the hand was last supported;
    grown at reacquire_speed_mps from the moment of loss it stays short and a new tracker
    takes the hand (an identity switch)."""
    frames = two_people_frames(80, b_from=0)
    rest = frames[44][1]
    went = rest + [0.45, 0.0, 0.3]
    for i in range(45, 80):
        frames[i][1] = rest + min(1.0, (i - 44) / 3) * (went - rest)
    sets = [
        candidates([p for k, p in enumerate(pts) if k != 1 or not 45 <= i <= 47], rng)
        for i, pts in enumerate(frames)
    ]
    out, hand = _left_hand_run(rig, sets, reacquire_hand_speed_mps=hand_speed_mps)
    assert {s.target_id: s.phase for s in out[47].targets}[hand] is Phase.LOST
    now = {s.label: s for s in out[-1].targets}
    assert np.linalg.norm(now["p1/left_hand"].mean_m - went) < 0.03
    assert (now["p1/left_hand"].target_id == hand) is back
    assert len({s.target_id for f in out for s in f.targets}) == (6 if back else 7)


@pytest.mark.parametrize("own_body", [True, False])
def test_a_lost_hand_is_not_reacquired_on_another_persons_body(rig, rng, own_body):
    """b holds its right hand out towards a, where it goes unseen for 1 s (in the exchange
    scene, seed 0, the taker's hand was hidden by the ball and the giver's). Then something
    shows at a's chest, 0.36 m from where b's hand was lost: inside the re-acquisition gate
    (0.75 m after 1 s), but a's head is nearer to it than b's by more than the labelling's
    person margin. b's lost hand must not come back there (it came back on the giver's hand
    and took the taker's label to the other body); with the setting off it does."""
    a, b = body((2.0, 2.0), 0.0), body((2.9, 2.0), 180.0)
    out_m = np.array([2.55, 2.1, 1.05])
    at_a = np.array([2.2, 1.95, 1.1])
    still = [a["head"], a["left_hand"], a["right_hand"], b["head"], b["left_hand"]]
    frames = [[*still, b["right_hand"]] for _ in range(45)]
    frames += [
        [*still, b["right_hand"] + u * (out_m - b["right_hand"])] for u in np.linspace(0, 1, 9)[1:]
    ]
    frames += [still] * 15 + [[*still, at_a]] * 15
    cfg = TrackingConfig(lifecycle=LifecycleConfig(reacquire_own_body=own_body))
    out = run(MultiTargetTracker(cfg, rig, seed=5), frames, rng)
    b_hand = next(s for s in out[52].targets if np.linalg.norm(s.mean_m - out_m) < 0.1)
    assert b_hand.label.endswith("/right_hand")
    last = {s.target_id: s for s in out[-1].targets}
    came_back = b_hand.target_id in last and (
        np.linalg.norm(last[b_hand.target_id].mean_m - at_a) < 0.1
    )
    assert came_back is not own_body


def test_a_hand_that_left_a_pair_unseen_parts_it_where_it_came_back(rig, rng):
    """After a clap the right hand leaves unseen (two frame sets without its candidate) and
    comes back at rest 35 cm from the left hand, which stays where they met. The modes
    appeared already apart and never move farther apart, so separate_gain_m alone keeps the
    pair combined (both labels on the left hand); with separate_far_m the pair parts and
    each label goes to its own hand."""
    frames, _, p = clap_frames(cross=False)
    rest_end = 35 + 8 + 5
    head, meet = frames[rest_end - 1][0], frames[rest_end - 1][1]
    back = meet - 0.35 * p["left"]
    frames = frames[:rest_end] + [[head, meet]] * 2 + [[head, meet, back]] * 15

    def final(far_m: float) -> dict[str, tuple[np.ndarray, Phase]]:
        cfg = TrackingConfig(
            lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, separate_far_m=far_m)
        )
        out = run(MultiTargetTracker(cfg, rig, seed=7), frames, rng)
        return {s.label: (s.mean_m, s.phase) for s in out[-1].targets}

    assert LifecycleConfig().separate_far_m == 0.3  # on by default
    parted = final(0.3)
    assert np.linalg.norm(parted["p1/left_hand"][0] - meet) < 0.04
    assert np.linalg.norm(parted["p1/right_hand"][0] - back) < 0.04
    assert parted["p1/right_hand"][1] is Phase.NORMAL
    stuck = final(0.0)
    assert stuck["p1/right_hand"][1] is Phase.COMBINED


def test_a_steady_stray_for_fewer_than_separate_far_frames_does_not_part_a_pair(rig, rng):
    """A candidate 36 cm from joined hands, in the same place for three frame sets (a
    skin-coloured patch of a shirt seen for a moment), is not a hand that left the pair:
    separate_far_frames (4) asks for more. Seen for four, it parts them."""
    frames, _, p = clap_frames(cross=False)
    joined = list(range(35 + 8, 35 + 8 + 5))
    stray = frames[joined[0]][1] + 0.36 * p["fwd"]

    def splits(n_stray: int) -> list[int]:
        fr = [[*f, stray] if i in joined[1 : 1 + n_stray] else f for i, f in enumerate(frames)]
        out = run(MultiTargetTracker(LONE, rig, seed=7), fr, rng)
        return [i for i, f in enumerate(out) for t in f.transitions if t.old is Phase.COMBINED]

    assert min(splits(3)) > max(joined)  # parted only when the hands themselves part
    assert min(splits(4)) <= max(joined)


def _ghost_joins_the_left_hand(rng):
    """A person (head, left hand) with a strong ghost (prior 0.95, seen by as many views as a
    hand) 20 cm right of the left hand for 30 frame sets, while the right hand is hidden:
    the ghost takes the right hand's slot. The right hand then shows (0.95), 30 cm right of
    the ghost, and gets a tracker with no slot free; after 10 frame sets the ghost slides
    onto the left hand over four and stays in it (one candidate). Returns (body, candidate
    sets)."""
    a = body((2.0, 2.0), 0.0)
    ghost = a["left_hand"] - 0.2 * a["left"]
    sets = [_noisy_set(rng, [a["head"], a["left_hand"], ghost], [0.95] * 3) for _ in range(30)]
    seen = [a["head"], a["left_hand"], a["right_hand"]]
    sets += [_noisy_set(rng, [*seen, ghost], [0.95] * 4) for _ in range(10)]
    for u in (0.25, 0.5, 0.75, 1.0):
        slid = merged([*seen, ghost * (1 - u) + a["left_hand"] * u])
        sets.append(_noisy_set(rng, slid, [0.95] * len(slid)))
    sets += [_noisy_set(rng, seen, [0.95] * 3) for _ in range(40)]
    return a, sets


@pytest.mark.parametrize("wait_s", [0.5, 0.0])
def test_a_pair_of_one_persons_hands_parts_onto_a_third_hand(rig, wait_s):
    """The ghost's tracker, holding the right hand's slot, combines with the left hand when it
    slides in; the real right hand then gets a tracker that no slot is free for. Seen as
    well as the pair, 30 cm from it, it is a third hand of the person: after
    ``own_pair_third_hand_s`` the pair parts onto it, each label on its own side, as a pair
    that never met, and the third tracker is retired. With 0 (never) both labels stay on
    the left hand."""
    a, sets = _ghost_joins_the_left_hand(np.random.default_rng(7))
    cfg = TrackingConfig(lifecycle=LifecycleConfig(own_pair_third_hand_s=wait_s))
    trk = MultiTargetTracker(cfg, rig, seed=16)
    out = [trk.step(i * DT_NS, c) for i, c in enumerate(sets)]
    assert _owner_of(out[39], a["left_hand"]) == "p1/left_hand"
    joined = [t for f in out[40:50] for t in f.transitions if t.new is Phase.COMBINED]
    assert {t.label for t in joined} == {"p1/left_hand", "p1/right_hand"}
    final = {s.label: s for s in out[-1].targets}
    if wait_s > 0:
        parted = [t for f in out[50:] for t in f.transitions if t.old is Phase.COMBINED]
        assert len(parted) == 2 and not any(t.met for t in parted)
        assert _owner_of(out[-1], a["left_hand"]) == "p1/left_hand"
        assert _owner_of(out[-1], a["right_hand"]) == "p1/right_hand"
        assert final["p1/left_hand"].phase is final["p1/right_hand"].phase is Phase.NORMAL
    else:
        assert final["p1/left_hand"].phase is Phase.COMBINED
        assert not _owner_of(out[-1], a["right_hand"]).startswith("p1/")


def test_a_pair_out_of_one_owners_reach_gives_the_estimate_to_the_other_owner(rig, rng):
    """a's and b's right hands come side by side in front of them and close in along y to
    shake; the pair then follows b's hand home while a's hand goes unseen, and a candidate
    shows by b's chest, just within a's reach (a ghost, or a's hand held out). Out of a's
    reach, the pair's estimate is b's hand and the candidate is where a's hand may be: the
    pair parts so. The owner rule cannot tell (the candidate is nearer b's head, the
    estimate nearer b's too: 0.09 m between the two ways), and the angle rule, reading the
    sideways approach, gave b's label to the candidate and a's to b's hand."""
    a, b = body((2.0, 2.0), 0.0), body((3.0, 2.0), 180.0)
    rest = _head_and_left
    meet = np.array([2.5, 2.0, 1.05])
    side_a, side_b = np.array([2.5, 1.7, 1.05]), np.array([2.5, 2.3, 1.05])
    frames = [[*rest(a), a["right_hand"], *rest(b), b["right_hand"]] for _ in range(45)]
    for u in np.linspace(0, 1, 7)[1:]:
        ra = a["right_hand"] + u * (side_a - a["right_hand"])
        frames.append([*rest(a), *rest(b), ra, b["right_hand"] + u * (side_b - b["right_hand"])])
    for u in np.linspace(0, 1, 5)[1:]:
        frames.append(
            [
                *rest(a),
                *rest(b),
                *merged([side_a + u * (meet - side_a), side_b + u * (meet - side_b)]),
            ]
        )
    frames += [[*rest(a), *rest(b), meet] for _ in range(6)]
    home_b = [meet + u * (b["right_hand"] - meet) for u in np.linspace(0, 1, 7)[1:]]
    spot = np.array([2.75, 2.35, 1.35])
    frames += [
        [*rest(a), *rest(b), rb] + ([spot] if k >= 5 else [])
        for k, rb in enumerate(home_b + [home_b[-1]] * 20)
    ]
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=11), frames, rng)
    heads = {s.person: s.mean_m for s in out[-1].targets if s.label.endswith("/head")}
    pa = min(heads, key=lambda k: np.linalg.norm(heads[k] - a["head"]))
    pb = min(heads, key=lambda k: np.linalg.norm(heads[k] - b["head"]))
    assert _owner_of(out[-1], b["right_hand"]) == f"p{pb}/right_hand"
    assert _owner_of(out[-1], spot) == f"p{pa}/right_hand"


@pytest.mark.parametrize("wait_s", [0.05, 0.0])
def test_a_hand_seen_again_only_at_home_parts_the_pair_it_left(rig, rng, wait_s):
    """a (x 1.9) and b (x 3.1) shake right hands; b's hand then leaves unseen and shows again
    at b's side, 0.7 m from the pair, beyond ``pair_seed_gate_m``: a new tracker starts on it
    while the pair holds a's hand. It is clearly b's, b's left hand is tracked elsewhere,
    and a cannot reach it: it is b's hand gone home, and after ``home_hand_s`` the pair
    parts onto it, b's label there, a's on a's hand, as a pair that met. With 0 (never)
    b's label stays with a's hand in the pair."""
    a, b = body((1.9, 2.0), 0.0), body((3.1, 2.0), 180.0)
    rest = _head_and_left
    meet = np.array([2.5, 2.0, 1.05])
    frames = [[*rest(a), a["right_hand"], *rest(b), b["right_hand"]] for _ in range(45)]
    for u in np.linspace(0, 1, 9)[1:]:
        ra = a["right_hand"] + u * (meet - a["right_hand"])
        rb = b["right_hand"] + u * (meet - b["right_hand"])
        frames.append([*rest(a), *rest(b), *merged([ra, rb])])
    frames += [[*rest(a), *rest(b), meet] for _ in range(10)]
    frames += [[*rest(a), *rest(b), meet] for _ in range(3)]  # b's hand leaves unseen
    frames += [[*rest(a), *rest(b), meet, b["right_hand"]] for _ in range(15)]
    cfg = TrackingConfig(lifecycle=LifecycleConfig(home_hand_s=wait_s))
    out = run(MultiTargetTracker(cfg, rig, seed=11), frames, rng)
    heads = {s.person: s.mean_m for s in out[-1].targets if s.label.endswith("/head")}
    pa = min(heads, key=lambda k: np.linalg.norm(heads[k] - a["head"]))
    pb = min(heads, key=lambda k: np.linalg.norm(heads[k] - b["head"]))
    parted = [t for f in out for t in f.transitions if t.old is Phase.COMBINED]
    if wait_s > 0:
        assert len(parted) == 2 and all(t.met for t in parted)
        assert _owner_of(out[-1], b["right_hand"]) == f"p{pb}/right_hand"
        assert _owner_of(out[-1], meet) == f"p{pa}/right_hand"
    else:
        assert not parted
        assert not _owner_of(out[-1], b["right_hand"]).startswith(f"p{pb}/")


def walking_with_a_bare_forearm(hidden: int, back: int, n: int):
    """One person walking along x at 0.5 m/s. From frame ``hidden`` the left hand's own
    candidate is missing while one on its bare forearm rises over 6 frames to 20 cm above
    it; from ``back`` the hand's candidate shows again beside it, and from ``back`` + 8 the
    forearm's is gone. Returns the frames and the left hand's path."""
    p = body((1.5, 2.0), 0.0)
    step = np.array([0.5 * DT_NS * 1e-9, 0.0, 0.0])
    up = np.array([0.0, 0.0, 0.2])
    frames, left = [], []
    for k in range(n):
        shift = k * step
        hand = p["left_hand"] + shift
        pts = [p["head"] + shift, p["right_hand"] + shift]
        if hidden <= k < back + 8:
            pts.append(hand + min((k - hidden + 1) / 6, 1.0) * up)
        if not hidden <= k < back:
            pts.append(hand)
        frames.append(pts)
        left.append(hand)
    return frames, left


@pytest.mark.parametrize("gate_m", [0.5, 0.0])
def test_a_hand_tracker_that_slid_up_its_bare_forearm_is_put_back_on_the_hand(rig, rng, gate_m):
    """A walking person's left hand loses its candidate for 10 frame sets while one on its
    bare forearm, 20 cm up, stays (the bare-forearm option: p2 of the negative scene, in all
    six seeds at 4.5 s), and its tracker slides up onto it. When the hand's candidate shows
    again, it lies where the tracker stood relative to the head, farther out from the head:
    the hand's own tracker is put back on it and keeps its label. With the rule off
    (``slid_hand_gate_m`` 0) a new tracker takes the hand."""
    hidden, back = 40, 50
    frames, left = walking_with_a_bare_forearm(hidden, back, 75)
    cfg = TrackingConfig(lifecycle=LifecycleConfig(slid_hand_gate_m=gate_m))
    out = run(MultiTargetTracker(cfg, rig, seed=5), frames, rng)
    before = next(s for s in out[hidden - 1].targets if s.label == "p1/left_hand")
    assert np.linalg.norm(before.mean_m - left[hidden - 1]) < 0.05
    slid = next(s for s in out[back - 1].targets if s.target_id == before.target_id)
    assert np.linalg.norm(slid.mean_m - left[back - 1]) > 0.12  # it followed the forearm up
    near = min(out[-1].targets, key=lambda s: np.linalg.norm(s.mean_m - left[-1]))
    assert np.linalg.norm(near.mean_m - left[-1]) < 0.05
    if gate_m > 0:
        assert near.target_id == before.target_id and near.label == "p1/left_hand"
    else:
        assert near.target_id != before.target_id


@pytest.mark.parametrize("covered", [False, True])
def test_a_hand_dropped_fast_from_the_face_parts_from_the_head(rig, rng, covered):
    """A person raises the left hand to the face and holds it there: the two trackers
    combine, whether the hand's candidate merges with the head's or hides it from 40 cm
    away (the head's tracker then loses its support as the hand comes to it: they met, it
    has not drifted onto the hand, as with two hands meeting; without that, the head is
    lost and the two labels end up swapped). Then the hand drops back to the hip in
    0.2 s, unseen on the way. Its candidate shows again 0.9 m from the pair, beyond
    ``pair_seed_gate_m``; a person's hand is within arm's reach of the head, so the pair
    parts on it: the hand's tracker takes it with its label and the head's stays on the head
    (negative scene, bare-forearm option on, p2 at 9 s: a new tracker took the hand, and in
    seed 5 the head's tracker was lost as drifted)."""
    p = body((2.0, 2.0), 0.0)
    face = p["head"] + 0.06 * p["fwd"] - [0.0, 0.0, 0.05]
    rest = [p["head"], p["left_hand"], p["right_hand"]]
    frames = [list(rest) for _ in range(30)]
    for k in range(1, 7):
        hand = p["left_hand"] + k / 6 * (face - p["left_hand"])
        if covered and np.linalg.norm(hand - p["head"]) < 0.4:  # the hand hides the face
            frames.append([hand, p["right_hand"]])
        else:
            frames.append(merged([p["head"], hand, p["right_hand"]]))
    at_face = [face, p["right_hand"]] if covered else merged([p["head"], face, p["right_hand"]])
    frames += [list(at_face) for _ in range(15)]
    frames += [[p["head"], p["right_hand"]] for _ in range(3)]  # dropping, unseen
    frames += [list(rest) for _ in range(25)]
    out = run(MultiTargetTracker(LONE, rig, seed=3), frames, rng)
    ids = {s.label: s.target_id for s in out[29].targets}
    assert any(t.new is Phase.COMBINED for f in out[30:51] for t in f.transitions)
    assert not any(t.new is Phase.LOST for f in out[30:] for t in f.transitions)
    final = {s.label: s for s in out[-1].targets}
    hand, head = final["p1/left_hand"], final["p1/head"]
    assert hand.target_id == ids["p1/left_hand"] and head.target_id == ids["p1/head"]
    assert np.linalg.norm(hand.mean_m - p["left_hand"]) < 0.05
    assert np.linalg.norm(head.mean_m[:2] - p["head"][:2]) < 0.05  # (reported above its skin)


@pytest.mark.parametrize("on", [True, False])
def test_a_hand_seen_again_just_before_its_tracker_is_lost_keeps_its_tracker(rig, rng, on):
    """A person's right hand, drawn back unseen from a handshake, shows again 40 cm from
    where its tracker coasts: the tracker loses its support at once, and the hand's new
    candidate is a confirmed seed in the very frame set that the tracker is lost (handshake
    scene with ``tops_from_heads``, p2 at 10.07 s, four seeds of six). The hand's tracker,
    unsupported, is matched with the seed as a lost one would be (``reacquire_unsupported``;
    the seed is within its head's reach) and keeps its identity and label; with the rule
    off a new tracker takes the hand."""
    p = body((2.0, 2.0), 0.0)
    out_there = p["right_hand"] + 0.4 * p["fwd"] + [0.0, 0.0, 0.2]
    frames = [[p["head"], p["left_hand"], out_there] for _ in range(30)]
    frames += [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(20)]
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, reacquire_unsupported=on)
    )
    out = run(MultiTargetTracker(cfg, rig, seed=2), frames, rng)
    before = {s.label: s.target_id for s in out[29].targets}
    assert set(before) == {"p1/head", "p1/left_hand", "p1/right_hand"}
    near = min(out[-1].targets, key=lambda s: np.linalg.norm(s.mean_m - p["right_hand"]))
    assert np.linalg.norm(near.mean_m - p["right_hand"]) < 0.05
    if on:
        assert near.target_id == before["p1/right_hand"] and near.label == "p1/right_hand"
        assert not any(t.new is Phase.LOST for f in out[30:] for t in f.transitions)
    else:
        assert near.target_id != before["p1/right_hand"]


@pytest.mark.parametrize("bridge", [True, False])
def test_a_lost_hand_whose_candidate_shows_two_frame_sets_in_three_is_reacquired(rig, rng, bridge):
    """A right hand reaches for a box past a table's edge, hidden long enough for its
    tracker to be lost; at the box its candidate is there two frame sets in three (the
    three_people scene, p3 at 8.9-9.7 s), so no seed lasts ``init_confirm_frames`` in a row.
    With ``reacquire_bridge`` the lost tracker takes a seed whose run skipped those single
    frame sets and follows the hand again; without it the hand stays lost. No new tracker
    starts either way: a new one still needs an unbroken run."""
    p = body((2.0, 2.0), 0.0)
    at_box = p["right_hand"] + 0.3 * p["fwd"] + [0.0, 0.0, 0.1]
    frames = [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(30)]
    frames += [[p["head"], p["left_hand"]] for _ in range(6)]
    n_hidden = len(frames)
    for k in range(12):
        frames.append([p["head"], p["left_hand"]] + ([at_box] if k % 3 != 2 else []))
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, reacquire_bridge=bridge)
    )
    out = run(MultiTargetTracker(cfg, rig, seed=4), frames, rng)
    hand_id = {s.label: s.target_id for s in out[29].targets}["p1/right_hand"]
    lost = [t for f in out[30:n_hidden] for t in f.transitions if t.new is Phase.LOST]
    assert [t.target_id for t in lost] == [hand_id]
    assert not [t for f in out[n_hidden:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    hand = {s.target_id: s for s in out[-2].targets}[hand_id]
    if bridge:
        assert hand.phase is not Phase.LOST
        assert np.linalg.norm(hand.mean_m - at_box) < 0.05
    else:
        assert hand.phase is Phase.LOST


@pytest.mark.parametrize("on", [True, False])
def test_a_hand_that_outran_its_tracker_is_not_taken_by_its_lost_other_hand(rig, rng, on):
    """The right hand is hidden and its tracker lost; then the left hand jumps 37 cm out
    and up (swung faster than its tracker follows). Its seed confirms in the frame set its tracker
    runs out of support, within the lost right hand's growing gate: the left hand's
    tracker, unsupported but not yet lost, is matched together with the lost one and, being
    nearer, takes it (demo with ``tops_from_heads``, p2 at 10.0 s, seeds 1-3). With
    ``reacquire_unsupported`` off the lost right hand's tracker takes the left hand."""
    p = body((2.0, 2.0), 0.0)
    out_left = p["left_hand"] + 0.3 * p["fwd"] + 0.15 * p["left"] + [0.0, 0.0, 0.15]
    frames = [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(30)]
    frames += [[p["head"], p["left_hand"]] for _ in range(4)]
    frames += [[p["head"], out_left] for _ in range(10)]
    frames += [[p["head"], out_left, p["right_hand"]] for _ in range(10)]
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(retire_unclaimed_s=0.0, reacquire_unsupported=on)
    )
    out = run(MultiTargetTracker(cfg, rig, seed=4), frames, rng)
    before = {s.label: s.target_id for s in out[29].targets}
    assert set(before) == {"p1/head", "p1/left_hand", "p1/right_hand"}
    on_left = min(out[-1].targets, key=lambda s: np.linalg.norm(s.mean_m - out_left))
    assert np.linalg.norm(on_left.mean_m - out_left) < 0.05
    if on:
        assert on_left.target_id == before["p1/left_hand"] and on_left.label == "p1/left_hand"
    else:
        assert on_left.target_id == before["p1/right_hand"]


@pytest.mark.parametrize("lost_claim_s", [0.5, 0.0])
def test_a_hand_lost_beside_another_keeps_its_candidate_from_the_neighbour(rig, rng, lost_claim_s):
    """Two people hold their right hands out 24 cm apart (the negative scene). b's
    candidate vanishes and b's tracker is lost; then a's candidate vanishes just as b's
    comes back. Only active targets claiming candidates, a's tracker, unsupported and
    spreading, slides onto b's candidate, and when a's shows again b's lost tracker takes
    it: the two hands swap trackers. A labelled target lost at most ``lost_claim_s`` still
    claims the candidates around where it is looked for, so a's tracker stays clear of b's
    candidate and each hand keeps its own."""
    held_a, held_b = np.array([2.38, 1.95, 1.05]), np.array([2.62, 1.97, 1.05])
    frames, rest = right_hands_held_out(held_a, held_b)
    frames += [[*rest, held_a, held_b]] * 15 + [[*rest, held_a]] * 6
    frames += [[*rest, held_b]] * 3 + [[*rest, held_a, held_b]] * 4
    cfg = TrackingConfig(filter=FilterConfig(lost_claim_s=lost_claim_s))
    out = run(MultiTargetTracker(cfg, rig, seed=13), frames, rng)
    owners = (_owner_of(out[-1], held_a), _owner_of(out[-1], held_b))
    if lost_claim_s > 0:
        assert owners == ("p1/right_hand", "p2/right_hand")
    else:
        assert owners == ("p2/right_hand", "p1/right_hand")


@pytest.mark.parametrize("radius_m", [0.3, 0.0])
def test_a_lost_hand_is_not_reacquired_on_its_heads_crown(rig, rng, radius_m):
    """A raised right hand goes unseen for a second while the head shows a second
    candidate 17 cm above its first (a crown; just beyond explained_radius_m, so a seed).
    The lost hand's gate has grown to reacquire_max_m, which reaches the crown (held-out
    pick_place take 102 at 12.2 s: the hand then stayed combined with its head to the end).
    It must wait for its own candidate and come back on it with its label; with the test off
    (``reacquire_above_head_m`` 0) it is re-acquired on the crown."""
    p = body((2.5, 2.0), 90.0)
    raised = p["right_hand"] + 0.3 * p["fwd"] + [0.0, 0.0, 0.4]
    crown = p["head"] + [0.0, 0.0, 0.17]
    frames = [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(35)]
    frames += [
        [p["head"], p["left_hand"], p["right_hand"] + u * (raised - p["right_hand"])]
        for u in np.linspace(0, 1, 6)[1:]
    ]
    frames += [[p["head"], p["left_hand"], raised] for _ in range(10)]
    n_hidden = len(frames)
    frames += [[p["head"], p["left_hand"]] + ([crown] if k >= 2 else []) for k in range(16)]
    frames += [[p["head"], p["left_hand"], raised, crown] for _ in range(10)]
    cfg = TrackingConfig(lifecycle=LifecycleConfig(reacquire_above_head_m=radius_m))
    out = run(MultiTargetTracker(cfg, rig, seed=5), frames, rng)
    hand_id = {s.label: s.target_id for s in out[n_hidden - 1].targets}["p1/right_hand"]
    on_crown = [
        f
        for f in out[n_hidden:]
        for s in f.targets
        if s.target_id == hand_id
        and s.phase is not Phase.LOST
        and np.linalg.norm(s.mean_m - crown) < 0.08
    ]
    if radius_m == 0:
        assert on_crown
        return
    assert not on_crown
    final = {s.label: s for s in out[-1].targets}
    assert final["p1/right_hand"].target_id == hand_id
    assert np.linalg.norm(final["p1/right_hand"].mean_m - raised) < 0.05


def test_a_lost_hand_rising_to_the_face_is_reacquired_there(rig, rng):
    """A right hand rises to the face at 0.6 m/s and is lost 35 cm below it (its blob
    merges with the face's); its candidate shows again at the face, 13 cm above the head's
    estimate. It was moving towards that point when lost (held-out negative takes 101 and
    103, touch_face at 8.1-8.8 s), so it is re-acquired there, keeping its tracker; no new
    tracker starts on it."""
    p = body((2.5, 2.0), 90.0)
    face = p["head"] + 0.12 * p["fwd"] + [0.0, 0.0, 0.13]
    frames = [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(35)]
    path = [p["right_hand"] + u * (face - p["right_hand"]) for u in np.linspace(0, 1, 18)[1:]]
    frames += [[p["head"], p["left_hand"], q] for q in path[:11]]
    n_lost = len(frames)
    frames += [[p["head"], p["left_hand"]] for _ in range(6)]
    frames += [[p["head"], p["left_hand"], face] for _ in range(10)]
    out = run(MultiTargetTracker(TrackingConfig(), rig, seed=5), frames, rng)
    hand_id = {s.label: s.target_id for s in out[n_lost - 1].targets}["p1/right_hand"]
    starts = [t for f in out[n_lost:] for t in f.transitions if t.old is Phase.UNINITIALISED]
    assert not [t for t in starts if np.linalg.norm(t.position_m - face) < 0.1]
    near = [s for s in out[-1].targets if np.linalg.norm(s.mean_m - face) < 0.08]
    assert hand_id in {s.target_id for s in near}


@pytest.mark.parametrize(("supported", "near_m"), [(False, 0.0), (True, 0.0), (True, 0.1)])
def test_a_hand_swung_up_past_a_ghost_keeps_the_tracker_that_follows_it(
    rig, rng, supported, near_m
):
    """A right hand swung up (the negative scene's wave, 5.8-6.1 s) loses its candidate for
    two frame sets while a ghost shows 0.4 m in front of it; the hand's candidate is back
    beside its tracker, which followed it, in the frame set the ghost's seed confirms. With
    ``reacquire_supported`` off the tracker, supported again, stays on the hand; on (the
    session-77 rule as it was) it is restarted on the ghost, and a new tracker takes the hand;
    on with ``reacquire_supported_near_m`` 0.1 m it is spared, a candidate being that near
    it (session 95)."""
    p = body((2.0, 2.0), 0.0)
    rise = [p["right_hand"] + [0.0, 0.0, 0.06 * k] for k in range(12)]
    ghost = p["right_hand"] + 0.4 * p["fwd"] + [0.0, 0.0, 0.3]
    frames = [[p["head"], p["left_hand"], p["right_hand"]] for _ in range(30)]
    frames += [[p["head"], p["left_hand"], rise[k]] for k in range(3)]
    frames += [[p["head"], p["left_hand"], ghost] for k in range(3, 5)]
    frames += [[p["head"], p["left_hand"], rise[k], ghost] for k in range(5, 12)]
    cfg = TrackingConfig(
        lifecycle=LifecycleConfig(
            retire_unclaimed_s=0.0,
            reacquire_supported=supported,
            reacquire_supported_near_m=near_m,
        )
    )
    out = run(MultiTargetTracker(cfg, rig, seed=3), frames, rng)
    before = {s.label: s.target_id for s in out[29].targets}
    assert set(before) == {"p1/head", "p1/left_hand", "p1/right_hand"}
    on_hand = min(out[-1].targets, key=lambda s: np.linalg.norm(s.mean_m - rise[-1]))
    assert np.linalg.norm(on_hand.mean_m - rise[-1]) < 0.1
    if supported and not near_m:
        assert on_hand.target_id != before["p1/right_hand"]
    else:
        assert on_hand.target_id == before["p1/right_hand"]
        assert on_hand.label == "p1/right_hand"
