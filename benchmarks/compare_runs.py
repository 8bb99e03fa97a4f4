"""Two sets of runs side by side, per scene and seed: events matched and false, identity
switches, head and hand error, false targets per frame.

    python benchmarks/compare_runs.py --a CONFIG_A[,CONFIG_A2] --b CONFIG_B[,CONFIG_B2]
        [--seeds 0-5] [--out out/bench_synth] [--out-b DIR] [--all] [NAME ...]

Reads the MCAPs that ``seed_spread.py --config FILE`` (or ``pipeline_bench.py``) wrote:
``<name>.<stem>.seed<N>.mcap`` for each config file's stem; ``-`` stands for the default
settings (``<name>.seed<N>.mcap``). Several configs for one side are read in turn, the first
that has a run of a scene and seed counting: the usual way to compare a change is two
frozen worktrees, each running ``seed_spread.py --seeds 0-2`` and ``--seeds 3-5`` in
parallel under two config names (which may hold nothing but a comment), and this script
then sees both halves as one side. Nothing is run here.

``--out-b`` reads side B from another folder (e.g. the recordings with per-camera skin
models that ``camera_skin_models.py`` makes).

Prints the rows that differ (``--all``: every row), the totals of each side, and how far
B's events (matched minus false, per run) and identity switches can be told from A's over
paired runs: a bootstrap interval of the total difference and a sign test
(:mod:`surveil.eval.paired`); then, per scene, each side's means over the seeds of tracking
recall, head and hand error, false targets per frame and label accuracy. Scenes and seeds
where either side has no run are skipped and counted.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from pipeline_bench import (  # noqa: E402
    add_scene_arguments,
    output_path,
    parse_seeds,
    scene_names,
)

from surveil.eval.paired import paired_difference  # noqa: E402
from surveil.eval.score import EvalConfig, evaluate  # noqa: E402

COLUMNS = ("matched", "false", "switches", "head mm", "hand mm", "false / frame")
MEANS = ("recall", "head mm", "hand mm", "false / frame", "label acc")


def _configs(text: str) -> list[Path | None]:
    return [None if part == "-" else Path(part) for part in text.split(",")]


def _run(out: Path, name: str, configs: list[Path | None], seed: int) -> Path | None:
    for config in configs:
        mcap = output_path(out, name, config, seed)
        if mcap.exists():
            return mcap
    return None


@dataclass
class Pooled:
    """Issue 5's event figures pooled over runs: every matched event's climax error (ms) and
    the exchanges with a true direction, and how many of those were right."""

    climax_errors_ms: list[float] = field(default_factory=list)
    n_direction: int = 0
    n_direction_right: int = 0

    def add(self, other: Pooled) -> None:
        self.climax_errors_ms += other.climax_errors_ms
        self.n_direction += other.n_direction
        self.n_direction_right += other.n_direction_right

    def summary(self) -> str:
        errs = self.climax_errors_ms
        median = f"{statistics.median(errs):.0f} ms" if errs else "-"
        return (
            f"median climax error {median} over {len(errs)} matched events, exchange "
            f"direction right in {self.n_direction_right} of {self.n_direction}"
        )


def scores(out: Path, name: str, mcap: Path) -> tuple[tuple, Pooled]:
    """(events matched, false events, identity switches, mean head error mm, mean hand error
    mm, false targets per frame, tracking recall, label accuracy) of one run, and its matched
    events' climax errors and exchange directions."""
    report = evaluate(out / name, mcap, EvalConfig())
    e, t = report.events, report.targets
    row = (
        e.n_matched,
        e.n_pred - e.n_matched,
        t.id_switches,
        t.head_error_mm_mean or float("nan"),
        t.hand_error_mm_mean or float("nan"),
        t.false_targets_per_frame or 0.0,
        t.recall or 0.0,
        t.label_accuracy or 0.0,
    )
    pooled = Pooled(
        [x for a in e.activities for x in a.climax_errors_ms],
        sum(a.n_direction for a in e.activities),
        sum(a.n_direction_right for a in e.activities),
    )
    return row, pooled


def _cells(row: tuple) -> str:
    return f"{row[0]} | {row[1]} | {row[2]} | {row[3]:.0f} | {row[4]:.0f} | {row[5]:.2f}"


def _means(rows: list[tuple]) -> str:
    """Cells of MEANS: the mean over runs of recall, head and hand error, false per frame,
    label accuracy."""
    m = np.nanmean(np.array([(r[6], r[3], r[4], r[5], r[7]) for r in rows], dtype=float), axis=0)
    return f"{m[0]:.3f} | {m[1]:.1f} | {m[2]:.1f} | {m[3]:.2f} | {m[4]:.3f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--a", required=True, help="config file(s) of side A, comma-separated")
    parser.add_argument("--b", required=True, help="config file(s) of side B, comma-separated")
    parser.add_argument("--seeds", type=parse_seeds, default=parse_seeds("0-5"))
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--out-b", type=Path, help="side B's folder (default: --out)")
    parser.add_argument("--all", action="store_true", help="print rows that agree too")
    args = parser.parse_args(argv)
    outs = (args.out, args.out_b or args.out)
    sides = (_configs(args.a), _configs(args.b))
    counts: list[list[tuple]] = [[], []]  # per side, per run: matched, false, switches
    pooled = [Pooled(), Pooled()]
    skipped = 0
    by_scene: dict[str, tuple[list[tuple], list[tuple]]] = {}
    head = " | ".join(COLUMNS)
    print(f"| scene | seed | A: {head} | B: {head} |")
    print("|---|---|" + "---|" * (2 * len(COLUMNS)))
    for name in scene_names(args):
        for seed in args.seeds:
            runs = [
                _run(out, name, configs, seed) for out, configs in zip(outs, sides, strict=True)
            ]
            if None in runs:
                skipped += 1
                continue
            (a, pa), (b, pb) = (
                scores(out, name, mcap) for out, mcap in zip(outs, runs, strict=True)
            )
            counts[0].append(a[:3])
            counts[1].append(b[:3])
            scene = by_scene.setdefault(name, ([], []))
            scene[0].append(a)
            scene[1].append(b)
            pooled[0].add(pa)
            pooled[1].add(pb)
            if args.all or a[:3] != b[:3]:
                print(f"| {name} | {seed} | {_cells(a)} | {_cells(b)} |")
    a_runs, b_runs = (np.array(side, dtype=np.int64).reshape(-1, 3) for side in counts)
    for label, runs, pool in zip("AB", (a_runs, b_runs), pooled, strict=True):
        matched, false, switches = runs.sum(axis=0).tolist()
        print(
            f"{label}: {matched} events matched, {false} false, {switches} identity switches; "
            + pool.summary()
        )
    if len(a_runs):
        diff = paired_difference(a_runs[:, 0] - a_runs[:, 1], b_runs[:, 0] - b_runs[:, 1])
        print(diff.summary("events matched minus false"))
        print(paired_difference(a_runs[:, 2], b_runs[:, 2]).summary("identity switches"))
    if by_scene:
        cols = " | ".join(MEANS)
        print(f"\n| scene, mean over seeds | A: {cols} | B: {cols} |")
        print("|---|" + "---|" * (2 * len(MEANS)))
        for name, (a_rows, b_rows) in by_scene.items():
            print(f"| {name} | {_means(a_rows)} | {_means(b_rows)} |")
    if skipped:
        print(f"{skipped} scene and seed pairs skipped: a side has no run of them")
    return 0


if __name__ == "__main__":
    sys.exit(main())
