"""Benchmark the multi-target tracker on candidates made from synthetic ground truth.

    python benchmarks/tracking_bench.py [--out out/bench_synth] [--particles 50 100 200 500]
                                        [--seed 0] [NAME ...]

For every bundled scenario (rendered with ``surveil synth`` into ``--out`` if missing), each
frame set's candidates are made from the ground truth, not from images:

- every true head / hand seen by >= 2 cameras (two limbs closer than 8 cm count as one merged
  blob: they share their views) gives a candidate with probability 0.9
  (dropout 0.1), displaced by isotropic Gaussian noise of 3-D RMS drawn in [5, 15] mm, prior
  drawn in [0.5, 1.0]; with probability 0.3 a second, independently noisy candidate (another
  camera pair);
- Poisson(2) ghost candidates per frame set between two random true limbs (the triangulation
  of non-corresponding blobs lands near the segment joining them), 5 cm scatter, prior in
  [0.05, 0.35].

Reported per scenario and particle count: mean / median 3-D error (mm) of heads and hands
matched (Hungarian, gate 150 mm) to live trackers; recall (true limbs in >= 2 views matched);
false trackers per frame set (live, unmatched); limb-type accuracy (head vs hand, labelled
trackers); left / right accuracy (labelled hands); person accuracy (trackers' person numbers
mapped to true persons by majority); milliseconds per step (median, mean).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from surveil.datatypes import CandidateSet, Limb, Phase, parse_label
from surveil.io.calibration import load_rig
from surveil.io.ground_truth import load_ground_truth
from surveil.synth.scene import synthesise
from surveil.tracking import MultiTargetTracker, TrackingConfig
from surveil.tracking.settings import FilterConfig

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = (
    "clap",
    "handshake",
    "exchange",
    "self_exchange",
    "pick_place",
    "negative",
    "three_people",
    "demo",
)
GATE_M = 0.15
MERGE_M = 0.08


def merged_views(positions_m: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """(F, L) cameras that see each limb, where limbs closer than MERGE_M share their views.

    Two hands that touch hide each other in the ground truth's per-limb visibility, but their
    skin blobs merge into one blob that the cameras do see; the candidate stage then finds a
    point there."""
    d = np.linalg.norm(positions_m[:, :, None] - positions_m[:, None], axis=3)
    close = np.nan_to_num(d, nan=np.inf) < MERGE_M  # (F, L, L), diagonal true
    shared = np.einsum("flk,fkc->flc", close.astype(np.int32), visible.astype(np.int32)) > 0
    return shared.sum(axis=2)


def make_candidates(positions_m: np.ndarray, n_views: np.ndarray, rng: np.random.Generator):
    """Candidates of one frame set from the true limb positions (L, 3)."""
    pts, pri = [], []
    seen = np.flatnonzero((n_views >= 2) & np.isfinite(positions_m[:, 0]))
    for k in seen:
        if rng.random() < 0.1:
            continue
        for _ in range(2 if rng.random() < 0.3 else 1):
            rms = rng.uniform(0.005, 0.015)
            pts.append(positions_m[k] + rng.standard_normal(3) * rms / np.sqrt(3))
            pri.append(rng.uniform(0.5, 1.0))
    valid = np.flatnonzero(np.isfinite(positions_m[:, 0]))
    for _ in range(rng.poisson(2.0) if len(valid) >= 2 else 0):
        a, b = rng.choice(valid, 2, replace=False)
        u = rng.uniform(0.2, 0.8)
        pts.append(positions_m[a] + u * (positions_m[b] - positions_m[a]) + rng.normal(0, 0.05, 3))
        pri.append(rng.uniform(0.05, 0.35))
    if not pts:
        return CandidateSet.empty()
    return CandidateSet(np.array(pts), np.array(pri))


def run(rec_dir: Path, n_particles: int, seed: int) -> dict:
    gt = load_ground_truth(rec_dir)
    rig_path = rec_dir / "ground_truth" / "rig_true.yaml"
    rig = load_rig(rig_path)
    cfg = TrackingConfig(filter=FilterConfig(n_particles=n_particles))
    tracker = MultiTargetTracker(cfg, rig, seed=seed)
    rng = np.random.default_rng(seed + 1000)
    true_person, true_limb = zip(*(parse_label(lbl) for lbl in gt.labels), strict=True)
    n_views = merged_views(gt.positions_m, gt.visible)
    errs: dict[str, list[float]] = defaultdict(list)
    eligible = matched = false = 0
    type_ok = type_n = lr_ok = lr_n = 0
    person_votes: dict[int, Counter] = defaultdict(Counter)
    times = []
    for f in range(len(gt.frames)):
        cands = make_candidates(gt.positions_m[f], n_views[f], rng)
        t0 = time.perf_counter()
        out = tracker.step(int(gt.t_ns[f]), cands)
        times.append((time.perf_counter() - t0) * 1e3)
        live = [s for s in out.targets if s.phase is not Phase.LOST]
        truth = np.flatnonzero(n_views[f] >= 2)
        eligible += len(truth)
        if not live or not len(truth):
            false += len(live)
            continue
        est = np.array([s.mean_m for s in live])
        d = np.linalg.norm(gt.positions_m[f, truth][:, None] - est[None], axis=2)
        rows, cols = linear_sum_assignment(np.where(d <= GATE_M, d, 1e6))
        ok = d[rows, cols] <= GATE_M
        matched += int(ok.sum())
        false += len(live) - int(ok.sum())
        for r, c in zip(rows[ok], cols[ok], strict=True):
            k, s = truth[r], live[c]
            kind = "head" if true_limb[k] is Limb.HEAD else "hand"
            errs[kind].append(d[r, c] * 1e3)
            if s.limb is not Limb.UNKNOWN:
                type_n += 1
                type_ok += (s.limb is Limb.HEAD) == (true_limb[k] is Limb.HEAD)
                if s.limb.is_hand and true_limb[k].is_hand:
                    lr_n += 1
                    lr_ok += s.limb is true_limb[k]
            if s.person > 0:
                person_votes[s.person][true_person[k]] += 1
    person_n = sum(sum(c.values()) for c in person_votes.values())
    person_ok = sum(c.most_common(1)[0][1] for c in person_votes.values())
    frames = len(gt.frames)
    return {
        "head_mean": np.mean(errs["head"]) if errs["head"] else np.nan,
        "head_median": np.median(errs["head"]) if errs["head"] else np.nan,
        "hand_mean": np.mean(errs["hand"]) if errs["hand"] else np.nan,
        "hand_median": np.median(errs["hand"]) if errs["hand"] else np.nan,
        "recall": matched / max(eligible, 1),
        "false": false / frames,
        "type_acc": type_ok / max(type_n, 1),
        "lr_acc": lr_ok / max(lr_n, 1),
        "person_acc": person_ok / max(person_n, 1),
        "ms_median": float(np.median(times[1:])),
        "ms_mean": float(np.mean(times[1:])),
        "persons": len(person_votes),
        "true_persons": len(set(true_person)),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("names", nargs="*", default=list(SCENARIOS))
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench_tracking")
    ap.add_argument("--particles", type=int, nargs="+", default=[50, 100, 200, 500])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    cols = (
        "scenario | N | head mean/median mm | hand mean/median mm | recall | false / set | "
        "type acc | L/R acc | person acc | persons (true) | ms/step median (mean)"
    )
    print("| " + cols + " |")
    print("|" + "---|" * (cols.count("|") + 1))
    for name in args.names:
        rec = args.out / name
        if not (rec / "ground_truth" / "scene.json").is_file():
            synthesise(ROOT / "recordings" / f"{name}.toml", rec)
        for n in args.particles:
            r = run(rec, n, args.seed)
            print(
                f"| {name} | {n} | {r['head_mean']:.0f} / {r['head_median']:.0f} | "
                f"{r['hand_mean']:.0f} / {r['hand_median']:.0f} | {r['recall']:.3f} | "
                f"{r['false']:.2f} | {r['type_acc']:.3f} | {r['lr_acc']:.3f} | "
                f"{r['person_acc']:.3f} | {r['persons']} ({r['true_persons']}) | "
                f"{r['ms_median']:.2f} ({r['ms_mean']:.2f}) |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
