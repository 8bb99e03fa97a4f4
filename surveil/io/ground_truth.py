"""Ground-truth annotations of a recording: ``<recording>/ground_truth/``.

Written by ``surveil synth`` (or by a person); read by ``surveil eval``. Layout (documented
for users in docs/formats.md, "Ground truth"):

``scene.json``
    ``{"format": "surveil-ground-truth", "version": 1, "fps": 15.0, "n_frames": 300,
    "cameras": [...], "persons": [{"id": "p1", ...}], "objects": [{"name", "hue_deg", ...}]}``
``limbs.csv``
    ``frame,t_ns,label,x_m,y_m,z_m,visible_in`` -- one row per frame and true limb
    (``p1/head``, ``p1/left_hand``, ``p1/right_hand``...); ``visible_in`` lists the cameras
    (separated by ``;``) whose frame exists and shows the limb unoccluded.
``joints.csv`` (optional)
    ``frame,t_ns,label,x_m,y_m,z_m`` -- one row per frame and arm joint of each person
    present (``p1/left_shoulder``, ``p1/left_elbow``, ``p1/left_wrist``, ``p1/right_shoulder``,
    ``p1/right_elbow``, ``p1/right_wrist``...).
``facing.csv`` (optional)
    ``frame,t_ns,person,yaw_deg`` -- one row per frame and person present: the body's facing,
    degrees in [-180, 180), 0 = +X, counter-clockwise (``surveil.synth.actors.body_axes``).
``objects.csv``
    ``frame,t_ns,object,x_m,y_m,z_m,held_by`` -- ``held_by`` is a hand label or empty.
``events.json``
    a list of events: ``activity, start_ns, climax_ns, end_ns, actors, persons,
    object, object_hue_deg, from, to``.
``rig_true.yaml``
    the rig the images were really rendered with (the recording's rig may carry a
    deliberate calibration error).
``masks/<camera>/<frame:06d>.png``
    optional per-pixel labels (BGR PNG): B = class (see ``MaskClass``), G = person number
    (0 none), R = part code (see ``surveil.synth.actors.Part``).
"""

from __future__ import annotations

import csv
import enum
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from surveil.datatypes import ActivityEvent
from surveil.errors import InputError

GT_DIR = "ground_truth"
JOINTS_CSV = "joints.csv"
JOINTS_COLUMNS = ["frame", "t_ns", "label", "x_m", "y_m", "z_m"]
FACING_CSV = "facing.csv"
FACING_COLUMNS = ["frame", "t_ns", "person", "yaw_deg"]
FORMAT_NAME = "surveil-ground-truth"
FORMAT_VERSION = 1


class MaskClass(enum.IntEnum):
    """Blue channel of ground-truth masks."""

    BACKGROUND = 0
    SKIN_DISTRACTOR = 1  # static skin-coloured scenery (e.g. a wooden table)
    SKIN = 2  # a person's skin: face, neck, hands (and forearms with short sleeves)
    HAIR = 3
    CLOTHING = 4  # torso, sleeves, legs, shoes
    OBJECT = 5  # a small coloured object


@dataclass(frozen=True, slots=True)
class GroundTruth:
    """Per-frame truth of a recording.

    frames : (F,) int64 frame-set indices;  t_ns : (F,) int64 times, ns
    labels : (L,) limb labels (``p1/head``...);  cameras : (C,) camera names
    positions_m : (F, L, 3) float64 world frame (NaN where the limb does not exist)
    visible : (F, L, C) bool -- the camera's frame exists and the limb is unoccluded in it
    object_names : (O,);  object_hue_deg : (O,) float64
    object_positions_m : (F, O, 3) float64;  held_by : (F, O) str ('' when not held)
    events : true activities
    meta : the content of scene.json
    joint_labels : (J,) arm-joint labels (``p1/left_shoulder``...); empty without joints.csv
    joint_positions_m : (F, J, 3) float64 world frame (NaN where the person is absent)
    persons : (P,) person ids of facing.csv; empty without it
    facing_yaw_rad : (F, P) float64 body facing, radians in [-pi, pi), 0 = +X,
        counter-clockwise (NaN where the person is absent)
    """

    frames: np.ndarray
    t_ns: np.ndarray
    labels: tuple[str, ...]
    cameras: tuple[str, ...]
    positions_m: np.ndarray
    visible: np.ndarray
    object_names: tuple[str, ...]
    object_hue_deg: np.ndarray
    object_positions_m: np.ndarray
    held_by: np.ndarray
    events: tuple[ActivityEvent, ...]
    meta: dict
    joint_labels: tuple[str, ...] = ()
    joint_positions_m: np.ndarray = field(default_factory=lambda: np.full((0, 0, 3), np.nan))
    persons: tuple[str, ...] = ()
    facing_yaw_rad: np.ndarray = field(default_factory=lambda: np.full((0, 0), np.nan))

    @property
    def n_views(self) -> np.ndarray:
        """(F, L) int: number of cameras that see each limb."""
        return self.visible.sum(axis=2)

    @property
    def fps(self) -> float:
        return float(self.meta["fps"])

    def frame_at(self, t_ns: int) -> int:
        """Index of the truth frame nearest to time ``t_ns`` (ns, the recording clock)."""
        return int(np.argmin(np.abs(self.t_ns - t_ns)))


