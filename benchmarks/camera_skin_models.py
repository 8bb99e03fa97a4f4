"""Per-camera skin models for the bundled scenes, trained on each take's first frames.

    python benchmarks/camera_skin_models.py [--fraction 0.34] [--threshold 0.1]
        [--unbounded] [--src out/bench_synth] --out out/bench_cam
        [--scene-seeds 101-102] [NAME ...]

For each scene, ``OUT/<name>/`` becomes a view of ``SRC/<name>/`` (links to its videos and
ground truth, a copy of its rig) whose ``ground_truth/masks`` hold only the first
``--fraction`` of the mask frames of every camera, and ``surveil train-skin``'s models
(:func:`train_camera_skin_models`, every mask frame of that part) are saved beside the rig,
where a run picks them up. The later frames stay out of training, as a user would annotate a
few frames of a camera and run on the rest. Then

    python benchmarks/seed_spread.py --out OUT --config FILE
    python benchmarks/candidates_bench.py --out OUT
    python benchmarks/carry_bench.py --masks none --out OUT

measure the pipeline with those models (docs/blobs.md, "Per-camera models"). ``NAME@N`` and
``--scene-seeds`` name held-out takes, as in ``pipeline_bench.py``; they are rendered into
``--src`` first if missing.
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import sys
from pathlib import Path

import numpy as np
from pipeline_bench import ROOT, add_scene_arguments, render, scene_names

from surveil.blobs.settings import SkinConfig
from surveil.io.skin_model import save_skin_model, skin_models_dir, train_camera_skin_models


def early_view(src: Path, dst: Path, fraction: float) -> int:
    """Make ``dst`` a view of recording ``src`` with the first ``fraction`` of its mask frames;
    returns the mask frames kept per camera (of the first camera)."""
    if dst.exists():
        shutil.rmtree(dst)
    dst.mkdir(parents=True)
    for p in src.iterdir():
        if p.name not in ("ground_truth", "rig.yaml") and not p.name.endswith("_skin"):
            (dst / p.name).symlink_to(p.resolve())
    shutil.copy(src / "rig.yaml", dst / "rig.yaml")
    gt = dst / "ground_truth"
    gt.mkdir()
    for p in (src / "ground_truth").iterdir():
        if p.name != "masks":
            (gt / p.name).symlink_to(p.resolve())
    kept = []
    for cam_dir in sorted((src / "ground_truth" / "masks").iterdir()):
        frames = sorted(cam_dir.glob("*.png"))
        keep = frames[: max(1, round(fraction * len(frames)))]
        (gt / "masks" / cam_dir.name).mkdir(parents=True)
        for f in keep:
            (gt / "masks" / cam_dir.name / f.name).symlink_to(f.resolve())
        kept.append(len(keep))
    return kept[0]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--src", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--fraction", type=float, default=0.34)
    parser.add_argument("--threshold", type=float, default=SkinConfig().camera_threshold)
    parser.add_argument("--unbounded", action="store_true")
    args = parser.parse_args(argv)
    if args.out.resolve() == args.src.resolve():
        parser.error("--out must differ from --src (its recordings are linked, not copied)")
    names = scene_names(args)
    cfg = dataclasses.replace(
        SkinConfig(), camera_threshold=args.threshold, bound_by_generic=not args.unbounded
    )
    for name in names:
        render(name, args.src)
        dst = args.out / name
        n = early_view(args.src / name, dst, args.fraction)
        models = train_camera_skin_models(dst, np.random.default_rng(0), cfg, every=1)
        folder = skin_models_dir(dst / "rig.yaml")
        for cam, model in models.items():
            save_skin_model(model, folder / f"{cam}.npz")
        print(f"{name}: {len(models)} models from {n} mask frames per camera -> {folder}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
