"""Benchmark `surveil synth` on every bundled scenario: render speed and ground-truth quality.

    python benchmarks/synth_bench.py [--out out/bench_synth] [scenario.toml ...]

For each scenario it reports: frames, camera frames, render milliseconds per camera frame
(whole run, including video encoding and ground truth), the fraction of visible true hands
whose projection lands on a skin pixel of the rendered mask, the fraction of limb-frames
seen by two or more cameras, and the number of true events. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from surveil.eval.truth_checks import visible_hands_on_skin
from surveil.io.ground_truth import load_ground_truth
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    args = parser.parse_args(argv)
    scenarios = args.scenarios or sorted((ROOT / "recordings").glob("*.toml"))
    rows = []
    for path in scenarios:
        summary = synthesise(path, args.out / path.stem, overwrite=True)
        gt = load_ground_truth(args.out / path.stem)
        hits, total = visible_hands_on_skin(args.out / path.stem)
        two_views = float((gt.n_views >= 2).mean())
        ms = 1000 * summary.render_s / summary.n_camera_frames
        rows.append(
            (
                path.stem,
                summary.n_frames,
                len(summary.cameras),
                summary.n_camera_frames,
                ms,
                summary.render_s,
                hits / max(total, 1),
                total,
                two_views,
                len(summary.events),
            )
        )
        print(f"{path.stem}: {ms:.1f} ms per camera frame", file=sys.stderr)
    print(
        "| scenario | frame sets | cameras | camera frames | ms / camera frame | total s "
        "| visible hands on skin | hands checked | limb-frames in >= 2 views | events |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]:.1f} | {r[5]:.1f} | {r[6]:.3f} "
            f"| {r[7]} | {r[8]:.3f} | {r[9]} |"
        )
    med = float(np.median([r[4] for r in rows]))
    print(f"\nmedian {med:.1f} ms per 640x480 camera frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
