"""``surveil rules-check`` and ``surveil events``, run in-process through ``cli.main``."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from surveil.camera import Rig, look_at
from surveil.cli import ExitCode, main
from surveil.datatypes import ActivityEvent
from surveil.io.mcap_writer import McapWriter

S = 1_000_000_000
REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def rig() -> Rig:
    cam = look_at(
        "cam0", np.array([3.0, -3, 2.5]), np.array([0.0, 0, 1]), width=64, height=48, hfov_deg=70
    )
    return Rig((cam,))


EXCHANGE = ActivityEvent(
    "exchange",
    12 * S,
    int(12.4 * S),
    13 * S,
    ("p1/right_hand", "p2/left_hand"),
    ("p1", "p2"),
    "default.toml:exchange",
    0.91,
    120.0,
    "p1/right_hand",
    "p2/left_hand",
)
CLAP = ActivityEvent(
    "clap", 2 * S, int(2.5 * S), 3 * S, ("p1/left_hand", "p1/right_hand"), ("p1",), "x:clap", 0.8
)


def write_run(path: Path, rig: Rig, events: list[ActivityEvent]) -> Path:
    with McapWriter(path, rig, start_time_ns=1_700_000_000 * S) as w:
        for ev in events:
            w.write_event(ev)
    return path


def test_rules_check_lists_default_rules(capsys):
    assert main(["rules-check"]) == ExitCode.OK
    out = capsys.readouterr().out
    for name in ("clap", "handshake", "exchange", "pick", "place"):
        assert f"default.toml:{name}:" in out
    assert "5 rules OK" in out


def test_rules_check_several_files_as_json(capsys):
    files = [REPO / "rules" / "default.toml", REPO / "rules" / "examples" / "touch_face.toml"]
    assert main(["rules-check", "--json", *map(str, files)]) == ExitCode.OK
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["name"] for r in rows][-1] == "touch_face"
    assert rows[-1]["limbs"] == ["hand", "head"] and rows[-1]["coincidence_m"] == 0.2


def test_rules_check_reports_the_bad_field(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[rule.wave]\nlimbs = ['hand', 'elbow']\n")
    assert main(["rules-check", str(bad)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "bad.toml: rule.wave.limbs[1]" in err and "valid limbs: hand" in err


def test_events_table_in_climax_order(tmp_path, rig, capsys):
    path = write_run(tmp_path / "run.mcap", rig, [EXCHANGE, CLAP])
    assert main(["events", str(path)]) == ExitCode.OK
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:3] == ["time_s", "activity", "actors"]
    assert lines[1].startswith("2.50") and "clap" in lines[1]
    assert lines[2].startswith("12.40") and "exchange" in lines[2]
    assert "p1/right_hand -> p2/left_hand" in lines[2]
    assert "green (120 deg)" in lines[2] and "0.91" in lines[2]
    assert "12.00-13.00" in lines[2]


def test_events_table_read_back_matches_the_one_a_run_prints(tmp_path, rig, capsys):
    """/events stores the confidence with 3 decimals; a run's table rounds the same way, so
    a confidence of 0.98512 reads 0.99 in neither or both (stored 0.985 -> 0.98)."""
    from surveil.activity.timeline import format_event_table
    from surveil.io.mcap_writer import hue_name

    ev = dataclasses.replace(CLAP, confidence=0.98512)
    path = write_run(tmp_path / "run.mcap", rig, [ev])
    assert main(["events", str(path)]) == ExitCode.OK
    read_back = capsys.readouterr().out.splitlines()
    assert format_event_table([ev], hue_name).splitlines() == read_back
    assert " 0.98 " in read_back[1]


def test_events_json_lines(tmp_path, rig, capsys):
    path = write_run(tmp_path / "run.mcap", rig, [EXCHANGE, CLAP])
    assert main(["events", "--json", str(path)]) == ExitCode.OK
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["activity"] for r in rows] == ["clap", "exchange"]
    ex = rows[1]
    assert ex["climax_ns"] == EXCHANGE.climax_ns  # ns from t = 0, not the recording clock
    assert (ex["from"], ex["to"]) == ("p1/right_hand", "p2/left_hand")
    assert ex["object_colour"] == "green" and ex["object_hue_deg"] == pytest.approx(120.0)
    assert ex["confidence"] == pytest.approx(0.91) and ex["rule"] == "default.toml:exchange"
    assert rows[0]["object_hue_deg"] is None and rows[0]["from"] is None


def test_events_of_a_run_without_events(tmp_path, rig, capsys):
    path = write_run(tmp_path / "run.mcap", rig, [])
    assert main(["events", str(path)]) == ExitCode.OK
    assert "no events" in capsys.readouterr().out
    assert main(["events", "--json", str(path)]) == ExitCode.OK
    assert capsys.readouterr().out == ""


def test_events_of_a_missing_file(tmp_path, capsys):
    assert main(["events", str(tmp_path / "absent.mcap")]) == ExitCode.BAD_INPUT
    assert "absent.mcap" in capsys.readouterr().err


def test_events_piped_into_a_reader_that_stops_early_is_not_an_error(tmp_path, rig):
    # `surveil events OUT.mcap --json | head -1`: the pipe closes after the first line
    path = write_run(tmp_path / "run.mcap", rig, [EXCHANGE, CLAP] * 2000)
    cmd = [sys.executable, "-m", "surveil", "events", "--json", str(path)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    first = proc.stdout.readline()
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert json.loads(first)["activity"] == "clap"
    assert proc.wait(timeout=60) == ExitCode.OK, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
