"""How much the event scores move with the particle filters' seed alone (issues 4, 5).

    python benchmarks/seed_spread.py [--seeds 0-5] [--out out/bench_synth] [--config TOML]
        [NAME ...]

The recordings stay the same; only the pipeline's seed (the particles' random draws)
changes. Decisions in the tracker (combine, lose, re-acquire) sit on thresholds, so a
perturbation as small as another seed, or a code change that moves a number in the fifth
digit, can flip an event. Judge a change by its totals over several seeds against this
spread, not by one seed. Runs `pipeline_bench.bench` per scenario and seed (about 3-4 minutes
per seed for the eight scenes on one core) and prints:

- per seed: events recognised, predicted, false (predicted - recognised), F1;
- the mean and standard deviation of those over the seeds;
- per scenario and activity: recognised and false summed over the seeds, out of
  true x seeds;
- per scenario, the tracking figures of issue 4 averaged over the seeds (recall, mean hand
  error, false targets per frame, left/right accuracy, label accuracy, identity switches per
  minute): one seed's switches move by a whole switch (4 per minute in a 15 s scene) on a
  coin flip.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import numpy as np
from pipeline_bench import ROOT, add_scene_arguments, bench, parse_seeds, scene_names


def f1(matched: int, n_true: int, n_pred: int) -> float:
    return 2 * matched / (n_true + n_pred) if n_true + n_pred else 0.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--seeds", type=parse_seeds, default=parse_seeds("0-5"))
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument(
        "--config", type=Path, help="pipeline settings (TOML); output <name>.<stem>.seed<N>.mcap"
    )
    args = parser.parse_args(argv)
    names = scene_names(args)
    per_seed: list[tuple[int, int, int, int]] = []  # seed, true, predicted, matched
    by_activity: dict[tuple[str, str], list[int]] = {}  # true, predicted, matched summed
    tracking: dict[str, list[tuple[float, ...]]] = {}  # per scenario, one row per seed
    for seed in args.seeds:
        n_true = n_pred = n_matched = 0
        for name in names:
            report, _, _ = bench(name, args.out, seed, args.config)
            e, t = report.events, report.targets
            tracking.setdefault(name, []).append(
                tuple(
                    np.nan if v is None else v
                    for v in (
                        t.recall,
                        t.hand_error_mm_mean,
                        t.false_targets_per_frame,
                        t.left_right_accuracy,
                        t.label_accuracy,
                        t.id_switches_per_min,
                    )
                )
            )
            n_true += e.n_true
            n_pred += e.n_pred
            n_matched += e.n_matched
            for a in e.activities:
                if a.n_true or a.n_pred:
                    row = by_activity.setdefault((name, a.activity), [0, 0, 0])
                    row[0] += a.n_true
                    row[1] += a.n_pred
                    row[2] += a.n_matched
        per_seed.append((seed, n_true, n_pred, n_matched))
        print(
            f"seed {seed}: {n_matched} of {n_true} recognised, {n_pred} predicted",
            file=sys.stderr,
            flush=True,
        )
    print("| seed | recognised | predicted | false | F1 |")
    print("|---|---|---|---|---|")
    for seed, n_true, n_pred, matched in per_seed:
        print(
            f"| {seed} | {matched} / {n_true} | {n_pred} | {n_pred - matched} "
            f"| {f1(matched, n_true, n_pred):.3f} |"
        )
    columns = {
        "recognised": [m for _, _, _, m in per_seed],
        "predicted": [p for _, _, p, _ in per_seed],
        "false": [p - m for _, _, p, m in per_seed],
        "F1": [f1(m, t, p) for _, t, p, m in per_seed],
    }
    spread = ", ".join(
        f"{key} {statistics.mean(v):.2f} +- {statistics.stdev(v) if len(v) > 1 else 0.0:.2f}"
        for key, v in columns.items()
    )
    total_true = sum(t for _, t, _, _ in per_seed)
    total_matched = sum(columns["recognised"])
    total_pred = sum(columns["predicted"])
    print()
    print(
        f"Over {len(per_seed)} seeds: {total_matched} of {total_true} recognised, "
        f"{total_pred} predicted (F1 {f1(total_matched, total_true, total_pred):.3f}); "
        f"per seed mean +- sd: {spread}."
    )
    print()
    print("| scenario | activity | recognised / true, all seeds | false, all seeds |")
    print("|---|---|---|---|")
    for (name, activity), (n_true, n_pred, matched) in sorted(by_activity.items()):
        print(f"| {name} | {activity} | {matched} / {n_true} | {n_pred - matched} |")
    print()
    print(
        "| scenario, mean over seeds | recall | hand mm | false / frame | left/right "
        "| label acc | ID switches / min |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, rows in tracking.items():
        r, hand, false, lr, la, sw = np.nanmean(np.array(rows, dtype=float), axis=0)
        print(f"| {name} | {r:.3f} | {hand:.0f} | {false:.2f} | {lr:.3f} | {la:.3f} | {sw:.1f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
