"""The ground truth as an output MCAP ("perfect tracker")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from surveil.camera import Rig, look_at
from surveil.cli import ExitCode, main
from surveil.datatypes import ActivityEvent
from surveil.errors import ConfigError, InputError
from surveil.eval.truth_mcap import write_truth_mcap
from surveil.io.calibration import save_rig
from surveil.io.ground_truth import GroundTruth, write_ground_truth
from surveil.io.mcap_reader import read_run

S = 1_000_000_000
LABELS = ("p1/head", "p1/left_hand", "p1/right_hand")


def small_truth() -> GroundTruth:
    """1 person, 3 limbs, 5 frames at 10 fps, 2 cameras; the right hand is absent in frame 4
    and unseen in frames 0-1; one pick event."""
    n = 5
    pos = np.array([[0.0, 0, 1.6], [0.0, 0.3, 1.0], [0.0, -0.3, 1.0]])[None].repeat(n, 0)
    pos[:, :, 0] += 0.01 * np.arange(n)[:, None]
    pos[4, 2] = np.nan
    vis = np.ones((n, 3, 2), dtype=bool)
    vis[:2, 2] = False
    vis[4, 2] = False
    ev = ActivityEvent(
        "pick",
        0,
        S // 5,
        2 * S // 5,
        ("p1/right_hand",),
        ("p1",),
        "ground_truth",
        object_hue_deg=30.0,
        object_name="cup",
    )
    return GroundTruth(
        frames=np.arange(n, dtype=np.int64),
        t_ns=np.arange(n, dtype=np.int64) * S // 10,
        labels=LABELS,
        cameras=("cam0", "cam1"),
        positions_m=pos,
        visible=vis,
        object_names=(),
        object_hue_deg=np.zeros(0),
        object_positions_m=np.zeros((n, 0, 3)),
        held_by=np.zeros((n, 0), dtype=object),
        events=(ev,),
        meta={"fps": 10.0},
    )


@pytest.fixture
def rig() -> Rig:
    return Rig(
        tuple(
            look_at(
                f"cam{k}",
                np.array([x, -3.0, 2.0]),
                np.array([0.0, 0, 1]),
                width=160,
                height=120,
                hfov_deg=60,
            )
            for k, x in enumerate((-2.0, 2.0))
        )
    )


@pytest.fixture
def rec(tmp_path: Path, rig: Rig) -> Path:
    rec_dir = tmp_path / "rec"
    write_ground_truth(rec_dir / "ground_truth", small_truth())
    save_rig(rig, tmp_path / "lab.yaml")
    (rec_dir / "recording.toml").write_text(
        'rig = "../lab.yaml"\nfps = 10.0\nstart_time_ns = 5000000000\n'
        '[[cameras]]\nname = "solo"\nvideo = "solo.mp4"\n'
    )
    return rec_dir


def test_truth_mcap_holds_every_true_limb_and_event(rec: Path, tmp_path: Path) -> None:
    out = tmp_path / "truth.mcap"
    write_truth_mcap(rec, out)  # rig from recording.toml
    run = read_run(out)
    gt = small_truth()
    assert run.start_time_ns == 5 * S
    assert run.frame_t_ns.tolist() == gt.t_ns.tolist()
    assert np.bincount(run.target_frame).tolist() == [3, 3, 3, 3, 2]
    assert set(run.target_state.tolist()) == {1}  # normal
    for label in LABELS:  # one stable tracker per limb
        assert len(set(run.target_tracker[run.target_label == label].tolist())) == 1
    assert len(set(run.target_tracker.tolist())) == 3
    rows = run.frame_rows(3)
    np.testing.assert_allclose(run.target_pos_m[rows], gt.positions_m[3], atol=1e-5)
    # candidates: limbs seen by at least one camera, prior 1
    assert np.bincount(run.candidate_frame).tolist() == [2, 2, 3, 3, 2]
    assert set(run.candidate_prior.tolist()) == {1.0}
    (ev,) = run.events
    want = gt.events[0]
    assert (ev.activity, ev.start_ns, ev.climax_ns, ev.end_ns, ev.actors, ev.object_hue_deg) == (
        want.activity,
        want.start_ns,
        want.climax_ns,
        want.end_ns,
        want.actors,
        30.0,
    )
    assert ev.rule == "ground_truth"
    assert set(run.channels) >= {"/cameras/cam0/calibration", "/cameras/cam1/calibration"}


def test_explicit_rig_overrides_the_recordings(rec: Path, tmp_path: Path) -> None:
    one = Rig(
        (look_at("solo", np.array([0.0, -3, 2]), np.zeros(3), width=64, height=48, hfov_deg=60),)
    )
    out = tmp_path / "solo.mcap"
    write_truth_mcap(rec, out, rig=one)
    assert "/cameras/solo/calibration" in read_run(out).channels


def test_missing_recording_or_rig_is_an_input_error(rec: Path, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="recording.toml is missing"):
        write_truth_mcap(tmp_path / "nowhere", tmp_path / "x.mcap")
    (rec / "recording.toml").write_text("fps = 10.0\n")
    with pytest.raises(ConfigError, match=r"recording\.toml: rig is required"):
        write_truth_mcap(rec, tmp_path / "x.mcap")


def test_cli_truth_then_eval(
    rec: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "t.mcap"
    assert main(["truth", str(rec), "--out", str(out)]) == ExitCode.OK
    assert main(["eval", str(rec), str(out), "--min-views", "1"]) == ExitCode.OK
    text = capsys.readouterr().out
    assert "wrote" in text and "recall" in text
