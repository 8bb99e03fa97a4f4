"""Time the candidate stage alone on a recording's observations, optionally against another
checkout's candidate stage, call by call.

    python benchmarks/candidates_speed.py [--out out/bench_synth] [--rounds 5]
        [--against CHECKOUT] [NAME ...]

Runs the pipeline once over each scene (default: three_people, issue 3's "4 cameras and 3
people" case) and keeps every frame set's observations and the tracker's expected hands;
then calls :func:`surveil.recon.candidates.make_candidates` on them ``--rounds`` times and
prints the median milliseconds per frame set. With ``--against``, the same calls also go to
``CHECKOUT/surveil/recon/candidates.py`` (a worktree of an older commit), alternating call by
call (and which goes first) so that the shared machine's load and warm caches fall on both
alike; it prints both medians and the median per-call ratio, and checks that both give the
same candidates in every frame set.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np
from pipeline_bench import ROOT, add_scene_arguments, render, scene_names

import surveil.recon.candidates as current
from surveil.activity import load_rules
from surveil.io.recording import open_recording
from surveil.pipeline import Pipeline, load_pipeline_config, use_one_opencv_thread

FIELDS = ("points_m", "prior", "half_gap_m", "cam_pairs", "blob_pairs")


def _module_from(checkout: Path):
    path = checkout / "surveil" / "recon" / "candidates.py"
    if not path.is_file():
        raise SystemExit(f"--against {checkout}: no {path.relative_to(checkout)} there")
    spec = importlib.util.spec_from_file_location("candidates_against", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def recorded_calls(rec_dir: Path):
    """The pipeline's arguments to ``make_candidates`` in every frame set of a run."""
    rec = open_recording(rec_dir)
    cfg = dataclasses.replace(load_pipeline_config(None), seed=0)
    pipeline = Pipeline.for_recording(rec, cfg, load_rules())
    calls = []
    for fs in rec.framesets():
        expected = pipeline.tracker.expected_hands(fs.t_ns)
        result = pipeline.step(fs)
        calls.append((list(result.observations.values()), expected))
    return pipeline.rig, cfg.candidates, calls


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--against", type=Path, help="another checkout to time alongside")
    args = parser.parse_args(argv)
    if not args.names and args.scene_seeds is None:
        args.names = ["three_people"]
    other = _module_from(args.against) if args.against else None
    use_one_opencv_thread()
    print("| scene | frame sets | ms per set (this) | ms per set (--against) | ratio |")
    print("|---|---|---|---|---|")
    for name in scene_names(args):
        rig, ccfg, calls = recorded_calls(render(name, args.out))
        mine, theirs = [], []
        for r in range(args.rounds):
            for k, (obs, expected) in enumerate(calls):
                # the second call on the same data finds it in the caches: who goes first
                # alternates
                order = [(current, mine), (other, theirs)] if other is not None else []
                if (r + k) % 2 and order:
                    order.reverse()
                for module, times in order or [(current, mine)]:
                    t0 = time.perf_counter()
                    module.make_candidates(obs, rig, ccfg, expected_m=expected)
                    times.append(time.perf_counter() - t0)
        ms = 1000 * np.median(mine)
        if other is None:
            print(f"| {name} | {len(calls)} | {ms:.3f} | - | - |")
            continue
        for obs, expected in calls:
            a = current.make_candidates(obs, rig, ccfg, expected_m=expected)
            b = other.make_candidates(obs, rig, ccfg, expected_m=expected)
            if not all(np.array_equal(getattr(a, f), getattr(b, f)) for f in FIELDS):
                print(f"{name}: the two candidate stages differ", file=sys.stderr)
                return 1
        ratio = np.median(np.array(mine) / np.array(theirs))
        print(
            f"| {name} | {len(calls)} | {ms:.3f} | {1000 * np.median(theirs):.3f} | {ratio:.3f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
