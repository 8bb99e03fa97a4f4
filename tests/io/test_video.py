"""Frame sources (video file, image folder) and timestamp CSVs."""

from __future__ import annotations

import logging
from pathlib import Path

import cv2
import numpy as np
import pytest

from surveil.errors import InputError
from surveil.io.video import (
    ImageFolderSource,
    VideoFileSource,
    open_source,
    read_timestamps,
)

W, H = 64, 48


def grey(value: int) -> np.ndarray:
    return np.full((H, W, 3), value, dtype=np.uint8)


def write_avi(path: Path, n: int, step: int = 10, fourcc: str = "MJPG") -> Path:
    """A video (MJPG AVI by default) whose frame i is uniform grey 10 * i."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*fourcc), 10.0, (W, H))
    assert writer.isOpened()
    for i in range(n):
        writer.write(grey(step * i))
    writer.release()
    return path


def decode_grey(img: np.ndarray, step: int = 10) -> int:
    return round(float(img.mean()) / step)


def write_folder(path: Path, numbers: list[int], pattern: str = "frame_{}.png") -> Path:
    path.mkdir(parents=True, exist_ok=True)
    for n in numbers:
        cv2.imwrite(str(path / pattern.format(n)), grey(n))
    return path


# ---------------------------------------------------------------------------------------------
# video files


@pytest.mark.parametrize(("fourcc", "name"), [("MJPG", "c.avi"), ("mp4v", "c.mp4")])
def test_video_source_reads_every_frame_in_order(tmp_path, fourcc, name):
    src = VideoFileSource(write_avi(tmp_path / name, 12, fourcc=fourcc))
    assert src.size == (W, H)
    assert src.n_frames == 12
    frames = list(src)
    assert [decode_grey(f) for f in frames] == list(range(12))
    assert all(f.shape == (H, W, 3) and f.dtype == np.uint8 for f in frames)
    assert src.read() is None and src.last_index == 11 and src.n_corrupt == 0
    src.close()


def test_video_source_skip_then_read(tmp_path):
    with VideoFileSource(write_avi(tmp_path / "c.avi", 12)) as src:
        src.skip(5)
        assert src.position == 5
        frame = src.read()
        assert decode_grey(frame) == 5 and src.last_index == 5


def test_open_source_picks_the_kind(tmp_path):
    assert isinstance(open_source(write_avi(tmp_path / "c.avi", 2)), VideoFileSource)
    assert isinstance(open_source(write_folder(tmp_path / "imgs", [0])), ImageFolderSource)


def test_video_source_missing_file_names_it(tmp_path):
    with pytest.raises(InputError, match=r"nope\.mp4: video file not found"):
        VideoFileSource(tmp_path / "nope.mp4")


def test_video_source_not_a_video_names_it(tmp_path):
    bad = tmp_path / "notes.mp4"
    bad.write_text("this is not a video\n" * 50)
    with pytest.raises(InputError, match=r"notes\.mp4"):
        VideoFileSource(bad)


# ---------------------------------------------------------------------------------------------
# image folders


def test_image_folder_orders_by_the_number_not_the_text(tmp_path):
    folder = write_folder(tmp_path / "cam0", [10, 2, 1, 0, 3], pattern="cam0_{}.png")
    (folder / "notes.txt").write_text("ignored")
    src = ImageFolderSource(folder)
    assert [p.name for p in src.files] == [f"cam0_{n}.png" for n in (0, 1, 2, 3, 10)]
    assert src.n_frames == 5 and src.size == (W, H)
    assert [int(f[0, 0, 0]) for f in src] == [0, 1, 2, 3, 10]


def test_image_folder_skip(tmp_path):
    src = ImageFolderSource(write_folder(tmp_path / "c", list(range(6))))
    src.skip(4)
    assert int(src.read()[0, 0, 0]) == 4 and src.last_index == 4


def test_image_folder_corrupt_frame_is_skipped_counted_and_logged(tmp_path, caplog):
    folder = write_folder(tmp_path / "c", list(range(5)))
    (folder / "frame_2.png").write_bytes(b"\x89PNG garbage")
    src = ImageFolderSource(folder)
    with caplog.at_level(logging.WARNING):
        got = [(int(f[0, 0, 0]), src.last_index) for f in src]
    assert got == [(0, 0), (1, 1), (3, 3), (4, 4)]
    assert src.n_corrupt == 1
    assert "frame_2.png: frame 2 cannot be decoded" in caplog.text


def test_image_folder_wrong_size_frame_is_treated_as_missing(tmp_path):
    folder = write_folder(tmp_path / "c", list(range(3)))
    cv2.imwrite(str(folder / "frame_1.png"), np.zeros((10, 10, 3), np.uint8))
    src = ImageFolderSource(folder)
    assert [src.last_index for _ in src] == [0, 2] and src.n_corrupt == 1


@pytest.mark.parametrize(
    ("names", "match"),
    [
        ([], r"folder holds no image"),
        (["a.png"], r"a\.png: image name has no frame number"),
        (["1.png", "001.png"], r"001\.png and 1\.png have the same frame number 1"),
    ],
)
def test_image_folder_errors_name_the_problem(tmp_path, names, match):
    folder = tmp_path / "c"
    folder.mkdir()
    for n in names:
        cv2.imwrite(str(folder / n), grey(0))
    with pytest.raises(InputError, match=match):
        ImageFolderSource(folder)


def test_image_folder_unreadable_first_image(tmp_path):
    folder = tmp_path / "c"
    folder.mkdir()
    (folder / "0.png").write_bytes(b"nope")
    with pytest.raises(InputError, match=r"0\.png: cannot read the first image"):
        ImageFolderSource(folder)


def test_image_folder_missing(tmp_path):
    with pytest.raises(InputError, match=r"nowhere: image folder not found"):
        ImageFolderSource(tmp_path / "nowhere")


# ---------------------------------------------------------------------------------------------
# timestamps


def write_csv(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "cam0.csv"
    p.write_text(text)
    return p


def test_read_timestamps_returns_int64(tmp_path):
    ts = read_timestamps(write_csv(tmp_path, "frame,timestamp_ns\n0,5\n1,100000000\n\n"))
    assert ts.dtype == np.int64 and ts.tolist() == [5, 100_000_000]
    assert not ts.flags.writeable


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("frame,t\n0,0\n", r"cam0\.csv:1: header must be exactly 'frame,timestamp_ns'"),
        ("frame,timestamp_ns\n0,0\n1\n", r"cam0\.csv:3: expected 2 fields"),
        ("frame,timestamp_ns\n0,0\n1,1.5e8\n", r"cam0\.csv:3: .* must be integers"),
        ("frame,timestamp_ns\n0,0\n2,100\n", r"cam0\.csv:3: frame must be 1 .*got 2"),
        (
            "frame,timestamp_ns\n0,0\n1,100\n2,100\n",
            r"cam0\.csv:4: timestamp_ns must be "
            r"greater than the previous row's \(100\)",
        ),
        ("frame,timestamp_ns\n0,-5\n", r"cam0\.csv:2: timestamp_ns must be >= 0"),
        ("frame,timestamp_ns\n", r"cam0\.csv: no frames"),
    ],
)
def test_read_timestamps_errors_give_file_and_line(tmp_path, text, match):
    with pytest.raises(InputError, match=match):
        read_timestamps(write_csv(tmp_path, text))


def test_read_timestamps_missing_file(tmp_path):
    with pytest.raises(InputError, match=r"gone\.csv: timestamps file not found"):
        read_timestamps(tmp_path / "gone.csv")
