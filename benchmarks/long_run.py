"""Long-run benchmark: do people who stay in view for minutes stay in the foreground?

    python benchmarks/long_run.py [--out out/bench_synth] [--seed 0] [--window-s 15]

Renders (or reuses) ``benchmarks/scenarios/long_stay.toml`` (two people standing face to face
for 90 s, shaking hands and clapping now and then; not a bundled recording, so the other
benchmarks do not grow by it) and runs the whole pipeline on it twice: with the default
settings and with ``[background] protect_people = false`` (MOG2 learning the whole frame, as it
does by itself). For each run it prints, per time window, the fraction of the true person
pixels (ground-truth masks, every camera) inside the silhouettes, and then the run's tracking
recall, identity switches, events recognised and frame sets per second (wall clock, one
process).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np

from surveil.activity import load_rules
from surveil.eval.score import EvalConfig, evaluate
from surveil.io.ground_truth import GT_DIR
from surveil.io.mcap_writer import McapSink, McapWriter
from surveil.io.recording import open_recording
from surveil.pipeline import FrameResult, Pipeline, load_pipeline_config, run_recording
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "benchmarks" / "scenarios" / "long_stay.toml"


class ForegroundSink:
    """Per ground-truth mask: the fraction of true person pixels inside the silhouettes."""

    def __init__(self, rec_dir: Path, window_s: float) -> None:
        self.masks = rec_dir / GT_DIR / "masks"
        self.window_s = window_s
        self.found: dict[int, list[int]] = defaultdict(lambda: [0, 0])  # window -> [in, all]

    def write(self, result: FrameResult) -> None:
        fs = result.frameset
        for cam, obs in result.observations.items():
            path = self.masks / cam / f"{fs.index:06d}.png"
            if not path.exists():
                continue
            person = cv2.imread(str(path))[..., 1] > 0
            cell = self.found[int(fs.t_ns * 1e-9 // self.window_s)]
            cell[0] += int(np.count_nonzero(person & obs.silhouettes.mask))
            cell[1] += int(np.count_nonzero(person))

    def close(self) -> None:
        pass


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--window-s", type=float, default=15.0)
    args = parser.parse_args(argv)
    rec_dir = args.out / "long_stay"
    synthesise(SCENARIO, rec_dir)
    rec = open_recording(rec_dir)
    base = dataclasses.replace(load_pipeline_config(None), seed=args.seed)
    runs = {
        "protect_people (default)": base,
        "protect_people = false": dataclasses.replace(
            base, background=dataclasses.replace(base.background, protect_people=False)
        ),
    }
    rows, summaries = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, cfg in runs.items():
            mcap = Path(tmp) / "run.mcap"
            fg = ForegroundSink(rec_dir, args.window_s)
            sinks = [McapSink(McapWriter(mcap, rec.rig, start_time_ns=rec.start_time_ns)), fg]
            pipeline = Pipeline.for_recording(rec, cfg, load_rules())
            summary = run_recording(rec.framesets, rec.n_framesets, pipeline, sinks)
            report = evaluate(rec_dir, mcap, EvalConfig())
            rows[name] = fg.found
            summaries[name] = (report, summary)
    windows = sorted(set().union(*(r.keys() for r in rows.values())))
    print(
        "| setting | "
        + " | ".join(f"{w * args.window_s:.0f}-{(w + 1) * args.window_s:.0f} s" for w in windows)
        + " |"
    )
    print("|---|" + "---|" * len(windows))
    for name, found in rows.items():
        cells = [f"{found[w][0] / found[w][1]:.2f}" if found[w][1] else "-" for w in windows]
        print(f"| {name} | " + " | ".join(cells) + " |")
    print()
    print(
        "| setting | tracking recall | ID switches / min | events recognised | predicted "
        "| frame sets / s |"
    )
    print("|---|---|---|---|---|---|")
    for name, (report, summary) in summaries.items():
        t, e = report.targets, report.events
        print(
            f"| {name} | {t.recall:.3f} | {t.id_switches_per_min:.1f} | {e.n_matched} of "
            f"{e.n_true} | {e.n_pred} | {summary.n_framesets / summary.wall_s:.1f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
