"""Benchmark the per-camera observations and 3D candidates (issue 3) on synthetic recordings.

    python benchmarks/candidates_bench.py [--out out/bench_synth] [--max-frames N] [--config TOML]
        [NAME ...]

Renders (or reuses) every bundled scenario, runs background subtraction, skin
classification, blob extraction and candidate generation with the default settings on the
recording's own (slightly wrong) calibration, and reports against the ground truth:

- candidate recall: fraction of true heads and hands seen by >= 2 cameras with a candidate
  within 50 mm and within 100 mm;
- false candidates per frame set: candidates farther than 100 mm from every true limb;
- mean distance of the candidates matched to true limbs (nearest within 100 mm), mm;
- skin pixel precision and recall against the ground-truth masks (frames with masks);
- milliseconds per camera frame for background, skin, blobs and the silhouettes' crowns,
  and per frame set for candidates (medians). Skin is classified only near the silhouettes
  and their distances capped, as in a run (since session 70; before, skin was classified
  over the whole frame, which timed skin at about 1.8 ms per camera frame where a run spends
  about 0.3-0.5).

The front end here has no tracker, so it chooses blobs for N_h = each view's own silhouette
count; where people merge into one silhouette in a view, that view keeps too few blobs.
``--in-run`` adds a second table scored the same way on the candidates a run of
``surveil run`` wrote (``/candidates`` of ``pipeline_bench.py``'s MCAP for ``--seed``, run
first when missing or with ``--rerun``): there N_h is also the tracked heads, and the
trackers' predictions feed back into the background model and the explaining away.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from front_end import observe_recording
from pipeline_bench import add_scene_arguments, render, run_of, scene_names

from surveil.eval.score import align_frames
from surveil.io.ground_truth import MaskClass, load_ground_truth
from surveil.io.mcap_reader import read_run
from surveil.io.recording import open_recording
from surveil.pipeline import PipelineConfig, load_pipeline_config
from surveil.recon.candidates import make_candidates

ROOT = Path(__file__).resolve().parents[1]


class CandidateScore:
    """Candidates against the true heads and hands, accumulated over frame sets."""

    def __init__(self) -> None:
        self.found50 = self.found100 = self.countable = self.false = self.n_sets = 0
        self.dists: list[float] = []
        # per true limb (index into the ground truth's labels): the offset, m, of the
        # nearest candidate in each frame set that two or more views see it (NaN: none)
        self.offsets: dict[int, list[np.ndarray]] = {}

    def add(self, points_m: np.ndarray, truth_m: np.ndarray, n_views: np.ndarray) -> None:
        """One frame set: candidates (K, 3) and every true limb's position (L, 3; NaN where
        absent) and number of cameras that see it (L,)."""
        self.n_sets += 1
        present = np.isfinite(truth_m).all(axis=1)
        seen2 = present & (n_views >= 2)
        self.countable += int(seen2.sum())
        for j in np.flatnonzero(seen2):
            off = points_m - truth_m[j] if len(points_m) else np.full((1, 3), np.nan)
            nearest = off[int(np.argmin(np.linalg.norm(off, axis=1)))] if len(points_m) else off[0]
            self.offsets.setdefault(int(j), []).append(nearest)
        if not len(points_m):
            return
        d = np.linalg.norm(points_m[:, None, :] - truth_m[None, present, :], axis=2)
        nearest_true = d.min(axis=0)  # per true limb
        self.found50 += int((nearest_true[seen2[present]] < 0.05).sum())
        self.found100 += int((nearest_true[seen2[present]] < 0.10).sum())
        self.false += int((d.min(axis=1) > 0.10).sum())
        self.dists.extend(nearest_true[nearest_true < 0.10].tolist())

    def summary(self) -> dict[str, float]:
        return {
            "recall50": self.found50 / max(self.countable, 1),
            "recall100": self.found100 / max(self.countable, 1),
            "false_per_set": self.false / max(self.n_sets, 1),
            "limbs_per_set": self.countable / max(self.n_sets, 1),
            "mean_mm": 1000 * float(np.mean(self.dists)) if self.dists else float("nan"),
        }

    def limb_rows(self, labels: list[str]) -> list[str]:
        """Markdown rows per true limb: limb-frames seen by two or more views, recall within
        100 mm, the median distance of the nearest candidate where it is farther, and the
        median offset (x, y, z) of the nearest candidate, mm."""
        rows = []
        for j, found in sorted(self.offsets.items()):
            off = np.array(found)
            dist = np.linalg.norm(off, axis=1)  # NaN where no candidate at all
            missed = dist[~(dist < 0.10)]
            far = f"{1000 * np.nanmedian(missed):.0f}" if np.isfinite(missed).any() else "-"
            med = 1000 * np.nanmedian(off, axis=0) if np.isfinite(dist).any() else [np.nan] * 3
            rows.append(
                f"| {labels[j]} | {len(off)} | {(dist < 0.10).mean():.3f} | {far} | "
                f"{med[0]:+.0f}, {med[1]:+.0f}, {med[2]:+.0f} |"
            )
        return rows


def score_run(rec_dir: Path, mcap: Path, learning_frames: int) -> CandidateScore:
    """:class:`CandidateScore` of the candidates a run wrote (its ``/candidates``), frame
    sets after the background models' learning phase."""
    gt = load_ground_truth(rec_dir)
    run = read_run(mcap)
    rows = align_frames(gt.t_ns, run.candidate_t_ns, gt.fps)
    score = CandidateScore()
    for m, g in enumerate(rows):
        if g < 0 or gt.frames[g] < learning_frames:
            continue
        score.add(run.candidate_pos_m[run.candidate_rows(m)], gt.positions_m[g], gt.n_views[g])
    return score


