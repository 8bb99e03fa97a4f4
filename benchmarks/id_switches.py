"""Every identity switch of a run, and what became of the tracker the limb had before.

    python benchmarks/id_switches.py [--out out/bench_synth] [--seed 0] [--rerun]
        [--config TOML] [--list] [NAME ...]

Reads ``out/bench_synth/<name>[.<config stem>].seed<N>.mcap`` (written by
``benchmarks/pipeline_bench.py``; run here when missing or with ``--rerun``) and the ground
truth, and sorts the switches that ``surveil eval`` counts
(:func:`surveil.eval.score.identity_switches`) by kind:

- ``not re-acquired``: the old tracker was lost (or retired) and a new tracker was started on
  the limb: the lost tracker did not find it again;
- ``taken over``: the old tracker was lost (or retired) and an older tracker, which had been
  following something else, took the limb;
- ``drifted``: the old tracker still runs but follows something else now (it slid onto
  another target, or two trackers swapped).

``--list`` prints every switch: time, true limb, old -> new tracker, how long the limb went
unmatched in between, the old tracker's phase then and the new tracker's age.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

from surveil.eval.score import EvalConfig, identity_switches
from surveil.io.ground_truth import load_ground_truth
from surveil.io.mcap_reader import read_run

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from pipeline_bench import add_run_arguments, print_kind_counts, run_of, scene_names  # noqa: E402

KINDS = ("not re-acquired", "taken over", "drifted")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser)
    parser.add_argument("--list", action="store_true", help="print every switch")
    args = parser.parse_args(argv)
    names = scene_names(args)
    rows, listing = [], []
    totals: Counter = Counter()
    for name in names:
        mcap = run_of(name, args)
        gt = load_ground_truth(args.out / name)
        switches = identity_switches(gt, read_run(mcap), EvalConfig())
        kinds = Counter(sw.kind for sw in switches)
        totals.update(kinds)
        counts = " | ".join(str(kinds[k]) for k in KINDS)
        rows.append(f"| {name} | {len(switches)} | {counts} |")
        listing += [
            f"| {name} | {sw.t_s:.2f} | {sw.limb} | t{sw.from_tracker} -> t{sw.to_tracker} "
            f"| {sw.unmatched_s:.2f} | {sw.from_phase} | {sw.to_age_s:.2f} | {sw.kind} |"
            for sw in sorted(switches, key=lambda sw: sw.t_s)
        ]
    print_kind_counts(
        "switches",
        KINDS,
        rows,
        totals,
        "scenario | t s | true limb | trackers | unmatched s | old phase | new age s | kind"
        if args.list
        else None,
        listing,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
