"""CLI boundary: run, demo arguments, train-skin; exit codes and messages."""

from __future__ import annotations

from surveil.blobs import SkinConfig, default_skin_model
from surveil.cli import ExitCode, main
from surveil.io.skin_model import load_skin_model


def test_run_writes_mcap_and_prints_a_summary(small_recording, tmp_path, capsys):
    out = tmp_path / "out.mcap"
    code = main(["-q", "run", str(small_recording), "--out", str(out), "--max-frames", "25"])
    assert code == ExitCode.OK
    text = capsys.readouterr().out
    assert "25 frame sets" in text and "ms per frame set" in text and out.is_file()


def test_run_names_the_bad_config_key(small_recording, tmp_path, capsys):
    cfg = tmp_path / "run.toml"
    cfg.write_text("[tracking.filter]\nn_particles = 3\n")
    code = main(["-q", "run", str(small_recording), "--out", str(tmp_path / "o.mcap"),
                 "--config", str(cfg)])  # fmt: skip
    assert code == ExitCode.BAD_INPUT
    assert "tracking.filter.n_particles must be >= 10, got 3" in capsys.readouterr().err


def test_run_on_a_missing_recording_is_bad_input(tmp_path, capsys):
    code = main(["-q", "run", str(tmp_path / "nowhere"), "--out", str(tmp_path / "o.mcap")])
    assert code == ExitCode.BAD_INPUT
    assert "nowhere" in capsys.readouterr().err


def test_train_skin_writes_one_model_per_camera(small_recording, tmp_path, capsys):
    out = tmp_path / "skin"
    code = main(["-q", "train-skin", str(small_recording), "--out", str(out), "--every", "6"])
    assert code == ExitCode.OK
    models = sorted(out.glob("*.npz"))
    assert [p.stem for p in models] == ["cam0", "cam1", "cam2", "cam3"]
    model = load_skin_model(models[0])
    assert model.meta["camera"] == "cam0" and 0.0 < model.lut.mean() < 0.6
    assert model.meta["threshold"] == SkinConfig().camera_threshold
    # bounded by the generic model: it calls skin no colour the generic model does not
    generic = default_skin_model().lut
    assert "bounded_by" in model.meta and not (model.lut & ~generic).any()


def test_train_skin_unbounded_models_reach_beyond_the_generic_one(small_recording, tmp_path):
    out = tmp_path / "skin"
    args = ["-q", "train-skin", str(small_recording), "--out", str(out), "--every", "6"]
    assert main([*args, "--unbounded"]) == ExitCode.OK
    model = load_skin_model(out / "cam0.npz")
    assert "bounded_by" not in model.meta
    assert (model.lut & ~default_skin_model().lut).any()
    assert main([*args, "--generic", "--unbounded"]) == ExitCode.BAD_INPUT


def test_run_also_writes_a_rerun_review_file(small_recording, tmp_path, capsys):
    from surveil.viz.viewer import verify

    rrd = tmp_path / "out.rrd"
    code = main(["-q", "run", str(small_recording), "--out", str(tmp_path / "o.mcap"),
                 "--rrd", str(rrd), "--max-frames", "40"])  # fmt: skip
    assert code == ExitCode.OK
    assert rrd.is_file() and rrd.stat().st_size > 10_000
    verify(rrd)  # `rerun rrd verify` accepts it (raises otherwise)
