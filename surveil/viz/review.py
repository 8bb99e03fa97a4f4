"""``surveil review``: a review .rrd from an existing output MCAP plus its recording.

The MCAP gives targets, candidates, events and the start time; the recording gives the images
and the rig. The cheap per-camera observations (silhouettes, skin blobs) are recomputed with
:mod:`surveil.blobs` so that blob boxes and silhouettes show; tracker particles, transitions
and carry estimates are not in the MCAP and are not shown.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from surveil.blobs import BackgroundModel, default_skin_model, observe
from surveil.blobs.settings import BackgroundConfig, BlobConfig
from surveil.datatypes import (
    CameraObservation,
    CandidateSet,
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
    """Per-camera background models + the default skin model (one per camera, stateful)."""

    def __init__(self) -> None:
        self.bg_cfg, self.blob_cfg = BackgroundConfig(), BlobConfig()
        self.skin = default_skin_model()
        self.models: dict[str, BackgroundModel] = {}

    def __call__(self, fs: FrameSet) -> dict[str, CameraObservation]:
        out = {}
        for cam, img in fs.images.items():
            model = self.models.get(cam)
            if model is None:
                model = self.models[cam] = BackgroundModel(self.bg_cfg, img.shape[:2])
            out[cam] = observe(img, model, self.skin, self.blob_cfg, cam)
        return out


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
    observer = _Observer() if observations else None
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
        last = FrameResult(
            frameset=fs,
            observations=observer(fs) if observer is not None else {},
            candidates=candidates.get(t_run, CandidateSet.empty())
            if t_run is not None
            else CandidateSet.empty(),
            track=TrackFrame(fs.t_ns, tuple(targets.get(t_run, ())) if t_run is not None else ()),
            events=due,
        )
    if last is not None:
        if pending:
            last = FrameResult(
                last.frameset,
                last.observations,
                last.candidates,
                last.track,
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
    observations : recompute silhouettes and skin blobs (the slow part; False skips them).
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
