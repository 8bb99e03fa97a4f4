"""Background model: speed of its parts at full and half size, and how long still people stay
in the foreground (issue 3).

    python benchmarks/background_bench.py [--out out/bench_synth] [--scenario demo] [--camera cam0]
        [--false-foreground [SCENARIO ...]]

Part 1 times (median of 30 runs, one 640x480 frame) MOG2, connected components and the
distance transform at full size and at ``model_scale`` 0.5. Part 2 runs ``BackgroundModel``
over the scenario with MOG2's default rates (0.002, background ratio 0.9) and with the
project defaults, printing the fraction of true person pixels (ground-truth masks) that are
foreground at several times. Part 3 (``--false-foreground``) runs every camera's model over
whole scenarios with and without ``gain_compensation`` and scores its silhouettes against the
ground-truth masks (:func:`part_false_foreground`).
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


def part_false_foreground(rec_dir: Path) -> list[str]:
    """One table row per gain-compensation setting: over the ground-truth mask frames after
    the learning phase, every camera, the silhouette pixels on true background per true
    person pixel (mean, 90th percentile), the share of person pixels in silhouettes, the
    most silhouettes beyond the people in view, and the median ms of a model step."""
    rec = open_recording(rec_dir)
    rows = []
    for compensate in (False, True):
        cfg = dataclasses.replace(BackgroundConfig(), gain_compensation=compensate)
        models: dict[str, BackgroundModel] = {}
        false_share, recall, extra, step_s = [], [], [], []
        for fs in rec.framesets():
            for cam, img in fs.images.items():
                model = models.setdefault(cam, BackgroundModel(cfg, img.shape[:2]))
                t0 = time.perf_counter()
                sil = model.step(img)
                step_s.append(time.perf_counter() - t0)
                path = rec_dir / GT_DIR / "masks" / cam / f"{fs.index:06d}.png"
                if model.learning or not path.exists():
                    continue
                person_id = cv2.imread(str(path))[..., 1]
                person = person_id > 0
                n_person = max(int(person.sum()), 1)
                false_share.append(np.count_nonzero(sil.mask & ~person) / n_person)
                recall.append(np.count_nonzero(sil.mask & person) / n_person)
                extra.append(sil.n - len(np.unique(person_id[person])))
        rows.append(
            f"| {rec_dir.name} | {'on' if compensate else 'off'} | {np.mean(false_share):.2f} | "
            f"{np.percentile(false_share, 90):.2f} | {np.mean(recall):.3f} | {max(extra)} | "
            f"{1000 * np.median(step_s):.2f} |"
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--scenario", default="demo")
    parser.add_argument("--camera", default="cam0")
    parser.add_argument(
        "--false-foreground",
        nargs="*",
        metavar="SCENARIO",
        help="also measure false foreground with and without gain compensation on these "
        "bundled scenarios (all when none is named)",
    )
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
    if args.false_foreground is not None:
        names = args.false_foreground or sorted(
            p.stem for p in (ROOT / "recordings").glob("*.toml")
        )
        print()
        print(
            "| scenario | gain compensation | false / person px, mean | p90 | person px found "
            "| most extra silhouettes | ms per step |"
        )
        print("|---|---|---|---|---|---|---|")
        for name in names:
            synthesise(ROOT / "recordings" / f"{name}.toml", args.out / name)
            print("\n".join(part_false_foreground(args.out / name)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