def bench_recording(
    rec_dir: Path, max_frames: int | None, cfg: PipelineConfig | None = None
) -> dict:
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    cfg = cfg or PipelineConfig()
    bg_cfg, cand_cfg = cfg.background, cfg.candidates
    times: dict[str, list[float]] = {
        "background": [],
        "skin": [],
        "blobs": [],
        "crowns": [],
        "candidates": [],
    }
    score = CandidateScore()
    tp = fp = fn = 0
    frames = observe_recording(rec, cfg, max_frames=max_frames, skin_near_people=True)
    for fs, by_cam, cam_times in frames:
        for stage, seconds in cam_times.items():
            times[stage] += seconds
        observations = list(by_cam.values())
        for cam, obs in by_cam.items():
            mask_path = rec_dir / "ground_truth" / "masks" / cam / f"{fs.index:06d}.png"
            if fs.index >= bg_cfg.learning_frames and mask_path.exists():
                truth = cv2.imread(str(mask_path))[..., 0] == MaskClass.SKIN
                pred = obs.skin & obs.silhouettes.mask
                tp += int(np.count_nonzero(pred & truth))
                fp += int(np.count_nonzero(pred & ~truth))
                fn += int(np.count_nonzero(~pred & truth))
        t0 = time.perf_counter()
        cands = make_candidates(observations, rec.rig, cand_cfg)
        times["candidates"].append(time.perf_counter() - t0)
        if fs.index < bg_cfg.learning_frames:
            continue  # the background model is still learning
        i = int(np.searchsorted(gt.frames, fs.index))
        score.add(cands.points_m, gt.positions_m[i], gt.n_views[i])
    return {
        **score.summary(),
        "skin_precision": tp / max(tp + fp, 1),
        "skin_recall": tp / max(tp + fn, 1),
        **{f"{k}_ms": 1000 * float(np.median(v)) for k, v in times.items()},
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--max-frames", type=int, default=None)
    parser.add_argument(
        "--config", type=Path, default=None, help="pipeline settings (TOML) instead of defaults"
    )
    parser.add_argument(
        "--in-run",
        action="store_true",
        help="also score the candidates of a run (pipeline_bench.py's MCAP, N_h from tracked "
        "heads)",
    )
    parser.add_argument("--seed", type=int, default=0, help="tracker seed of that run")
    parser.add_argument("--rerun", action="store_true", help="run the pipeline again")
    parser.add_argument(
        "--by-limb", action="store_true", help="with --in-run: also a table per true limb"
    )
    args = parser.parse_args(argv)
    cfg = load_pipeline_config(args.config)
    print(
        "| scenario | recall 50 mm | recall 100 mm | false / set | true limbs / set "
        "| mean dist mm | skin P | skin R | bg ms | skin ms | blobs ms | crowns ms | cand ms |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in scene_names(args):
        rec_dir = render(name, args.out)
        r = bench_recording(rec_dir, args.max_frames, cfg)
        print(
            f"| {name} | {r['recall50']:.3f} | {r['recall100']:.3f} "
            f"| {r['false_per_set']:.2f} | {r['limbs_per_set']:.2f} | {r['mean_mm']:.0f} "
            f"| {r['skin_precision']:.3f} | {r['skin_recall']:.3f} "
            f"| {r['background_ms']:.2f} | {r['skin_ms']:.2f} | {r['blobs_ms']:.2f} "
            f"| {r['crowns_ms']:.2f} | {r['candidates_ms']:.2f} |",
            flush=True,
        )
    if args.in_run:
        print(
            f"\nIn a run (tracker seed {args.seed}: N_h from the tracked heads, the trackers' "
            "feedback):\n"
        )
        print("| scenario | recall 50 mm | recall 100 mm | false / set | true limbs / set |")
        print("|---|---|---|---|---|")
        scores = {}
        for name in scene_names(args):
            scores[name] = score_run(
                args.out / name, run_of(name, args), cfg.background.learning_frames
            )
            r = scores[name].summary()
            print(
                f"| {name} | {r['recall50']:.3f} | {r['recall100']:.3f} "
                f"| {r['false_per_set']:.2f} | {r['limbs_per_set']:.2f} |",
                flush=True,
            )
        if args.by_limb:
            print("\nIn a run, per true limb (limb-frames seen by two or more views):\n")
            print(
                "| scene, limb | limb-frames | recall 100 mm | nearest when missed, median mm "
                "| nearest offset x, y, z, median mm |"
            )
            print("|---|---|---|---|---|")
            for name, score in scores.items():
                labels = load_ground_truth(args.out / name).labels
                for row in score.limb_rows(list(labels)):
                    print(f"| {name} {row[2:]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
