"""Recordings: recording.toml validation, timestamp synchronisation, streaming, info, CLI.

The synthetic recording (fps 10, period 100 ms, 64x48 images):

- cam0: PNG folder with a CSV; frames at k * 100 ms + a few ms of jitter for k = 0..19,
  except k = 7 (dropped).
- cam1: PNG folder with a CSV; starts late (first frame at 300 ms); the frame meant for
  1000 ms comes at 1060 ms (more than half a period late: it falls in set 11's window, where the
  1100 ms frame is nearer, so it is unused); the frame meant for 1400 ms comes at 1460 ms and
  the 1500 ms frame is dropped, so the late frame serves set 15.
- cam2: MJPG AVI without a CSV (frame i at i / fps), 12 frames: ends early.

PNG pixels encode (camera, frame index in the folder); AVI frame i is uniform grey 10 * i.
"""

from __future__ import annotations

import json
import weakref
from pathlib import Path

import cv2
import numpy as np
import pytest

from surveil.cli import ExitCode, main
from surveil.errors import ConfigError, InputError
from surveil.io import video
from surveil.io.recording import (
    assign_frames,
    describe_recording,
    frame_set_of,
    open_recording,
)

W, H = 64, 48
MS = 1_000_000
CAM0_JITTER_MS = [0, 2, -3, 1, 4, -2, 3, None, -4, 2, 0, 1, -1, 3, -3, 2, 0, -2, 1, 4]
CAM0_MS = [k * 100 + j for k, j in enumerate(CAM0_JITTER_MS) if j is not None]
CAM1_MS = [k * 100 for k in range(3, 20) if k != 15]
CAM1_MS[CAM1_MS.index(1000)] = 1060
CAM1_MS[CAM1_MS.index(1400)] = 1460
N_CAM2 = 12


def write_rig(path: Path, names: list[str], size: tuple[int, int] = (W, H)) -> Path:
    """A rig YAML per formats.md, written with cv2.FileStorage."""
    fs = cv2.FileStorage(str(path), cv2.FileStorage_WRITE)
    fs.write("units", "m")
    fs.startWriteStruct("cameras", cv2.FileNode_SEQ)
    for i, name in enumerate(names):
        fs.startWriteStruct("", cv2.FileNode_MAP)
        fs.write("name", name)
        fs.write("image_width", size[0])
        fs.write("image_height", size[1])
        fs.write("K", np.array([[50.0, 0, 32], [0, 50, 24], [0, 0, 1]]))
        fs.write("dist", np.zeros((1, 5)))
        fs.write("R", np.eye(3))
        fs.write("t", np.array([[float(i)], [0.0], [3.0]]))
        fs.endWriteStruct()
    fs.endWriteStruct()
    fs.release()
    return path


def coded(cam: int, frame: int, size: tuple[int, int] = (W, H)) -> np.ndarray:
    img = np.zeros((size[1], size[0], 3), np.uint8)
    img[..., 0] = cam
    img[..., 1] = frame % 256
    img[..., 2] = frame // 256
    return img


def decode(img: np.ndarray) -> tuple[int, int]:
    """(camera, frame) of a coded PNG frame."""
    return int(img[0, 0, 0]), int(img[0, 0, 1]) + 256 * int(img[0, 0, 2])


def write_png_camera(directory: Path, cam: int, n: int, size=(W, H)) -> Path:
    directory.mkdir(parents=True)
    for i in range(n):
        cv2.imwrite(str(directory / f"{i:06d}.png"), coded(cam, i, size))
    return directory


def write_csv(path: Path, times_ns: list[int]) -> Path:
    path.write_text("frame,timestamp_ns\n" + "".join(f"{i},{t}\n" for i, t in enumerate(times_ns)))
    return path


def write_toml(
    directory: Path,
    cameras: list[dict],
    *,
    rig: str = "rig.yaml",
    fps: float = 10,
    extra: str = "",
) -> Path:
    lines = [f'rig = "{rig}"', f"fps = {fps}", extra]
    for cam in cameras:
        lines.append("[[cameras]]")
        lines += [f'{k} = "{v}"' for k, v in cam.items()]
    path = directory / "recording.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def rec_dir(tmp_path) -> Path:
    d = tmp_path / "rec"
    d.mkdir()
    write_rig(d / "rig.yaml", ["cam0", "cam1", "cam2", "cam3"])
    write_png_camera(d / "cam0", 0, len(CAM0_MS))
    write_csv(d / "cam0.csv", [t * MS for t in CAM0_MS])
    write_png_camera(d / "cam1", 1, len(CAM1_MS))
    write_csv(d / "cam1.csv", [t * MS for t in CAM1_MS])
    writer = cv2.VideoWriter(str(d / "cam2.avi"), cv2.VideoWriter.fourcc(*"MJPG"), 10.0, (W, H))
    for i in range(N_CAM2):
        writer.write(np.full((H, W, 3), 10 * i, np.uint8))
    writer.release()
    write_toml(
        d,
        [
            {"name": "cam0", "video": "cam0", "timestamps": "cam0.csv"},
            {"name": "cam1", "video": "cam1", "timestamps": "cam1.csv"},
            {"name": "cam2", "video": "cam2.avi"},
        ],
    )
    return d


