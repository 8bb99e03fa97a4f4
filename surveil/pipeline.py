"""The processing pipeline: frame sets in, FrameResults out to sinks (paper 004, whole).

``Pipeline.step`` reads top to bottom: per camera background + skin + blobs (section 6.1-6.2)
-> 3D candidate points (5.1, 6.3) -> parallel particle filters with the state machine and
labelling (4, 5, 7.1) -> carried objects per hand (7.2-7.3) -> activity decision points and
rules (7, Table 1). ``run_recording`` streams a recording through it into sinks (MCAP, Rerun)
with bounded memory: nothing is kept per frame beyond the stages' own bounded state.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import cv2
import numpy as np

from surveil.activity import ActivityEngine, RuleSet
from surveil.armpose import ArmPoseConfig, ArmTracker
from surveil.armpose.feed import with_arm_hands
from surveil.blobs.background import BackgroundModel, learning_frames_after, shadow_region
from surveil.blobs.extract import SceneryMask, blob_margin_px, extract_blobs
from surveil.blobs.settings import BackgroundConfig, BlobConfig
from surveil.blobs.skin import SkinModel, default_skin_model
from surveil.camera import Rig
from surveil.carry import CarryAnalyser, CarryConfig
from surveil.config import from_table, read_toml, setting
from surveil.datatypes import (
    ActivityEvent,
    ArmPose,
    CameraObservation,
    FrameResult,
    FrameSet,
    Limb,
    Phase,
    TargetSnapshot,
)
from surveil.io.recording import Recording
from surveil.recon.candidates import make_candidates
from surveil.recon.crowns import people_from_crowns, silhouette_crowns
from surveil.recon.settings import CandidateConfig
from surveil.tracking import MultiTargetTracker, TrackingConfig
from surveil.tracking.blob_pull import one_view_hand_points, pull_hands_onto_blobs

log = logging.getLogger(__name__)


@dataclass(frozen=True, kw_only=True)
class PipelineConfig:
    """Every setting of a run; a TOML file with these tables (all optional) overrides them.

    See docs/pipeline.md for the file format; ``surveil run --config FILE``.
    """

    seed: int = setting(0, "seed of every random choice (particle filters)", min=0)
    people_hint: int = setting(
        0, "number of people N_h for blob selection (0 = from silhouettes and heads)", min=0
    )
    carry_enabled: bool = setting(True, "run the carried-object analysis")
    background: BackgroundConfig = setting(
        default_factory=BackgroundConfig, doc="background model and silhouettes"
    )
    blobs: BlobConfig = setting(default_factory=BlobConfig, doc="skin blobs")
    candidates: CandidateConfig = setting(default_factory=CandidateConfig, doc="3D candidates")
    tracking: TrackingConfig = setting(default_factory=TrackingConfig, doc="particle filters")
    carry: CarryConfig = setting(default_factory=CarryConfig, doc="carried objects")
    arms: ArmPoseConfig = setting(default_factory=ArmPoseConfig, doc="arm trackers")

    def background_requests(self) -> dict[str, bool]:
        """What the later stages need from ``BackgroundModel.step`` besides the silhouettes."""
        return self.blobs.background_requests(
            foreground_share=self.candidates.min_pair_foreground_share > 0
        )


OPENCV_THREADS_ENV = "OPENCV_FOR_THREADS_NUM"


def use_one_opencv_thread() -> int:
    """Let OpenCV run its functions on the calling thread only, unless the environment
    variable ``OPENCV_FOR_THREADS_NUM`` (OpenCV's own) says otherwise; returns the number of
    threads OpenCV now uses.

    A frame set's OpenCV calls work on small images (320x240 masks, hand crops), where
    OpenCV's worker threads cost more in hand-offs than they gain: on the demo the process
    took about a fifth more CPU time with two threads than with one, for the same wall time
    (docs/pipeline.md, "Threads"). A run is one core's work; several recordings run side by
    side as separate processes. The output does not depend on the number of threads
    (tests/test_pipeline.py). Called by the command line and the benchmarks, not on import:
    it changes OpenCV's state for the whole process.
    """
    if OPENCV_THREADS_ENV not in os.environ:
        cv2.setNumThreads(1)
    return int(cv2.getNumThreads())


def load_pipeline_config(path: Path | None) -> PipelineConfig:
    """The defaults, overridden by the TOML file ``path`` (unknown keys and bad values fail
    with a ``ConfigError`` naming the file and the dotted key)."""
    if path is None:
        return PipelineConfig()
    return from_table(PipelineConfig, read_toml(Path(path)), f"{path}: ")


def silhouette_distance_cap_px(cfg: PipelineConfig) -> float | None:
    """How far from the silhouettes a run needs exact distances (``dist_outside_px``), frame
    pixels; None: everywhere.

    The silhouette prior p_b reads them: one camera's term exp(-0.5 (d / sigma)^2) rejects a
    candidate once it is below t = max(``term_threshold``, ``prior_threshold``) (p_b and
    the prior's product are at most that term), from d = sigma sqrt(2 ln(1 / t)). The cap
    is one sigma beyond that, and at least 4 sigma (the bilinear scaling from the model's
    size reads neighbours a pixel away). The head body check compares distances with
    ``body_tolerance_px``: at least twice that. Beyond the cap every value is moot, so a run
    finds the same candidates and tracks as with exact distances.

    >>> silhouette_distance_cap_px(PipelineConfig())
    24.0
    """
    c = cfg.candidates
    t = max(c.term_threshold, c.prior_threshold)
    if t <= 0.0:
        return None
    sigmas = max(4.0, math.sqrt(2.0 * math.log(1.0 / t)) + 1.0)
    return max(sigmas * c.sigma_silhouette_px, 2.0 * cfg.tracking.labelling.body_tolerance_px)


def config_as_dict(cfg: Any) -> Any:
    """A config dataclass as plain JSON-able values (for the MCAP metadata)."""
    return json.loads(json.dumps(dataclasses.asdict(cfg), default=str))


class Sink(Protocol):
    """Where FrameResults go (MCAP file, Rerun recording)."""

    def write(self, result: FrameResult) -> None: ...

    def close(self) -> None: ...


CAMERA_STEPS = ("background", "skin", "blobs", "crowns")


def new_background(
    cfg: PipelineConfig, rig: Rig, cam: str, shape: tuple[int, int], frame_index: int
) -> BackgroundModel:
    """Camera ``cam``'s background model as a run starts it at frame set ``frame_index``
    (its learning phase on the run's clock, :func:`learning_frames_after`)."""
    return BackgroundModel(
        cfg.background,
        shape,
        learning_frames_after(cfg.background, frame_index),
        silhouette_distance_cap_px(cfg),
        shadow_region(cfg.background, rig, cam, shape),
    )


def observe_cameras(
    cfg: PipelineConfig,
    rig: Rig,
    images: Mapping[str, np.ndarray],
    backgrounds: Mapping[str, BackgroundModel],
    skin_models: Mapping[str, SkinModel],
    scenery: Mapping[str, SceneryMask],
    n_people: int | None,
    *,
    at_least_people: int = 1,
    people_px: Mapping[str, np.ndarray] | None = None,
    changed: bool = False,
    skin_everywhere: bool = False,
) -> tuple[dict[str, CameraObservation], dict[str, dict[str, float]]]:
    """A frame set's images through the per-camera stage (sections 6.1-6.2 and the crowns):
    every camera's observation and the seconds it spent in each of ``CAMERA_STEPS``, both by
    camera name, in the order of ``images``.

    ``n_people``: the number of people the blobs are chosen for (None: as many as the view's
    silhouettes, the frame set's crowns (``BlobConfig.people_from_crowns``) and
    ``at_least_people``, a run's tracked heads, whichever is most). ``people_px``: where
    tracked people project in each view (the background does not learn them). ``changed``:
    the silhouettes carry MOG2's changed mask even when ``cfg`` does not ask for it.
    ``skin_everywhere``: classify skin in the whole frame, not only in the boxes around the
    silhouettes as a run does (for diagnostics that look at skin far from people).
    """
    requests = cfg.background_requests()
    requests["changed"] |= changed
    crowns_cfg = cfg.candidates.crowns
    find_crowns = crowns_cfg.enabled or cfg.blobs.people_from_crowns
    seconds: dict[str, dict[str, float]] = {}
    sensed = {}
    # first every view's silhouettes, skin and crowns: the views' crowns count the people
    # that each view's blobs are chosen for
    for cam, img in images.items():
        t0 = time.perf_counter()
        silhouettes = backgrounds[cam].step(
            img, **requests, people_px=None if people_px is None else people_px.get(cam)
        )
        t1 = time.perf_counter()
        margin = blob_margin_px(cfg.blobs, img.shape[1])
        skin = skin_models[cam].classify(
            img, None if skin_everywhere else silhouettes.boxes(margin)
        )
        t2 = time.perf_counter()
        crowns = silhouette_crowns(silhouettes, rig[cam], crowns_cfg) if find_crowns else None
        t3 = time.perf_counter()
        sensed[cam] = silhouettes, skin, crowns
        seconds[cam] = {"background": t1 - t0, "skin": t2 - t1, "crowns": t3 - t2}
    crowd = 0
    if cfg.blobs.people_from_crowns:
        crowd = people_from_crowns([len(crowns) for _, _, crowns in sensed.values()])
    observations = {}
    for cam, (silhouettes, skin, crowns) in sensed.items():
        t0 = time.perf_counter()
        people = n_people or max(silhouettes.n, crowd, at_least_people)
        on_scenery = scenery[cam].mask(backgrounds[cam]) if cfg.blobs.scenery_share > 0 else None
        blobs = extract_blobs(skin, silhouettes, cfg.blobs, people, images[cam], on_scenery)
        seconds[cam]["blobs"] = time.perf_counter() - t0
        observations[cam] = CameraObservation(cam, silhouettes, skin, blobs, crowns)
    return observations, seconds


class Pipeline:
    """One run over synchronised frame sets of a rig.

    Parameters
    ----------
    cfg : PipelineConfig
    rig : Rig -- the recording's cameras (candidate ``cam_pairs`` index this order)
    rules : RuleSet -- activity rules
    skin_models : per camera name; cameras without one use the default model
    """

    def __init__(
        self,
        cfg: PipelineConfig,
        rig: Rig,
        rules: RuleSet,
        skin_models: Mapping[str, SkinModel] | None = None,
    ) -> None:
        self.cfg = cfg
        self.rig = rig
        self.rules = rules
        self.skin_models = {
            cam.name: (skin_models or {}).get(cam.name) or default_skin_model() for cam in rig
        }
        self.backgrounds: dict[str, BackgroundModel] = {}
        self.scenery = {name: SceneryMask(model) for name, model in self.skin_models.items()}
        self.tracker = MultiTargetTracker(cfg.tracking, rig, seed=cfg.seed)
        self.carry = CarryAnalyser(cfg.carry, rig)
        self.activity = ActivityEngine(rules)
        self.arms = ArmTracker(cfg.arms, rig, seed=cfg.seed)
        self._n_heads = 0
        self._n_framesets = 0  # frame sets stepped since the start (or reset)
        # the previous frame set's heads and hands of people: the background model does not
        # learn the silhouettes that hold them
        self._people_m = np.zeros((0, 3))
        self._person_seen: dict[int, tuple[int, int]] = {}  # person -> first, last t_ns

    @classmethod
    def for_recording(cls, recording: Recording, cfg: PipelineConfig, rules: RuleSet) -> Pipeline:
        """A pipeline for ``recording``'s rig, with the per-camera skin models saved beside
        that rig (``surveil train-skin``) and the default model elsewhere."""
        from surveil.io.skin_model import load_camera_skin_models

        skin = load_camera_skin_models(recording.rig_path, recording.camera_names)
        return cls(cfg, recording.rig, rules, skin)

    def reset(self) -> None:
        self.backgrounds.clear()
        self.tracker.reset()
        self.carry.reset()
        self.activity.reset()
        self.arms.reset()
        self._n_heads = 0
        self._n_framesets = 0
        self._people_m = np.zeros((0, 3))
        self._person_seen.clear()

    def _protected_people(self, t_ns: int, targets: Sequence[TargetSnapshot]) -> np.ndarray:
        """(N, 3) the live heads and hands of persons tracked for at least
        ``background.protect_after_s``: the background model learns around them. A person
        unseen for that long is forgotten (their clock restarts)."""
        after_ns = self.cfg.background.protect_after_s * 1e9
        for person, (_, last) in list(self._person_seen.items()):
            if t_ns - last > after_ns:
                del self._person_seen[person]
        live = [t for t in targets if t.person > 0 and t.phase is not Phase.LOST]
        for t in live:
            first, _ = self._person_seen.get(t.person, (t_ns, t_ns))
            self._person_seen[t.person] = (first, t_ns)
        old = [t.mean_m for t in live if t_ns - self._person_seen[t.person][0] >= after_ns]
        return np.array(old).reshape(-1, 3)

    def _people_px(self, cam: str) -> np.ndarray:
        """(N, 2) where the previous frame set's protected people (:meth:`_protected_people`)
        project in camera ``cam``, pixels; only points in front of it."""
        if len(self._people_m) == 0:
            return np.zeros((0, 2))
        px, depth = self.rig[cam].project(self._people_m)
        return px[depth > 0]

    def _observe(self, fs: FrameSet, timings: dict[str, float]) -> dict[str, CameraObservation]:
        images = {cam: fs.images[cam] for cam in self.rig.names if cam in fs.images}
        for cam, img in images.items():
            if cam not in self.backgrounds:
                self.backgrounds[cam] = new_background(
                    self.cfg, self.rig, cam, img.shape[:2], self._n_framesets
                )
        observations, seconds = observe_cameras(
            self.cfg,
            self.rig,
            images,
            self.backgrounds,
            self.skin_models,
            self.scenery,
            self.cfg.people_hint or None,
            at_least_people=max(self._n_heads, 1),
            people_px={cam: self._people_px(cam) for cam in images},
        )
        for cam_seconds in seconds.values():
            for step, sec in cam_seconds.items():
                timings[step] += 1000 * sec
        return observations

    def step(self, fs: FrameSet) -> FrameResult:
        """Process one frame set through every stage."""
        timings = dict.fromkeys(CAMERA_STEPS, 0.0)
        observations = self._observe(fs, timings)
        self._n_framesets += 1
        learning = any(bg.learning for bg in self.backgrounds.values())
        arms_on = self.cfg.arms.enabled and not learning
        feed = arms_on and self.cfg.arms.feed_candidates
        t0 = time.perf_counter()
        arms: tuple[ArmPose, ...] = ()
        if feed:
            # the arms go first, on the trackers predicted to this frame set, so that their
            # hands can be candidates of this frame set's step
            arms = self.arms.step(fs.t_ns, self.tracker.predicted_targets(fs.t_ns), observations)
        t_arms = time.perf_counter() - t0
        t0 = time.perf_counter()
        candidates = make_candidates(
            list(observations.values()),
            self.rig,
            self.cfg.candidates,
            expected_m=self.tracker.expected_hands(fs.t_ns),
            expected_alone=self.tracker.expected_alone(),
            crowns_m=(
                self.tracker.expected_crowns(fs.t_ns)
                if self.cfg.candidates.tops_from_heads
                else None
            ),
        )
        if feed:
            candidates = with_arm_hands(
                candidates,
                arms,
                observations,
                self.rig,
                self.cfg.arms,
                self.cfg.candidates.support_radius_px,
            )
        tcfg = self.cfg.tracking
        if tcfg.one_view_prior > 0 and not learning:
            points, n_views = one_view_hand_points(
                self.tracker.predicted_targets(fs.t_ns),
                candidates.points_m,
                observations,
                self.rig,
                tcfg.blob_pull_sigma_px,
                tcfg.blob_pull_gate_px,
                tcfg.blob_pull_floor_m,
                tcfg.lifecycle.explained_radius_m,
            )
            candidates = candidates.with_points(points, tcfg.one_view_prior, n_views)
        t1 = time.perf_counter()
        track = self.tracker.step(fs.t_ns, candidates, observations)
        self._n_heads = sum(
            1 for t in track.targets if t.limb is Limb.HEAD and t.phase is not Phase.LOST
        )
        # the filter's own estimates: what the front end is fed back stays the tracker's
        self._people_m = self._protected_people(fs.t_ns, track.targets)
        if tcfg.blob_pull_sigma_px > 0:
            track = dataclasses.replace(
                track,
                targets=pull_hands_onto_blobs(
                    track.targets,
                    observations,
                    self.rig,
                    tcfg.blob_pull_sigma_px,
                    tcfg.blob_pull_gate_px,
                    tcfg.blob_pull_floor_m,
                    (tcfg.blob_pull_hand_end_sigma_px, tcfg.blob_pull_lone_hand_end_sigma_px),
                ),
            )
        t2 = time.perf_counter()
        carry = {}
        if self.cfg.carry_enabled and not learning:
            carry = self.carry.step(fs.t_ns, fs.images, observations, track.targets)
        t3 = time.perf_counter()
        events = tuple(self.activity.step(track, carry))
        for hand_id in self.activity.released_hands:
            self.carry.restart(hand_id)
        t4 = time.perf_counter()
        if arms_on and not feed:
            arms = self.arms.step(fs.t_ns, track.targets, observations)
        t_arms += time.perf_counter() - t4
        timings.update(
            candidates=1000 * (t1 - t0),
            tracking=1000 * (t2 - t1),
            carry=1000 * (t3 - t2),
            activity=1000 * (t4 - t3),
        )
        if self.cfg.arms.enabled:
            timings["arms"] = 1000 * t_arms
        return FrameResult(
            fs, observations, candidates, track, carry, events, arms=arms, timings_ms=timings
        )

    def finish(self) -> list[ActivityEvent]:
        """Decide the activities still pending at the end of the stream."""
        return self.activity.finish()


@dataclass
class RunSummary:
    """What a run did: counts, labels seen, events and time per stage."""

    n_framesets: int = 0
    n_camera_frames: int = 0
    events: list[ActivityEvent] = dataclasses.field(default_factory=list)
    persons: set[int] = dataclasses.field(default_factory=set)
    trackers: set[int] = dataclasses.field(default_factory=set)
    wall_s: float = 0.0
    stage_ms: dict[str, list[float]] = dataclasses.field(default_factory=dict)

    def median_ms(self) -> dict[str, float]:
        return {k: float(np.median(v)) for k, v in self.stage_ms.items() if v}

    def format(self) -> str:
        per_set = 1000 * self.wall_s / max(self.n_framesets, 1)
        stages = ", ".join(f"{k} {v:.1f}" for k, v in self.median_ms().items())
        lines = [
            f"{self.n_framesets} frame sets ({self.n_camera_frames} camera frames) in "
            f"{self.wall_s:.1f} s: {per_set:.1f} ms per frame set "
            f"({1000 / per_set if per_set else 0:.1f} sets/s)",
            f"median ms per frame set: {stages}",
            f"people found: {len(self.persons)}; trackers started: {len(self.trackers)}; "
            f"events: {len(self.events)}",
        ]
        return "\n".join(lines)


def run_recording(
    frames: Callable[[], Any],
    n_framesets: int,
    pipeline: Pipeline,
    sinks: Sequence[Sink],
    on_progress: Callable[[int, int], None] | None = None,
) -> RunSummary:
    """Stream frame sets through ``pipeline`` into ``sinks``; events decided at the end go
    out with the last frame's result. Sinks are closed even when processing fails.

    Parameters
    ----------
    frames : callable returning an iterator of FrameSet (e.g. ``recording.framesets``)
    n_framesets : for the progress callback
    """
    summary = RunSummary()
    t_start = time.perf_counter()
    last: FrameResult | None = None
    try:
        for fs in frames():
            result = pipeline.step(fs)
            if last is not None:
                for sink in sinks:
                    sink.write(last)
            last = result
            summary.n_framesets += 1
            summary.n_camera_frames += len(fs.images)
            summary.events.extend(result.events)
            for t in result.track.targets:
                summary.trackers.add(t.target_id)
                if t.person > 0:
                    summary.persons.add(t.person)
            for k, v in result.timings_ms.items():
                summary.stage_ms.setdefault(k, []).append(v)
            if on_progress is not None:
                on_progress(summary.n_framesets, n_framesets)
        tail = pipeline.finish()
        summary.events.extend(tail)
        if last is not None:
            last = dataclasses.replace(last, events=last.events + tuple(tail))
            for sink in sinks:
                sink.write(last)
    finally:
        for sink in sinks:
            sink.close()
    summary.wall_s = time.perf_counter() - t_start
    return summary
