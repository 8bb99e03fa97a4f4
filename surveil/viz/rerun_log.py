"""``RerunSink``: one processed frame set at a time into a Rerun recording (.rrd) for review.

What is drawn where is listed in :mod:`surveil.viz.paths`. Timelines: ``frame`` (the frame-set
index, a sequence) and ``time`` (the recording clock, a duration from t = 0); when the
recording has a wall-clock origin (``start_time_ns > 0``) also ``wall_time`` (a timestamp).

Camera frames are stored as JPEG (``EncodedImage``), optionally downscaled: everything drawn
in a camera view (blob boxes, silhouettes, projected targets, the pinhole) is scaled with it,
so overlays stay aligned. See docs/review.md for the size per minute.
"""

from __future__ import annotations

import bisect
import colorsys
import logging
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import rerun as rr

from surveil.camera import Camera, Rig
from surveil.datatypes import (
    ActivityEvent,
    CameraObservation,
    CandidateSet,
    CarryEstimate,
    FrameResult,
    Limb,
    Phase,
    TargetSnapshot,
    Transition,
)
from surveil.io.mcap_writer import event_log_line, hue_name, target_rgba
from surveil.viz import paths
from surveil.viz.blueprint import HAS_STATE_LANES, build_blueprint

log = logging.getLogger(__name__)

#: Display colour (RGB 0-255) of each tracker state in the state lanes.
STATE_COLOURS = {
    Phase.UNLABELLED: (150, 150, 150),
    Phase.NORMAL: (60, 180, 75),
    Phase.COMBINED: (255, 165, 0),
    Phase.LOST: (220, 40, 40),
}
_LIMB_RADIUS_M = {0: 0.09, 1: 0.05, 2: 0.05}  # head larger than hands
_CANDIDATE_RGBA = (200, 200, 200, 90)
_PARTICLE_ALPHA = 60
_BLOB_RGB = (255, 140, 0)
_SILHOUETTE_RGB = (0, 255, 255)
_EVENT_MARK_S = 1.5  # how long an event's 3D marker stays after its climax
_HISTORY_S = 60.0  # positions kept per label, to place late-decided events in 3D


def hue_rgb(hue_deg: float) -> tuple[int, int, int]:
    """Saturated RGB (0-255) of a hue in degrees.

    >>> hue_rgb(0.0), hue_rgb(120.0)
    ((255, 0, 0), (0, 255, 0))
    """
    r, g, b = colorsys.hsv_to_rgb((float(hue_deg) % 360.0) / 360.0, 1.0, 1.0)
    return round(255 * r), round(255 * g), round(255 * b)


def target_colour(snap: TargetSnapshot) -> tuple[int, int, int, int]:
    """RGBA 0-255 of a target: the person's colour shaded by limb (as in the MCAP output)."""
    rgba = target_rgba(snap.person, int(snap.limb), snap.phase)
    return tuple(round(255 * c) for c in rgba)  # type: ignore[return-value]


def short_label(snap: TargetSnapshot) -> str:
    """A compact label for camera views: ``p1`` (head), ``p1 L``, ``p1 R``, or ``t7``.

    >>> from surveil.datatypes import Limb
    >>> short_label(TargetSnapshot(3, 1, Limb.LEFT_HAND, Phase.NORMAL, np.zeros(3)))
    'p1 L'
    """
    if snap.person <= 0 or snap.limb is Limb.UNKNOWN:
        return snap.label
    suffix = {Limb.HEAD: "", Limb.LEFT_HAND: " L", Limb.RIGHT_HAND: " R"}[snap.limb]
    return f"p{snap.person}{suffix}"


def default_eye(rig: Rig, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray] | None:
    """(eye position, look target), world frame, metres: above and behind the middle of the
    cameras' footprint, looking at its centre 0.8 m above the floor. None without cameras."""
    if not names:
        return None
    centres = np.array([rig[c].centre_m for c in names])
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1.0))
    target = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, 0.8])
    eye = target + np.array([0.0, -0.9 * span, 0.7 * span])
    return eye, target


