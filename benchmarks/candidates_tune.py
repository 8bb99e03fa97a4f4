"""Tune the candidate prior's Gaussian widths and threshold on synthetic recordings (issue 3).

    python benchmarks/candidates_tune.py [--out out/bench_synth] [--every 3] [NAME ...]

Runs the per-camera stage once per recording (default settings), keeps the observations of
every ``--every``-th frame set after the background's learning phase, then evaluates a grid of
``CandidateConfig`` values on them: candidate recall within 100 mm of true heads and hands
seen by >= 2 cameras, and false candidates (farther than 100 mm from every true limb) per
frame set. Prints the grid sorted by the objective ``recall100 - 0.02 * false_per_set``
(one false candidate per set costs as much as 2 points of recall), summed over recordings.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
from pathlib import Path

import numpy as np

from surveil.blobs.background import BackgroundModel
from surveil.blobs.extract import extract_blobs
from surveil.blobs.settings import BackgroundConfig, BlobConfig
from surveil.blobs.skin import default_skin_model
from surveil.datatypes import CameraObservation
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.recon.candidates import make_candidates
from surveil.recon.settings import CandidateConfig
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]

GRID = {
    "sigma_gap_m": [0.015, 0.02, 0.03],
    "sigma_rel_v": [0.05, 0.1, 0.2],
    "sigma_silhouette_px": [3.0, 6.0],
    "prior_threshold": [0.1, 0.2, 0.3],
}


def collect(rec_dir: Path, every: int) -> list[tuple[list[CameraObservation], np.ndarray, object]]:
    """(observations, true positions of limbs seen by >= 2 cameras, rig) per kept frame set."""
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    bg_cfg, blob_cfg, skin = BackgroundConfig(), BlobConfig(), default_skin_model()
    models: dict[str, BackgroundModel] = {}
    kept = []
    for fs in rec.framesets():
        obs = []
        for cam in rec.camera_names:
            img = fs.images.get(cam)
            if img is None:
                continue
            bg = models.setdefault(cam, BackgroundModel(bg_cfg, img.shape[:2]))
            sil = bg.step(img)
            if fs.index >= bg_cfg.learning_frames and fs.index % every == 0:
                blobs = extract_blobs(skin.classify(img), sil, blob_cfg)
                # keep only what the candidate stage reads (the images are large)
                obs.append(CameraObservation(cam, sil, np.zeros((1, 1), bool), blobs))
        if obs:
            i = int(np.searchsorted(gt.frames, fs.index))
            pos = gt.positions_m[i]
            seen2 = np.isfinite(pos).all(axis=1) & (gt.n_views[i] >= 2)
            kept.append((obs, pos[np.isfinite(pos).all(axis=1)], pos[seen2]))
    return kept, rec.rig


def score(kept, rig, cfg: CandidateConfig) -> tuple[float, float]:
    found = countable = false = 0
    for obs, present, seen2 in kept:
        pts = make_candidates(obs, rig, cfg).points_m
        countable += len(seen2)
        if len(pts) == 0:
            continue
        if len(seen2):
            d = np.linalg.norm(pts[:, None] - seen2[None], axis=2)
            found += int((d.min(axis=0) < 0.10).sum())
        if len(present):
            false += int(
                (np.linalg.norm(pts[:, None] - present[None], axis=2).min(axis=1) > 0.1).sum()
            )
        else:
            false += len(pts)
    return found / max(countable, 1), false / max(len(kept), 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", default=["demo", "handshake", "exchange"])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--every", type=int, default=3)
    parser.add_argument("--top", type=int, default=12)
    args = parser.parse_args(argv)
    data = []
    for name in args.names:
        rec_dir = args.out / name
        synthesise(ROOT / "recordings" / f"{name}.toml", rec_dir)
        data.append((name, *collect(rec_dir, args.every)))
    rows = []
    keys = list(GRID)
    for values in itertools.product(*GRID.values()):
        cfg = dataclasses.replace(CandidateConfig(), **dict(zip(keys, values, strict=True)))
        per = [score(kept, rig, cfg) for _, kept, rig in data]
        objective = sum(r - 0.02 * f for r, f in per)
        rows.append((objective, values, per))
    rows.sort(key=lambda r: -r[0])
    print(
        "| "
        + " | ".join(keys)
        + " | "
        + " | ".join(f"{n} recall / false" for n, *_ in data)
        + " |"
    )
    print("|" + "---|" * (len(keys) + len(data)))
    default = tuple(getattr(CandidateConfig(), k) for k in keys)
    for _objective, values, per in rows[: args.top] + [r for r in rows if r[1] == default]:
        cells = [f"{v:g}" for v in values] + [f"{r:.3f} / {f:.1f}" for r, f in per]
        mark = " (current default)" if values == default else ""
        print("| " + " | ".join(cells) + f" |{mark}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
