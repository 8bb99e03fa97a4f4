"""Read back an output MCAP of ``surveil run`` (or ``surveil truth``) for scoring and review.

Times: every time in :class:`RunData` is ns from t = 0, i.e. the file's ``log_time`` (or the
``climax_ns``/start/end of an event) minus the ``start_time_ns`` stored in the file's
``surveil`` metadata record (0 when the record is absent, e.g. a file written by another
tool).

A closed file is read through its summary; a file without one (the writer died) is read
sequentially up to its last complete chunk, and ``RunData.complete`` is False.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from google.protobuf.message import DecodeError
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap_protobuf.decoder import DecoderFactory

from surveil.datatypes import ActivityEvent, Phase, parse_label
from surveil.errors import InputError
from surveil.io.mcap_writer import (
    SURVEIL_METADATA,
    TOPIC_CANDIDATES,
    TOPIC_EVENTS,
    TOPIC_TARGETS,
)

log = logging.getLogger(__name__)

_PHASE_BY_VALUE = {p.value: p for p in Phase}
# PackedElementField.NumericType -> numpy dtype (little-endian)
_NUMPY_TYPE = {1: "u1", 2: "i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<f4", 8: "<f8"}
_READ_ERRORS = (McapError, EOFError, struct.error, ValueError, KeyError, DecodeError)


@dataclass(frozen=True, slots=True)
class RunData:
    """The content of an output MCAP, struct-of-arrays.

    Attributes
    ----------
    path : Path
    start_time_ns : int
        Recording-clock time of t = 0 (subtracted from every time below).
    frame_t_ns : (M,) int64
        Time of each ``/targets`` message, ns from t = 0, ascending.
    target_frame : (N,) int64
        For each target row, its index into ``frame_t_ns`` (rows grouped by frame).
    target_label : (N,) str
        Entity id: ``p<N>/<limb>`` or ``t<K>``.
    target_tracker : (N,) int64
        Tracker id (``tracker`` metadata; -1 if absent).
    target_person : (N,) int64
        Person number N of the label (0 = unlabelled).
    target_limb : (N,) uint8
        ``Limb`` code of the label (255 = unlabelled).
    target_state : (N,) uint8
        ``Phase.code`` of the ``state`` metadata (0 unlabelled, 1 normal, 2 combined, 3 lost).
    target_pos_m : (N, 3) float64
        Sphere centre, world frame, metres.
    candidate_t_ns : (Mc,) int64
        Time of each ``/candidates`` message, ns from t = 0.
    candidate_frame : (K,) int64
        Index into ``candidate_t_ns`` of each candidate point.
    candidate_pos_m : (K, 3) float64;  candidate_prior : (K,) float64
    events : tuple of ActivityEvent
        ``/events`` in climax order; times ns from t = 0.
    metadata : dict[str, dict[str, str]]
        MCAP metadata records by name (``surveil``, ``config``, ``rules``...).
    channels : dict[str, str]
        Every channel's topic -> schema name, including channels without messages.
    complete : bool
        False when the file has no summary (truncated) and was read up to its last chunk.
    """

    path: Path
    start_time_ns: int
    frame_t_ns: np.ndarray
    target_frame: np.ndarray
    target_label: np.ndarray
    target_tracker: np.ndarray
    target_person: np.ndarray
    target_limb: np.ndarray
    target_state: np.ndarray
    target_pos_m: np.ndarray
    candidate_t_ns: np.ndarray
    candidate_frame: np.ndarray
    candidate_pos_m: np.ndarray
    candidate_prior: np.ndarray
    events: tuple[ActivityEvent, ...]
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    channels: dict[str, str] = field(default_factory=dict)
    complete: bool = True

    @property
    def n_frames(self) -> int:
        return len(self.frame_t_ns)

    def frame_rows(self, i: int) -> slice:
        """The target rows of frame ``i`` (rows are grouped by frame)."""
        lo, hi = np.searchsorted(self.target_frame, [i, i + 1])
        return slice(int(lo), int(hi))

    def candidate_rows(self, i: int) -> slice:
        """The candidate rows of ``/candidates`` message ``i`` (rows are grouped by
        message)."""
        lo, hi = np.searchsorted(self.candidate_frame, [i, i + 1])
        return slice(int(lo), int(hi))


def decode_point_cloud(msg: Any) -> dict[str, np.ndarray]:
    """Decode a ``foxglove.PointCloud``'s packed ``data`` into one array per field.

    Parameters
    ----------
    msg : foxglove.PointCloud (any protobuf class with that schema)

    Returns
    -------
    dict[str, (P,) ndarray]
        One array per field, with the field's numeric type.

    Raises
    ------
    ValueError
        If the field layout does not fit ``point_stride`` or ``data``.
    """
    stride = int(msg.point_stride)
    if stride <= 0:
        raise ValueError(f"point_stride must be > 0, got {stride}")
    names, formats, offsets = [], [], []
    for f in msg.fields:
        if f.type not in _NUMPY_TYPE:
            raise ValueError(f"field {f.name!r} has unknown numeric type {f.type}")
        names.append(f.name)
        formats.append(_NUMPY_TYPE[f.type])
        offsets.append(int(f.offset))
    dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": stride})
    if len(msg.data) % stride:
        raise ValueError(f"data length {len(msg.data)} is not a multiple of point_stride {stride}")
    points = np.frombuffer(msg.data, dtype=dtype)
    return {name: points[name].copy() for name in names}


def _decoder(
    factory: DecoderFactory,
    cache: dict[int, Callable[[bytes], Any]],
    schema: Schema | None,
    channel: Channel,
) -> Callable[[bytes], Any] | None:
    if channel.id not in cache:
        dec = factory.decoder_for(channel.message_encoding, schema)
        if dec is None:
            return None
        cache[channel.id] = dec
    return cache[channel.id]


@dataclass
class _Raw:
    """Undecoded content collected from either reading path."""

    channels: dict[str, str] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    messages: dict[str, list[tuple[int, Any]]] = field(default_factory=dict)
    complete: bool = True


_WANTED = (TOPIC_TARGETS, TOPIC_EVENTS, TOPIC_CANDIDATES)


def _read_indexed(path: Path) -> _Raw | None:
    """Read a closed file through its summary; None if it has no usable summary."""
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        try:
            summary = reader.get_summary()
        except Exception:  # any footer/summary problem: read sequentially instead
            return None
        if summary is None:
            return None
        raw = _Raw()
        for ch in summary.channels.values():
            schema = summary.schemas.get(ch.schema_id)
            raw.channels[ch.topic] = schema.name if schema is not None else ""
        raw.metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        for _, channel, message, decoded in reader.iter_decoded_messages(
            topics=[t for t in _WANTED if t in raw.channels]
        ):
            raw.messages.setdefault(channel.topic, []).append((message.log_time, decoded))
    return raw


def _read_sequential(path: Path) -> _Raw:
    """Read record by record up to the first incomplete one (a truncated file)."""
    raw = _Raw(complete=False)
    factory, cache = DecoderFactory(), {}
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    saw_header = False
    with open(path, "rb") as f:
        records: Iterator[Any] = StreamReader(f).records
        while True:
            try:
                record = next(records)
            except StopIteration:
                break
            except _READ_ERRORS as exc:
                if not saw_header:
                    raise InputError(f"{path}: not an MCAP file ({exc})") from None
                log.warning(
                    "%s: truncated or damaged after the last complete chunk (%s); "
                    "read what precedes it",
                    path,
                    str(exc) or type(exc).__name__,
                )
                break
            if isinstance(record, Header):
                saw_header = True
            elif isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
                schema = schemas.get(record.schema_id)
                raw.channels[record.topic] = schema.name if schema is not None else ""
            elif isinstance(record, Metadata):
                raw.metadata[record.name] = dict(record.metadata)
            elif isinstance(record, Message):
                channel = channels.get(record.channel_id)
                if channel is None or channel.topic not in _WANTED:
                    continue
                dec = _decoder(factory, cache, schemas.get(channel.schema_id), channel)
                if dec is None:
                    raise InputError(f"{path}: {channel.topic} is not protobuf-encoded")
                try:
                    decoded = dec(record.data)
                except DecodeError as exc:
                    raise InputError(
                        f"{path}: {channel.topic} message at log time "
                        f"{record.log_time} does not decode: {exc}"
                    ) from None
                raw.messages.setdefault(channel.topic, []).append((record.log_time, decoded))
            elif isinstance(record, Footer):
                raw.complete = True
    for msgs in raw.messages.values():
        msgs.sort(key=lambda item: item[0])
    return raw


def _kv(pairs: Any) -> dict[str, str]:
    return {kv.key: kv.value for kv in pairs}


def _ts_ns(ts: Any) -> int:
    return int(ts.seconds) * 1_000_000_000 + int(ts.nanos)


def _parse_event(msg: Any, start_time_ns: int, where: str) -> ActivityEvent:
    meta = _kv(msg.metadata)
    try:
        hue = meta.get("object_hue_deg")
        return ActivityEvent(
            activity=meta["activity"],
            start_ns=_ts_ns(msg.start_time) - start_time_ns,
            climax_ns=int(meta["climax_ns"]) - start_time_ns,
            end_ns=_ts_ns(msg.end_time) - start_time_ns,
            actors=tuple(a for a in meta.get("actors", "").split(",") if a),
            persons=tuple(p for p in meta.get("persons", "").split(",") if p),
            rule=meta.get("rule", ""),
            confidence=float(meta.get("confidence", "1")),
            object_hue_deg=None if hue in (None, "") else float(hue),
            from_actor=meta.get("from") or None,
            to_actor=meta.get("to") or None,
        )
    except (KeyError, ValueError) as exc:
        raise InputError(f"{where}: bad /events message {meta!r}: {exc}") from None


def read_run(path: Path) -> RunData:
    """Read an output MCAP.

    Parameters
    ----------
    path : Path
        An MCAP written by :class:`surveil.io.mcap_writer.McapWriter` (closed, or truncated
        by a crash: then read up to the last complete chunk).

    Returns
    -------
    RunData
        Targets, candidates, events and metadata; times in ns from t = 0.

    Raises
    ------
    InputError
        If the file is missing, not an MCAP, damaged before its first chunk, has no
        ``/targets`` channel, or holds a message that does not decode.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: MCAP file not found")
    try:
        raw = _read_indexed(path)
    except _READ_ERRORS as exc:
        log.warning("%s: index unreadable (%s); reading sequentially", path, exc)
        raw = None
    if raw is None:
        raw = _read_sequential(path)
    if TOPIC_TARGETS not in raw.channels:
        raise InputError(
            f"{path}: no {TOPIC_TARGETS} channel; is this an output of "
            f"`surveil run`? (channels: {', '.join(sorted(raw.channels)) or '-'})"
        )
    try:
        start = int(raw.metadata.get(SURVEIL_METADATA, {}).get("start_time_ns", "0"))
    except ValueError:
        raise InputError(
            f"{path}: metadata {SURVEIL_METADATA}.start_time_ns is not an integer"
        ) from None

    frame_t, t_frame, t_label, t_tracker, t_state, t_pos = [], [], [], [], [], []
    for i, (log_time, msg) in enumerate(raw.messages.get(TOPIC_TARGETS, [])):
        frame_t.append(log_time - start)
        for ent in msg.entities:
            meta = _kv(ent.metadata)
            if not ent.spheres:
                raise InputError(
                    f"{path}: /targets entity {ent.id!r} at log time {log_time} has no sphere"
                )
            p = ent.spheres[0].pose.position
            phase = _PHASE_BY_VALUE.get(meta.get("state", "normal"))
            if phase is None:
                raise InputError(
                    f"{path}: /targets entity {ent.id!r} has unknown state {meta.get('state')!r}"
                )
            try:
                parse_label(ent.id)
                tracker = int(meta.get("tracker", "-1"))
            except ValueError as exc:
                raise InputError(
                    f"{path}: /targets entity at log time {log_time}: {exc}"
                ) from None
            t_frame.append(i)
            t_label.append(ent.id)
            t_tracker.append(tracker)
            t_state.append(phase.code)
            t_pos.append((p.x, p.y, p.z))
    parsed = [parse_label(lab) for lab in t_label]

    c_t, c_frame, c_pos, c_prior = [], [], [], []
    for i, (log_time, msg) in enumerate(raw.messages.get(TOPIC_CANDIDATES, [])):
        c_t.append(log_time - start)
        try:
            cols = decode_point_cloud(msg)
        except ValueError as exc:
            raise InputError(f"{path}: /candidates at log time {log_time}: {exc}") from None
        n = len(next(iter(cols.values()), ()))
        c_frame.extend([i] * n)
        c_pos.append(np.column_stack([cols.get(k, np.full(n, np.nan)) for k in "xyz"]))
        c_prior.append(cols.get("prior", np.ones(n)))

    events = sorted(
        (_parse_event(msg, start, str(path)) for _, msg in raw.messages.get(TOPIC_EVENTS, [])),
        key=lambda e: e.climax_ns,
    )
    return RunData(
        path=path,
        start_time_ns=start,
        frame_t_ns=np.array(frame_t, dtype=np.int64),
        target_frame=np.array(t_frame, dtype=np.int64),
        target_label=np.array(t_label, dtype=str) if t_label else np.zeros(0, dtype="<U1"),
        target_tracker=np.array(t_tracker, dtype=np.int64),
        target_person=np.array([p for p, _ in parsed], dtype=np.int64),
        target_limb=np.array([int(limb) for _, limb in parsed], dtype=np.uint8),
        target_state=np.array(t_state, dtype=np.uint8),
        target_pos_m=np.array(t_pos, dtype=np.float64).reshape(-1, 3),
        candidate_t_ns=np.array(c_t, dtype=np.int64),
        candidate_frame=np.array(c_frame, dtype=np.int64),
        candidate_pos_m=(np.concatenate(c_pos).astype(np.float64) if c_pos else np.zeros((0, 3))),
        candidate_prior=(np.concatenate(c_prior).astype(np.float64) if c_prior else np.zeros(0)),
        events=tuple(events),
        metadata=raw.metadata,
        channels=raw.channels,
        complete=raw.complete,
    )
