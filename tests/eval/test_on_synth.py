"""The scorer against a real synthetic recording: its own ground truth scores perfectly."""

from surveil.cli import ExitCode, main
from surveil.eval.score import EvalConfig, evaluate


def test_truth_of_a_synthetic_recording_scores_perfectly(small_recording, tmp_path):
    out = tmp_path / "truth.mcap"
    assert main(["truth", str(small_recording), "--out", str(out)]) == ExitCode.OK
    report = evaluate(small_recording, out, EvalConfig()).to_dict()
    assert report["targets"]["recall"] == 1.0
    assert report["targets"]["hand_error_mm_mean"] == 0.0
    assert report["events"]["f1"] == 1.0
