"""Whether hands pulled onto their blobs lie nearer the true hands, move by move (docs/tracking.md,
"Hands pulled onto their blobs").

    python benchmarks/pull_moves.py [--config TOML] [--seed N] [--off-sigma PX] [NAME ...]

Runs each take through two pipelines side by side, one with the settings given (default: the
defaults) and one with ``[tracking] blob_pull_sigma_px = 0`` (the filter's estimates). The
trackers are the same in both (the pull moves only the reported point), so every reported
hand that differs is one move. A move is judged against the true hand nearest the filter's
estimate, if one lies within ``JUDGE_M``: *nearer* when the pulled point lies nearer to it.
Prints per take the moves judged, the share nearer and the median and mean gain (filter's
distance minus the pulled point's, mm). Unit tests check the pull's maths
(tests/tracking/test_blob_pull.py); this says whether it helps on a take.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from pipeline_bench import add_scene_arguments, render, scene_names

from surveil.activity import load_rules
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import Pipeline, load_pipeline_config

ROOT = Path(__file__).resolve().parents[1]
JUDGE_M = 0.1  # a move is judged against the true hand this near the filter's estimate


def move_gain_mm(before_m: np.ndarray, after_m: np.ndarray, hands_m: np.ndarray) -> float | None:
    """How much nearer (mm; negative: farther) the pulled point ``after_m`` lies than the
    filter's ``before_m`` to the true hand nearest ``before_m`` among ``hands_m`` ((H, 3), NaN
    rows for hands not in the room); None when none lies within ``JUDGE_M``.

    >>> hands = np.array([[0.0, 0, 1], [np.nan, np.nan, np.nan]])
    >>> move_gain_mm(np.array([0.05, 0, 1]), np.array([0.01, 0, 1]), hands)
    40.0
    >>> move_gain_mm(np.array([0.5, 0, 1]), np.array([0.0, 0, 1]), hands) is None
    True
    """
    d = np.linalg.norm(hands_m - before_m, axis=1)
    if np.all(np.isnan(d)):
        return None
    k = int(np.nanargmin(d))
    if d[k] >= JUDGE_M:
        return None
    return round(1000.0 * float(d[k] - np.linalg.norm(hands_m[k] - after_m)), 6)


def take_gains(rec_dir: Path, cfg, seed: int) -> np.ndarray:
    """Every judged move's gain (mm) over one take."""
    rec = open_recording(rec_dir)
    truth = load_ground_truth(rec_dir)
    hands = [i for i, label in enumerate(truth.labels) if label.endswith("hand")]
    no_pull = dataclasses.replace(cfg.tracking, blob_pull_sigma_px=0.0)
    off = dataclasses.replace(cfg, tracking=no_pull)
    rules = load_rules()
    pipes = [Pipeline(dataclasses.replace(c, seed=seed), rec.rig, rules) for c in (off, cfg)]
    gains = []
    for fs in rec.framesets():
        a, b = (p.step(fs) for p in pipes)
        true_hands = truth.positions_m[truth.frame_at(fs.t_ns), hands]
        for s, p in zip(a.track.targets, b.track.targets, strict=True):
            if not np.array_equal(s.mean_m, p.mean_m):
                gain = move_gain_mm(s.mean_m, p.mean_m, true_hands)
                if gain is not None:
                    gains.append(gain)
    return np.array(gains)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--config", type=Path, help="settings (default: the defaults)")
    parser.add_argument("--seed", type=int, default=0, help="tracker seed")
    args = parser.parse_args(argv)
    cfg = load_pipeline_config(args.config)
    if cfg.tracking.blob_pull_sigma_px <= 0:
        parser.error("the settings have the pull off ([tracking] blob_pull_sigma_px = 0)")
    print("| scenario | moves judged | nearer | median gain mm | mean gain mm |")
    print("|---|---|---|---|---|")
    for name in scene_names(args):
        gains = take_gains(render(name, args.out), cfg, args.seed)
        if not len(gains):
            print(f"| {name} | 0 | - | - | - |", flush=True)
            continue
        print(
            f"| {name} | {len(gains)} | {(gains > 0).mean():.3f} | {np.median(gains):+.1f} "
            f"| {gains.mean():+.1f} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
