"""A recording's ground truth written as an output MCAP (``surveil truth``): what a perfect
tracker would write. Useful to check the scorer (it scores perfectly) and to view the truth in
Foxglove or Rerun next to a run."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from surveil.camera import Rig
from surveil.datatypes import CandidateSet, Phase, TargetSnapshot, parse_label
from surveil.errors import InputError
from surveil.io.ground_truth import GroundTruth, load_ground_truth
from surveil.io.mcap_writer import McapWriter
from surveil.io.recording import load_spec

log = logging.getLogger(__name__)


def truth_frames(gt: GroundTruth) -> list[tuple[int, list[TargetSnapshot], CandidateSet]]:
    """One (t_ns, targets, candidates) per ground-truth frame.

    Targets: every true limb with a finite position, phase NORMAL, tracker id = label index + 1
    (stable per limb). Candidates: the true positions of limbs seen by at least one camera,
    prior 1.
    """
    parsed = [parse_label(lab) for lab in gt.labels]
    n_views = gt.n_views
    frames = []
    for i, t in enumerate(gt.t_ns):
        pos = gt.positions_m[i]
        present = np.isfinite(pos).all(axis=1)
        targets = [
            TargetSnapshot(
                target_id=j + 1,
                person=parsed[j][0],
                limb=parsed[j][1],
                phase=Phase.NORMAL,
                mean_m=pos[j],
            )
            for j in np.flatnonzero(present)
        ]
        seen = present & (n_views[i] > 0)
        cands = CandidateSet(pos[seen].astype(np.float64), np.ones(int(seen.sum())))
        frames.append((int(t), targets, cands))
    return frames


def write_truth_mcap(recording_dir: Path, out: Path, *, rig: Rig | None = None) -> None:
    """Write the ground truth of ``recording_dir`` as an output MCAP at ``out``.

    Parameters
    ----------
    recording_dir : Path
        Recording directory (``recording.toml`` and ``ground_truth/``).
    out : Path
        MCAP file to write (overwritten).
    rig : Rig, optional
        Cameras for the calibration topics; default: the rig named by ``recording.toml``.
        ``start_time_ns`` of ``recording.toml`` is honoured.

    Raises
    ------
    InputError
        If the recording, its rig or its ground truth cannot be read.
    """
    recording_dir = Path(recording_dir)
    toml_path = recording_dir / "recording.toml"
    if not toml_path.is_file():
        raise InputError(f"{recording_dir}: not a recording (recording.toml is missing)")
    spec = load_spec(toml_path)
    gt = load_ground_truth(recording_dir)
    if rig is None:
        from surveil.io.calibration import load_rig

        rig = load_rig(recording_dir / spec.rig)  # an absolute rig path stays absolute
    start = spec.start_time_ns
    with McapWriter(
        Path(out),
        rig,
        start_time_ns=start,
        metadata={"ground_truth": {"recording": str(recording_dir), "source": "surveil truth"}},
    ) as writer:
        for t_ns, targets, cands in truth_frames(gt):
            writer.write_frame(t_ns, targets, cands)
        for ev in sorted(gt.events, key=lambda e: e.climax_ns):
            writer.write_event(ev)
    log.info(
        "wrote ground truth of %s (%d frames, %d events) to %s",
        recording_dir,
        len(gt.frames),
        len(gt.events),
        out,
    )
