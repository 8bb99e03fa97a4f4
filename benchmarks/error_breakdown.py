"""Where a run's hand error comes from: the eval's matched hand-frames split by how many
cameras see the hand, by the tracker's phase, and by how near its nearest candidate was.

    python benchmarks/error_breakdown.py [--out out/bench_synth] [--seed N] [--config FILE]
        [--rerun] [--by-limb] [NAME ...]

Reads (or runs, as ``pipeline_bench.py`` does) each scene's output MCAP and matches it to
the ground truth exactly as ``surveil eval`` does (``surveil.eval.score``). Each row: the
matched hand-frames in that group, their share, mean and median 3-D error, mm, and the
group's share of the summed error. Views are the ground truth's unoccluded views; the
nearest candidate is the run's own ``/candidates`` of that frame set nearest the true hand.
``--by-limb`` adds a row per true hand.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from pipeline_bench import add_run_arguments, render, run_of, scene_names

from surveil.datatypes import Phase
from surveil.eval.score import EvalConfig, match_targets
from surveil.io.ground_truth import load_ground_truth
from surveil.io.mcap_reader import read_run


def nearest_candidate_mm(run, frame_rows: np.ndarray, truth_m: np.ndarray) -> np.ndarray:
    """(M,) distance from each true limb to the nearest candidate of its frame set, mm
    (inf where there is none)."""
    out = np.full(len(frame_rows), np.inf)
    by_time = {int(t): k for k, t in enumerate(run.candidate_t_ns)}
    for i, (f, truth) in enumerate(zip(frame_rows, truth_m, strict=True)):
        k = by_time.get(int(run.frame_t_ns[f]))
        if k is None:
            continue
        points = run.candidate_pos_m[run.candidate_frame == k]
        if len(points):
            out[i] = 1000 * np.linalg.norm(points - truth, axis=1).min()
    return out


def groups(
    rec_dir: Path, mcap: Path, by_limb: bool = False
) -> list[tuple[str, np.ndarray, np.ndarray]]:
    gt, run = load_ground_truth(rec_dir), read_run(mcap)
    m = match_targets(gt, run, EvalConfig())
    hand = np.array(["hand" in gt.labels[j] for j in m.true_idx], dtype=bool)
    truth = gt.positions_m[m.gt_frame, m.true_idx][hand]
    rows = m.pred_row[hand]
    err = 1000 * np.linalg.norm(run.target_pos_m[rows] - truth, axis=1)
    views = gt.n_views[m.gt_frame, m.true_idx][hand]
    state = run.target_state[rows]
    cand = nearest_candidate_mm(run, run.target_frame[rows], truth)
    out = [("all", err, np.ones(len(err), bool))]
    out += [(f"views {v}", err, views == v) for v in (0, 1)] + [("views >= 2", err, views >= 2)]
    out += [
        (f"phase {p.value}", err, state == p.code)
        for p in (Phase.UNLABELLED, Phase.NORMAL, Phase.COMBINED)
    ]
    out += [
        ("candidate <= 50 mm", err, cand <= 50),
        ("candidate 50-100 mm", err, (cand > 50) & (cand <= 100)),
        ("candidate > 100 mm", err, cand > 100),
    ]
    if by_limb:
        limbs = np.array([gt.labels[j] for j in m.true_idx[hand]])
        out += [(f"limb {label}", err, limbs == label) for label in sorted(set(limbs))]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser)
    parser.add_argument("--by-limb", action="store_true", help="also a row per true hand")
    args = parser.parse_args(argv)
    print("| scenario | hand-frames | n | share | mean mm | median mm | share of error |")
    print("|---|---|---|---|---|---|---|")
    for name in scene_names(args):
        rec_dir = render(name, args.out)
        parts = groups(rec_dir, run_of(name, args), args.by_limb)
        total = parts[0][1].sum()
        for what, err, sel in parts:
            if not sel.any():
                continue
            e = err[sel]
            print(
                f"| {name} | {what} | {sel.sum()} | {sel.mean():.2f} | {e.mean():.1f} | "
                f"{np.median(e):.1f} | {e.sum() / total:.2f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
