"""Recordings: a directory with ``recording.toml``, one video (or image folder) per camera,
optional timestamp CSVs, and the frame sets synchronised from them.

The format is the contract of docs/formats.md, "Recording"::

    rig = "../../calibration/lab4.yaml"   # relative to recording.toml, or absolute
    fps = 15.0                            # nominal rate; frame i is at i / fps without a CSV
    start_time_ns = 0                     # optional: wall-clock time of t = 0

    [[cameras]]
    name = "cam0"                         # a camera of the rig
    video = "cam0.mp4"                    # a video file, or a folder of numbered images
    timestamps = "cam0.csv"               # optional: "frame,timestamp_ns"

Synchronisation (:func:`assign_frames`) is by timestamp, never by frame index. With the
period ``p = round(1e9 / fps)`` ns, frame set ``k`` is at ``t_k = k * p`` and owns the
half-open window ``(t_k - p/2, t_k + p/2]``: every frame falls in exactly one window (a frame
exactly half-way between two set times goes to the earlier set). Each camera contributes to
set ``k`` the frame in that window nearest to ``t_k`` (ties: the earlier frame); another frame
of the same camera in the same window is *unused* (counted, never used twice). A camera with
no frame in the window is absent from the set. The sets run from the earliest to the latest
frame of any camera; a grid time with no frame from any camera is skipped (counted as an
*empty* set), so every yielded :class:`~surveil.datatypes.FrameSet` holds at least one camera.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from surveil.camera import CAMERA_NAME_RE, Rig
from surveil.config import from_table, read_toml, setting
from surveil.datatypes import FrameSet
from surveil.errors import ConfigError, InputError
from surveil.io.video import FrameSource, ImageFolderSource, open_source, read_timestamps

log = logging.getLogger(__name__)

RECORDING_FILE = "recording.toml"
GROUND_TRUTH_DIR = "ground_truth"


# ---------------------------------------------------------------------------------------------
# recording.toml


@dataclass(frozen=True)
class CameraEntry:
    """One ``[[cameras]]`` table of ``recording.toml``."""

    name: str = setting(doc="camera name; must name a camera of the rig")
    video: str = setting(doc="video file or folder of numbered images, relative to the toml")
    timestamps: str | None = setting(None, "CSV 'frame,timestamp_ns', relative to the toml")


@dataclass(frozen=True)
class RecordingSpec:
    """The validated contents of ``recording.toml`` (paths as written, not resolved)."""

    rig: str = setting(doc="rig calibration YAML, relative to recording.toml or absolute")
    fps: float = setting(doc="nominal frame rate, frames per second", max=1e6)
    cameras: tuple[CameraEntry, ...] = setting(doc="one [[cameras]] table per camera")
    start_time_ns: int = setting(0, "wall-clock time of t = 0, ns", min=0)


def load_spec(toml_path: Path) -> RecordingSpec:
    """Read and validate ``recording.toml``.

    Raises
    ------
    ConfigError
        Naming the file and the dotted key: unknown key, wrong type, missing key, fps not
        positive, no camera, a repeated camera name.
    """
    path = Path(toml_path)
    spec = from_table(RecordingSpec, read_toml(path), f"{path}: ")
    if not math.isfinite(spec.fps) or spec.fps <= 0:
        raise ConfigError(f"{path}: fps must be > 0, got {spec.fps!r}")
    if not spec.cameras:
        raise ConfigError(f"{path}: cameras must list at least one [[cameras]] table")
    names = [c.name for c in spec.cameras]
    for i, name in enumerate(names):
        if not CAMERA_NAME_RE.match(name):
            raise ConfigError(
                f"{path}: cameras[{i}].name must match [A-Za-z0-9_.-]+, got {name!r}"
            )
        if name in names[:i]:
            raise ConfigError(f"{path}: cameras[{i}].name {name!r} is repeated")
    return spec


# ---------------------------------------------------------------------------------------------
# synchronisation (pure)


def period_ns(fps: float) -> int:
    """The frame-set period in integer ns, ``round(1e9 / fps)``.

    >>> period_ns(15.0), period_ns(30.0)
    (66666667, 33333333)
    """
    return max(round(1e9 / fps), 1)


def frame_set_of(timestamps_ns: np.ndarray, period: int) -> np.ndarray:
    """Index ``k`` of the set window ``(k p - p/2, k p + p/2]`` holding each timestamp.

    >>> frame_set_of(np.array([0, 49, 50, 51, 149, 150, 151]), 100).tolist()
    [0, 0, 0, 1, 1, 1, 2]
    """
    ts = np.asarray(timestamps_ns, dtype=np.int64)
    # k = ceil((2 ts - p) / (2 p)), in exact integer arithmetic
    return -((period - 2 * ts) // (2 * period))


@dataclass(frozen=True, slots=True)
class FrameAssignment:
    """Which frame of each camera goes into each non-empty frame set.

    set_idx : (S,) int64
        Grid index ``k`` of each non-empty set, increasing; the set is at ``k * period_ns``.
    frame_idx : (S, C) int64
        Frame index of camera ``c`` in set ``s``, or -1 where the camera is absent.
    n_empty : int
        Grid times between the first and the last set with no frame from any camera.
    """

    set_idx: np.ndarray
    frame_idx: np.ndarray
    n_empty: int


def assign_frames(timestamps_ns: Sequence[np.ndarray], period: int) -> FrameAssignment:
    """Synchronise cameras by timestamp (the rule in this module's docstring).

    Parameters
    ----------
    timestamps_ns : sequence of C arrays (N_c,) int64
        Each camera's frame timestamps, strictly increasing, ns.
    period : int
        Frame-set period, ns.

    Returns
    -------
    FrameAssignment

    Examples
    --------
    Camera 1 drops its frame near 100 and has two frames in the window of 200:

    >>> a = assign_frames([np.array([0, 100, 200, 300]), np.array([2, 180, 230, 290])], 100)
    >>> a.set_idx.tolist(), a.frame_idx.tolist(), a.n_empty
    ([0, 1, 2, 3], [[0, 0], [1, -1], [2, 1], [3, 3]], 0)
    """
    per_cam = []
    for ts in timestamps_ns:
        ts = np.asarray(ts, dtype=np.int64)
        k = frame_set_of(ts, period)
        dev = np.abs(ts - k * period)
        order = np.lexsort((np.arange(len(ts)), dev, k))  # by set, then nearest, then earliest
        k_sorted = k[order]
        first = np.ones(len(order), dtype=bool)
        first[1:] = k_sorted[1:] != k_sorted[:-1]
        chosen = order[first]
        per_cam.append((k[chosen], chosen))
    all_k = [k for k, _ in per_cam if len(k)]
    set_idx = np.unique(np.concatenate(all_k)) if all_k else np.zeros(0, dtype=np.int64)
    frame_idx = np.full((len(set_idx), len(per_cam)), -1, dtype=np.int64)
    for c, (k, chosen) in enumerate(per_cam):
        frame_idx[np.searchsorted(set_idx, k), c] = chosen
    n_empty = int(set_idx[-1] - set_idx[0] + 1 - len(set_idx)) if len(set_idx) else 0
    for arr in (set_idx, frame_idx):
        arr.flags.writeable = False
    return FrameAssignment(set_idx.astype(np.int64), frame_idx, n_empty)


# ---------------------------------------------------------------------------------------------
# the recording


class Recording:
    """An opened recording: validated spec, rig, timestamps and frame sources.

    Use :func:`open_recording` to make one. Frames are only decoded by :meth:`framesets` (and
    by :meth:`open_source` for callers that want one camera's raw frames).

    Attributes
    ----------
    path : Path
        The ``recording.toml``.
    directory : Path
        The recording directory (holding ``recording.toml``).
    spec : RecordingSpec
    rig : Rig
        The rig restricted to the recording's cameras, in the recording's order.
    rig_path : Path | None
        The rig file (per-camera skin models live beside it, see ``surveil train-skin``).
    camera_names : tuple[str, ...]
    fps : float
        Nominal rate.
    period_ns : int
        Frame-set period, ``round(1e9 / fps)``.
    start_time_ns : int
        Wall-clock time of t = 0 (add it to every output time).
    timestamps_ns : Mapping[str, (N,) int64]
        Each camera's frame timestamps on the recording clock (from its CSV, or ``i / fps``).
    sizes : Mapping[str, tuple[int, int]]
        Each camera's image ``(width, height)``.
    assignment : FrameAssignment
        Which frame of which camera goes into each frame set (from timestamps alone).
    n_corrupt : dict[str, int]
        Frames found undecodable by the last :meth:`framesets` run (logged as warnings).
    """

    def __init__(
        self,
        path: Path,
        spec: RecordingSpec,
        rig: Rig,
        video_paths: Mapping[str, Path],
        timestamp_paths: Mapping[str, Path | None],
        timestamps_ns: Mapping[str, np.ndarray],
        sizes: Mapping[str, tuple[int, int]],
        rig_path: Path | None = None,
    ) -> None:
        self.path = path
        self.rig_path = rig_path
        self.directory = path.parent
        self.spec = spec
        self.rig = rig
        self.camera_names = tuple(c.name for c in spec.cameras)
        self.fps = spec.fps
        self.period_ns = period_ns(spec.fps)
        self.start_time_ns = spec.start_time_ns
        self.video_paths = dict(video_paths)
        self.timestamp_paths = dict(timestamp_paths)
        self.timestamps_ns = dict(timestamps_ns)
        self.sizes = dict(sizes)
        self.assignment = assign_frames(
            [self.timestamps_ns[c] for c in self.camera_names], self.period_ns
        )
        self.n_corrupt = dict.fromkeys(self.camera_names, 0)

    def __repr__(self) -> str:
        return (
            f"Recording({str(self.directory)!r}, cameras={list(self.camera_names)}, "
            f"fps={self.fps}, n_framesets={self.n_framesets})"
        )

    @property
    def n_framesets(self) -> int:
        """Number of frame sets :meth:`framesets` yields over the whole recording."""
        return len(self.assignment.set_idx)

    @property
    def set_indices(self) -> np.ndarray:
        """(S,) int64 grid index of each frame set, i.e. each ``FrameSet.index``."""
        return self.assignment.set_idx

    def count_framesets(self, start: int = 0, stop: int | None = None) -> int:
        """Number of frame sets :meth:`framesets(start, stop) <framesets>` yields."""
        idx = self.assignment.set_idx
        hi = len(idx) if stop is None else int(np.searchsorted(idx, stop))
        return max(hi - int(np.searchsorted(idx, start)), 0)

    @property
    def ground_truth_dir(self) -> Path | None:
        """``directory / "ground_truth"`` if it exists, else None."""
        gt = self.directory / GROUND_TRUTH_DIR
        return gt if gt.is_dir() else None

    def open_source(self, camera: str) -> FrameSource:
        """A fresh frame source for ``camera`` (close it when done)."""
        return open_source(self.video_paths[camera])

    def framesets(self, start: int = 0, stop: int | None = None) -> Iterator[FrameSet]:
        """Stream the synchronised frame sets with ``start <= index < stop``.

        Each camera's frames are decoded once, in order; frames that belong to no yielded
        set are skipped without being kept. At most one decoded frame per camera is held
        besides the sets the caller keeps, so memory does not grow with the recording.

        Parameters
        ----------
        start, stop : int
            Range of ``FrameSet.index`` (grid index ``k``, the set at ``k * period_ns``).

        Yields
        ------
        FrameSet
            ``images`` holds the cameras with a frame for the set (in the recording's camera
            order) and ``frame_t_ns`` their frame timestamps. A set whose only frames turn out
            to be undecodable is yielded with no image (the count stays :meth:`count_framesets`).
        """
        a = self.assignment
        lo = int(np.searchsorted(a.set_idx, start))
        hi = len(a.set_idx) if stop is None else int(np.searchsorted(a.set_idx, stop))
        readers = {c: _FrameReader(self.open_source(c)) for c in self.camera_names}
        try:
            for row in range(lo, hi):
                # built in a helper so that this generator keeps no reference to the set
                yield self._frameset(row, readers)
        finally:
            for cam, reader in readers.items():
                self.n_corrupt[cam] = reader.source.n_corrupt
                reader.source.close()

    def _frameset(self, row: int, readers: Mapping[str, _FrameReader]) -> FrameSet:
        k = int(self.assignment.set_idx[row])
        images: dict[str, np.ndarray] = {}
        frame_t: dict[str, int] = {}
        for cam, fi in zip(
            self.camera_names, self.assignment.frame_idx[row].tolist(), strict=True
        ):
            if fi < 0:
                continue
            img = readers[cam].get(fi)
            if img is not None:
                images[cam] = img
                frame_t[cam] = int(self.timestamps_ns[cam][fi])
        return FrameSet(k, k * self.period_ns, images, frame_t)


class _FrameReader:
    """One camera's frames by increasing index, holding at most one frame of lookahead (the
    frame read after an undecodable one, which may belong to a later set)."""

    def __init__(self, source: FrameSource) -> None:
        self.source = source
        self.pending: tuple[int, np.ndarray] | None = None

    @property
    def n_buffered(self) -> int:
        return 0 if self.pending is None else 1

    def get(self, index: int) -> np.ndarray | None:
        """Frame ``index`` (increasing between calls), or None if it is undecodable/absent."""
        if self.pending is not None:
            idx, frame = self.pending
            if idx > index:
                return None
            self.pending = None
            if idx == index:
                return frame
        self.source.skip(index - self.source.position)
        frame = self.source.read()
        if frame is None:
            return None
        if self.source.last_index == index:
            return frame
        self.pending = (self.source.last_index, frame)
        return None


def _resolve(base: Path, name: str) -> Path:
    p = Path(name).expanduser()
    return p if p.is_absolute() else base / p


def open_recording(path: Path) -> Recording:
    """Open and check a recording without decoding it (one image per image folder is read
    for its size).

    Parameters
    ----------
    path : Path
        The recording directory, or its ``recording.toml``.

    Returns
    -------
    Recording

    Raises
    ------
    InputError
        Missing directory or ``recording.toml``, missing rig/video/timestamp file, a camera
        not in the rig (listing the rig's cameras), an image size that differs from the rig's,
        an unreadable video or timestamp CSV, or a timestamp CSV whose row count differs from
        an image folder's image count.
    ConfigError
        ``recording.toml`` is invalid (unknown key, bad value...), naming the file and key.
    """
    from surveil.io.calibration import load_rig

    path = Path(path)
    if path.is_dir():
        toml_path = path / RECORDING_FILE
        if not toml_path.is_file():
            raise InputError(f"{path}: not a recording directory ({RECORDING_FILE} is missing)")
    elif path.is_file():
        toml_path = path
    else:
        raise InputError(
            f"{path}: recording not found (give a directory holding "
            f"{RECORDING_FILE}, or the file itself)"
        )
    spec = load_spec(toml_path)
    base = toml_path.parent

    rig_path = _resolve(base, spec.rig)
    if not rig_path.is_file():
        raise InputError(f"{toml_path}: rig file {spec.rig!r} not found (looked for {rig_path})")
    full_rig = load_rig(rig_path)
    missing = [c.name for c in spec.cameras if c.name not in full_rig]
    if missing:
        raise InputError(
            f"{toml_path}: camera {missing[0]!r} is not in the rig {rig_path} "
            f"(rig cameras: {', '.join(full_rig.names)})"
        )
    rig = full_rig.subset([c.name for c in spec.cameras])

    video_paths: dict[str, Path] = {}
    ts_paths: dict[str, Path | None] = {}
    timestamps: dict[str, np.ndarray] = {}
    sizes: dict[str, tuple[int, int]] = {}
    for entry in spec.cameras:
        cam = entry.name
        video = _resolve(base, entry.video)
        if not video.exists():
            raise InputError(
                f"{toml_path}: camera {cam}: video {entry.video!r} not found (looked for {video})"
            )
        try:
            source = open_source(video)
        except InputError as exc:
            raise InputError(f"camera {cam}: {exc}") from None
        try:
            size, n_frames = source.size, source.n_frames
            is_folder = isinstance(source, ImageFolderSource)
        finally:
            source.close()
        expected = rig[cam].size
        if size != expected:
            raise InputError(
                f"camera {cam}: images are {size[0]}x{size[1]} ({video}) but the "
                f"rig says {expected[0]}x{expected[1]} ({rig_path})"
            )
        ts_path = None if entry.timestamps is None else _resolve(base, entry.timestamps)
        if ts_path is None:
            ts = np.round(np.arange(n_frames) * (1e9 / spec.fps)).astype(np.int64)
            ts.flags.writeable = False
        else:
            ts = read_timestamps(ts_path)
            if len(ts) != n_frames:
                if is_folder:
                    raise InputError(
                        f"camera {cam}: {ts_path} has {len(ts)} timestamps but "
                        f"{video} holds {n_frames} images"
                    )
                log.warning(
                    "camera %s: %s has %d timestamps, the video header states %d "
                    "frames; the timestamps are used",
                    cam,
                    ts_path,
                    len(ts),
                    n_frames,
                )
        video_paths[cam], ts_paths[cam] = video, ts_path
        timestamps[cam], sizes[cam] = ts, size
    rec = Recording(toml_path, spec, rig, video_paths, ts_paths, timestamps, sizes, rig_path)
    log.info("opened recording %s: %d cameras, %d frame sets", base, len(rig), rec.n_framesets)
    return rec


# ---------------------------------------------------------------------------------------------
# description (surveil info)


@dataclass(frozen=True, slots=True)
class CameraInfo:
    """Statistics of one camera, from its timestamps alone.

    Times in s unless suffixed ``_ms``. ``dropped`` counts frames missing from the camera's
    own sequence (each interval ``d > 1.5`` periods counts ``round(d / period) - 1``);
    ``jitter_*`` is the deviation of timestamps from the nearest set time ``k * period``;
    ``late_start_s`` / ``early_end_s`` are how much later / earlier than the recording's first
    / last frame (any camera) this camera starts / ends, 0 when within half a period;
    ``unused`` counts frames that lost their set to a nearer frame of the same camera.
    ``video`` and ``timestamps`` are as written in ``recording.toml`` (relative to it).
    """

    name: str
    width: int
    height: int
    video: str
    timestamps: str | None
    n_frames: int
    first_s: float
    last_s: float
    duration_s: float
    fps_nominal: float
    fps_measured: float | None
    dropped: int
    jitter_std_ms: float
    jitter_max_ms: float
    late_start_s: float
    early_end_s: float
    n_sets: int
    unused: int


@dataclass(frozen=True, slots=True)
class RecordingInfo:
    """What ``surveil info`` reports; :meth:`format` for people, :meth:`to_dict` for JSON."""

    directory: str
    rig: str
    fps: float
    period_ns: int
    start_time_ns: int
    cameras: tuple[CameraInfo, ...]
    n_framesets: int
    n_complete: int
    n_incomplete: int
    n_empty: int
    first_set_s: float
    last_set_s: float
    duration_s: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict (str, int, float, None, lists, dicts)."""
        d = dataclasses.asdict(self)
        d["cameras"] = [dataclasses.asdict(c) for c in self.cameras]
        return d

    def format(self) -> str:
        """A readable report: a header, one aligned row per camera, the frame-set summary."""
        lines = [
            f"recording {self.directory}",
            f"  rig {self.rig}, nominal {self.fps:g} fps (period {self.period_ns} ns), "
            f"start_time_ns {self.start_time_ns}",
        ]
        head = (
            "camera",
            "size",
            "frames",
            "first s",
            "last s",
            "meas fps",
            "dropped",
            "jitter std/max ms",
            "late start s",
            "early end s",
            "unused",
            "sets",
            "clock",
        )
        rows = [head]
        for c in self.cameras:
            fps = "-" if c.fps_measured is None else f"{c.fps_measured:.2f}"
            rows.append(
                (
                    c.name,
                    f"{c.width}x{c.height}",
                    str(c.n_frames),
                    f"{c.first_s:.3f}",
                    f"{c.last_s:.3f}",
                    fps,
                    str(c.dropped),
                    f"{c.jitter_std_ms:.2f} / {c.jitter_max_ms:.2f}",
                    f"{c.late_start_s:.3f}" if c.late_start_s else "-",
                    f"{c.early_end_s:.3f}" if c.early_end_s else "-",
                    str(c.unused),
                    str(c.n_sets),
                    c.timestamps or "nominal",
                )
            )
        widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
        for r in rows:
            cells = [r[0].ljust(widths[0])] + [
                v.rjust(w) for v, w in zip(r[1:-1], widths[1:-1], strict=True)
            ]
            lines.append("  " + "  ".join([*cells, r[-1]]))
        n_cam = len(self.cameras)
        lines.append(
            f"  frame sets: {self.n_framesets} ({self.n_complete} with all {n_cam} "
            f"cameras, {self.n_incomplete} missing at least one; {self.n_empty} empty "
            f"grid times skipped)"
        )
        lines.append(
            f"  duration: {self.duration_s:.3f} s (sets {self.first_set_s:.3f} .. "
            f"{self.last_set_s:.3f} s)"
        )
        return "\n".join(lines)


def describe_recording(rec: Recording) -> RecordingInfo:
    """Camera and synchronisation statistics of ``rec``, from timestamps alone (no decoding).

    See :class:`CameraInfo` for the definitions.
    """
    p = rec.period_ns
    a = rec.assignment
    all_first = min(int(ts[0]) for ts in rec.timestamps_ns.values() if len(ts))
    all_last = max(int(ts[-1]) for ts in rec.timestamps_ns.values() if len(ts))
    cams = []
    for ci, name in enumerate(rec.camera_names):
        ts = rec.timestamps_ns[name]
        n = len(ts)
        d = np.diff(ts)
        big = d[d > 1.5 * p]
        dropped = int(np.sum(np.round(big / p).astype(np.int64) - 1)) if len(big) else 0
        dev = ts - ((2 * ts + p) // (2 * p)) * p  # deviation from the nearest k * p
        n_sets = int(np.count_nonzero(a.frame_idx[:, ci] >= 0))
        first = int(ts[0]) if n else 0
        last = int(ts[-1]) if n else 0
        late = first - all_first
        early = all_last - last
        w, h = rec.sizes[name]
        entry = rec.spec.cameras[ci]
        cams.append(
            CameraInfo(
                name=name,
                width=w,
                height=h,
                video=entry.video,
                timestamps=entry.timestamps,
                n_frames=n,
                first_s=first / 1e9,
                last_s=last / 1e9,
                duration_s=(last - first) / 1e9,
                fps_nominal=rec.fps,
                fps_measured=float(1e9 / np.median(d)) if len(d) else None,
                dropped=dropped,
                jitter_std_ms=float(np.std(dev) / 1e6) if n else 0.0,
                jitter_max_ms=float(np.max(np.abs(dev)) / 1e6) if n else 0.0,
                late_start_s=late / 1e9 if late > p / 2 else 0.0,
                early_end_s=early / 1e9 if early > p / 2 else 0.0,
                n_sets=n_sets,
                unused=n - n_sets,
            )
        )
    present = a.frame_idx >= 0
    n_complete = int(np.count_nonzero(present.all(axis=1)))
    first_k = int(a.set_idx[0]) if len(a.set_idx) else 0
    last_k = int(a.set_idx[-1]) if len(a.set_idx) else 0
    return RecordingInfo(
        directory=str(rec.directory),
        rig=str(_resolve(rec.directory, rec.spec.rig)),
        fps=rec.fps,
        period_ns=p,
        start_time_ns=rec.start_time_ns,
        cameras=tuple(cams),
        n_framesets=rec.n_framesets,
        n_complete=n_complete,
        n_incomplete=rec.n_framesets - n_complete,
        n_empty=a.n_empty,
        first_set_s=first_k * p / 1e9,
        last_set_s=last_k * p / 1e9,
        duration_s=(last_k - first_k) * p / 1e9,
    )
