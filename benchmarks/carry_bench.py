"""Benchmark the carried-object stage on ground-truth hand positions (synthetic recordings).

    python benchmarks/carry_bench.py [--out out/bench_carry] [--masks all|skin|none]
                                     [--set key=value ...] [NAME ...]

Renders (or reuses) the scenarios (default: exchange, pick_place, handshake, self_exchange),
runs the per-camera stage (MOG2 silhouettes, skin, blobs) and :class:`CarryAnalyser` with the
*true* hand positions as targets, and scores every (frame, true hand visible in >= 1 camera)
against the ground truth's ``held_by``:

- accuracy of the carrying flag over all such hand-frames, and "steady" accuracy excluding
  hand-frames within ``window_s`` + 0.5 s after (or 0.5 s before) a change of what that hand
  holds (the fusion window lags by design) and frames where two hands overlap (the analyser
  then repeats its pre-overlap estimate);
- recall on carrying hand-frames and the false-carry rate on empty ones (steady frames);
- hue error of the carried objects (true positives, circular, degrees);
- milliseconds per frame set of ``CarryAnalyser.step`` (median, 95th percentile).

``--masks`` chooses where the per-camera inputs come from: ``none`` each camera's skin model
(saved beside the rig by ``surveil train-skin``, else the default) and
MOG2 silhouettes on every frame; ``skin`` the ground-truth skin mask with MOG2 silhouettes;
``all`` ground-truth skin and silhouettes. With ground-truth masks only the frames that have
masks (every 5th) are analysed (the background model still sees every frame).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from surveil.blobs.background import BackgroundModel, silhouettes_from_mask
from surveil.blobs.extract import extract_blobs
from surveil.blobs.settings import BackgroundConfig, BlobConfig
from surveil.carry import CarryAnalyser, CarryConfig
from surveil.carry.hue import circular_distance_deg
from surveil.datatypes import CameraObservation, Phase, TargetSnapshot, parse_label
from surveil.io.ground_truth import MaskClass, load_ground_truth
from surveil.io.recording import open_recording
from surveil.io.skin_model import load_camera_skin_models
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_NAMES = ("exchange", "pick_place", "handshake", "self_exchange")
PERSON_CLASSES = (MaskClass.SKIN, MaskClass.HAIR, MaskClass.CLOTHING, MaskClass.OBJECT)


def parse_overrides(items: list[str]) -> dict:
    """``["carry_mass=0.05", "subtract_clothing=false"]`` -> typed CarryConfig overrides."""
    types = {f.name: f.type for f in dataclasses.fields(CarryConfig)}
    out = {}
    for item in items:
        key, _, value = item.partition("=")
        if key not in types:
            raise SystemExit(f"--set: unknown CarryConfig key {key!r}")
        tp = types[key]
        if tp in (bool, "bool"):
            out[key] = value.lower() in ("1", "true", "yes")
        elif tp in (int, "int"):
            out[key] = int(value)
        else:
            out[key] = float(value)
    return out


def steady_mask(held: np.ndarray, t_s: np.ndarray, before_s: float, after_s: float) -> np.ndarray:
    """(F,) bool: frames not within ``before_s`` before / ``after_s`` after a change of
    ``held`` ((F,) bool)."""
    change_t = t_s[1:][held[1:] != held[:-1]]
    ok = np.ones(len(t_s), bool)
    for tc in change_t:
        ok &= ~((t_s > tc - before_s) & (t_s < tc + after_s))
    return ok


def bench_recording(rec_dir: Path, masks: str, cfg: CarryConfig, details: bool = False) -> dict:
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    bg_cfg, blob_cfg = BackgroundConfig(), BlobConfig()
    skin_models = load_camera_skin_models(rec.rig_path, rec.camera_names)
    models: dict[str, BackgroundModel] = {}
    analyser = CarryAnalyser(cfg, rec.rig)
    hand_idx = [j for j, lab in enumerate(gt.labels) if lab.endswith("hand")]
    n_f = len(gt.frames)
    pred = np.full((n_f, len(gt.labels)), -1, np.int8)  # -1 not scored
    hue_pred = np.full((n_f, len(gt.labels)), np.nan)
    frozen_any = np.zeros((n_f, len(gt.labels)), bool)
    times: list[float] = []
    for fs in rec.framesets():
        i = int(np.searchsorted(gt.frames, fs.index))
        observations = {}
        images = {}
        for cam, img in fs.images.items():
            if cam not in models:
                models[cam] = BackgroundModel(bg_cfg, img.shape[:2])
            sil = models[cam].step(img)
            if masks == "none":
                skin = skin_models[cam].classify(img)
            else:
                path = rec_dir / "ground_truth" / "masks" / cam / f"{fs.index:06d}.png"
                if not path.exists():
                    continue
                cls = cv2.imread(str(path))[..., 0]
                skin = cls == MaskClass.SKIN
                if masks == "all":
                    sil = silhouettes_from_mask(
                        np.isin(cls, PERSON_CLASSES), bg_cfg.min_person_area_px
                    )
            observations[cam] = CameraObservation(
                cam, sil, skin, extract_blobs(skin, sil, blob_cfg, bgr=img)
            )
            images[cam] = img
        if fs.index < bg_cfg.learning_frames or not images or i >= n_f:
            continue
        targets = []
        for j, label in enumerate(gt.labels):
            p = gt.positions_m[i, j]
            if np.all(np.isfinite(p)):
                person, limb = parse_label(label)
                targets.append(TargetSnapshot(j, person, limb, Phase.NORMAL, p))
        t0 = time.perf_counter()
        est = analyser.step(fs.t_ns, images, observations, targets)
        times.append(time.perf_counter() - t0)
        for j in hand_idx:
            if j in est and gt.visible[i, j].any():
                pred[i, j] = int(est[j].carrying)
                if est[j].hue_deg is not None:
                    hue_pred[i, j] = est[j].hue_deg
                frozen_any[i, j] = analyser.is_frozen(j)
                if details:
                    e = est[j]
                    top = np.argsort(-e.hue_pdf)[:3] * (360.0 / cfg.hue_bins)
                    held = gt.held_by[i].tolist() if gt.held_by.shape[1] else []
                    print(
                        f"{fs.index:4d} {gt.labels[j]:15s} truth={int(gt.labels[j] in held)} "
                        f"pred={int(e.carrying)} hue={e.hue_deg} conf={e.confidence:.2f} "
                        f"frozen={int(frozen_any[i, j])} top_bins={top.tolist()}"
                    )
    t_s = gt.t_ns / 1e9
    n = correct = n_st = correct_st = pos = tp = neg = fp = 0
    hue_err: list[float] = []
    for j in hand_idx:
        label = gt.labels[j]
        held = (gt.held_by == label).any(axis=1)
        obj = np.argmax(gt.held_by == label, axis=1) if gt.held_by.shape[1] else np.zeros(n_f, int)
        scored = pred[:, j] >= 0
        ok = pred[:, j] == held.astype(np.int8)
        steady = scored & steady_mask(held, t_s, 0.5, cfg.window_s + 0.5) & ~frozen_any[:, j]
        n += int(scored.sum())
        correct += int((ok & scored).sum())
        n_st += int(steady.sum())
        correct_st += int((ok & steady).sum())
        pos += int((steady & held).sum())
        tp += int((steady & held & ok).sum())
        neg += int((steady & ~held).sum())
        fp += int((steady & ~held & ~ok).sum())
        good = steady & held & ok
        hue_err.extend(
            circular_distance_deg(hue_pred[good, j], gt.object_hue_deg[obj[good]]).tolist()
        )
    return {
        "hand_frames": n,
        "accuracy": correct / max(n, 1),
        "steady_frames": n_st,
        "steady_accuracy": correct_st / max(n_st, 1),
        "carry_recall": tp / pos if pos else float("nan"),
        "carry_pos": pos,
        "false_carry": fp / neg if neg else float("nan"),
        "hue_err_median": float(np.median(hue_err)) if hue_err else float("nan"),
        "hue_err_max": float(np.max(hue_err)) if hue_err else float("nan"),
        "ms_median": 1000 * float(np.median(times)),
        "ms_p95": 1000 * float(np.percentile(times, 95)),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_carry")
    parser.add_argument("--masks", choices=("none", "skin", "all"), default="all")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--details", action="store_true", help="print every scored hand-frame")
    args = parser.parse_args(argv)
    cfg = CarryConfig(**parse_overrides(args.set))
    names = args.names or list(DEFAULT_NAMES)
    print(f"masks={args.masks} overrides={args.set}")
    print(
        "| scenario | hand-frames | accuracy | steady hand-frames | steady accuracy "
        "| carry recall (n) | false carry | hue err median / max deg | ms / set median / p95 |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name in names:
        rec_dir = args.out / name
        if not (rec_dir / "recording.toml").exists():
            synthesise(ROOT / "recordings" / f"{name}.toml", rec_dir)
        r = bench_recording(rec_dir, args.masks, cfg, args.details)
        print(
            f"| {name} | {r['hand_frames']} | {r['accuracy']:.3f} | {r['steady_frames']} "
            f"| {r['steady_accuracy']:.3f} | {r['carry_recall']:.3f} ({r['carry_pos']}) "
            f"| {r['false_carry']:.3f} | {r['hue_err_median']:.1f} / {r['hue_err_max']:.1f} "
            f"| {r['ms_median']:.2f} / {r['ms_p95']:.2f} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