def frame_of(fs, cam: str) -> int:
    img = fs.images[cam]
    if cam == "cam2":
        return round(float(img.mean()) / 10)
    c, f = decode(img)
    assert c == int(cam[-1])
    return f


# ---------------------------------------------------------------------------------------------
# synchronisation


def test_frame_sets_hold_the_nearest_frame_of_each_camera(rec_dir):
    rec = open_recording(rec_dir)
    assert rec.camera_names == ("cam0", "cam1", "cam2")
    assert rec.rig.names == ("cam0", "cam1", "cam2")  # subset of the 4-camera rig
    sets = list(rec.framesets())
    assert [fs.index for fs in sets] == list(range(20)) and rec.n_framesets == 20
    assert all(fs.t_ns == fs.index * 100 * MS for fs in sets)
    got = {fs.index: {cam: frame_of(fs, cam) for cam in fs.images} for fs in sets}

    cam0 = {k: (k if k < 7 else k - 1) for k in range(20) if k != 7}  # dropped around 700 ms
    cam1 = {
        k: i
        for i, k in enumerate([3, 4, 5, 6, 7, 8, 9, None, 11, 12, 13, 15, 16, 17, 18, 19])
        if k is not None
    }  # 10, 14 absent
    cam2 = {k: k for k in range(N_CAM2)}  # ends early
    expected = {
        k: {c: m[k] for c, m in (("cam0", cam0), ("cam1", cam1), ("cam2", cam2)) if k in m}
        for k in range(20)
    }
    assert got == expected
    # the 1060 ms frame (cam1 #7) lost set 11 to the on-time frame; the 1460 ms one serves 15
    assert sets[11].frame_t_ns["cam1"] == 1100 * MS
    assert sets[15].frame_t_ns["cam1"] == 1460 * MS
    assert sets[1].frame_t_ns == {"cam0": 102 * MS, "cam2": 100 * MS}
    assert list(sets[5].images) == ["cam0", "cam1", "cam2"]


def test_frame_sets_start_stop_select_by_index(rec_dir):
    rec = open_recording(rec_dir)
    sets = list(rec.framesets(start=9, stop=13))
    assert [fs.index for fs in sets] == [9, 10, 11, 12] == list(range(9, 13))
    assert rec.count_framesets(9, 13) == 4
    assert frame_of(sets[0], "cam0") == 8 and frame_of(sets[0], "cam2") == 9
    assert frame_of(sets[2], "cam1") == 8


def test_assign_frames_skips_and_counts_empty_grid_times():
    a = assign_frames([np.array([0, 100, 500]), np.array([110, 520, 610])], 100)
    assert a.set_idx.tolist() == [0, 1, 5, 6]
    assert a.frame_idx.tolist() == [[0, -1], [1, 0], [2, 1], [-1, 2]]
    assert a.n_empty == 3  # grid times 2, 3, 4


def test_half_period_window_is_half_open_and_ties_go_to_the_earlier_frame():
    assert frame_set_of(np.array([50, 51, -49]), 100).tolist() == [0, 1, 0]
    a = assign_frames([np.array([90, 110])], 100)  # both 10 ns from t=100: earlier wins
    assert a.frame_idx.tolist() == [[0]]


def test_corrupt_frame_makes_the_camera_absent_for_that_set_only(rec_dir, caplog):
    (rec_dir / "cam0" / "000004.png").write_bytes(b"not a png")
    rec = open_recording(rec_dir)
    sets = {fs.index: fs for fs in rec.framesets()}
    assert "cam0" not in sets[4].images
    assert frame_of(sets[3], "cam0") == 3 and frame_of(sets[5], "cam0") == 5
    assert rec.n_corrupt["cam0"] == 1
    assert "000004.png: frame 4 cannot be decoded" in caplog.text


