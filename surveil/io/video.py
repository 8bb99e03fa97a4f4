"""Frame sources: one camera's frames, read one at a time, and its timestamp CSV.

A camera's frames come from a video file (anything OpenCV/FFmpeg reads: ``.mp4``, ``.avi``,
``.mkv``...) or from a folder of numbered images (``.png``, ``.jpg``, ``.jpeg``, ``.bmp``,
``.tif``, ``.tiff``). Both sources stream: they hold at most the frame being returned, so
memory does not grow with the length of the recording.

Frames are ``(H, W, 3) uint8 BGR`` arrays as OpenCV delivers them. Frame ``i`` is the ``i``-th
frame of the video, or the ``i``-th image of the folder in the order of the number in its name.

A frame that cannot be decoded in the middle of a stream is not fatal ("no lost data": one bad
frame must not cost the rest of the recording): the source logs a warning, counts it in
``n_corrupt`` and returns the next good frame; ``last_index`` tells which frame that was, so a
caller aligning frames with timestamps sees the gap. A file that cannot be opened at all raises
:class:`~surveil.errors.InputError` naming it.
"""

from __future__ import annotations

import itertools
import logging
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np

from surveil.errors import InputError

log = logging.getLogger(__name__)

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
TIMESTAMP_HEADER = "frame,timestamp_ns"
_NUMBER_RE = re.compile(r"(\d+)")
# consecutive failed reads after which a video is taken to have ended (rather than to hold a
# run of corrupt frames)
_MAX_CONSECUTIVE_FAILURES = 8


class FrameSource(Protocol):
    """What the recording needs from one camera's frames.

    Attributes
    ----------
    path : Path
        The video file or image folder.
    n_frames : int
        Number of frames (exact for image folders; the container's claim for videos).
    size : tuple[int, int]
        ``(width, height)`` in pixels.
    position : int
        Index of the next frame :meth:`read` will try.
    last_index : int
        Index of the frame the last :meth:`read` returned (-1 before the first).
    n_corrupt : int
        Frames skipped so far because they could not be decoded.
    """

    path: Path
    n_frames: int
    size: tuple[int, int]
    n_corrupt: int

    @property
    def position(self) -> int: ...

    @property
    def last_index(self) -> int: ...

    def read(self) -> np.ndarray | None:
        """The next good frame ``(H, W, 3) uint8 BGR``, or None at the end."""
        ...

    def skip(self, n: int) -> None:
        """Move ``n`` frames forward without returning them."""
        ...

    def close(self) -> None: ...

    def __iter__(self) -> Iterator[np.ndarray]: ...


def open_source(path: Path) -> VideoFileSource | ImageFolderSource:
    """An :class:`ImageFolderSource` for a directory, a :class:`VideoFileSource` otherwise."""
    path = Path(path)
    return ImageFolderSource(path) if path.is_dir() else VideoFileSource(path)


