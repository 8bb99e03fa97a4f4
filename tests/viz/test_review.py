"""``surveil review``: an .rrd from an output MCAP and its recording (the ground truth MCAP of
the small synthetic recording stands in for a run)."""

import pytest

from surveil.cli import ExitCode, main
from surveil.eval.truth_mcap import write_truth_mcap
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
