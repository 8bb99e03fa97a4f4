"""``surveil review``: an .rrd from an output MCAP and its recording (the ground truth MCAP of
the small synthetic recording stands in for a run)."""

import numpy as np
import pytest

from surveil.cli import ExitCode, main
from surveil.eval.truth_mcap import write_truth_mcap
from surveil.io.ground_truth import load_ground_truth
from surveil.io.mcap_reader import read_run
from surveil.io.mcap_writer import McapWriter
from surveil.io.recording import open_recording
from surveil.viz.review import recording_of, review_results
from surveil.viz.viewer import verify


@pytest.fixture(scope="module")
def truth_mcap(small_recording, tmp_path_factory):
    path = tmp_path_factory.mktemp("review") / "truth.mcap"
    write_truth_mcap(small_recording, path)
    return path


def test_recording_is_found_from_the_mcap_metadata(truth_mcap, small_recording):
    assert recording_of(read_run(truth_mcap)) == small_recording


def test_results_cover_every_frame_set_and_every_event(truth_mcap, small_recording):
    run, rec = read_run(truth_mcap), open_recording(small_recording)
    results = list(review_results(run, rec, observations=False))
    assert len(results) == len(rec.assignment.set_idx)
    assert sum(len(r.events) for r in results) == len(run.events) > 0
    for r in results:
        for ev in r.events:
            assert ev.climax_ns <= r.frameset.t_ns or r is results[-1]
    assert sum(len(r.track.targets) for r in results) == len(run.target_label)


def test_cli_review_save_writes_a_valid_rrd(truth_mcap, tmp_path, entity_paths, capsys):
    out = tmp_path / "review.rrd"
    assert main(["-q", "review", str(truth_mcap), "--out", str(out), "--save"]) == ExitCode.OK
    assert "wrote" in capsys.readouterr().out
    verify(out)
    found = entity_paths(out)
    assert {"/events", "/world/candidates", "/world/cameras/cam0/blobs"} <= found


def test_cli_review_without_a_known_recording_is_bad_input(small_recording, tmp_path, capsys):
    rec = open_recording(small_recording)
    mcap = tmp_path / "bare.mcap"
    with McapWriter(mcap, rec.rig):
        pass
    code = main(["review", str(mcap), "--out", str(tmp_path / "x.rrd"), "--save"])
    assert code == ExitCode.BAD_INPUT
    assert "--recording" in capsys.readouterr().err


def test_review_reanalyses_what_the_hands_carry(truth_mcap, small_recording):
    # p1's right hand holds a green ball (hue 120) and gives it to p2's left hand
    # (tests/conftest.py); the MCAP has no carry estimates, the review recomputes them
    run, rec = read_run(truth_mcap), open_recording(small_recording)
    results = list(review_results(run, rec))
    assert not any(r.carry for r in results[:30]), "no carry analysis while learning"
    hands = {"p1/left_hand", "p1/right_hand", "p2/left_hand", "p2/right_hand"}
    assert {e.label for r in results[30:] for e in r.carry.values()} == hands
    carrying = [(r.frameset.index, e) for r in results for e in r.carry.values() if e.carrying]
    assert np.all(np.abs(np.array([e.hue_deg for _, e in carrying]) - 120.0) < 10.0)
    # the estimates the rules trust (confidence >= 0.3) name the hand that holds the ball
    # (p1's right hand hands it over at frame 50; weaker estimates linger while the hands
    # overlap, the fusion window being closed then)
    gt = load_ground_truth(small_recording)
    holder = dict(zip(gt.frames.tolist(), gt.held_by[:, 0].tolist(), strict=True))
    confident = [(k, e.label) for k, e in carrying if e.confidence >= 0.3]
    assert all(label == holder[k] for k, label in confident), confident
    assert {label for _, label in confident} >= {"p2/left_hand"}
