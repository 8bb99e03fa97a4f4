"""Where the front end's false candidates lie, and how many views support them.

    python benchmarks/false_candidates.py [--out out/bench_synth] [--config FILE]
        [--max-frames N] [NAME ...]

Replays the front end (``front_end.observe_recording``, ``make_candidates``) and sorts every
candidate farther than 100 mm from every true head and hand (frame sets after the
background's learning) by the nearest body part of the ground truth (``joints.csv``, the
heads):

- ``forearm``: within 60 mm of an elbow-wrist segment (a bare forearm's blob);
- ``upper arm``: within 60 mm of a shoulder-elbow segment;
- ``neck``: within 0.25 m across of a head's vertical axis and less than 0.3 m below the
  head's centre (the face and neck below a head candidate);
- ``torso``: the same, lower (lines of sight of two limbs crossing over a body, clothing);
- ``free``: elsewhere.

Per class, candidates per frame set and the share supported by 2, 3 and 4 views (a view
supports a candidate when a blob centroid lies within ``[candidates] support_radius_px`` of
its projection inside the image, or made it: ``view_support``, as explaining away counts).
The true candidates (within 100 mm of a limb) are the last column for comparison.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from front_end import observe_recording
from pipeline_bench import ROOT, add_scene_arguments, render, scene_names

from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import load_pipeline_config
from surveil.recon.candidates import make_candidates, view_support

MATCH_M = 0.10
LIMB_SEGMENT_M = 0.06
BODY_RADIUS_M = 0.25
NECK_DEPTH_M = 0.3
CLASSES = ("forearm", "upper arm", "neck", "torso", "free", "true")


def segment_distance_m(points_m: np.ndarray, a_m: np.ndarray, b_m: np.ndarray) -> np.ndarray:
    """(K,) distance of each point to the segment a-b."""
    ab = b_m - a_m
    t = np.clip((points_m - a_m) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points_m - (a_m + t[:, None] * ab), axis=1)


def classify(points_m: np.ndarray, limbs_m: np.ndarray, heads_m: np.ndarray, arms: dict) -> list:
    """Class name per candidate. ``limbs_m`` (L, 3) true heads and hands, ``heads_m`` (P, 3),
    ``arms``: {"forearm": [(elbow, wrist)...], "upper arm": [(shoulder, elbow)...]}."""
    k = len(points_m)
    out = ["free"] * k
    if k == 0:
        return out
    to_limb = np.linalg.norm(points_m[:, None] - limbs_m[None], axis=2).min(axis=1)
    near = {
        name: np.min([segment_distance_m(points_m, a, b) for a, b in segs], axis=0)
        if segs
        else np.full(k, np.inf)
        for name, segs in arms.items()
    }
    for i in range(k):
        if to_limb[i] < MATCH_M:
            out[i] = "true"
        elif near["forearm"][i] < LIMB_SEGMENT_M:
            out[i] = "forearm"
        elif near["upper arm"][i] < LIMB_SEGMENT_M:
            out[i] = "upper arm"
        elif len(heads_m):
            below = points_m[i, 2] < heads_m[:, 2]
            across = np.where(
                below,
                np.linalg.norm(points_m[i, :2] - heads_m[:, :2], axis=1),
                np.linalg.norm(points_m[i] - heads_m, axis=1),
            )
            h = int(np.argmin(across))
            if across[h] < BODY_RADIUS_M:
                out[i] = "neck" if heads_m[h, 2] - points_m[i, 2] < NECK_DEPTH_M else "torso"
    return out


def measure(rec_dir: Path, cfg, max_frames: int | None) -> tuple[int, dict]:
    """Frame sets counted and, per class, the support-view count of every candidate."""
    rec, gt = open_recording(rec_dir), load_ground_truth(rec_dir)
    joint = {label: j for j, label in enumerate(gt.joint_labels)}
    heads = [j for j, label in enumerate(gt.labels) if label.endswith("/head")]
    found: dict[str, list[int]] = {c: [] for c in CLASSES}
    n_sets = 0
    for fs, obs, _ in observe_recording(rec, cfg, max_frames=max_frames):
        if fs.index < cfg.background.learning_frames:
            continue
        n_sets += 1
        cands = make_candidates(list(obs.values()), rec.rig, cfg.candidates)
        g = gt.frame_at(fs.t_ns)
        limbs = gt.positions_m[g]
        limbs = limbs[np.isfinite(limbs).all(axis=1)]
        head_m = gt.positions_m[g, heads]
        head_m = head_m[np.isfinite(head_m).all(axis=1)]
        arms: dict[str, list] = {"forearm": [], "upper arm": []}
        for label in gt.joint_labels:
            if not label.endswith("_elbow"):
                continue
            side = label[: -len("_elbow")]
            elbow = gt.joint_positions_m[g, joint[label]]
            for name, other in (("forearm", "_wrist"), ("upper arm", "_shoulder")):
                end = gt.joint_positions_m[g, joint.get(side + other, joint[label])]
                if np.isfinite(elbow).all() and np.isfinite(end).all():
                    arms[name].append((elbow, end))
        kinds = classify(cands.points_m, limbs, head_m, arms)
        by_cam = {rec.rig.names.index(cam): o for cam, o in obs.items()}
        # not CandidateSet.views: that counts every crown head as two views, where this
        # table wants the blobs each point's projection meets, crown heads included
        support = view_support(
            cands.points_m,
            cands.cam_pairs,
            cands.blob_pairs,
            rec.rig,
            by_cam,
            cfg.candidates.support_radius_px,
        )
        views = (support >= 0).sum(axis=1)
        for kind, v in zip(kinds, views.tolist(), strict=True):
            found[kind].append(v)
    return n_sets, found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML)")
    parser.add_argument("--max-frames", type=int, default=None)
    args = parser.parse_args(argv)
    cfg = load_pipeline_config(args.config)
    print(
        "Candidates per frame set by where they lie; in brackets the share supported by "
        "2 / 3 / 4 views.\n"
    )
    print("| scenario | " + " | ".join(CLASSES) + " |")
    print("|---|" + "---|" * len(CLASSES))
    for name in scene_names(args):
        n_sets, found = measure(render(name, args.out), cfg, args.max_frames)
        cells = []
        for kind in CLASSES:
            v = np.array(found[kind], dtype=np.int64)
            share = [float(np.mean(v == k)) if len(v) else 0.0 for k in (2, 3, 4)]
            cells.append(
                f"{len(v) / max(n_sets, 1):.2f} ({' / '.join(f'{s:.2f}' for s in share)})"
            )
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
