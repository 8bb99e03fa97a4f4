"""The 3D tracker's facing estimate against the ground truth, per scene.

    python benchmarks/facing_bench.py [--out out/bench_synth] [--seed 0] [--config X.toml]
        [NAME ...]

Left and right hands are told apart by each person's accumulated facing evidence
(docs/tracking.md, "Left and right"), and a hand tracker on the wrong side of the body may
not take a slot (``contest_side_m``): both act only as well as that direction is right.
Per frame set after the learning phase, every tracked person whose head target lies within
0.3 m of a true head is compared with that person's body facing (``ground_truth/facing.csv``):
the angle between the accumulated evidence and the truth. Rows: person-frames matched, the
share of them with evidence at or above ``facing_min`` (where the sides are decided by it),
and of those the median and 90th percentile angle error and the share within 45 and 90
degrees (beyond 90, left and right come out swapped).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from surveil.activity import load_rules
from surveil.datatypes import Limb
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import Pipeline, load_pipeline_config
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]


def facing_errors_deg(
    name: str, out_dir: Path, seed: int, config: Path | None
) -> tuple[int, np.ndarray]:
    """(person-frames matched, angle errors in degrees of those with decided facing)."""
    rec_dir = out_dir / name
    synthesise(ROOT / "recordings" / f"{name}.toml", rec_dir)
    gt = load_ground_truth(rec_dir)
    rec = open_recording(rec_dir)
    cfg = dataclasses.replace(load_pipeline_config(config), seed=seed)
    pipeline = Pipeline.for_recording(rec, cfg, load_rules(None))
    facing_min = cfg.tracking.labelling.facing_min
    head_j = [gt.labels.index(f"{p}/head") for p in gt.persons]
    frame_of = {int(i): f for f, i in enumerate(gt.frames)}
    matched, errors = 0, []
    for fs in rec.framesets():
        result = pipeline.step(fs)
        f = frame_of.get(int(fs.index))
        if f is None or any(bg.learning for bg in pipeline.backgrounds.values()):
            continue
        true_heads = gt.positions_m[f, head_j]
        for t in result.track.targets:
            if t.limb is not Limb.HEAD or t.person <= 0:
                continue
            d = np.linalg.norm(true_heads - t.mean_m, axis=1)
            d[~np.isfinite(d)] = np.inf
            p = int(np.argmin(d))
            yaw = gt.facing_yaw_rad[f, p]
            if d[p] > 0.3 or not np.isfinite(yaw):
                continue
            matched += 1
            ev = pipeline.tracker.person_facing(t.person)
            if ev is None or np.linalg.norm(ev) < facing_min:
                continue
            diff = np.angle(np.exp(1j * (np.arctan2(ev[1], ev[0]) - yaw)))
            errors.append(abs(np.degrees(diff)))
    return matched, np.asarray(errors)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--config", type=Path, default=None, help="pipeline settings (TOML)")
    args = ap.parse_args(argv)
    print(
        "| scenario | person-frames | decided | median deg | p90 deg | within 45 deg | "
        "within 90 deg |"
    )
    print("|---|---|---|---|---|---|---|")
    names = args.names or sorted(p.stem for p in (ROOT / "recordings").glob("*.toml"))
    for name in names:
        matched, err = facing_errors_deg(name, args.out, args.seed, args.config)
        if not len(err):
            print(f"| {name} | {matched} | 0.00 | - | - | - | - |")
            continue
        print(
            f"| {name} | {matched} | {len(err) / max(matched, 1):.2f} | {np.median(err):.0f} | "
            f"{np.percentile(err, 90):.0f} | {np.mean(err <= 45):.2f} | {np.mean(err <= 90):.2f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
