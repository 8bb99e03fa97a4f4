"""How far the front end's candidates lie from the true heads and hands, and how much of it
the recordings' calibration error alone explains, per limb type.

    python benchmarks/candidate_bias.py [--out out/bench_synth] [--config FILE]
        [--max-frames N] [--by-limb] [NAME ...]

For every true limb seen by >= 2 cameras (ground truth, frames after the background's
learning), per scenario and limb type (head, hand):

- ``cand``: the nearest candidate within 100 mm (``make_candidates`` on the replayed front
  end, ``front_end.observe_recording``): mean and median distance, mm, and its mean offset
  (x, y, z; z up), mm -- a bias the tracker inherits;
- ``floor``: the limb's *true* projections (the rig it was rendered with,
  ``ground_truth/rig_true.yaml``) triangulated through the recording's own rig (which carries
  the synthetic calibration error), mean of the pairwise midpoints over the views that see
  it: the error a perfect blob centre would still have, mm;
- ``px``: the nearest blob point within 25 px of the true projection in each of those views:
  median distance and mean offset (u, v; v down), px;
- ``steadiness``: how much the candidate's offset changes from one frame set to the next
  where the limb has a candidate in both, median and 90th percentile, mm -- jitter the
  tracker has to smooth (a limb whose candidate comes from a different pair of views in
  each frame set jumps by the difference of their calibration errors).

``--by-limb`` also prints the candidate figures per true limb (``p1/left_hand``...).
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np
from front_end import observe_recording
from pipeline_bench import add_scene_arguments, render, scene_names

from surveil.io.calibration import load_rig
from surveil.io.ground_truth import GT_DIR, load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import PipelineConfig, load_pipeline_config
from surveil.recon.candidates import make_candidates
from surveil.recon.triangulate import closest_points

ROOT = Path(__file__).resolve().parents[1]
MATCH_M = 0.10
BLOB_PX = 25.0


def calibration_floor_m(rays: list, truth_m: np.ndarray) -> float:
    """Mean distance to ``truth_m`` of the midpoints of every pair of lines of sight."""
    errs = []
    for (o1, d1), (o2, d2) in itertools.combinations(rays, 2):
        z, _ = closest_points(o1[None], d1[None], o2[None], d2[None])
        errs.append(float(np.linalg.norm(z[0] - truth_m)))
    return float(np.mean(errs))


def measure(rec_dir: Path, cfg: PipelineConfig, max_frames: int | None) -> dict:
    """Per limb label: lists of candidate offsets (m), floors (m), blob offsets (px)."""
    rec, gt = open_recording(rec_dir), load_ground_truth(rec_dir)
    true_rig = load_rig(rec_dir / GT_DIR / "rig_true.yaml")
    cams = list(gt.cameras)
    out = {label: {"cand": [], "floor": [], "px": [], "step": []} for label in gt.labels}
    last: dict[str, tuple[int, np.ndarray]] = {}  # label -> (frame set, candidate offset)
    for fs, obs, _ in observe_recording(rec, cfg, max_frames=max_frames):
        if fs.index < cfg.background.learning_frames:
            continue
        cands = make_candidates(list(obs.values()), rec.rig, cfg.candidates)
        g = gt.frame_at(fs.t_ns)
        for j, label in enumerate(gt.labels):
            truth = gt.positions_m[g, j]
            views = [c for k, c in enumerate(cams) if gt.visible[g, j, k] and c in obs]
            if not np.isfinite(truth).all() or len(views) < 2:
                continue
            rays = []
            for cam in views:
                px, _ = true_rig[cam].project(truth[None])
                origin, direction = rec.rig[cam].backproject(px)
                rays.append((origin, direction[0]))
                points = obs[cam].blobs.centroids_px
                if len(points):
                    d = np.linalg.norm(points - px[0], axis=1)
                    if d.min() < BLOB_PX:
                        out[label]["px"].append(points[d.argmin()] - px[0])
            out[label]["floor"].append(calibration_floor_m(rays, truth))
            if len(cands.points_m):
                d = np.linalg.norm(cands.points_m - truth, axis=1)
                if d.min() < MATCH_M:
                    offset = cands.points_m[d.argmin()] - truth
                    out[label]["cand"].append(offset)
                    before = last.get(label)
                    if before is not None and before[0] == fs.index - 1:
                        out[label]["step"].append(float(np.linalg.norm(offset - before[1])))
                    last[label] = (fs.index, offset)
    return out


def row(name: str, what: str, parts: list[dict]) -> str:
    cand = 1000 * np.array([o for p in parts for o in p["cand"]]).reshape(-1, 3)
    floor = 1000 * np.array([f for p in parts for f in p["floor"]])
    px = np.array([o for p in parts for o in p["px"]]).reshape(-1, 2)
    step = 1000 * np.array([s for p in parts for s in p["step"]])
    dist = np.linalg.norm(cand, axis=1)
    steady = f"{np.median(step):.0f} / {np.percentile(step, 90):.0f}" if len(step) else "-"

    def vec(v: np.ndarray) -> str:
        return ", ".join(f"{x:+.0f}" if v.shape[1] == 3 else f"{x:+.1f}" for x in v.mean(0))

    if not len(cand):
        return f"| {name} | {what} | 0 | - | - | - | - | - | - |"
    return (
        f"| {name} | {what} | {len(cand)} | {dist.mean():.0f} / {np.median(dist):.0f} | "
        f"{vec(cand)} | {floor.mean():.0f} / {np.median(floor):.0f} | "
        f"{np.median(np.linalg.norm(px, axis=1)):.1f} | {vec(px)} | {steady} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML)")
    parser.add_argument("--max-frames", type=int, default=None)
    parser.add_argument("--by-limb", action="store_true", help="also a row per true limb")
    args = parser.parse_args(argv)
    cfg = load_pipeline_config(args.config)
    print(
        "| scenario | limbs | matched | cand mean / median mm | cand offset x, y, z mm | "
        "calibration floor mean / median mm | blob px median | blob offset u, v px | "
        "steadiness median / 90 % mm |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name in scene_names(args):
        found = measure(render(name, args.out), cfg, args.max_frames)
        for kind in ("head", "hand"):
            parts = [v for label, v in found.items() if kind in label]
            print(row(name, kind + "s", parts), flush=True)
        if args.by_limb:
            for label, v in found.items():
                print(row(name, label, [v]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
