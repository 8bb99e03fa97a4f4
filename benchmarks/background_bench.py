"""Background model: speed of its parts at full and half size, and how long still people stay
in the foreground (issue 3).

    python benchmarks/background_bench.py [--out out/bench_synth] [--scenario demo] [--camera cam0]

Part 1 times (median of 30 runs, one 640x480 frame) MOG2, connected components and the
distance transform at full size and at ``model_scale`` 0.5. Part 2 runs ``BackgroundModel``
over the scenario with MOG2's default rates (0.002, background ratio 0.9) and with the
project defaults, printing the fraction of true person pixels (ground-truth masks) that are
foreground at several times.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import cv2
import numpy as np

from surveil.blobs.background import BackgroundModel
from surveil.blobs.settings import BackgroundConfig
from surveil.io.ground_truth import GT_DIR
from surveil.io.recording import open_recording
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]


def _median_ms(fn, n: int = 30) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1000 * float(np.median(times))


def part_timings(frame: np.ndarray, mask: np.ndarray) -> None:
    print("| part | full size ms | half size ms |")
    print("|---|---|---|")
    half = cv2.resize(frame, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA)
    small_mask = cv2.resize(mask, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_NEAREST)
    outside = (mask == 0).astype(np.uint8)
    small_outside = (small_mask == 0).astype(np.uint8)
    mogs = []
    for img in (frame, half):  # steady state: a model that has seen frames already
        mog = cv2.createBackgroundSubtractorMOG2(300, 16, True)
        for _ in range(5):
            mog.apply(img)
        mogs.append((mog, img))
    rows = {
        "MOG2 apply": [
            lambda mog=mog, img=img: mog.apply(img, learningRate=0.0005) for mog, img in mogs
        ],
        "connected components": [
            lambda m=m: cv2.connectedComponentsWithStats(m, connectivity=8)
            for m in (mask, small_mask)
        ],
        "distance transform": [
            lambda o=o: cv2.distanceTransform(o, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
            for o in (outside, small_outside)
        ],
    }
    for name, (full_fn, half_fn) in rows.items():
        print(f"| {name} | {_median_ms(full_fn):.2f} | {_median_ms(half_fn):.2f} |")


def part_absorption(rec_dir: Path, camera: str) -> None:
    rec = open_recording(rec_dir)
    settings = {
        "MOG2 defaults (0.002, ratio 0.9)": dataclasses.replace(
            BackgroundConfig(), learning_rate=0.002, background_ratio=0.9
        ),
        "project defaults": BackgroundConfig(),
    }
    checkpoints = (45, 60, 100, 150, 200)
    print("| settings | " + " | ".join(f"frame {k}" for k in checkpoints) + " |")
    print("|---|" + "---|" * len(checkpoints))
    for name, cfg in settings.items():
        model, cells = None, []
        for fs in rec.framesets():
            img = fs.images.get(camera)
            if img is None:
                continue
            model = model or BackgroundModel(cfg, img.shape[:2])
            sil = model.step(img)
            if fs.index in checkpoints:
                gt = cv2.imread(str(rec_dir / GT_DIR / "masks" / camera / f"{fs.index:06d}.png"))
                if gt is None:
                    cells.append("-")
                    continue
                person = gt[..., 1] > 0
                cells.append(f"{np.count_nonzero(sil.mask & person) / person.sum():.2f}")
        print(f"| {name} | " + " | ".join(cells) + " |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--scenario", default="demo")
    parser.add_argument("--camera", default="cam0")
    args = parser.parse_args(argv)
    rec_dir = args.out / args.scenario
    synthesise(ROOT / "recordings" / f"{args.scenario}.toml", rec_dir)
    rec = open_recording(rec_dir)
    fs = next(iter(rec.framesets(start=100, stop=101)))
    frame = fs.images[args.camera]
    gt = cv2.imread(str(rec_dir / GT_DIR / "masks" / args.camera / f"{fs.index:06d}.png"))
    part_timings(frame, (gt[..., 1] > 0).astype(np.uint8))
    print()
    part_absorption(rec_dir, args.camera)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