def event_to_dict(ev: ActivityEvent) -> dict:
    return {
        "activity": ev.activity,
        "start_ns": ev.start_ns,
        "climax_ns": ev.climax_ns,
        "end_ns": ev.end_ns,
        "actors": list(ev.actors),
        "persons": list(ev.persons),
        "object": ev.object_name,
        "object_hue_deg": ev.object_hue_deg,
        "from": ev.from_actor,
        "to": ev.to_actor,
    }


def event_from_dict(d: dict, where: str) -> ActivityEvent:
    try:
        return ActivityEvent(
            activity=str(d["activity"]),
            start_ns=int(d["start_ns"]),
            climax_ns=int(d["climax_ns"]),
            end_ns=int(d["end_ns"]),
            actors=tuple(d.get("actors", ())),
            persons=tuple(d.get("persons", ())),
            rule="ground_truth",
            object_hue_deg=d.get("object_hue_deg"),
            from_actor=d.get("from"),
            to_actor=d.get("to"),
            object_name=d.get("object"),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{where}: bad event {d!r}: {exc}") from None


def write_ground_truth(directory: Path, gt: GroundTruth) -> None:
    """Write ``gt`` into ``directory`` (the recording's ``ground_truth/``), masks aside."""
    directory.mkdir(parents=True, exist_ok=True)
    meta = dict(
        gt.meta,
        format=FORMAT_NAME,
        version=FORMAT_VERSION,
        cameras=list(gt.cameras),
        n_frames=len(gt.frames),
    )
    (directory / "scene.json").write_text(json.dumps(meta, indent=2))
    with open(directory / "limbs.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "t_ns", "label", "x_m", "y_m", "z_m", "visible_in"])
        cams = np.array(gt.cameras)
        for i, (frame, t) in enumerate(zip(gt.frames, gt.t_ns, strict=False)):
            for j, label in enumerate(gt.labels):
                x, y, z = gt.positions_m[i, j]
                if not np.isfinite(x):
                    continue
                w.writerow(
                    [
                        int(frame),
                        int(t),
                        label,
                        f"{x:.5f}",
                        f"{y:.5f}",
                        f"{z:.5f}",
                        ";".join(cams[gt.visible[i, j]]),
                    ]
                )
    with open(directory / "objects.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "t_ns", "object", "x_m", "y_m", "z_m", "held_by"])
        for i, (frame, t) in enumerate(zip(gt.frames, gt.t_ns, strict=False)):
            for k, name in enumerate(gt.object_names):
                x, y, z = gt.object_positions_m[i, k]
                w.writerow(
                    [
                        int(frame),
                        int(t),
                        name,
                        f"{x:.5f}",
                        f"{y:.5f}",
                        f"{z:.5f}",
                        gt.held_by[i, k],
                    ]
                )
    _write_joints(directory / JOINTS_CSV, gt)
    _write_facing(directory / FACING_CSV, gt)
    (directory / "events.json").write_text(
        json.dumps([event_to_dict(e) for e in gt.events], indent=2)
    )


def _write_joints(path: Path, gt: GroundTruth) -> None:
    if not gt.joint_labels:
        path.unlink(missing_ok=True)  # no stale joints from an earlier write
        return
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(JOINTS_COLUMNS)
        for i, (frame, t) in enumerate(zip(gt.frames, gt.t_ns, strict=True)):
            for j, label in enumerate(gt.joint_labels):
                x, y, z = gt.joint_positions_m[i, j]
                if not np.isfinite(x):
                    continue
                w.writerow([int(frame), int(t), label, f"{x:.5f}", f"{y:.5f}", f"{z:.5f}"])


def _write_facing(path: Path, gt: GroundTruth) -> None:
    if not gt.persons:
        path.unlink(missing_ok=True)
        return
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(FACING_COLUMNS)
        for i, (frame, t) in enumerate(zip(gt.frames, gt.t_ns, strict=True)):
            for p, person in enumerate(gt.persons):
                yaw = gt.facing_yaw_rad[i, p]
                if not np.isfinite(yaw):
                    continue
                w.writerow([int(frame), int(t), person, f"{wrap_deg(np.degrees(yaw)):.4f}"])


def wrap_deg(angle_deg: float) -> float:
    """``angle_deg`` in [-180, 180).

    >>> wrap_deg(540.0), wrap_deg(-190.0), wrap_deg(180.0)
    (-180.0, 170.0, -180.0)
    """
    return float((angle_deg + 180.0) % 360.0 - 180.0)


def _read_csv(path: Path, columns: list[str], *, optional: bool = False) -> list[dict[str, str]]:
    """The rows of ``path``; an ``optional`` file that is missing has none."""
    if optional and not path.is_file():
        return []
    if not path.is_file():
        raise InputError(
            f"{path}: ground-truth file is missing; regenerate the recording "
            f"with `surveil synth` or add the file (see docs/formats.md)"
        )
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in columns if c not in (reader.fieldnames or [])]
        if missing:
            raise InputError(
                f"{path}: missing column(s) {', '.join(missing)}; "
                f"expected header {','.join(columns)}"
            )
        return list(reader)


def load_ground_truth(recording_dir: Path) -> GroundTruth:
    """Read ``recording_dir/ground_truth``. Raises InputError naming the file and problem."""
    directory = Path(recording_dir) / GT_DIR
    scene_path = directory / "scene.json"
    if not scene_path.is_file():
        raise InputError(
            f"{recording_dir}: no ground truth ({scene_path} is missing); "
            f"only recordings made by `surveil synth` or annotated ones can be "
            f"scored"
        )
    try:
        meta = json.loads(scene_path.read_text())
    except json.JSONDecodeError as exc:
        raise InputError(f"{scene_path}: not valid JSON: {exc}") from None
    if meta.get("format") != FORMAT_NAME or meta.get("version") != FORMAT_VERSION:
        raise InputError(
            f"{scene_path}: expected format {FORMAT_NAME!r} version "
            f"{FORMAT_VERSION}, got {meta.get('format')!r} "
            f"version {meta.get('version')!r}"
        )
    cameras = tuple(meta["cameras"])
    cam_idx = {c: i for i, c in enumerate(cameras)}
    limb_path = directory / "limbs.csv"
    rows = _read_csv(limb_path, ["frame", "t_ns", "label", "x_m", "y_m", "z_m", "visible_in"])
    frame_t: dict[int, int] = {}
    labels: list[str] = []
    for r in rows:
        frame_t.setdefault(int(r["frame"]), int(r["t_ns"]))
        if r["label"] not in labels:
            labels.append(r["label"])
    obj_rows = _read_csv(
        directory / "objects.csv", ["frame", "t_ns", "object", "x_m", "y_m", "z_m", "held_by"]
    )
    for r in obj_rows:
        frame_t.setdefault(int(r["frame"]), int(r["t_ns"]))
    # frames with no row at all (an empty room: nothing to list) still exist
    if isinstance(meta.get("n_frames"), int) and float(meta.get("fps", 0)) > 0:
        for k in range(meta["n_frames"]):
            frame_t.setdefault(k, round(k * 1e9 / float(meta["fps"])))
    frames = np.array(sorted(frame_t), dtype=np.int64)
    t_ns = np.array([frame_t[f] for f in frames], dtype=np.int64)
    f_idx = {int(f): i for i, f in enumerate(frames)}
    l_idx = {lab: j for j, lab in enumerate(labels)}
    pos = np.full((len(frames), len(labels), 3), np.nan)
    vis = np.zeros((len(frames), len(labels), len(cameras)), dtype=bool)
    for n, r in enumerate(rows, start=2):
        i, j = f_idx[int(r["frame"])], l_idx[r["label"]]
        try:
            pos[i, j] = float(r["x_m"]), float(r["y_m"]), float(r["z_m"])
        except ValueError:
            raise InputError(
                f"{limb_path}:{n}: coordinates must be numbers, got "
                f"{r['x_m']!r}, {r['y_m']!r}, {r['z_m']!r}"
            ) from None
        for cam in filter(None, r["visible_in"].split(";")):
            if cam not in cam_idx:
                raise InputError(
                    f"{limb_path}:{n}: camera {cam!r} is not in scene.json "
                    f"cameras ({', '.join(cameras)})"
                )
            vis[i, j, cam_idx[cam]] = True
    obj_names = tuple(o["name"] for o in meta.get("objects", []))
    o_idx = {name: k for k, name in enumerate(obj_names)}
    obj_pos = np.full((len(frames), len(obj_names), 3), np.nan)
    held = np.full((len(frames), len(obj_names)), "", dtype=object)
    for r in obj_rows:
        if r["object"] not in o_idx:
            raise InputError(
                f"{directory / 'objects.csv'}: object {r['object']!r} is not listed in scene.json"
            )
        i, k = f_idx[int(r["frame"])], o_idx[r["object"]]
        obj_pos[i, k] = float(r["x_m"]), float(r["y_m"]), float(r["z_m"])
        held[i, k] = r["held_by"]
    joint_labels, joint_pos = _read_joints(directory / JOINTS_CSV, f_idx)
    persons, facing = _read_facing(directory / FACING_CSV, f_idx)
    events_path = directory / "events.json"
    events: tuple[ActivityEvent, ...] = ()
    if events_path.is_file():
        try:
            raw = json.loads(events_path.read_text())
        except json.JSONDecodeError as exc:
            raise InputError(f"{events_path}: not valid JSON: {exc}") from None
        events = tuple(event_from_dict(d, str(events_path)) for d in raw)
    return GroundTruth(
        frames=frames,
        t_ns=t_ns,
        labels=tuple(labels),
        cameras=cameras,
        positions_m=pos,
        visible=vis,
        object_names=obj_names,
        object_hue_deg=np.array(
            [o.get("hue_deg", np.nan) for o in meta.get("objects", [])], dtype=np.float64
        ),
        object_positions_m=obj_pos,
        held_by=held,
        events=events,
        meta=meta,
        joint_labels=joint_labels,
        joint_positions_m=joint_pos,
        persons=persons,
        facing_yaw_rad=facing,
    )


def _frame_index(path: Path, line: int, row: dict[str, str], f_idx: dict[int, int]) -> int:
    """The row's index in the recording's frames; InputError for an unknown frame."""
    try:
        frame = int(row["frame"])
    except (TypeError, ValueError):
        raise InputError(
            f"{path}:{line}: frame must be an integer, got {row['frame']!r}"
        ) from None
    if frame not in f_idx:
        raise InputError(
            f"{path}:{line}: frame {frame} is not a frame of the recording (frames come from "
            f"limbs.csv, objects.csv and scene.json n_frames)"
        )
    return f_idx[frame]


def _read_joints(path: Path, f_idx: dict[int, int]) -> tuple[tuple[str, ...], np.ndarray]:
    """joints.csv, if present: labels (J,) and positions (F, J, 3) NaN where absent."""
    rows = _read_csv(path, JOINTS_COLUMNS, optional=True)
    labels = tuple(dict.fromkeys(r["label"] for r in rows))
    j_idx = {lab: j for j, lab in enumerate(labels)}
    pos = np.full((len(f_idx) if rows else 0, len(labels), 3), np.nan)
    for n, r in enumerate(rows, start=2):
        i = _frame_index(path, n, r, f_idx)
        try:
            pos[i, j_idx[r["label"]]] = float(r["x_m"]), float(r["y_m"]), float(r["z_m"])
        except (TypeError, ValueError):
            raise InputError(
                f"{path}:{n}: coordinates must be numbers, got "
                f"{r['x_m']!r}, {r['y_m']!r}, {r['z_m']!r}"
            ) from None
    return labels, pos


def _read_facing(path: Path, f_idx: dict[int, int]) -> tuple[tuple[str, ...], np.ndarray]:
    """facing.csv, if present: persons (P,) and yaw (F, P) radians, NaN where absent."""
    rows = _read_csv(path, FACING_COLUMNS, optional=True)
    persons = tuple(dict.fromkeys(r["person"] for r in rows))
    p_idx = {pid: p for p, pid in enumerate(persons)}
    yaw = np.full((len(f_idx) if rows else 0, len(persons)), np.nan)
    for n, r in enumerate(rows, start=2):
        i = _frame_index(path, n, r, f_idx)
        try:
            yaw[i, p_idx[r["person"]]] = np.radians(float(r["yaw_deg"]))
        except (TypeError, ValueError):
            raise InputError(
                f"{path}:{n}: yaw_deg must be a number, got {r['yaw_deg']!r}"
            ) from None
    return persons, yaw