class _SourceBase:
    path: Path
    n_corrupt: int
    _next: int
    _last: int

    @property
    def position(self) -> int:
        return self._next

    @property
    def last_index(self) -> int:
        return self._last

    def read(self) -> np.ndarray | None:  # pragma: no cover - overridden
        raise NotImplementedError

    def close(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __iter__(self) -> Iterator[np.ndarray]:
        while (frame := self.read()) is not None:
            yield frame

    def __enter__(self):
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class VideoFileSource(_SourceBase):
    """Frames of a video file, decoded sequentially with ``cv2.VideoCapture``.

    Parameters
    ----------
    path : Path
        Any file OpenCV's FFmpeg backend reads (or an MJPG AVI, which OpenCV reads itself).

    Notes
    -----
    ``n_frames`` is ``CAP_PROP_FRAME_COUNT``, which the container states and FFmpeg sometimes
    estimates (from duration x rate): it may be off by a few frames for variable-rate or
    truncated files. Where it is not positive the file is counted once by grabbing every frame.
    A recording's timestamps CSV, when there is one, is the authority on the number of frames.

    Raises
    ------
    InputError
        The file is missing, OpenCV cannot open it, or it has no readable frame.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise InputError(f"{self.path}: video file not found")
        self._cap = self._open()
        self.n_corrupt = 0
        self._next = 0
        self._last = -1
        width = int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        height = int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        n_frames = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT))
        if width <= 0 or height <= 0 or n_frames <= 0:
            width, height, n_frames = self._probe()
        self.size = (width, height)
        self.n_frames = n_frames

    def _open(self) -> cv2.VideoCapture:
        cap = cv2.VideoCapture(str(self.path))
        if not cap.isOpened():
            raise InputError(
                f"{self.path}: OpenCV cannot open this video (unknown container "
                f"or codec, or not a video); convert it, e.g. `ffmpeg -i "
                f"{self.path.name} out.mp4`, or export numbered images"
            )
        return cap

    def _probe(self) -> tuple[int, int, int]:
        """Size from the first frame and the count by grabbing every frame; then rewind."""
        ok, frame = self._cap.read()
        if not ok or frame is None:
            self._cap.release()
            raise InputError(f"{self.path}: video has no readable frame")
        n = 1
        while self._cap.grab():
            n += 1
        self._cap.release()
        self._cap = self._open()
        return frame.shape[1], frame.shape[0], n

    def read(self) -> np.ndarray | None:
        failures = 0
        while failures < _MAX_CONSECUTIVE_FAILURES:
            ok, frame = self._cap.read()
            if ok and frame is not None:
                frame = _as_bgr(frame)
                if frame.shape[1::-1] == self.size:
                    if failures:
                        self.n_corrupt += failures
                        log.warning(
                            "%s: frames %d-%d could not be decoded; treated as missing",
                            self.path,
                            self._next,
                            self._next + failures - 1,
                        )
                    self._last = self._next + failures
                    self._next = self._last + 1
                    return frame
            failures += 1
            if self._next + failures >= self.n_frames:
                break  # at or past the stated end: an end of stream, not corruption
        if self._next < self.n_frames:
            log.warning(
                "%s: video ended after %d frames, its header states %d",
                self.path,
                self._next,
                self.n_frames,
            )
        self._next += failures
        return None

    def skip(self, n: int) -> None:
        for _ in range(max(int(n), 0)):
            self._cap.grab()  # decodes (inter-frame codecs need it) without colour conversion
            self._next += 1

    def close(self) -> None:
        self._cap.release()


class ImageFolderSource(_SourceBase):
    """Frames from a folder of numbered images, read one file at a time.

    Images are ordered by the last number in their file name (``frame_000012.png`` -> 12,
    ``cam0_7.jpg`` -> 7); files with other suffixes are ignored. Frame ``i`` is the ``i``-th
    image in that order; gaps in the numbering are reported (warning) but do not create
    missing frames -- timestamps come from the recording's CSV or the nominal rate.

    Parameters
    ----------
    path : Path
        The folder.

    Raises
    ------
    InputError
        The folder is missing or holds no image, an image name has no number, two images share
        a number, or the first image cannot be read.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        if not self.path.is_dir():
            raise InputError(f"{self.path}: image folder not found")
        numbered: list[tuple[int, Path]] = []
        for p in self.path.iterdir():
            if p.suffix.lower() not in IMAGE_SUFFIXES or not p.is_file():
                continue
            numbers = _NUMBER_RE.findall(p.stem)
            if not numbers:
                raise InputError(
                    f"{p}: image name has no frame number; name images like 000123{p.suffix}"
                )
            numbered.append((int(numbers[-1]), p))
        if not numbered:
            raise InputError(f"{self.path}: folder holds no image ({', '.join(IMAGE_SUFFIXES)})")
        numbered.sort()
        for (a, pa), (b, pb) in itertools.pairwise(numbered):
            if a == b:
                raise InputError(
                    f"{self.path}: {pa.name} and {pb.name} have the same frame number {a}"
                )
        first, last = numbered[0][0], numbered[-1][0]
        if last - first + 1 != len(numbered):
            log.warning(
                "%s: image numbers %d..%d have gaps (%d images); frame i is the i-th image",
                self.path,
                first,
                last,
                len(numbered),
            )
        self._files = tuple(p for _, p in numbered)
        self.n_frames = len(self._files)
        self.n_corrupt = 0
        self._next = 0
        self._last = -1
        img = cv2.imread(str(self._files[0]), cv2.IMREAD_COLOR)
        if img is None:
            raise InputError(f"{self._files[0]}: cannot read the first image of the folder")
        self.size = (int(img.shape[1]), int(img.shape[0]))

    @property
    def files(self) -> tuple[Path, ...]:
        """The image files, in frame order."""
        return self._files

    def read(self) -> np.ndarray | None:
        while self._next < self.n_frames:
            i = self._next
            self._next += 1
            path = self._files[i]
            img = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if img is None:
                self.n_corrupt += 1
                log.warning("%s: frame %d cannot be decoded; treated as missing", path, i)
                continue
            if img.shape[1::-1] != self.size:
                self.n_corrupt += 1
                log.warning(
                    "%s: frame %d is %dx%d, the folder's images are %dx%d; treated as missing",
                    path,
                    i,
                    img.shape[1],
                    img.shape[0],
                    *self.size,
                )
                continue
            self._last = i
            return _as_bgr(img)
        return None

    def skip(self, n: int) -> None:
        self._next = min(self._next + max(int(n), 0), self.n_frames)

    def close(self) -> None:
        self._next = self.n_frames


def _as_bgr(img: np.ndarray) -> np.ndarray:
    """uint8 BGR, whatever OpenCV returned (grey or 16-bit are rescaled, not cast)."""
    if img.dtype == np.uint16:
        img = cv2.convertScaleAbs(img, alpha=255.0 / 65535.0)
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    return img


def read_timestamps(csv_path: Path) -> np.ndarray:
    """Read a camera's timestamp CSV.

    The file has the header ``frame,timestamp_ns`` and one row per frame: ``frame`` is the
    0-based frame index (rows are frames 0, 1, 2, ... in order, none missing) and
    ``timestamp_ns`` an integer time in ns on the recording clock (>= 0, strictly increasing).
    Blank lines are ignored.

    Parameters
    ----------
    csv_path : Path

    Returns
    -------
    timestamps_ns : (N,) int64
        Timestamp of frame ``i`` at ``[i]``, read-only.

    Raises
    ------
    InputError
        Naming ``file:line`` and what is wrong: missing file, wrong header, a row without two
        integer fields, an out-of-order frame index, a timestamp that does not increase, or no
        rows at all.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "cam0.csv"
    >>> _ = p.write_text("frame,timestamp_ns\\n0,0\\n1,66666667\\n")
    >>> read_timestamps(p).tolist()
    [0, 66666667]
    >>> _ = p.write_text("frame,timestamp_ns\\n0,5\\n1,5\\n")
    >>> read_timestamps(p)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    surveil.errors.InputError: ...cam0.csv:3: timestamp_ns must be greater than the previous \
row's (5), got 5
    """
    path = Path(csv_path)
    if not path.is_file():
        raise InputError(f"{path}: timestamps file not found")
    values: list[int] = []
    prev = -1
    with open(path, encoding="utf-8-sig", newline="") as f:
        header = f.readline().strip()
        if header != TIMESTAMP_HEADER:
            raise InputError(
                f"{path}:1: header must be exactly {TIMESTAMP_HEADER!r}, got {header!r}"
            )
        for line_no, line in enumerate(f, start=2):
            line = line.strip()
            if not line:
                continue
            where = f"{path}:{line_no}"
            fields = line.split(",")
            if len(fields) != 2:
                raise InputError(f"{where}: expected 2 fields 'frame,timestamp_ns', got {line!r}")
            try:
                frame, t_ns = int(fields[0]), int(fields[1])
            except ValueError:
                raise InputError(
                    f"{where}: frame and timestamp_ns must be integers, got {line!r}"
                ) from None
            if frame != len(values):
                raise InputError(
                    f"{where}: frame must be {len(values)} (rows are frames 0, "
                    f"1, 2, ... in order), got {frame}"
                )
            if t_ns < 0:
                raise InputError(f"{where}: timestamp_ns must be >= 0 (ns from t = 0), got {t_ns}")
            if t_ns <= prev:
                raise InputError(
                    f"{where}: timestamp_ns must be greater than the previous "
                    f"row's ({prev}), got {t_ns}"
                )
            values.append(t_ns)
            prev = t_ns
    if not values:
        raise InputError(f"{path}: no frames (only a header)")
    out = np.array(values, dtype=np.int64)
    out.flags.writeable = False
    return out
