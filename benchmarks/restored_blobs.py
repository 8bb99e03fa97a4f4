"""Where the blobs restored by ``[blobs] open_keeps_isolated`` lie: on a hand or not, by
relative height in their silhouette (docs/blobs.md, "Keeping what the opening would erase").

    python benchmarks/restored_blobs.py [--out out/bench_synth] [--config TOML] [--radius-px 12]
        [NAME ...]

Replays each recording's front end (``front_end.observe_recording``, the true number of
people as N_h) with the given settings, ``open_keeps_isolated`` on and, unless the config
sets one, no height band (0 to 1), so every region the setting would admit is counted. For
each admitted blob: its relative height (v - top) / (bottom - top) in its silhouette, and
whether its centroid lies within ``--radius-px`` of a true hand's projection. Prints, per
scene and band of relative height, the blobs admitted and those on a hand.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import sys
from pathlib import Path

import numpy as np
from front_end import observe_recording

from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import load_pipeline_config
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]
BANDS = (0.0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 1.01)


def restored_rows(rec_dir: Path, cfg, radius_px: float) -> np.ndarray:
    """(K, 2): relative height and on-a-hand (0/1) of every restored blob admitted."""
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    n_people = len({lab.split("/")[0] for lab in gt.labels})
    hands = [j for j, lab in enumerate(gt.labels) if lab.endswith("hand")]
    rows = []
    for fs, by_name, _ in observe_recording(rec, cfg, n_people):
        if fs.index < cfg.background.learning_frames:
            continue
        i = int(np.searchsorted(gt.frames, fs.index))
        pts = gt.positions_m[i, hands]
        known = np.isfinite(pts).all(axis=1)
        for cam, obs in by_name.items():
            blobs = obs.blobs
            if blobs.restored is None or not blobs.restored.any():
                continue
            px, _ = rec.rig[cam].project(np.where(known[:, None], pts, 0.0))
            for k in np.flatnonzero(blobs.restored):
                d = np.where(known, np.linalg.norm(px - blobs.centroids_px[k], axis=1), np.inf)
                rows.append((blobs.rel_v[k], float(d.min() <= radius_px)))
    return np.array(rows).reshape(-1, 2)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML)")
    parser.add_argument("--radius-px", type=float, default=12.0)
    args = parser.parse_args(argv)
    cfg = load_pipeline_config(args.config)
    blobs = cfg.blobs
    if args.config is None or "restore_" not in args.config.read_text():
        blobs = dataclasses.replace(blobs, restore_min_rel_v=0.0, restore_max_rel_v=1.0)
    cfg = dataclasses.replace(cfg, blobs=dataclasses.replace(blobs, open_keeps_isolated=True))
    names = args.names or sorted(p.stem for p in (ROOT / "recordings").glob("*.toml"))
    heads = " | ".join(f"{lo:.1f}-{min(hi, 1.0):.1f}" for lo, hi in itertools.pairwise(BANDS))
    print(f"| scene | admitted / on a hand | {heads} |")
    print("|---|---|" + "---|" * (len(BANDS) - 1))
    for name in names:
        rec_dir = args.out / name
        synthesise(ROOT / "recordings" / f"{name}.toml", rec_dir)
        rows = restored_rows(rec_dir, cfg, args.radius_px)
        cells = []
        for lo, hi in itertools.pairwise(BANDS):
            m = (rows[:, 0] >= lo) & (rows[:, 0] < hi)
            cells.append(f"{int(m.sum())} / {int(rows[m, 1].sum())}")
        print(f"| {name} | {len(rows)} / {int(rows[:, 1].sum())} | {' | '.join(cells)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
