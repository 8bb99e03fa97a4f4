"""Where the crown heads lie relative to the true head centres, per scenario.

    python benchmarks/crown_offsets.py [--out out/bench_synth] [--max-frames N] [NAME ...]

Replays each recording's front end (``front_end.observe_recording``) and makes the crown
heads alone (``surveil.recon.candidates.with_crowns`` on an empty skin set: every crown head
the default settings find, whatever skin candidates lie near). Each crown head within 15 cm
of a true head (ground truth, frames after the background's learning) is matched to it;
printed per scenario: the number matched, the mean offset (x, y, z) from the true centre and
the mean distance, horizontal and in 3-D, mm. A bias along the people's facing shows where
the silhouettes' tops are not above the head's centre (hair behind the face).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from front_end import observe_recording
from pipeline_bench import add_scene_arguments, render, scene_names

from surveil.datatypes import CandidateSet
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import PipelineConfig
from surveil.recon.candidates import with_crowns

ROOT = Path(__file__).resolve().parents[1]
MATCH_M = 0.15


def offsets(rec_dir: Path, cfg: PipelineConfig, max_frames: int | None) -> np.ndarray:
    """(M, 3) crown head minus the nearest true head centre, m, for the matched ones."""
    rec, gt = open_recording(rec_dir), load_ground_truth(rec_dir)
    heads = [j for j, label in enumerate(gt.labels) if label.endswith("head")]
    index = {name: m for m, name in enumerate(rec.rig.names)}
    learn = cfg.background.learning_frames
    out = []
    for fs, observations, _ in observe_recording(rec, cfg, max_frames=max_frames):
        if fs.index < learn:
            continue
        by_cam = {index[name]: obs for name, obs in observations.items()}
        crowns = with_crowns(CandidateSet.empty(), by_cam, rec.rig, cfg.candidates.crowns)
        truth = gt.positions_m[int(np.searchsorted(gt.frames, fs.index)), heads]
        truth = truth[np.isfinite(truth).all(axis=1)]
        if not len(truth) or not len(crowns.points_m):
            continue
        d = np.linalg.norm(crowns.points_m[:, None] - truth[None], axis=2)
        near = d.argmin(axis=1)
        ok = d[np.arange(len(near)), near] < MATCH_M
        out.append(crowns.points_m[ok] - truth[near[ok]])
    return np.concatenate(out) if out else np.zeros((0, 3))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--max-frames", type=int, default=None)
    args = parser.parse_args(argv)
    cfg = PipelineConfig()
    print("| scenario | matched | mean offset x, y, z mm | mean horizontal mm | mean 3-D mm |")
    print("|---|---|---|---|---|")
    for name in scene_names(args):
        o = 1000 * offsets(render(name, args.out), cfg, args.max_frames)
        if not len(o):
            print(f"| {name} | 0 | - | - | - |")
            continue
        x, y, z = o.mean(axis=0)
        horizontal = np.linalg.norm(o[:, :2], axis=1).mean()
        print(
            f"| {name} | {len(o)} | {x:.0f}, {y:.0f}, {z:.0f} | {horizontal:.0f} | "
            f"{np.linalg.norm(o, axis=1).mean():.0f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
