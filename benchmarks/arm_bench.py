"""Arm trackers against the ground truth: hand, elbow and facing errors, by hand visibility.

    python benchmarks/arm_bench.py [--out out/bench_synth] [--seed 0] [--config X.toml]
        [--max-frames N] [NAME ...]

Runs the pipeline with the arm trackers on (``[arms] enabled = true`` added to ``--config``)
over each scenario (default: self_exchange, pick_place, three_people, demo) and compares
every ``ArmPose`` with the true joints (``ground_truth/joints.csv``, ``limbs.csv``,
``facing.csv``). A tracked person is matched per frame set to the true person whose head
is nearest its head (within 0.3 m). Hands are split by how many cameras see the true hand:
"< 2 views" is where the 3D tracker has no candidate to follow (paper 004's lost state),
which the arm model exists for. For the same hands, "3D tracker" is the error of that
person's hand target of the same side (any state; absent targets count as missing).

"either side" is the arm model's hand of either arm that is nearer the true hand: where it is
much below the side's own error, the left/right assignment (or the 3D tracker's labels the
arms are pulled to) is at fault, not the position.

Figures: median / mean error in mm, and coverage (share of the true hand-frames, of people
present and matched, that have an estimate).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from surveil.activity import load_rules
from surveil.datatypes import Limb, Phase
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import Pipeline, load_pipeline_config
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]
SIDES = ("left", "right")
DEFAULT_NAMES = ("self_exchange", "pick_place", "three_people", "demo")


def _stat(errors: list[float], scale: float = 1000.0) -> str:
    """median / mean of ``errors`` times ``scale`` (metres to mm by default)."""
    if not errors:
        return "-"
    e = scale * np.asarray(errors)
    return f"{np.median(e):.0f} / {np.mean(e):.0f}"


def bench(name: str, out_dir: Path, seed: int, config: Path | None, max_frames: int) -> dict:
    rec_dir = out_dir / name
    synthesise(ROOT / "recordings" / f"{name}.toml", rec_dir)
    gt = load_ground_truth(rec_dir)
    if not gt.joint_labels:
        raise SystemExit(
            f"{rec_dir}: ground truth has no joints.csv; re-render it "
            f"(surveil synth recordings/{name}.toml --out {rec_dir} --force)"
        )
    rec = open_recording(rec_dir)
    cfg = load_pipeline_config(config)
    cfg = dataclasses.replace(cfg, seed=seed, arms=dataclasses.replace(cfg.arms, enabled=True))
    pipeline = Pipeline.for_recording(rec, cfg, load_rules())
    frame_of = {int(f): i for i, f in enumerate(gt.frames)}
    persons = sorted({lab.split("/")[0] for lab in gt.labels})
    head_j = [gt.labels.index(f"{p}/head") for p in persons]
    rows: dict[str, list[float]] = {
        k: []
        for k in (
            "arm_lt2",
            "arm_ge2",
            "trk_lt2",
            "trk_ge2",
            "elbow",
            "facing_deg",
            "fused_lt2",
            "either_lt2",
            "either_ge2",
        )
    }
    counts = {"lt2": 0, "ge2": 0, "arm_lt2": 0, "trk_lt2": 0, "arm_ge2": 0, "trk_ge2": 0}
    ms = []
    for k, fs in enumerate(rec.framesets()):
        if max_frames and k >= max_frames:
            break
        result = pipeline.step(fs)
        if "arms" in result.timings_ms:
            ms.append(result.timings_ms["arms"])
        f = frame_of.get(int(fs.index))
        if f is None:
            continue
        true_heads = gt.positions_m[f, head_j]  # (P, 3)
        targets = result.track.targets
        for arm in result.arms:
            head = next(
                (t.mean_m for t in targets if t.person == arm.person and t.limb is Limb.HEAD),
                None,
            )
            if head is None or not np.isfinite(true_heads).any():
                continue
            d = np.linalg.norm(true_heads - head, axis=1)
            d[~np.isfinite(d)] = np.inf
            p = int(np.argmin(d))
            if d[p] > 0.3:
                continue
            pid = persons[p]
            yaw = gt.facing_yaw_rad[f, gt.persons.index(pid)]
            if np.isfinite(yaw):
                diff = np.angle(np.exp(1j * (arm.facing_rad - yaw)))
                rows["facing_deg"].append(abs(np.degrees(diff)))
            for s, side in enumerate(SIDES):
                j = gt.labels.index(f"{pid}/{side}_hand")
                true_hand = gt.positions_m[f, j]
                if not np.isfinite(true_hand).all():
                    continue
                views = int(gt.visible[f, j].sum())
                key = "lt2" if views < 2 else "ge2"
                counts[key] += 1
                e_arm = float(np.linalg.norm(arm.hands_m[s] - true_hand))
                rows[f"arm_{key}"].append(e_arm)
                e_other = float(np.linalg.norm(arm.hands_m[1 - s] - true_hand))
                rows[f"either_{key}"].append(min(e_arm, e_other))
                counts[f"arm_{key}"] += 1
                limb = Limb.LEFT_HAND if s == 0 else Limb.RIGHT_HAND
                trk = next((t for t in targets if t.person == arm.person and t.limb is limb), None)
                if trk is not None:
                    rows[f"trk_{key}"].append(float(np.linalg.norm(trk.mean_m - true_hand)))
                    counts[f"trk_{key}"] += 1
                if key == "lt2":
                    use_trk = trk is not None and trk.phase is Phase.NORMAL
                    rows["fused_lt2"].append(
                        float(np.linalg.norm(trk.mean_m - true_hand)) if use_trk else e_arm
                    )
                je = gt.joint_labels.index(f"{pid}/{side}_elbow")
                true_elbow = gt.joint_positions_m[f, je]
                if np.isfinite(true_elbow).all():
                    rows["elbow"].append(float(np.linalg.norm(arm.elbows_m[s] - true_elbow)))
    return {"rows": rows, "counts": counts, "ms": float(np.median(ms)) if ms else 0.0}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML)")
    parser.add_argument("--max-frames", type=int, default=0)
    args = parser.parse_args(argv)
    print(
        "| scenario | hand < 2 views: arm mm | coverage | 3D tracker mm | coverage "
        "| arm else tracker mm | arm, either side | hand >= 2 views: arm mm | 3D tracker mm "
        "| arm, either side | elbow mm "
        "| facing deg | arms ms / set |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.names or DEFAULT_NAMES:
        r = bench(name, args.out, args.seed, args.config, args.max_frames)
        rows, c = r["rows"], r["counts"]

        def cov(key: str, total: str, c=c) -> str:
            return f"{c[key] / c[total]:.2f}" if c[total] else "-"

        print(
            f"| {name} | {_stat(rows['arm_lt2'])} | {cov('arm_lt2', 'lt2')} "
            f"| {_stat(rows['trk_lt2'])} | {cov('trk_lt2', 'lt2')} | {_stat(rows['fused_lt2'])} "
            f"| {_stat(rows['either_lt2'])} | {_stat(rows['arm_ge2'])} | {_stat(rows['trk_ge2'])} "
            f"| {_stat(rows['either_ge2'])} | {_stat(rows['elbow'])} "
            f"| {_stat(rows['facing_deg'], 1.0)} | {r['ms']:.1f} |",
            flush=True,
        )
        print(f"  hand-frames: < 2 views {c['lt2']}, >= 2 views {c['ge2']}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
