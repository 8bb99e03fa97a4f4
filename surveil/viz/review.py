"""``surveil review``: a review .rrd from an existing output MCAP plus its recording.

The MCAP gives targets, candidates, events and the start time; the recording gives the images
and the rig. The cheap per-camera observations (silhouettes, skin blobs) are recomputed with
:mod:`surveil.blobs` (default settings, the skin models saved beside the rig) so that blob
boxes and silhouettes show, and from them and the run's hand positions the carry estimates
(:class:`~surveil.carry.CarryAnalyser`, default settings) for the "Carry" panel.
Those are a re-analysis, not the run's own: the run also restarts a hand's window when the
hand leaves the still point of a pick or place, which the MCAP does not record. Tracker
particles and transitions are not in the MCAP and are not shown.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from surveil.blobs import BackgroundModel, SceneryMask, observe
from surveil.blobs.background import learning_frames_after, shadow_region
from surveil.blobs.settings import BackgroundConfig, BlobConfig
from surveil.carry import CarryAnalyser, CarryConfig
from surveil.datatypes import (
    CameraObservation,
    CandidateSet,
    CarryEstimate,
    FrameResult,
    FrameSet,
    Limb,
    Phase,
    TargetSnapshot,
    TrackFrame,
)
from surveil.errors import InputError
from surveil.io.mcap_reader import RunData, read_run
from surveil.io.recording import Recording, open_recording
from surveil.io.skin_model import load_camera_skin_models
from surveil.viz.rerun_log import RerunSink

log = logging.getLogger(__name__)

_PHASE_BY_CODE = {p.code: p for p in Phase if p is not Phase.UNINITIALISED}
# metadata records that may name the recording a run was made from, most specific first
_RECORDING_KEYS = (("surveil", "recording"), ("run", "recording"), ("ground_truth", "recording"))


def recording_of(run: RunData) -> Path | None:
    """The recording directory named in a run's MCAP metadata, if any (and if it exists).

    Looks at the ``recording`` key of the ``surveil``, ``run`` and ``ground_truth`` records,
    then of any record; a relative path is taken from the working directory, then from the
    MCAP's directory.
    """
    meta = run.metadata
    found = [meta.get(rec, {}).get(key) for rec, key in _RECORDING_KEYS]
    found += [record.get("recording") for record in meta.values()]
    for value in found:
        if not value:
            continue
        p = Path(value).expanduser()
        for candidate in (p, run.path.parent / p):
            if (candidate / "recording.toml").is_file():
                return candidate
    return None


class _Observer:
    """What the run computed per frame set but did not write: per-camera observations (one
    stateful background model per camera, started as the run starts them) and, from those and
    the run's targets, the carry estimates of the hands."""

    def __init__(self, rec: Recording) -> None:
        self.bg_cfg, self.blob_cfg = BackgroundConfig(), BlobConfig()
        self.skin = load_camera_skin_models(rec.rig_path, rec.camera_names)
        self.scenery = {cam: SceneryMask(model) for cam, model in self.skin.items()}
        self.models: dict[str, BackgroundModel] = {}
        self.rig = rec.rig
        self.carry = CarryAnalyser(CarryConfig(), rec.rig)
        self._n_sets = 0

    def __call__(
        self, fs: FrameSet, targets: tuple[TargetSnapshot, ...]
    ) -> tuple[dict[str, CameraObservation], dict[int, CarryEstimate]]:
        heads = sum(1 for t in targets if t.limb is Limb.HEAD and t.phase is not Phase.LOST)
        out = {}
        for cam, img in fs.images.items():
            model = self.models.get(cam)
            if model is None:
                frames = learning_frames_after(self.bg_cfg, self._n_sets)
                region = shadow_region(self.bg_cfg, self.rig, cam, img.shape[:2])
                model = self.models[cam] = BackgroundModel(
                    self.bg_cfg, img.shape[:2], frames, shadow_region=region
                )
            out[cam] = observe(
                img, model, self.skin[cam], self.blob_cfg, cam, heads or None, self.scenery[cam]
            )
        self._n_sets += 1
        if any(m.learning for m in self.models.values()):
            return out, {}  # as in the run: no carry analysis while the background learns
        return out, self.carry.step(fs.t_ns, fs.images, out, targets)


