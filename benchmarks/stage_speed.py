"""Time one pipeline stage alone on a recording's inputs, optionally against another
checkout's version of it, call by call.

    python benchmarks/stage_speed.py [--stage candidates|blobs] [--frame-sets N]
        [--rounds 5] [--against CHECKOUT] [--out out/bench_synth] [NAME ...]

Runs the pipeline over the first ``--frame-sets`` frame sets of each scene (default:
three_people, issue 3's "4 cameras and 3 people" case) and keeps the arguments of every call
of the stage: :func:`surveil.recon.candidates.make_candidates` (the observations and the
tracker's expected hands) or :func:`surveil.blobs.extract.extract_blobs` (one call per camera
frame; its inputs hold the frame, so keep ``--frame-sets`` small: 60 take about 1 GB). It
then calls the stage on them ``--rounds`` times and prints milliseconds per frame set (each
call's median over the rounds, summed). With ``--against``, the same calls also go to
the module of ``CHECKOUT`` (a worktree of an older commit), alternating call by call and
which of the two goes first, so that the shared machine's load and warm caches fall on both
alike; it prints both figures and the median per-call ratio, and checks that both give the
same output in every call.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import importlib.util
import itertools
import sys
import time
from pathlib import Path

import numpy as np
from pipeline_bench import ROOT, add_scene_arguments, render, scene_names

import surveil.pipeline as pipeline_module
from surveil.activity import load_rules
from surveil.io.recording import open_recording
from surveil.pipeline import Pipeline, load_pipeline_config, use_one_opencv_thread

# stage: (module, function, output fields compared)
STAGES = {
    "candidates": (
        "surveil.recon.candidates",
        "make_candidates",
        ("points_m", "prior", "half_gap_m", "cam_pairs", "blob_pairs"),
    ),
    "blobs": (
        "surveil.blobs.extract",
        "extract_blobs",
        ("centroids_px", "areas_px", "bboxes_px", "silhouette", "rel_v", "labels"),
    ),
}


def _function_from(checkout: Path, module: str, name: str):
    path = checkout.joinpath(*module.split(".")).with_suffix(".py")
    if not path.is_file():
        raise SystemExit(f"--against {checkout}: no {path.relative_to(checkout)} there")
    spec = importlib.util.spec_from_file_location(f"against_{name}", path)
    loaded = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(loaded)
    return getattr(loaded, name)


def recorded_calls(rec_dir: Path, name: str, n_sets: int) -> tuple[list, int]:
    """The arguments of every call of pipeline function ``name`` in the first ``n_sets``
    frame sets of a run, and the number of frame sets run."""
    rec = open_recording(rec_dir)
    cfg = dataclasses.replace(load_pipeline_config(None), seed=0)
    pipeline = Pipeline.for_recording(rec, cfg, load_rules())
    original = getattr(pipeline_module, name)
    calls = []

    def spy(*args, **kwargs):
        calls.append((args, kwargs))
        return original(*args, **kwargs)

    setattr(pipeline_module, name, spy)
    try:
        n = 0
        for fs in itertools.islice(rec.framesets(), n_sets):
            pipeline.step(fs)
            n += 1
    finally:
        setattr(pipeline_module, name, original)
    return calls, n


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--stage", choices=sorted(STAGES), default="candidates")
    parser.add_argument("--frame-sets", type=int, default=None, help="default: 240 / 60")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--against", type=Path, help="another checkout to time alongside")
    args = parser.parse_args(argv)
    if not args.names and args.scene_seeds is None:
        args.names = ["three_people"]
    module, name, fields = STAGES[args.stage]
    n_sets = args.frame_sets or (60 if args.stage == "blobs" else 240)
    mine_fn = getattr(importlib.import_module(module), name)
    other_fn = _function_from(args.against, module, name) if args.against else None
    use_one_opencv_thread()
    print(f"{args.stage}: `{module}.{name}`")
    print("| scene | frame sets | calls | ms per set (this) | ms per set (--against) | ratio |")
    print("|---|---|---|---|---|---|")
    for scene in scene_names(args):
        calls, n = recorded_calls(render(scene, args.out), name, n_sets)
        mine = np.zeros((args.rounds, len(calls)))
        theirs = np.zeros_like(mine)
        for r in range(args.rounds):
            for k, (a, kw) in enumerate(calls):
                # the second call on the same data finds it in the caches: who goes first
                # alternates
                order = (
                    [(mine_fn, mine)]
                    if other_fn is None
                    else [(mine_fn, mine), (other_fn, theirs)]
                )
                if (r + k) % 2:
                    order.reverse()
                for fn, times in order:
                    t0 = time.perf_counter()
                    fn(*a, **kw)
                    times[r, k] = time.perf_counter() - t0
        # each call's median over the rounds (robust to the load's spikes), summed
        per_set = 1000 * np.median(mine, axis=0).sum() / n
        if other_fn is None:
            print(f"| {scene} | {n} | {len(calls)} | {per_set:.2f} | - | - |")
            continue
        for a, kw in calls:
            x, y = mine_fn(*a, **kw), other_fn(*a, **kw)
            if not all(np.array_equal(getattr(x, f), getattr(y, f)) for f in fields):
                print(f"{scene}: the two versions of {name} differ", file=sys.stderr)
                return 1
        theirs_per_set = 1000 * np.median(theirs, axis=0).sum() / n
        ratio = np.median(mine / theirs)
        print(
            f"| {scene} | {n} | {len(calls)} | {per_set:.2f} | {theirs_per_set:.2f} "
            f"| {ratio:.3f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