def silhouette_outlines(labels: np.ndarray, scale: float = 1.0) -> list[np.ndarray]:
    """Closed outer contours of the silhouettes, as (P, 2) float32 (u, v) polylines.

    Parameters
    ----------
    labels : (H, W) int silhouette labels (0 = background)
    scale : factor applied to the pixel coordinates

    >>> lab = np.zeros((6, 6), np.int32); lab[1:4, 1:4] = 1
    >>> [o.tolist() for o in silhouette_outlines(lab)]
    [[[1.0, 1.0], [1.0, 3.0], [3.0, 3.0], [3.0, 1.0], [1.0, 1.0]]]
    """
    mask = (np.asarray(labels) > 0).astype(np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    out = []
    for c in contours:
        if len(c) > 8:  # simplify long outlines to within 1 px: a tenth of the points
            c = cv2.approxPolyDP(c, 1.0, True)
        pts = c.reshape(-1, 2).astype(np.float32)
        out.append(np.vstack([pts, pts[:1]]) * np.float32(scale))
    return out


def _time_ns(t_ns: int) -> np.timedelta64:
    return np.timedelta64(int(t_ns), "ns")


@dataclass
class _Track:
    """What the sink remembers of one tracker between frames."""

    label: str
    trail: deque = field(default_factory=deque)  # (t_ns, (3,) position)
    phase: Phase | None = None


def carry_signal(est: CarryEstimate) -> float:
    """The plotted carry value: +confidence while the hand carries, -confidence while it is
    judged empty, so that one curve shows both the decision and how sure it is.

    >>> carry_signal(CarryEstimate(1, "p1/right_hand", 0, True, 120.0, 0.8))
    0.8
    >>> carry_signal(CarryEstimate(1, "p1/right_hand", 0, False, None, 0.3))
    -0.3
    """
    return float(est.confidence) if est.carrying else -float(est.confidence)


class RerunSink:
    """Write :class:`FrameResult` s to an .rrd file laid out for review.

    Parameters
    ----------
    path : Path
        The .rrd file to write (overwritten).
    rig : Rig
        Calibration; cameras are drawn as pinholes with their frusta.
    camera_names : sequence of str, optional
        The cameras to show, in this order (default: all of the rig's).
    jpeg_quality : int
        JPEG quality of the camera frames, 1-100.
    image_scale : float
        Scale of the stored camera frames, (0, 1]; 0.5 stores a quarter of the pixels.
    trail_s : float
        Length of the trajectory trails, seconds.
    start_time_ns : int
        Wall-clock time of t = 0; adds a ``wall_time`` timeline when > 0.
    application_id, recording_id : str
        Rerun identifiers (the recording id defaults to a random one).
    blueprint : bool
        Store the review layout in the file (default True).

    The sink is not thread-safe; call :meth:`write` once per frame set, in order, then
    :meth:`close` (or use it as a context manager).
    """

    def __init__(
        self,
        path: Path,
        rig: Rig,
        camera_names: Sequence[str] | None = None,
        *,
        jpeg_quality: int = 70,
        image_scale: float = 1.0,
        trail_s: float = 1.0,
        start_time_ns: int = 0,
        application_id: str = "surveil",
        recording_id: str | None = None,
        blueprint: bool = True,
    ) -> None:
        names = tuple(rig.names if camera_names is None else camera_names)
        for cam in names:
            if cam not in rig:
                raise ValueError(
                    f"camera_names: {cam!r} is not in the rig (rig cameras: "
                    f"{', '.join(rig.names)})"
                )
        if not 1 <= int(jpeg_quality) <= 100:
            raise ValueError(f"jpeg_quality must be in [1, 100], got {jpeg_quality}")
        if not 0.0 < float(image_scale) <= 1.0:
            raise ValueError(f"image_scale must be in (0, 1], got {image_scale}")
        if not trail_s >= 0.0:
            raise ValueError(f"trail_s must be >= 0, got {trail_s}")
        self.path = Path(path)
        self.rig = rig
        self.camera_names = names
        self.jpeg_quality = int(jpeg_quality)
        self.image_scale = float(image_scale)
        self.trail_ns = round(trail_s * 1e9)
        self.start_time_ns = int(start_time_ns)
        # Few, large chunks: with the default thresholds (0.2 s, 2 MiB) the camera frames
        # flush the batcher every few frames and each small entity gets a chunk of one or two
        # rows, whose schema costs more than its data (about a fifth of the file).
        batcher = rr.ChunkBatcherConfig(flush_tick=5.0, flush_num_bytes=64 << 20)
        self._rec = rr.RecordingStream(
            application_id, recording_id=recording_id, batcher_config=batcher
        )
        layout = build_blueprint(names, eye=default_eye(rig, names)) if blueprint else None
        self._rec.save(self.path, default_blueprint=layout)
        self._tracks: dict[int, _Track] = {}
        self._state_paths: set[str] = set()
        self._carry_paths: set[str] = set()
        self._history: dict[str, deque] = {}
        self._frame_t: list[int] = []
        self._frame_idx: list[int] = []
        self._closed = False
        self._log_static()

    # -----------------------------------------------------------------------------------------
    # static content

    def _log_static(self) -> None:
        rec = self._rec
        rec.log(paths.WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log(paths.FLOOR, self._floor(), static=True)
        for name in self.camera_names:
            cam = self.rig[name]
            rec.log(
                paths.camera_path(name),
                rr.Transform3D(translation=cam.centre_m, mat3x3=cam.R.T),
                rr.Pinhole(
                    image_from_camera=self._scaled_K(cam),
                    resolution=self._scaled_size(cam),
                    camera_xyz=rr.ViewCoordinates.RDF,
                    image_plane_distance=0.5,
                ),
                static=True,
            )

    def _floor(self) -> rr.LineStrips3D:
        """A 0.5 m grid on Z = 0 covering the cameras' footprint."""
        centres = np.array([self.rig[c].centre_m for c in self.camera_names]).reshape(-1, 3)
        if len(centres):
            lo = np.floor(centres[:, :2].min(axis=0) * 2) / 2
            hi = np.ceil(centres[:, :2].max(axis=0) * 2) / 2
        else:
            lo, hi = np.array([-3.0, -3.0]), np.array([3.0, 3.0])
        strips = [[(x, lo[1], 0.0), (x, hi[1], 0.0)] for x in np.arange(lo[0], hi[0] + 0.01, 0.5)]
        strips += [[(lo[0], y, 0.0), (hi[0], y, 0.0)] for y in np.arange(lo[1], hi[1] + 0.01, 0.5)]
        return rr.LineStrips3D(strips, colors=(90, 90, 90), radii=rr.Radius.ui_points(0.5))

    def _scaled_K(self, cam: Camera) -> np.ndarray:
        S = np.diag([self.image_scale, self.image_scale, 1.0])
        return S @ cam.K

    def _scaled_size(self, cam: Camera) -> tuple[int, int]:
        return round(cam.width * self.image_scale), round(cam.height * self.image_scale)

    # -----------------------------------------------------------------------------------------
    # per frame

    def write(self, result: FrameResult) -> None:
        """Log one processed frame set (times: ``result.frameset``)."""
        if self._closed:
            raise RuntimeError("RerunSink.write after close()")
        fs = result.frameset
        if self._frame_t and fs.t_ns < self._frame_t[-1]:
            raise ValueError(
                f"frame sets must come in time order: t_ns {fs.t_ns} after {self._frame_t[-1]}"
            )
        self._frame_t.append(int(fs.t_ns))
        self._frame_idx.append(int(fs.index))
        self._set_time(fs.index, fs.t_ns)
        live = [s for s in result.track.targets if s.phase is not Phase.UNINITIALISED]
        carry = dict(result.carry)
        for cam in self.camera_names:
            self._log_camera(cam, fs.images.get(cam), result.observations.get(cam), live, fs.index)
        self._log_candidates(result.candidates)
        self._log_targets(fs.t_ns, live, carry, result.track)
        self._log_carry(carry)
        for tr in result.track.transitions:
            self._log_transition(tr)
        for ev in result.events:
            self.log_event(ev)
            self._set_time(fs.index, fs.t_ns)

    def _set_time(self, index: int, t_ns: int) -> None:
        self._rec.set_time("frame", sequence=int(index))
        self._rec.set_time("time", duration=_time_ns(t_ns))
        if self.start_time_ns > 0:
            self._rec.set_time(
                "wall_time", timestamp=np.datetime64(self.start_time_ns + int(t_ns), "ns")
            )

    def _log_camera(
        self,
        name: str,
        image: np.ndarray | None,
        obs: CameraObservation | None,
        targets: Sequence[TargetSnapshot],
        index: int,
    ) -> None:
        rec, s = self._rec, self.image_scale
        if image is None:
            rec.log(paths.camera_image_path(name), rr.Clear(recursive=False))
        else:
            if s != 1.0:
                w, h = self._scaled_size(self.rig[name])
                image = cv2.resize(image, (w, h), interpolation=cv2.INTER_AREA)
            ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
            if not ok:  # OpenCV failed on a valid uint8 image: a broken build, not bad input
                raise RuntimeError(f"camera {name}: JPEG encoding failed at frame {index}")
            rec.log(
                paths.camera_image_path(name),
                rr.EncodedImage(contents=jpeg.tobytes(), media_type="image/jpeg"),
            )
        if obs is None:
            rec.log(paths.camera_blobs_path(name), rr.Clear(recursive=False))
            rec.log(paths.camera_silhouettes_path(name), rr.Clear(recursive=False))
        else:
            boxes = obs.blobs.bboxes_px.astype(np.float32) * np.float32(s)
            rec.log(
                paths.camera_blobs_path(name),
                rr.Boxes2D(
                    mins=boxes[:, :2].reshape(-1, 2),
                    sizes=boxes[:, 2:].reshape(-1, 2),
                    colors=_BLOB_RGB,
                    radii=rr.Radius.ui_points(1.0),
                ),
            )
            rec.log(
                paths.camera_silhouettes_path(name),
                rr.LineStrips2D(
                    silhouette_outlines(obs.silhouettes.labels, s),
                    colors=_SILHOUETTE_RGB,
                    radii=rr.Radius.ui_points(1.0),
                ),
            )
        self._log_projected(name, targets)

    def _log_projected(self, name: str, targets: Sequence[TargetSnapshot]) -> None:
        cam = self.rig[name]
        shown = [t for t in targets if t.phase is not Phase.LOST]
        pts = np.array([t.mean_m for t in shown]).reshape(-1, 3)
        px, depth = cam.project(pts)
        keep = cam.in_image(px, depth) if len(pts) else np.zeros(0, bool)
        self._rec.log(
            paths.camera_targets_path(name),
            rr.Points2D(
                (px[keep] * self.image_scale).reshape(-1, 2),
                colors=[target_colour(t) for t, k in zip(shown, keep, strict=True) if k],
                labels=[short_label(t) for t, k in zip(shown, keep, strict=True) if k],
                radii=rr.Radius.ui_points(5.0),
                show_labels=True,
            ),
        )

    def _log_candidates(self, cands: CandidateSet) -> None:
        prior = np.clip(np.asarray(cands.prior, dtype=np.float64), 0.0, 1.0)
        colours = np.tile(np.array(_CANDIDATE_RGBA, np.uint8), (len(prior), 1))
        colours[:, 3] = (40 + 120 * prior).astype(np.uint8)  # likelier -> less faint
        self._rec.log(
            paths.CANDIDATES,
            rr.Points3D(cands.points_m, colors=colours, radii=0.02),
        )

    def _log_targets(
        self,
        t_ns: int,
        targets: Sequence[TargetSnapshot],
        carry: dict[int, CarryEstimate],
        track,
    ) -> None:
        rec = self._rec
        seen: set[int] = set()
        labels_now = {t.label for t in targets}
        for snap in targets:
            seen.add(snap.target_id)
            label = snap.label
            tr = self._tracks.get(snap.target_id)
            if tr is None:
                tr = self._tracks[snap.target_id] = _Track(label)
            elif tr.label != label:  # relabelled (t7 -> p1/head): move everything to the new path
                self._retire(tr, keep_state=tr.label in labels_now)
                tr.label = label
                tr.phase = None
            self._remember(label, t_ns, snap.mean_m)
            if tr.phase is not snap.phase:
                self._log_state(label, snap.phase)
                tr.phase = snap.phase
            elif not HAS_STATE_LANES:
                self._log_state(label, snap.phase)
            if snap.phase is Phase.LOST:
                rec.log(paths.target_path(label), rr.Clear(recursive=True))
                tr.trail.clear()
                continue
            tr.trail.append((t_ns, snap.mean_m))
            while tr.trail and tr.trail[0][0] < t_ns - self.trail_ns:
                tr.trail.popleft()
            colour = target_colour(snap)
            rec.log(
                paths.target_estimate_path(label),
                rr.Points3D(
                    snap.mean_m.reshape(1, 3),
                    colors=[colour],
                    radii=_LIMB_RADIUS_M.get(int(snap.limb), 0.06),
                    labels=[label],
                    show_labels=True,
                ),
            )
            if len(tr.trail) >= 2:
                rec.log(
                    paths.target_trail_path(label),
                    rr.LineStrips3D(
                        [np.array([p for _, p in tr.trail])],
                        colors=[colour[:3]],
                        radii=rr.Radius.ui_points(2.0),
                    ),
                )
            self._log_particles(snap, track, colour)
            est = carry.get(snap.target_id)
            hue = snap.carried_hue_deg
            if est is not None:
                hue = est.hue_deg if est.carrying else None
            if hue is not None and snap.limb.is_hand:
                rec.log(
                    paths.target_carried_path(label),
                    rr.Points3D(
                        (snap.mean_m + np.array([0.0, 0.0, -0.08])).reshape(1, 3),
                        colors=[hue_rgb(hue)],
                        radii=0.045,
                        labels=[hue_name(hue)],
                        show_labels=False,
                    ),
                )
            else:
                rec.log(paths.target_carried_path(label), rr.Clear(recursive=False))
        for tid in [tid for tid in self._tracks if tid not in seen]:
            gone = self._tracks.pop(tid)
            self._retire(gone, keep_state=gone.label in labels_now)

    def _log_particles(self, snap: TargetSnapshot, track, colour) -> None:
        if track.particles_m is None or track.particle_owner is None:
            return
        mine = np.asarray(track.particles_m)[np.asarray(track.particle_owner) == snap.target_id]
        self._rec.log(
            paths.target_particles_path(snap.label),
            rr.Points3D(
                mine.reshape(-1, 3),
                colors=[(*colour[:3], _PARTICLE_ALPHA)],
                radii=rr.Radius.ui_points(1.5),
            ),
        )

    def _retire(self, tr: _Track, *, keep_state: bool) -> None:
        """Clear a tracker's 3D entities and end its state lane (a gone or relabelled one)."""
        self._rec.log(paths.target_path(tr.label), rr.Clear(recursive=True))
        if not keep_state:
            self._log_state(tr.label, None)

    def _log_state(self, label: str, phase: Phase | None) -> None:
        path = paths.state_path(label)
        if HAS_STATE_LANES:
            if path not in self._state_paths:
                self._state_paths.add(path)
                self._rec.log(
                    path,
                    rr.StateConfiguration(
                        values=[p.value for p in STATE_COLOURS],
                        colors=list(STATE_COLOURS.values()),
                    ),
                    static=True,
                )
            self._rec.log(path, rr.StateChange(state=["" if phase is None else phase.value]))
        elif phase is not None:
            self._rec.log(path, rr.Scalars(float(phase.code)))
        else:
            self._rec.log(path, rr.Clear(recursive=False))

    def _log_carry(self, carry: dict[int, CarryEstimate]) -> None:
        for est in carry.values():
            path = paths.carry_path(est.label)
            if path not in self._carry_paths:
                self._carry_paths.add(path)
                self._rec.log(path, rr.SeriesLines(names=[est.label]), static=True)
            self._rec.log(path, rr.Scalars(carry_signal(est)))

    def _log_transition(self, tr: Transition) -> None:
        partner = f" with {tr.partner_label}" if tr.partner_label else ""
        self._rec.log(
            paths.TRANSITIONS,
            rr.TextLog(
                f"{tr.t_ns / 1e9:.2f} s {tr.label}: {tr.old.value} -> {tr.new.value}{partner}",
                level="DEBUG",
            ),
        )

    def _remember(self, label: str, t_ns: int, pos: np.ndarray) -> None:
        hist = self._history.setdefault(label, deque())
        hist.append((int(t_ns), pos))
        while hist and hist[0][0] < t_ns - _HISTORY_S * 1e9:
            hist.popleft()

    def _position_at(self, label: str, t_ns: int) -> np.ndarray | None:
        hist = self._history.get(label)
        if not hist:
            return None
        best = min(hist, key=lambda item: abs(item[0] - t_ns))
        return best[1]

    def _frame_at(self, t_ns: int) -> int:
        """The frame index at ``t_ns``: the latest frame set at or before it, extrapolated at
        the last frame period beyond the last frame set seen."""
        if not self._frame_idx:
            return 0
        i = bisect.bisect_right(self._frame_t, int(t_ns)) - 1
        if i < len(self._frame_t) - 1 or len(self._frame_t) < 2:
            return self._frame_idx[max(i, 0)]
        dt = (self._frame_t[-1] - self._frame_t[-2]) / max(
            self._frame_idx[-1] - self._frame_idx[-2], 1
        )
        ahead = int((t_ns - self._frame_t[-1]) // dt) if dt > 0 else 0
        return self._frame_idx[-1] + ahead

    # -----------------------------------------------------------------------------------------
    # events

    def log_event(self, ev: ActivityEvent) -> None:
        """Log an event at its climax time: a line in the event log and, for a moment, a
        labelled marker in 3D between its actors (where their positions are known)."""
        rec = self._rec
        self._set_time(self._frame_at(ev.climax_ns), ev.climax_ns)
        rec.log(paths.EVENTS, rr.TextLog(event_log_line(ev), level="INFO"))
        where = [self._position_at(a, ev.climax_ns) for a in ev.actors]
        where = [p for p in where if p is not None]
        if not where:
            return
        centre = np.mean(where, axis=0) + np.array([0.0, 0.0, 0.25])
        colour = hue_rgb(ev.object_hue_deg) if ev.object_hue_deg is not None else (255, 255, 0)
        rec.log(
            paths.EVENT_MARKER,
            rr.Points3D(
                centre.reshape(1, 3),
                colors=[colour],
                radii=0.03,
                labels=[ev.activity],
                show_labels=True,
            ),
        )
        end_ns = ev.climax_ns + round(_EVENT_MARK_S * 1e9)
        self._set_time(self._frame_at(end_ns), end_ns)
        rec.log(paths.EVENT_MARKER, rr.Clear(recursive=False))

    # -----------------------------------------------------------------------------------------

    def close(self) -> None:
        """Flush and close the file. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._rec.flush()
        self._rec.disconnect()
        log.info("wrote review recording %s (%d frame sets)", self.path, len(self._frame_t))

    def __enter__(self) -> RerunSink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
