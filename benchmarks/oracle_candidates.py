"""How far tracking, labelling and the events get when the candidate stage is near perfect:
the whole pipeline, with the 3-D candidates of every frame set made from the ground truth.

    python benchmarks/oracle_candidates.py [--out out/bench_synth] [--seed 0] [--rerun]
        [--config TOML] [NAME ...]

Each scene runs twice, with the same settings and tracker seed:

- **images**: the pipeline as ``surveil run`` runs it (``pipeline_bench.py``'s run, reused
  when it exists);
- **oracle**: the same pipeline (background, skin, blobs, labelling cues, carry, activity
  rules all from the images), but the candidate stage's output replaced by candidates made
  from the true limb positions as ``tracking_bench.py`` makes them: each true head or hand
  seen by >= 2 cameras (touching limbs share their views, as merged blobs do) gets a
  candidate with probability 0.9, 5-15 mm RMS noise, prior 0.5-1.0 (30 % get a second one),
  plus Poisson(2) ghosts per frame set between two true limbs with prior 0.05-0.35.

Both are scored by ``surveil eval``. The difference is what the candidate stage (issue 3)
costs the tracks and the events (issues 4, 5); what the oracle run still misses is the
tracker's, the labelling's, the carry stage's and the rules' own share. The oracle's output
goes to ``<name>.oracle[.<config stem>].seed<N>.mcap``.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from pipeline_bench import add_run_arguments, cell, render, run_of, run_to, scene_names
from tracking_bench import make_candidates as truth_candidates
from tracking_bench import merged_views

import surveil.pipeline as pipeline_module
from surveil.eval.score import EvalConfig, EvalReport, evaluate
from surveil.io.ground_truth import load_ground_truth
from surveil.pipeline import Pipeline


@contextlib.contextmanager
def candidates_from_truth(rec_dir: Path, pipeline: Pipeline, seed: int) -> Iterator[None]:
    """Within the block, ``pipeline``'s candidate stage returns candidates made from the
    ground truth of the frame set it is processing (the front end still runs: its
    silhouettes and blobs feed the labelling cues and the carry stage)."""
    gt = load_ground_truth(rec_dir)
    n_views = merged_views(gt.positions_m, gt.visible)
    rng = np.random.default_rng(seed + 1000)
    current = {"index": -1, "calls": 0}
    step, make = Pipeline.step, pipeline_module.make_candidates

    def step_noting_the_frame_set(self, fs):
        current["index"] = fs.index
        return step(self, fs)

    def from_truth(*_args, **_kwargs):
        current["calls"] += 1
        i = int(np.searchsorted(gt.frames, current["index"]))
        if i >= len(gt.frames) or gt.frames[i] != current["index"]:
            raise RuntimeError(
                f"{rec_dir}: frame set {current['index']} has no ground truth; the oracle "
                "needs a position for every frame set (render the scene again)"
            )
        return truth_candidates(gt.positions_m[i], n_views[i], rng)

    pipeline.step = step_noting_the_frame_set.__get__(pipeline)
    pipeline_module.make_candidates = from_truth
    try:
        yield
    finally:
        pipeline_module.make_candidates = make
        del pipeline.step
    if current["index"] >= 0 and current["calls"] == 0:
        raise RuntimeError(
            "the pipeline never called surveil.pipeline.make_candidates: the oracle replaced "
            "nothing (update this script to where the candidate stage is called now)"
        )


def oracle_path(out_dir: Path, name: str, config: Path | None, seed: int) -> Path:
    stem = f"{name}.oracle" + (f".{config.stem}" if config else "")
    return out_dir / f"{stem}.seed{seed}.mcap"


def run_oracle(name: str, args: argparse.Namespace) -> Path:
    """The oracle run of ``name``, made first when missing or ``--rerun`` asks."""
    mcap = oracle_path(args.out, name, args.config, args.seed)
    if mcap.exists() and not args.rerun:
        return mcap
    rec_dir = render(name, args.out)
    run_to(
        rec_dir,
        mcap,
        args.seed,
        args.config,
        around=lambda pipeline: candidates_from_truth(rec_dir, pipeline, args.seed),
    )
    return mcap


def row(name: str, kind: str, report: EvalReport) -> str:
    t, e = report.targets, report.events
    return (
        f"| {name} | {kind} | {cell(t.recall)} | {cell(t.head_error_mm_mean, 0)} "
        f"| {cell(t.hand_error_mm_mean, 0)} | {cell(t.false_targets_per_frame, 2)} "
        f"| {cell(t.left_right_accuracy)} | {t.id_switches} | {cell(t.id_switches_per_min, 1)} "
        f"| {e.n_matched} / {e.n_true} | {e.n_pred - e.n_matched} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    print(
        "| scene | candidates | recall | head mm | hand mm | false / frame | left/right "
        "| switches | per min | events matched / true | false events |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in scene_names(args):
        rec_dir = render(name, args.out)
        for kind, mcap in (("images", run_of(name, args)), ("oracle", run_oracle(name, args))):
            print(row(name, kind, evaluate(rec_dir, mcap, EvalConfig())), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