def test_streaming_keeps_a_bounded_number_of_frames_alive(tmp_path, monkeypatch):
    d = tmp_path / "long"
    d.mkdir()
    n = 400
    write_rig(d / "rig.yaml", ["a", "b"], size=(8, 6))
    write_png_camera(d / "a", 0, n, size=(8, 6))
    write_png_camera(d / "b", 1, n - 1, size=(8, 6))
    write_csv(d / "b.csv", [(i * 100 + 30) * MS for i in range(n - 1)])  # offset: no grid sync
    (d / "a" / "000100.png").write_bytes(b"corrupt: exercises the lookahead")
    write_toml(
        d, [{"name": "a", "video": "a"}, {"name": "b", "video": "b", "timestamps": "b.csv"}]
    )
    alive: list[weakref.ref] = []
    original_read = video.ImageFolderSource.read

    def tracking_read(self):
        frame = original_read(self)
        if frame is not None:
            alive.append(weakref.ref(frame))
        return frame

    monkeypatch.setattr(video.ImageFolderSource, "read", tracking_read)
    rec = open_recording(d)
    max_alive = max_alive_held = 0
    n_sets = 0
    for fs in rec.framesets():
        n_sets += 1
        max_alive_held = max(max_alive_held, sum(r() is not None for r in alive))
        del fs
        max_alive = max(max_alive, sum(r() is not None for r in alive))
    assert len(alive) == 2 * n - 2  # every frame decoded once, the corrupt one not at all
    assert n_sets == rec.n_framesets == n
    assert max_alive_held <= 3  # the set's two images + one frame of lookahead
    assert max_alive == 1  # the frame after the corrupt one: held back for its own set


def test_video_shorter_than_its_timestamps_leaves_the_camera_absent(rec_dir, caplog):
    write_csv(rec_dir / "cam2.csv", [k * 100 * MS for k in range(N_CAM2 + 2)])
    write_toml(rec_dir, [{"name": "cam2", "video": "cam2.avi", "timestamps": "cam2.csv"}])
    rec = open_recording(rec_dir)
    assert "cam2.csv has 14 timestamps, the video header states 12 frames" in caplog.text
    sets = list(rec.framesets())
    assert [fs.index for fs in sets] == list(range(14))
    assert [frame_of(fs, "cam2") for fs in sets[:N_CAM2]] == list(range(N_CAM2))
    assert sets[12].images == {} and sets[13].images == {}


# ---------------------------------------------------------------------------------------------
# describe_recording / surveil info


def test_info_counts_dropped_jitter_late_start_early_end(rec_dir):
    info = describe_recording(open_recording(rec_dir))
    cams = {c.name: c for c in info.cameras}
    c0, c1, c2 = cams["cam0"], cams["cam1"], cams["cam2"]
    assert (c0.n_frames, c1.n_frames, c2.n_frames) == (19, 16, 12)
    assert (c0.width, c0.height, c2.width, c2.height) == (W, H, W, H)
    assert (c0.dropped, c1.dropped, c2.dropped) == (1, 2, 0)  # cam1: 1060 ms gap, 1500 ms
    jit = np.array([j for j in CAM0_JITTER_MS if j is not None], dtype=float)
    assert c0.jitter_max_ms == pytest.approx(4.0)
    assert c0.jitter_std_ms == pytest.approx(jit.std())
    assert c2.jitter_max_ms < 1e-3
    assert c1.late_start_s == pytest.approx(0.3) and c0.late_start_s == 0.0
    assert c2.early_end_s == pytest.approx(1.904 - 1.1) and c1.early_end_s == 0.0
    assert c0.fps_measured == pytest.approx(10.0, rel=0.05) and c0.fps_nominal == 10.0
    assert c1.unused == 1 and c1.n_sets == 15
    assert c2.timestamps is None and c0.timestamps == "cam0.csv"
    assert info.n_framesets == 20 and info.n_empty == 0
    assert info.n_complete == 7  # sets 3, 4, 5, 6, 8, 9, 11
    assert info.n_incomplete == 13
    assert info.duration_s == pytest.approx(1.9)


def test_info_format_and_dict(rec_dir):
    info = describe_recording(open_recording(rec_dir))
    text = info.format()
    table = text.splitlines()[2:6]
    assert [line.split()[0] for line in table] == ["camera", "cam0", "cam1", "cam2"]
    clock_col = table[0].index("clock")
    assert all(line[clock_col - 2 : clock_col] == "  " for line in table)  # aligned columns
    assert [line[clock_col:] for line in table] == ["clock", "cam0.csv", "cam1.csv", "nominal"]
    assert "20 (7 with all 3 cameras, 13 missing at least one" in text
    d = json.loads(json.dumps(info.to_dict()))
    assert [c["dropped"] for c in d["cameras"]] == [1, 2, 0]


def test_cli_info_prints_cameras_and_dropped_frames(rec_dir, capsys):
    assert main(["info", str(rec_dir)]) == ExitCode.OK
    out = capsys.readouterr().out
    lines = out.splitlines()
    header = next(line for line in lines if "dropped" in line)
    end = header.index("dropped") + len("dropped")  # numbers are right-aligned to the header
    dropped = {
        line.split()[0]: line[:end].split()[-1]
        for line in lines
        if line.startswith("  cam") and line.split()[0] != "camera"
    }
    assert dropped == {"cam0": "1", "cam1": "2", "cam2": "0"}


