"""The output MCAP file of a run: Foxglove protobuf schemas, topics of ``docs/formats.md``.

Every topic's channel is registered when the file is opened, so a run that recognised nothing
still has an (empty) ``/events`` channel. Times: every ``log_time``, ``publish_time`` and
message timestamp is ``start_time_ns + t_ns`` (the recording clock of formats.md); the
``surveil`` metadata record stores ``start_time_ns`` so that readers can go back to ``t_ns``
(ns from t = 0, the pipeline's clock).

The file is chunked (1 MiB, zstd) and flushed to disk after each chunk, so a run that dies
mid-way leaves a file readable up to its last complete chunk (``surveil.io.mcap_reader``
reads such files sequentially); ``close()`` writes the summary and index.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import numpy as np
from foxglove_schemas_protobuf.CameraCalibration_pb2 import CameraCalibration
from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.Event_pb2 import Event
from foxglove_schemas_protobuf.FrameTransform_pb2 import FrameTransform
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms
from foxglove_schemas_protobuf.KeyValuePair_pb2 import KeyValuePair
from foxglove_schemas_protobuf.Log_pb2 import Log
from foxglove_schemas_protobuf.PackedElementField_pb2 import PackedElementField
from foxglove_schemas_protobuf.PointCloud_pb2 import PointCloud
from foxglove_schemas_protobuf.Pose_pb2 import Pose
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneEntityDeletion_pb2 import SceneEntityDeletion
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.SpherePrimitive_pb2 import SpherePrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from google.protobuf.timestamp_pb2 import Timestamp
from mcap.well_known import MessageEncoding
from mcap.writer import CompressionType, Writer
from mcap_protobuf.schema import register_schema
from scipy.spatial.transform import Rotation

from surveil import __version__
from surveil.camera import Camera, Rig
from surveil.datatypes import ActivityEvent, CandidateSet, FrameResult, Phase, TargetSnapshot

log = logging.getLogger(__name__)

WORLD_FRAME = "world"
SURVEIL_METADATA = "surveil"  # metadata record holding start_time_ns and the writer version
MCAP_FORMAT_VERSION = "1"
TARGET_SPHERE_M = 0.08

TOPIC_EVENTS = "/events"
TOPIC_EVENTS_LOG = "/events/log"
TOPIC_TARGETS = "/targets"
TOPIC_TARGET_POINTS = "/targets/points"
TOPIC_CANDIDATES = "/candidates"
TOPIC_TF = "/tf"


def calibration_topic(camera_name: str) -> str:
    """``/cameras/<name>/calibration``."""
    return f"/cameras/{camera_name}/calibration"


_F32, _U8 = PackedElementField.FLOAT32, PackedElementField.UINT8

# Packed point layouts of formats.md (little-endian, no padding).
TARGET_POINT_DTYPE = np.dtype(
    [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("person", "u1"), ("limb", "u1"), ("state", "u1")]
)
CANDIDATE_POINT_DTYPE = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("prior", "<f4")])
_NUMERIC_TYPE = {np.dtype("<f4"): _F32, np.dtype("u1"): _U8}

# Person colours (RGB 0..1), cycled; limbs are shades of their person's colour.
_PERSON_RGB = np.array(
    [
        [0.12, 0.47, 0.71],
        [1.0, 0.5, 0.05],
        [0.17, 0.63, 0.17],
        [0.84, 0.15, 0.16],
        [0.58, 0.40, 0.74],
        [0.55, 0.34, 0.29],
    ]
)
_LIMB_SHADE = {0: 1.0, 1: 0.75, 2: 0.5}
_HUE_NAMES = (
    (15, "red"),
    (45, "orange"),
    (70, "yellow"),
    (165, "green"),
    (195, "cyan"),
    (255, "blue"),
    (285, "purple"),
    (330, "magenta"),
    (360, "red"),
)


def hue_name(hue_deg: float) -> str:
    """A colour word for a hue in degrees (any real; taken modulo 360).

    >>> [hue_name(h) for h in (0, 30, 60, 120, 180, 220, 270, 300, 350, -10)]
    ['red', 'orange', 'yellow', 'green', 'cyan', 'blue', 'purple', 'magenta', 'red', 'red']
    """
    h = float(hue_deg) % 360.0
    for upper, name in _HUE_NAMES:
        if h < upper:
            return name
    return "red"  # unreachable: h < 360


def event_log_line(ev: ActivityEvent) -> str:
    """The human-readable ``/events/log`` line; the time is the climax, seconds from t = 0.

    >>> ev = ActivityEvent("exchange", 12_000_000_000, 12_400_000_000, 13_000_000_000,
    ...                    ("p1/right_hand", "p2/left_hand"), ("p1", "p2"), "default.toml:x",
    ...                    0.912, 120.0, "p1/right_hand", "p2/left_hand")
    >>> event_log_line(ev)
    '12.40 s exchange p1/right_hand -> p2/left_hand (green, 0.91)'
    """
    if ev.from_actor is not None and ev.to_actor is not None:
        who = f"{ev.from_actor} -> {ev.to_actor}"
    else:
        who = ", ".join(ev.actors) or "-"
    detail = f"{ev.confidence:.2f}"
    if ev.object_hue_deg is not None:
        detail = f"{hue_name(ev.object_hue_deg)}, {detail}"
    return f"{ev.climax_ns / 1e9:.2f} s {ev.activity} {who} ({detail})"


def event_metadata(ev: ActivityEvent, start_time_ns: int = 0) -> dict[str, str]:
    """The ``/events`` metadata of formats.md (all values strings). ``climax_ns`` is on the
    recording clock: ``start_time_ns + ev.climax_ns``.

    >>> ev = ActivityEvent("clap", 0, 5, 9, ("p1/left_hand", "p1/right_hand"), ("p1",),
    ...                    "default.toml:clap", 0.5)
    >>> event_metadata(ev, 100)  # doctest: +NORMALIZE_WHITESPACE
    {'activity': 'clap', 'climax_ns': '105', 'actors': 'p1/left_hand,p1/right_hand',
     'persons': 'p1', 'confidence': '0.500', 'rule': 'default.toml:clap'}
    """
    meta = {
        "activity": ev.activity,
        "climax_ns": str(start_time_ns + ev.climax_ns),
        "actors": ",".join(ev.actors),
        "persons": ",".join(ev.persons),
    }
    if ev.object_hue_deg is not None:
        meta["object_hue_deg"] = f"{ev.object_hue_deg:.1f}"
    if ev.from_actor is not None:
        meta["from"] = ev.from_actor
    if ev.to_actor is not None:
        meta["to"] = ev.to_actor
    meta["confidence"] = f"{ev.confidence:.3f}"
    meta["rule"] = ev.rule
    return meta


def _timestamp(ns: int) -> Timestamp:
    ts = Timestamp()
    ts.FromNanoseconds(int(ns))
    return ts


def _point_fields(dtype: np.dtype) -> list[PackedElementField]:
    return [
        PackedElementField(
            name=name, offset=dtype.fields[name][1], type=_NUMERIC_TYPE[dtype.fields[name][0]]
        )
        for name in dtype.names
    ]


def _identity_pose() -> Pose:
    return Pose(
        position=Vector3(x=0.0, y=0.0, z=0.0), orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
    )


def target_rgba(person: int, limb: int, phase: Phase) -> tuple[float, float, float, float]:
    """Display colour of a target: a colour per person, shaded per limb; grey when unlabelled,
    translucent when lost or combined."""
    if person <= 0 or limb not in _LIMB_SHADE:
        rgb = np.array([0.6, 0.6, 0.6])
    else:
        rgb = _PERSON_RGB[(person - 1) % len(_PERSON_RGB)] * _LIMB_SHADE[limb]
    alpha = 0.35 if phase in (Phase.LOST, Phase.COMBINED) else 1.0
    return float(rgb[0]), float(rgb[1]), float(rgb[2]), alpha


def calibration_message(cam: Camera, t_ns: int) -> CameraCalibration:
    """``foxglove.CameraCalibration`` of one camera (frame_id = camera name).

    Foxglove knows ``plumb_bob`` (k1 k2 p1 p2 k3) and ``rational_polynomial`` (k1..k6 with
    p1 p2 in OpenCV order); 4 coefficients are padded to 5, and the thin-prism/tilt terms of
    12/14-coefficient models are dropped (with a warning if they are not zero).
    """
    dist = np.asarray(cam.dist, dtype=np.float64)
    if len(dist) <= 5:
        model, coeffs = "plumb_bob", np.pad(dist, (0, 5 - len(dist)))
    else:
        model, coeffs = "rational_polynomial", dist[:8]
        if np.any(dist[8:] != 0):
            log.warning(
                "camera %s: thin-prism/tilt distortion terms cannot be written to "
                "foxglove.CameraCalibration and are dropped",
                cam.name,
            )
    # P = K [I | 0] (rectified = raw camera, no stereo offset)
    P = np.hstack([cam.K, np.zeros((3, 1))])
    return CameraCalibration(
        timestamp=_timestamp(t_ns),
        frame_id=cam.name,
        width=cam.width,
        height=cam.height,
        distortion_model=model,
        D=coeffs.tolist(),
        K=cam.K.reshape(-1).tolist(),
        R=np.eye(3).reshape(-1).tolist(),
        P=P.reshape(-1).tolist(),
    )


def transforms_message(rig: Rig, t_ns: int) -> FrameTransforms:
    """``foxglove.FrameTransforms``: ``world`` -> each camera, the pose ``world_from_cam``
    (translation = camera centre, rotation = R.T)."""
    transforms = []
    for cam in rig:
        x, y, z, w = Rotation.from_matrix(cam.R.T).as_quat()  # scalar-last (x, y, z, w)
        c = cam.centre_m
        transforms.append(
            FrameTransform(
                timestamp=_timestamp(t_ns),
                parent_frame_id=WORLD_FRAME,
                child_frame_id=cam.name,
                translation=Vector3(x=float(c[0]), y=float(c[1]), z=float(c[2])),
                rotation=Quaternion(x=float(x), y=float(y), z=float(z), w=float(w)),
            )
        )
    return FrameTransforms(transforms=transforms)


class _FlushingFile:
    """A binary file that flushes after each write: mcap's Writer writes once per finished
    chunk, so a crash loses at most the chunk being built."""

    def __init__(self, path: Path) -> None:
        self._f: IO[bytes] = open(path, "wb")  # closed in close()

    def write(self, data: bytes) -> int:
        n = self._f.write(data)
        self._f.flush()
        return n

    def tell(self) -> int:
        return self._f.tell()

    def close(self) -> None:
        self._f.close()


class McapWriter:
    """Writes a run's output MCAP (topics and schemas of formats.md).

    Parameters
    ----------
    path : Path
        The file to create (overwritten).
    rig : Rig
        Cameras written once to ``/cameras/<name>/calibration`` and ``/tf``.
    metadata : dict[str, dict[str, str]], optional
        MCAP metadata records, e.g. ``{"config": {...}, "rules": {...}}``. The name
        ``surveil`` is reserved (it stores ``start_time_ns`` and the writer version).
    start_time_ns : int
        Wall-clock time of t = 0, added to every time written (formats.md).
    chunk_size : int
        Bytes per chunk before it is compressed and written (the crash-loss granularity).

    Examples
    --------
    >>> import tempfile
    >>> from surveil.camera import look_at
    >>> cam = look_at("cam0", np.array([0.0, -3, 1.5]), np.zeros(3), width=64, height=48,
    ...               hfov_deg=60)
    >>> out = Path(tempfile.mkdtemp()) / "run.mcap"
    >>> with McapWriter(out, Rig((cam,))) as w:
    ...     w.write_frame(0, [], CandidateSet.empty())
    >>> out.stat().st_size > 0
    True
    """

    def __init__(
        self,
        path: Path,
        rig: Rig,
        *,
        metadata: Mapping[str, Mapping[str, str]] | None = None,
        start_time_ns: int = 0,
        chunk_size: int = 1 << 20,
    ) -> None:
        if int(start_time_ns) < 0:
            raise ValueError(f"start_time_ns must be >= 0, got {start_time_ns}")
        metadata = dict(metadata or {})
        if SURVEIL_METADATA in metadata:
            raise ValueError(f"metadata name {SURVEIL_METADATA!r} is reserved; use another")
        self.path = Path(path)
        self.start_time_ns = int(start_time_ns)
        self._file = _FlushingFile(self.path)
        self._writer = Writer(
            self._file,
            chunk_size=chunk_size,  # type: ignore[arg-type]
            compression=CompressionType.ZSTD,
        )
        self._writer.start(profile="", library=f"surveil {__version__}")
        self._closed = False
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        schema_ids: dict[type, int] = {}
        topics: list[tuple[str, type]] = [
            (TOPIC_EVENTS, Event),
            (TOPIC_EVENTS_LOG, Log),
            (TOPIC_TARGETS, SceneUpdate),
            (TOPIC_TARGET_POINTS, PointCloud),
            (TOPIC_CANDIDATES, PointCloud),
            *((calibration_topic(cam.name), CameraCalibration) for cam in rig),
            (TOPIC_TF, FrameTransforms),
        ]
        for topic, cls in topics:
            if cls not in schema_ids:
                schema_ids[cls] = register_schema(self._writer, cls)
            self._channels[topic] = self._writer.register_channel(
                topic=topic, message_encoding=MessageEncoding.Protobuf, schema_id=schema_ids[cls]
            )
            self._sequence[topic] = 0
        self._writer.add_metadata(
            SURVEIL_METADATA,
            {
                "start_time_ns": str(self.start_time_ns),
                "writer": f"surveil {__version__}",
                "mcap_format_version": MCAP_FORMAT_VERSION,
            },
        )
        for name, record in metadata.items():
            self._writer.add_metadata(name, {str(k): str(v) for k, v in record.items()})
        for cam in rig:
            self._write(calibration_topic(cam.name), calibration_message(cam, self._clock(0)), 0)
        self._write(TOPIC_TF, transforms_message(rig, self._clock(0)), 0)
        self._target_fields = _point_fields(TARGET_POINT_DTYPE)
        self._candidate_fields = _point_fields(CANDIDATE_POINT_DTYPE)
        log.debug("opened %s for writing (%d cameras)", self.path, len(rig))

    # -----------------------------------------------------------------------------------------

    def _clock(self, t_ns: int) -> int:
        return self.start_time_ns + int(t_ns)

    def _write(self, topic: str, message: Any, t_ns: int) -> None:
        if self._closed:
            raise ValueError(f"{self.path}: the MCAP writer is closed")
        if int(t_ns) < -self.start_time_ns:
            raise ValueError(f"t_ns must be >= -start_time_ns ({-self.start_time_ns}), got {t_ns}")
        clock = self._clock(t_ns)
        self._writer.add_message(
            channel_id=self._channels[topic],
            log_time=clock,
            data=message.SerializeToString(),
            publish_time=clock,
            sequence=self._sequence[topic],
        )
        self._sequence[topic] += 1

    def write_frame(
        self, t_ns: int, targets: Sequence[TargetSnapshot], candidates: CandidateSet
    ) -> None:
        """Write ``/targets``, ``/targets/points`` and ``/candidates`` for one frame set.

        Parameters
        ----------
        t_ns : int
            Time of the frame set, ns from t = 0 (``start_time_ns`` is added).
        targets : sequence of TargetSnapshot
            Every tracker; uninitialised ones are skipped.
        candidates : CandidateSet
            The frame's 3D candidates (metres, world frame).
        """
        stamp = _timestamp(self._clock(t_ns))
        live = [tg for tg in targets if tg.phase is not Phase.UNINITIALISED]
        entities = []
        for tg in live:
            r, g, b, a = target_rgba(tg.person, int(tg.limb), tg.phase)
            x, y, z = (float(v) for v in tg.mean_m)
            sphere = SpherePrimitive(
                pose=Pose(
                    position=Vector3(x=x, y=y, z=z),
                    orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
                ),
                size=Vector3(x=TARGET_SPHERE_M, y=TARGET_SPHERE_M, z=TARGET_SPHERE_M),
                color=Color(r=r, g=g, b=b, a=a),
            )
            entities.append(
                SceneEntity(
                    timestamp=stamp,
                    frame_id=WORLD_FRAME,
                    id=tg.label,
                    spheres=[sphere],
                    metadata=[
                        KeyValuePair(key="state", value=tg.phase.value),
                        KeyValuePair(key="tracker", value=str(tg.target_id)),
                    ],
                )
            )
        # Delete-all first: targets that ended must disappear from the 3D view.
        deletion = SceneEntityDeletion(timestamp=stamp, type=SceneEntityDeletion.ALL)
        self._write(TOPIC_TARGETS, SceneUpdate(deletions=[deletion], entities=entities), t_ns)

        points = np.zeros(len(live), dtype=TARGET_POINT_DTYPE)
        if live:
            means = np.array([tg.mean_m for tg in live])
            points["x"], points["y"], points["z"] = means.T
            points["person"] = np.clip([tg.person for tg in live], 0, 255)
            points["limb"] = [int(tg.limb) for tg in live]
            points["state"] = [tg.phase.code for tg in live]
        self._write_cloud(TOPIC_TARGET_POINTS, stamp, self._target_fields, points, t_ns)

        cand = np.zeros(len(candidates.points_m), dtype=CANDIDATE_POINT_DTYPE)
        cand["x"], cand["y"], cand["z"] = candidates.points_m.T
        cand["prior"] = candidates.prior
        self._write_cloud(TOPIC_CANDIDATES, stamp, self._candidate_fields, cand, t_ns)

    def _write_cloud(self, topic: str, stamp, fields, points: np.ndarray, t_ns: int) -> None:
        """One PointCloud in the world frame from a packed structured array."""
        self._write(
            topic,
            PointCloud(
                timestamp=stamp,
                frame_id=WORLD_FRAME,
                pose=_identity_pose(),
                point_stride=points.dtype.itemsize,
                fields=fields,
                data=points.tobytes(),
            ),
            t_ns,
        )

    def write_event(self, ev: ActivityEvent) -> None:
        """Write ``/events`` (``foxglove.Event``) and its ``/events/log`` line.

        Both messages are logged at the climax time; the Event's ``start_time``/``end_time``
        span the activity (all on the recording clock).
        """
        meta = event_metadata(ev, self.start_time_ns)
        msg = Event(
            start_time=_timestamp(self._clock(ev.start_ns)),
            end_time=_timestamp(self._clock(ev.end_ns)),
            metadata=[KeyValuePair(key=k, value=v) for k, v in meta.items()],
        )
        self._write(TOPIC_EVENTS, msg, ev.climax_ns)
        line = Log(
            timestamp=_timestamp(self._clock(ev.climax_ns)),
            level=Log.INFO,
            message=event_log_line(ev),
            name="surveil",
        )
        self._write(TOPIC_EVENTS_LOG, line, ev.climax_ns)

    def close(self) -> None:
        """Write the last chunk, the summary and the index; close the file. Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self._writer.finish()
        finally:
            self._file.close()
        log.debug("closed %s", self.path)

    def __enter__(self) -> McapWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class McapSink:
    """A pipeline sink writing each FrameResult to an :class:`McapWriter`: targets,
    candidates, and the events decided in that step (as soon as they are decided)."""

    def __init__(self, writer: McapWriter) -> None:
        self.writer = writer

    def write(self, result: FrameResult) -> None:
        self.writer.write_frame(result.frameset.t_ns, result.track.targets, result.candidates)
        for ev in result.events:
            self.writer.write_event(ev)

    def close(self) -> None:
        self.writer.close()
