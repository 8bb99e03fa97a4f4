"""Scoring against ground truth: perfect predictions, controlled perturbations, edge cases."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from surveil.camera import Rig, look_at
from surveil.cli import ExitCode, main
from surveil.config import from_table
from surveil.datatypes import ActivityEvent, CandidateSet, Limb, Phase, TargetSnapshot
from surveil.errors import ConfigError, InputError
from surveil.eval.score import (
    EvalConfig,
    align_frames,
    evaluate,
    format_report,
    gated_assignment,
    identity_switches,
    match_targets,
)
from surveil.eval.truth_mcap import truth_frames, write_truth_mcap
from surveil.io.ground_truth import GroundTruth, load_ground_truth, write_ground_truth
from surveil.io.mcap_reader import read_run
from surveil.io.mcap_writer import McapWriter

FPS = 15.0
N_FRAMES = 60
LABELS = ("p1/head", "p1/left_hand", "p1/right_hand", "p2/head", "p2/left_hand", "p2/right_hand")
S = 1_000_000_000


def make_rig() -> Rig:
    centre = np.array([0.0, 0.0, 1.2])
    return Rig(
        tuple(
            look_at(
                f"cam{k}",
                np.array([4 * np.cos(a), 4 * np.sin(a), 2.5]),
                centre,
                width=320,
                height=240,
                hfov_deg=70,
            )
            for k, a in enumerate(np.radians([45, 135, 225, 315]))
        )
    )


def make_ground_truth() -> GroundTruth:
    """2 persons x 3 limbs, 60 frames at 15 fps, 4 cameras. p2/right_hand is seen by one
    camera in frames 0-19, p1/head by none in frames 40-44, p2/left_hand is absent (NaN) in
    frames 50-59. Limbs stay >= 0.4 m apart. Events: clap, exchange (p1 -> p2), handshake."""
    t = np.arange(N_FRAMES) / FPS
    base = np.array(
        [
            [-0.8, 0.0, 1.6],
            [-0.8, 0.3, 1.0],
            [-0.8, -0.3, 1.0],
            [0.8, 0.0, 1.6],
            [0.8, -0.3, 1.0],
            [0.8, 0.3, 1.0],
        ]
    )
    sway = 0.05 * np.stack([np.sin(t), np.cos(t), np.sin(2 * t)], axis=1)
    pos = base[None, :, :] + sway[:, None, :]
    pos[50:, 4] = np.nan
    vis = np.ones((N_FRAMES, len(LABELS), 4), dtype=bool)
    vis[:20, 5, 1:] = False
    vis[40:45, 0, :] = False
    vis[50:, 4, :] = False
    events = (
        ActivityEvent(
            "clap",
            int(0.8 * S),
            1 * S,
            int(1.2 * S),
            ("p1/left_hand", "p1/right_hand"),
            ("p1",),
            "ground_truth",
        ),
        ActivityEvent(
            "exchange",
            int(1.5 * S),
            2 * S,
            int(2.5 * S),
            ("p1/right_hand", "p2/left_hand"),
            ("p1", "p2"),
            "ground_truth",
            object_hue_deg=120.0,
            from_actor="p1/right_hand",
            to_actor="p2/left_hand",
            object_name="ball",
        ),
        ActivityEvent(
            "handshake",
            int(2.8 * S),
            3 * S,
            int(3.4 * S),
            ("p1/right_hand", "p2/right_hand"),
            ("p1", "p2"),
            "ground_truth",
        ),
    )
    return GroundTruth(
        frames=np.arange(N_FRAMES, dtype=np.int64),
        t_ns=np.round(np.arange(N_FRAMES) * S / FPS).astype(np.int64),
        labels=LABELS,
        cameras=("cam0", "cam1", "cam2", "cam3"),
        positions_m=pos,
        visible=vis,
        object_names=("ball",),
        object_hue_deg=np.array([120.0]),
        object_positions_m=np.zeros((N_FRAMES, 1, 3)),
        held_by=np.full((N_FRAMES, 1), "", dtype=object),
        events=events,
        meta={
            "fps": FPS,
            "persons": [{"id": "p1"}, {"id": "p2"}],
            "objects": [{"name": "ball", "hue_deg": 120.0}],
        },
    )


@pytest.fixture(scope="module")
def rig() -> Rig:
    return make_rig()


@pytest.fixture(scope="module")
def rec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rec_dir = tmp_path_factory.mktemp("data") / "rec"
    write_ground_truth(rec_dir / "ground_truth", make_ground_truth())
    (rec_dir / "recording.toml").write_text(
        'rig = "rig.yaml"\nfps = 15.0\n'
        + "".join(f'[[cameras]]\nname = "{c.name}"\nvideo = "{c.name}.mp4"\n' for c in make_rig())
    )
    return rec_dir


@pytest.fixture(scope="module")
def gt(rec: Path) -> GroundTruth:
    return load_ground_truth(rec)


Frames = list[tuple[int, list[TargetSnapshot], CandidateSet]]


def write_prediction(
    path: Path,
    gt: GroundTruth,
    rig: Rig,
    change: Callable[[int, list[TargetSnapshot]], list[TargetSnapshot]] = lambda i, tgs: tgs,
    events: tuple[ActivityEvent, ...] | None = None,
    start_time_ns: int = 0,
) -> Path:
    """An MCAP of the ground truth with ``change(frame index, targets)`` applied."""
    with McapWriter(path, rig, start_time_ns=start_time_ns) as w:
        for i, (t_ns, targets, cands) in enumerate(truth_frames(gt)):
            w.write_frame(t_ns, change(i, targets), cands)
        for ev in gt.events if events is None else events:
            w.write_event(ev)
    return path


def replace(tg: TargetSnapshot, **kw) -> TargetSnapshot:
    return dataclasses.replace(tg, **kw)


CFG = EvalConfig()


# ---------------------------------------------------------------------------------------------


def test_ground_truth_mcap_scores_perfectly(rec: Path, rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "truth.mcap"
    write_truth_mcap(rec, out, rig=rig)
    report = evaluate(rec, out, CFG)
    t, ev = report.targets, report.events
    assert t.n_frames_scored == N_FRAMES and t.n_frames_unaligned == 0
    assert t.recall == 1.0
    assert t.head_error_mm_mean == t.hand_error_mm_mean == 0.0
    assert t.head_error_mm_median == t.hand_error_mm_median == 0.0
    assert t.false_targets_per_frame == 0.0
    assert t.labelled_fraction == t.limb_type_accuracy == t.left_right_accuracy == 1.0
    assert t.person_consistency == 1.0 and t.person_mapping == {"p1": "p1", "p2": "p2"}
    assert t.label_accuracy == 1.0
    assert t.id_switches == 0 and t.id_switches_per_min == 0.0
    assert ev.precision == ev.recall == ev.f1 == 1.0
    scored = {s.activity: s for s in ev.activities}
    assert scored["exchange"].direction_accuracy == 1.0
    for name in ("clap", "exchange", "handshake"):
        assert scored[name].climax_error_ms_mean == 0.0
        assert scored[name].actors_accuracy == 1.0
    assert scored["pick"].n_true == scored["pick"].n_pred == 0
    assert scored["pick"].precision is None and scored["pick"].f1 is None


def test_countable_limbs_exclude_poorly_seen_ones(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    # 60*6 limb-frames, minus 10 absent, minus 20 seen by 1 camera, minus 5 seen by none
    report = evaluate(rec, write_prediction(tmp_path / "p.mcap", gt, rig), CFG)
    assert report.targets.n_true_countable == 360 - 10 - 20 - 5
    # dropping exactly the poorly seen limbs costs no recall and leaves no false target
    n_views = gt.n_views
    lab = {lab: j for j, lab in enumerate(gt.labels)}

    def drop_poorly_seen(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [tg for tg in tgs if n_views[i, lab[tg.label]] >= 2]

    report = evaluate(rec, write_prediction(tmp_path / "q.mcap", gt, rig, drop_poorly_seen), CFG)
    assert report.targets.recall == 1.0
    assert report.targets.n_matches == 360 - 10 - 20 - 5


def test_gaussian_noise_gives_the_expected_error(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    rng = np.random.default_rng(7)

    def noisy(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [replace(tg, mean_m=tg.mean_m + rng.normal(0, 0.030, 3)) for tg in tgs]

    report = evaluate(rec, write_prediction(tmp_path / "n.mcap", gt, rig, noisy), CFG)
    t = report.targets
    # 3D error of isotropic noise sigma=30 mm: Maxwell mean 30*sqrt(8/pi) = 47.9 mm
    for mean in (t.head_error_mm_mean, t.hand_error_mm_mean):
        assert 30.0 < mean < 60.0
    assert abs(t.hand_error_mm_mean - 30 * np.sqrt(8 / np.pi)) < 5.0
    assert t.recall == 1.0 and t.false_targets_per_frame == 0.0


def test_swapped_left_right_labels(rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path) -> None:
    other = {Limb.LEFT_HAND: Limb.RIGHT_HAND, Limb.RIGHT_HAND: Limb.LEFT_HAND}

    def swap(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [replace(tg, limb=other.get(tg.limb, tg.limb)) for tg in tgs]

    t = evaluate(rec, write_prediction(tmp_path / "lr.mcap", gt, rig, swap), CFG).targets
    assert t.left_right_accuracy == 0.0
    assert t.limb_type_accuracy == 1.0 and t.person_consistency == 1.0 and t.recall == 1.0


def test_tracker_id_swap_mid_run_counts_switches(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    def swap_ids(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        if i < 30:
            return tgs
        swapped = {2: 3, 3: 2}  # p1/left_hand <-> p1/right_hand trackers
        return [replace(tg, target_id=swapped.get(tg.target_id, tg.target_id)) for tg in tgs]

    t = evaluate(rec, write_prediction(tmp_path / "id.mcap", gt, rig, swap_ids), CFG).targets
    assert t.id_switches == 2
    minutes = N_FRAMES / FPS / 60
    assert t.id_switches_per_min == pytest.approx(2 / minutes)
    assert t.id_switches_per_person_per_min == pytest.approx({"p1": 2 / minutes, "p2": 0.0})


def test_label_accuracy_asks_for_the_name_on_the_limb_not_the_tracker_id(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    """Two trackers that swap limbs while their labels stay on the right limbs are two
    identity switches but no wrong label; a limb whose tracker loses its label from frame
    30 on is wrong in those frames, with no switch."""

    def swap_ids(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        swapped = {2: 3, 3: 2} if i >= 30 else {}
        return [replace(tg, target_id=swapped.get(tg.target_id, tg.target_id)) for tg in tgs]

    t = evaluate(rec, write_prediction(tmp_path / "id.mcap", gt, rig, swap_ids), CFG).targets
    assert t.id_switches == 2 and t.label_accuracy == 1.0

    def unlabel(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [
            replace(tg, person=0, limb=Limb.UNKNOWN, phase=Phase.UNLABELLED)
            if i >= 30 and tg.target_id == 3
            else tg
            for tg in tgs
        ]

    t = evaluate(rec, write_prediction(tmp_path / "u.mcap", gt, rig, unlabel), CFG).targets
    assert t.id_switches == 0
    assert t.label_accuracy == pytest.approx(1 - (N_FRAMES - 30) / t.n_matches)


def test_identity_switches_tell_what_became_of_the_old_tracker(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    """p1's left hand (tracker 2) is lost for frames 20-29, then a new tracker (99) follows
    it; p1's right hand (tracker 3) is followed from frame 30 by tracker 77, which was on
    something far away before; p2's hands (trackers 5 and 6) swap trackers at frame 40."""

    def change(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        out = []
        for tg in tgs:
            if tg.target_id == 2 and 20 <= i < 30:
                tg = replace(tg, phase=Phase.LOST)
            elif tg.target_id == 2 and i >= 30:
                tg = replace(tg, target_id=99)
            elif tg.target_id == 3 and i >= 30:
                tg = replace(tg, target_id=77)
            elif tg.target_id in (5, 6) and i >= 40:
                tg = replace(tg, target_id=11 - tg.target_id)
            out.append(tg)
        if i < 30:  # tracker 77 starts on something 3 m away from everyone
            far = replace(tgs[0], target_id=77, person=0, limb=Limb.UNKNOWN)
            out.append(replace(far, mean_m=far.mean_m + np.array([0.0, 0.0, 3.0])))
        return out

    run = read_run(write_prediction(tmp_path / "sw.mcap", gt, rig, change))
    got = {(sw.limb, sw.from_tracker, sw.to_tracker): sw for sw in identity_switches(gt, run, CFG)}
    assert set(got) == {
        ("p1/left_hand", 2, 99),
        ("p1/right_hand", 3, 77),
        ("p2/left_hand", 5, 6),
        ("p2/right_hand", 6, 5),
    }
    lost = got["p1/left_hand", 2, 99]
    assert lost.kind == "not re-acquired" and lost.from_phase == "gone"
    assert lost.to_age_s == 0.0 and lost.unmatched_s == pytest.approx(10 / FPS)
    assert lost.t_s == pytest.approx(gt.t_ns[30] * 1e-9)
    taken = got["p1/right_hand", 3, 77]
    assert taken.kind == "taken over" and taken.to_age_s == pytest.approx(30 / FPS)
    assert taken.unmatched_s == 0.0
    for key in (("p2/left_hand", 5, 6), ("p2/right_hand", 6, 5)):
        assert got[key].kind == "drifted" and got[key].from_phase == "normal"
    report = evaluate(rec, tmp_path / "sw.mcap", CFG)
    assert report.targets.id_switches == len(got)


def test_dropping_a_third_of_targets_lowers_recall(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    def drop(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [tg for tg in tgs if (i + tg.target_id) % 3 != 0]

    t = evaluate(rec, write_prediction(tmp_path / "d.mcap", gt, rig, drop), CFG).targets
    assert t.recall == pytest.approx(2 / 3, abs=0.03)
    assert t.head_error_mm_mean == 0.0 and t.false_targets_per_frame == 0.0


def test_matched_targets_are_the_pairs_the_errors_are_averaged_over(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    """Every true limb matched to the predicted row at its own place; the hand error over
    those pairs is the report's."""
    rng = np.random.default_rng(3)

    def noisy(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [replace(tg, mean_m=tg.mean_m + rng.normal(0, 0.02, 3)) for tg in tgs]

    mcap = write_prediction(tmp_path / "m.mcap", gt, rig, noisy)
    run = read_run(mcap)
    m = match_targets(gt, run, CFG)
    report = evaluate(rec, mcap, CFG).targets
    assert len(m.pred_row) == report.n_matches > 0
    err = np.linalg.norm(
        run.target_pos_m[m.pred_row] - gt.positions_m[m.gt_frame, m.true_idx], axis=1
    )
    assert err.max() < 0.15
    hands = np.array(["hand" in gt.labels[j] for j in m.true_idx])
    assert 1000 * err[hands].mean() == pytest.approx(report.hand_error_mm_mean)


def test_lost_targets_are_not_scored(rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path) -> None:
    def lose(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [replace(tg, phase=Phase.LOST) for tg in tgs]

    t = evaluate(rec, write_prediction(tmp_path / "l.mcap", gt, rig, lose), CFG).targets
    assert t.recall == 0.0 and t.n_matches == 0 and t.false_targets_per_frame == 0.0
    assert t.head_error_mm_mean is None and t.labelled_fraction is None


def test_far_and_unlabelled_targets(rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path) -> None:
    def far_and_unlabelled(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        far = replace(
            tgs[0], target_id=99, person=0, limb=Limb.UNKNOWN, mean_m=tgs[0].mean_m + [0, 0, 0.5]
        )  # beyond the 0.25 m gate
        return [replace(tg, person=0, limb=Limb.UNKNOWN, phase=Phase.UNLABELLED) for tg in tgs] + [
            far
        ]

    t = evaluate(
        rec, write_prediction(tmp_path / "u.mcap", gt, rig, far_and_unlabelled), CFG
    ).targets
    assert t.recall == 1.0 and t.false_targets_per_frame == 1.0
    assert t.labelled_fraction == 0.0 and t.label_accuracy == 0.0
    assert t.limb_type_accuracy is None and t.person_consistency is None
    assert t.person_mapping == {}


def test_renumbered_persons_stay_consistent(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    def renumber(i: int, tgs: list[TargetSnapshot]) -> list[TargetSnapshot]:
        return [replace(tg, person=3 - tg.person) for tg in tgs]

    def relabel(label: str | None) -> str | None:
        if label is None:
            return None
        return label.replace("p1", "px").replace("p2", "p1").replace("px", "p2")

    events = tuple(
        dataclasses.replace(
            ev,
            actors=tuple(relabel(a) for a in ev.actors),
            from_actor=relabel(ev.from_actor),
            to_actor=relabel(ev.to_actor),
        )
        for ev in gt.events
    )
    report = evaluate(rec, write_prediction(tmp_path / "r.mcap", gt, rig, renumber, events), CFG)
    assert report.targets.person_consistency == 1.0
    assert report.targets.person_mapping == {"p1": "p2", "p2": "p1"}
    exchange = next(s for s in report.events.activities if s.activity == "exchange")
    assert exchange.direction_accuracy == 1.0 and exchange.actors_accuracy == 1.0


def test_reversed_exchange_direction(rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path) -> None:
    events = tuple(
        dataclasses.replace(ev, from_actor=ev.to_actor, to_actor=ev.from_actor)
        if ev.activity == "exchange"
        else ev
        for ev in gt.events
    )
    report = evaluate(rec, write_prediction(tmp_path / "x.mcap", gt, rig, events=events), CFG)
    exchange = next(s for s in report.events.activities if s.activity == "exchange")
    assert exchange.recall == 1.0 and exchange.direction_accuracy == 0.0
    assert exchange.n_direction == exchange.n_matched and exchange.n_direction_right == 0
    assert exchange.actors_accuracy == 1.0


def test_events_shifted_beyond_tolerance_are_missed(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    events = tuple(
        dataclasses.replace(
            ev,
            start_ns=ev.start_ns + 2 * S,
            climax_ns=ev.climax_ns + 2 * S,
            end_ns=ev.end_ns + 2 * S,
        )
        for ev in gt.events
    )
    ev = evaluate(rec, write_prediction(tmp_path / "s.mcap", gt, rig, events=events), CFG).events
    assert ev.recall == 0.0 and ev.precision == 0.0 and ev.f1 == 0.0 and ev.n_matched == 0
    # within tolerance: matched, with the shift as climax error
    small = tuple(
        dataclasses.replace(e, climax_ns=e.climax_ns + S // 4, end_ns=e.end_ns + S // 4)
        for e in gt.events
    )
    ev = evaluate(rec, write_prediction(tmp_path / "t.mcap", gt, rig, events=small), CFG).events
    assert ev.recall == 1.0
    assert all(
        s.climax_error_ms_mean == pytest.approx(250.0) for s in ev.activities if s.n_matched
    )
    # every matched event's error, to pool over runs (benchmarks/compare_runs.py)
    errors = [x for s in ev.activities for x in s.climax_errors_ms]
    assert len(errors) == ev.n_matched and errors == pytest.approx([250.0] * ev.n_matched)


def test_extra_false_event_lowers_precision(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    extra = ActivityEvent(
        "clap",
        int(3.5 * S),
        int(3.6 * S),
        int(3.7 * S),
        ("p2/left_hand", "p2/right_hand"),
        ("p2",),
        "default.toml:clap",
        0.6,
    )
    report = evaluate(
        rec, write_prediction(tmp_path / "e.mcap", gt, rig, events=(*gt.events, extra)), CFG
    )
    ev = report.events
    assert ev.precision == pytest.approx(3 / 4) and ev.recall == 1.0
    clap = next(s for s in ev.activities if s.activity == "clap")
    assert clap.precision == 0.5 and clap.recall == 1.0 and clap.f1 == pytest.approx(2 / 3)


def test_user_activities_are_scored_and_can_be_selected(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    wave = ActivityEvent("wave", S, S, S, ("p1/left_hand",), ("p1",), "mine.toml:wave")
    path = write_prediction(tmp_path / "w.mcap", gt, rig, events=(*gt.events, wave))
    names = [s.activity for s in evaluate(rec, path, CFG).events.activities]
    assert names == ["clap", "handshake", "exchange", "pick", "place", "wave"]
    ev = evaluate(rec, path, EvalConfig(activities=("exchange",))).events
    assert [s.activity for s in ev.activities] == ["exchange"]
    assert ev.n_true == ev.n_pred == ev.n_matched == 1


def test_empty_mcap_has_undefined_scores(rec: Path, rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "empty.mcap"
    with McapWriter(out, rig):
        pass
    report = evaluate(rec, out, CFG)
    t = report.targets
    assert t.n_frames_scored == 0 and t.recall is None and t.false_targets_per_frame is None
    assert t.id_switches_per_min is None
    assert report.events.n_pred == 0 and report.events.precision is None
    assert report.events.recall == 0.0
    json.dumps(report.to_dict(), allow_nan=False)
    assert "recall" in format_report(report)


def test_frames_off_the_truth_grid_are_not_scored(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    out = tmp_path / "late.mcap"
    period = S / FPS
    frames = truth_frames(gt)
    with McapWriter(out, rig) as w:
        for t_ns, targets, cands in frames[:3]:
            w.write_frame(t_ns + int(0.4 * period), targets, cands)  # jitter: still aligned
        last_t, last_targets, last_cands = frames[-1]
        w.write_frame(last_t + int(0.6 * period), last_targets, last_cands)  # after the end
        w.write_frame(100 * S, [], CandidateSet.empty())
    t = evaluate(rec, out, CFG).targets
    assert t.n_frames_scored == 3 and t.n_frames_unaligned == 2
    assert t.recall == 1.0 and t.hand_error_mm_mean < 5.0


def test_start_time_is_removed_before_alignment(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path
) -> None:
    path = write_prediction(tmp_path / "st.mcap", gt, rig, start_time_ns=1_700_000_000 * S)
    report = evaluate(rec, path, CFG)
    assert report.targets.recall == 1.0 and report.events.f1 == 1.0


def test_report_text_and_json(rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path) -> None:
    report = evaluate(rec, write_prediction(tmp_path / "j.mcap", gt, rig), CFG)
    d = json.loads(json.dumps(report.to_dict(), allow_nan=False))
    assert d["targets"]["recall"] == 1.0 and d["config"]["gate_m"] == 0.25
    assert d["events"]["activities"][0]["activity"] == "clap"
    text = format_report(report)
    lines = text.splitlines()
    for word in (
        "recall",
        "left/right accuracy",
        "identity switches",
        "exchange",
        "all (micro)",
        "p1 -> p1",
    ):
        assert word in text
    table = [ln for ln in lines if ln.startswith("  ") and "precision" not in ln]
    assert len({len(ln) for ln in table if "micro" not in ln and "exchange" in ln}) == 1


def test_missing_ground_truth_is_an_input_error(rig: Rig, tmp_path: Path) -> None:
    (tmp_path / "rec").mkdir()
    with pytest.raises(InputError, match="no ground truth"):
        evaluate(tmp_path / "rec", tmp_path / "x.mcap", CFG)


def test_eval_config_validation() -> None:
    with pytest.raises(ConfigError, match="gate_m"):
        EvalConfig(gate_m=0.0)
    with pytest.raises(ConfigError, match="min_views must be >= 0"):
        from_table(EvalConfig, {"min_views": -1}, "eval.toml: eval")
    cfg = from_table(EvalConfig, {"activities": ["clap"], "gate_m": 0.1}, "eval.toml: eval")
    assert cfg.activities == ("clap",) and cfg.gate_m == 0.1


def test_gated_assignment_prefers_the_global_optimum() -> None:
    # greedy would take (0, 0) at 0.1 and leave row 1 unmatched
    cost = np.array([[0.1, 0.2], [0.15, 9.0]])
    rows, cols = gated_assignment(cost, 0.25)
    assert rows.tolist() == [0, 1] and cols.tolist() == [1, 0]
    rows, cols = gated_assignment(np.array([[0.3, np.nan]]), 0.25)
    assert rows.size == cols.size == 0


def test_align_frames_single_truth_frame() -> None:
    assert align_frames(np.array([0]), np.array([10, 10**9]), fps=15.0).tolist() == [0, -1]
    assert align_frames(np.zeros(0, np.int64), np.array([0]), fps=15.0).tolist() == [-1]


# ---------------------------------------------------------------------------------------------
# CLI


def test_cli_eval_json(
    rec: Path, rig: Rig, gt: GroundTruth, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_prediction(tmp_path / "c.mcap", gt, rig)
    code = main(["eval", str(rec), str(path), "--json"])
    out = capsys.readouterr().out
    assert code == ExitCode.OK
    assert json.loads(out)["events"]["f1"] == 1.0
    assert main(["eval", str(rec), str(path), "--activity", "clap"]) == ExitCode.OK
    assert "clap" in capsys.readouterr().out


def test_cli_eval_without_ground_truth(
    rig: Rig, gt: GroundTruth, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bare = tmp_path / "bare"
    bare.mkdir()
    (bare / "recording.toml").write_text('rig = "rig.yaml"\nfps = 15.0\n')
    path = write_prediction(tmp_path / "b.mcap", gt, rig)
    code = main(["eval", str(bare), str(path)])
    assert code == ExitCode.BAD_INPUT
    assert "no ground truth" in capsys.readouterr().err


def test_cli_eval_bad_mcap(rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap at all")
    assert main(["eval", str(rec), str(bad)]) == ExitCode.BAD_INPUT
    assert "not an MCAP file" in capsys.readouterr().err
