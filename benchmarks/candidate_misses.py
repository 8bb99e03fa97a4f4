"""Why true limbs go without a 3-D candidate: every miss of the candidate benchmark, by cause.

    python benchmarks/candidate_misses.py [--out out/bench_synth] [--max-frames N]
        [--approach S] [NAME ...]

For every true head or hand seen by >= 2 cameras (ground truth) with no candidate within
100 mm (the miss of ``candidates_bench.py``), the first stage that lost it:

- ``no skin``: fewer than two of the cameras that see the limb have skin pixels within
  ``R`` px of its projection (the skin classifier missed it);
- ``no silhouette``: skin there, but outside every (dilated) silhouette in all but < 2 views;
- ``no blob``: skin inside a silhouette, but no blob there (too small, or cut by the
  ceil(lambda 3 N_h) largest);
- ``blob merged``: a blob covers the projection but its centroid is more than ``R`` px away
  (the limb's skin joined another limb's or a skin-coloured region's);
- ``triangulation``: >= 2 views have the limb's own blob (centroid within ``R`` px), yet no
  pair of them triangulates within 100 mm (calibration error, centroid bias);
- ``prior p_o`` / ``prior p_t`` / ``prior p_b``: such a pair exists, but the prior rejects
  it; named after the term furthest below its threshold (or ``prior product``);
- ``merging``: the pair survives the prior but is absorbed by a candidate > 100 mm away;
- ``explained away``: dropped as a ghost (docs/candidates.md).

``--by-limb`` adds a table per scenario with every true limb's own misses and causes.

``--approach S`` counts only the actors of the true events (the hands, or hand and head, that
meet) during the S seconds up to each climax: the approach, where a lost candidate costs the
tracker its target just before the decision point.

Blobs are extracted with the true number of people as N_h (the tracker's head count in a
run); the recording's own (slightly wrong) calibration is used throughout, as in a run.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections import Counter
from pathlib import Path

import numpy as np
from front_end import observe_recording
from pipeline_bench import add_scene_arguments, render, scene_names

from surveil.datatypes import CameraObservation
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import PipelineConfig, load_pipeline_config
from surveil.recon.candidates import (
    blob_rows,
    floor_relative_v,
    gauss_term,
    make_candidates,
    silhouette_prior,
)
from surveil.recon.settings import CandidateConfig
from surveil.recon.triangulate import closest_points

ROOT = Path(__file__).resolve().parents[1]
CAUSES = (
    "no skin",
    "no silhouette",
    "no blob",
    "blob merged",
    "triangulation",
    "prior p_o",
    "prior p_t",
    "prior p_b",
    "prior product",
    "merging",
    "explained away",
)


def _near(mask: np.ndarray, uv: np.ndarray, r: int) -> bool:
    h, w = mask.shape
    u, v = int(round(uv[0])), int(round(uv[1]))
    if not (0 <= u < w and 0 <= v < h):
        return False
    return bool(mask[max(v - r, 0) : v + r + 1, max(u - r, 0) : u + r + 1].any())


def classify_miss(
    pos_m: np.ndarray,
    cams_seeing: list[int],
    obs_by_cam: dict[int, CameraObservation],
    rig,
    cfg: CandidateConfig,
    without_explaining: np.ndarray,
    radius_px: float,
) -> str:
    """The first stage that lost the true limb at ``pos_m`` (see the module docstring)."""
    own: dict[int, int] = {}  # camera -> blob index of the limb's own blob
    stage = Counter()
    for m in cams_seeing:
        obs = obs_by_cam.get(m)
        if obs is None:
            continue
        uv = rig.cameras[m].project(pos_m[None])[0][0]
        r = int(radius_px)
        blobs = obs.blobs
        if len(blobs):
            d = np.linalg.norm(blobs.centroids_px - uv, axis=1)
            if d.min() <= radius_px:
                own[m] = int(d.argmin())
                continue
        if not _near(obs.skin, uv, r // 2):
            stage["no skin"] += 1
        elif not _near(obs.skin & (obs.silhouettes.labels > 0), uv, r // 2):
            stage["no silhouette"] += 1
        elif _near(blobs.labels > 0, uv, r // 2):
            stage["blob merged"] += 1
        else:
            stage["no blob"] += 1
    if len(own) < 2:
        # the view losses that leave fewer than two: the most common one names the miss
        return stage.most_common(1)[0][0] if stage else "no blob"
    # every pair of own blobs: the points they triangulate and their prior terms
    cams = sorted(own)
    pairs = [(a, b) for i, a in enumerate(cams) for b in cams[i + 1 :]]
    o1, d1, o2, d2 = [], [], [], []
    for a, b in pairs:
        oa, da = rig.cameras[a].backproject(obs_by_cam[a].blobs.centroids_px[[own[a]]])
        ob, db = rig.cameras[b].backproject(obs_by_cam[b].blobs.centroids_px[[own[b]]])
        o1.append(oa)
        d1.append(da[0])
        o2.append(ob)
        d2.append(db[0])
    pts, gap = closest_points(np.array(o1), np.array(d1), np.array(o2), np.array(d2))
    close = np.linalg.norm(pts - pos_m, axis=1) < 0.1
    if not close.any():
        return "triangulation"
    d_v = []
    for side in (0, 1):
        cams = np.array([pair[side] for pair in pairs])
        if cfg.rel_v_to_floor:
            rows = np.array([[r[own[m]] for r in blob_rows(obs_by_cam[m])] for m in cams])
            d_v.append(floor_relative_v(pts, cams, rows[:, 0], rows[:, 1], rig))
        else:
            d_v.append(np.array([obs_by_cam[m].blobs.rel_v[own[m]] for m in cams]))
    p_o = gauss_term(d_v[0] - d_v[1], cfg.sigma_rel_v)
    p_t = gauss_term(gap, cfg.sigma_gap_m)
    p_b = silhouette_prior(
        pts, rig, obs_by_cam, cfg.sigma_silhouette_px, cfg.silhouette_drop_worst
    )
    prior = p_o * p_t * p_b
    ok = (
        close
        & (gap <= cfg.max_gap_m)
        & (np.minimum(np.minimum(p_o, p_t), p_b) >= cfg.term_threshold)
        & (prior >= cfg.prior_threshold)
    )
    if not ok.any():
        k = int(np.flatnonzero(close)[np.argmax(prior[close])])
        terms = {"prior p_o": p_o[k], "prior p_t": p_t[k], "prior p_b": p_b[k]}
        if gap[k] > cfg.max_gap_m:
            return "prior p_t"
        worst = min(terms, key=terms.get)
        return worst if terms[worst] < cfg.term_threshold else "prior product"
    if len(without_explaining) and (
        np.linalg.norm(without_explaining - pos_m, axis=1).min() < 0.1
    ):
        return "explained away"
    return "merging"


def approach_mask(gt, approach_s: float) -> np.ndarray:
    """(F, L) bool: the limb is an actor of a true event whose climax is at most
    ``approach_s`` after the frame set (and not before it)."""
    mask = np.zeros(gt.positions_m.shape[:2], dtype=bool)
    for ev in gt.events:
        rows = (gt.t_ns <= ev.climax_ns) & (gt.t_ns >= ev.climax_ns - approach_s * 1e9)
        for actor in ev.actors:
            if actor in gt.labels:
                mask[rows, gt.labels.index(actor)] = True
    return mask


def misses_of(
    rec_dir: Path,
    max_frames: int | None,
    radius_px: float,
    config: PipelineConfig,
    approach_s: float | None = None,
) -> tuple[Counter, Counter, float]:
    """Miss causes keyed by (limb label, cause), countable limb-frames per limb label,
    false candidates per frame set."""
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    bg_cfg, cfg = config.background, config.candidates
    no_explaining = dataclasses.replace(cfg, explain_away=False)
    n_people = len({lab.split("/")[0] for lab in gt.labels})
    cam_index = {c: rec.rig.names.index(c) for c in gt.cameras}
    only = approach_mask(gt, approach_s) if approach_s is not None else None
    causes: Counter = Counter()
    countable: Counter = Counter()
    n_sets = false = 0
    for fs, by_name, _ in observe_recording(rec, config, n_people, max_frames):
        obs_by_cam = {rec.rig.names.index(cam): obs for cam, obs in by_name.items()}
        if fs.index < bg_cfg.learning_frames:
            continue
        observations = list(obs_by_cam.values())
        cands = make_candidates(observations, rec.rig, cfg)
        i = int(np.searchsorted(gt.frames, fs.index))
        truth = gt.positions_m[i]
        seen2 = np.isfinite(truth).all(axis=1) & (gt.n_views[i] >= 2)
        if only is not None:
            seen2 &= only[i]
        countable.update(gt.labels[j] for j in np.flatnonzero(seen2))
        n_sets += 1
        missed = seen2.copy()
        if len(cands.points_m):
            d = np.linalg.norm(cands.points_m[:, None] - truth[None], axis=2)
            d = np.where(np.isfinite(d), d, np.inf)
            missed &= ~(d.min(axis=0) < 0.1)
            false += int((d.min(axis=1) > 0.1).sum())
        if not missed.any():
            continue
        loose = make_candidates(observations, rec.rig, no_explaining).points_m
        for j in np.flatnonzero(missed):
            cams = [cam_index[c] for c, v in zip(gt.cameras, gt.visible[i, j], strict=True) if v]
            cause = classify_miss(truth[j], cams, obs_by_cam, rec.rig, cfg, loose, radius_px)
            causes[gt.labels[j], cause] += 1
    return causes, countable, false / max(n_sets, 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--max-frames", type=int, default=None)
    parser.add_argument("--radius-px", type=float, default=10.0, help="R, px")
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML) to diagnose")
    parser.add_argument(
        "--approach", type=float, metavar="S", help="only event actors, S s before each climax"
    )
    parser.add_argument(
        "--by-limb", action="store_true", help="also a table per scenario, one row per limb"
    )
    args = parser.parse_args(argv)
    config = load_pipeline_config(args.config)
    limb_tables: dict[str, tuple[Counter, Counter]] = {}
    print("Fractions of the true limb-frames seen by >= 2 cameras, lost at each stage:\n")
    print("| scenario | limb-frames | false / set | missed | " + " | ".join(CAUSES) + " |")
    print("|---|---|---|---|" + "---|" * len(CAUSES))
    for name in scene_names(args):
        rec_dir = render(name, args.out)
        by_limb, countable, false = misses_of(
            rec_dir, args.max_frames, args.radius_px, config, args.approach
        )
        causes = Counter()
        for (_, cause), k in by_limb.items():
            causes[cause] += k
        n = sum(countable.values())
        cells = " | ".join(f"{causes[c] / max(n, 1):.3f}" for c in CAUSES)
        missed = sum(causes.values()) / max(n, 1)
        print(f"| {name} | {n} | {false:.2f} | {missed:.3f} | {cells} |", flush=True)
        if args.by_limb:
            limb_tables[name] = (by_limb, countable)
    for name, (by_limb, countable) in limb_tables.items():
        print(f"\n{name}, per limb:\n")
        print("| limb | limb-frames | missed | " + " | ".join(CAUSES) + " |")
        print("|---|---|---|" + "---|" * len(CAUSES))
        for limb, n in sorted(countable.items()):
            own = [by_limb[limb, c] for c in CAUSES]
            cells = " | ".join(f"{k / n:.3f}" for k in own)
            print(f"| {limb} | {n} | {sum(own) / n:.3f} | {cells} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