def test_cli_info_json(rec_dir, capsys):
    assert main(["info", str(rec_dir / "recording.toml"), "--json"]) == ExitCode.OK
    d = json.loads(capsys.readouterr().out)
    assert [c["name"] for c in d["cameras"]] == ["cam0", "cam1", "cam2"]
    assert d["n_framesets"] == 20


def test_cli_info_missing_directory_is_bad_input(tmp_path, capsys):
    assert main(["info", str(tmp_path / "nowhere")]) == ExitCode.BAD_INPUT
    assert "nowhere: recording not found" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# errors


def test_ground_truth_dir(rec_dir):
    assert open_recording(rec_dir).ground_truth_dir is None
    (rec_dir / "ground_truth").mkdir()
    assert open_recording(rec_dir).ground_truth_dir == rec_dir / "ground_truth"


def test_missing_recording_toml(tmp_path):
    with pytest.raises(InputError, match=r"empty: not a recording directory \(recording\.toml"):
        (tmp_path / "empty").mkdir()
        open_recording(tmp_path / "empty")


def test_unknown_key_names_file_and_key(rec_dir):
    write_toml(rec_dir, [{"name": "cam0", "video": "cam0", "timstamps": "cam0.csv"}])
    with pytest.raises(
        ConfigError,
        match=r"recording\.toml: cameras\[0\]\.timstamps is not a "
        r"known key",
    ):
        open_recording(rec_dir)


@pytest.mark.parametrize(
    ("fps", "extra", "match"),
    [
        (0, "", r"recording\.toml: fps must be > 0, got 0"),
        (10, "start_time_ns = -1", r"recording\.toml: start_time_ns must be >= 0"),
        (10, "colour = 1", r"recording\.toml: colour is not a known key"),
    ],
)
def test_bad_values_name_file_and_key(rec_dir, fps, extra, match):
    write_toml(rec_dir, [{"name": "cam0", "video": "cam0"}], fps=fps, extra=extra)
    with pytest.raises(ConfigError, match=match):
        open_recording(rec_dir)


def test_repeated_camera(rec_dir):
    write_toml(rec_dir, [{"name": "cam0", "video": "cam0"}, {"name": "cam0", "video": "cam1"}])
    with pytest.raises(ConfigError, match=r"cameras\[1\]\.name 'cam0' is repeated"):
        open_recording(rec_dir)


def test_camera_not_in_rig_lists_rig_cameras(rec_dir):
    write_toml(rec_dir, [{"name": "cam9", "video": "cam0"}])
    with pytest.raises(
        InputError,
        match=r"camera 'cam9' is not in the rig .*rig cameras: cam0, "
        r"cam1, cam2, cam3",
    ):
        open_recording(rec_dir)


def test_missing_rig(rec_dir):
    write_toml(rec_dir, [{"name": "cam0", "video": "cam0"}], rig="../lab.yaml")
    with pytest.raises(InputError, match=r"rig file '\.\./lab\.yaml' not found"):
        open_recording(rec_dir)


def test_missing_video_names_camera_and_file(rec_dir):
    write_toml(rec_dir, [{"name": "cam2", "video": "cam2.mp4"}])
    with pytest.raises(InputError, match=r"camera cam2: video 'cam2\.mp4' not found"):
        open_recording(rec_dir)


def test_bad_timestamp_line_names_file_and_line(rec_dir):
    (rec_dir / "cam0.csv").write_text("frame,timestamp_ns\n0,0\n1,abc\n")
    with pytest.raises(InputError, match=r"cam0\.csv:3: frame and timestamp_ns must be integers"):
        open_recording(rec_dir)


def test_bad_timestamp_header(rec_dir):
    (rec_dir / "cam1.csv").write_text("frame,t_ns\n0,0\n")
    with pytest.raises(InputError, match=r"cam1\.csv:1: header must be exactly"):
        open_recording(rec_dir)


def test_timestamp_count_must_match_image_count(rec_dir):
    write_csv(rec_dir / "cam0.csv", [0, 100 * MS])
    with pytest.raises(
        InputError,
        match=r"camera cam0: .*cam0\.csv has 2 timestamps but .*19 "
        r"images",
    ):
        open_recording(rec_dir)


def test_size_mismatch_names_camera_and_both_sizes(rec_dir):
    write_rig(rec_dir / "rig.yaml", ["cam0", "cam1", "cam2"], size=(640, 480))
    with pytest.raises(InputError, match=r"camera cam0: images are 64x48 .* rig says 640x480"):
        open_recording(rec_dir)