def run_frames(run: RunData) -> tuple[dict[int, list[TargetSnapshot]], dict[int, CandidateSet]]:
    """Targets and candidates of an output MCAP by their time (ns from t = 0)."""
    targets: dict[int, list[TargetSnapshot]] = {}
    for i, t in enumerate(run.frame_t_ns.tolist()):
        rows = run.frame_rows(i)
        snaps = []
        for j in range(rows.start, rows.stop):
            tracker = int(run.target_tracker[j])
            snaps.append(
                TargetSnapshot(
                    target_id=tracker if tracker >= 0 else 1_000_000 + j - rows.start,
                    person=int(run.target_person[j]),
                    limb=Limb(int(run.target_limb[j])),
                    phase=_PHASE_BY_CODE.get(int(run.target_state[j]), Phase.NORMAL),
                    mean_m=run.target_pos_m[j],
                )
            )
        targets[int(t)] = snaps
    candidates: dict[int, CandidateSet] = {}
    bounds = np.searchsorted(run.candidate_frame, np.arange(len(run.candidate_t_ns) + 1))
    for i, t in enumerate(run.candidate_t_ns.tolist()):
        sl = slice(int(bounds[i]), int(bounds[i + 1]))
        candidates[int(t)] = CandidateSet(
            np.ascontiguousarray(run.candidate_pos_m[sl]),
            np.ascontiguousarray(run.candidate_prior[sl]),
        )
    return targets, candidates


def review_results(
    run: RunData, rec: Recording, *, observations: bool = True
) -> Iterator[FrameResult]:
    """FrameResults rebuilt from a run and its recording, one per frame set of the recording.

    Each event rides on the first frame set at or after its climax (the last one if none).
    """
    targets, candidates = run_frames(run)
    target_t = np.array(sorted(targets), dtype=np.int64)
    half = rec.period_ns // 2
    events = sorted(run.events, key=lambda e: e.climax_ns)
    observer = _Observer(rec) if observations else None
    pending = list(events)
    last: FrameResult | None = None
    for fs in rec.framesets():
        # the run's frame nearest to this set, within half a period
        k = int(np.searchsorted(target_t, fs.t_ns))
        near = [i for i in (k - 1, k) if 0 <= i < len(target_t)]
        best = min(near, key=lambda i: abs(int(target_t[i]) - fs.t_ns), default=None)
        t_run = int(target_t[best]) if best is not None else None
        if t_run is not None and abs(t_run - fs.t_ns) > half:
            t_run = None
        due = tuple(e for e in pending if e.climax_ns <= fs.t_ns)
        pending = pending[len(due) :]
        if last is not None:
            yield last
        live = tuple(targets.get(t_run, ())) if t_run is not None else ()
        observed, carry = observer(fs, live) if observer is not None else ({}, {})
        last = FrameResult(
            frameset=fs,
            observations=observed,
            candidates=candidates.get(t_run, CandidateSet.empty())
            if t_run is not None
            else CandidateSet.empty(),
            track=TrackFrame(fs.t_ns, live),
            carry=carry,
            events=due,
        )
    if last is not None:
        if pending:
            last = FrameResult(
                last.frameset,
                last.observations,
                last.candidates,
                last.track,
                last.carry,
                events=last.events + tuple(pending),
            )
        yield last


def build_review(
    mcap: Path,
    out: Path,
    *,
    recording: Path | None = None,
    jpeg_quality: int = 70,
    image_scale: float = 1.0,
    observations: bool = True,
    on_progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Write the review .rrd of an output MCAP.

    Parameters
    ----------
    mcap : Path
        Output of ``surveil run`` (or ``surveil truth``).
    out : Path
        The .rrd to write.
    recording : Path, optional
        The recording the run was made from; default: the one named in the MCAP's metadata.
    jpeg_quality, image_scale : see :class:`RerunSink`.
    observations : recompute silhouettes, skin blobs and carry estimates (the slow part; False
        skips them).
    on_progress : callback ``(done, total)`` per frame set.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    InputError
        If the MCAP or the recording cannot be read, or no recording is known.
    """
    run = read_run(Path(mcap))
    rec_dir = recording if recording is not None else recording_of(run)
    if rec_dir is None:
        raise InputError(
            f"{mcap}: the MCAP does not name its recording (or it has moved); "
            "give it with --recording DIR"
        )
    rec = open_recording(Path(rec_dir))
    start = rec.start_time_ns if run.start_time_ns == 0 else run.start_time_ns
    total = len(rec.assignment.set_idx)
    log.info("review of %s with %s: %d frame sets", mcap, rec_dir, total)
    with RerunSink(
        Path(out),
        rec.rig,
        rec.camera_names,
        jpeg_quality=jpeg_quality,
        image_scale=image_scale,
        start_time_ns=start,
        recording_id=f"review-{Path(mcap).stem}",
    ) as sink:
        for done, result in enumerate(review_results(run, rec, observations=observations), 1):
            sink.write(result)
            if on_progress is not None:
                on_progress(done, total)
    return Path(out)
