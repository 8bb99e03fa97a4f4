"""One true hand through a run, frame set by frame set: what it holds, the tracker nearest
it, that tracker's carry estimate and the pick/place episodes open on the hand's trackers.

    python benchmarks/carry_timeline.py NAME --limb p1/right_hand [--from 6] [--to 10]
        [--every 1] [--tracker ID] [--out out/bench_synth] [--seed 0] [--config TOML]

Runs the pipeline on the recording in this process (carry estimates are not written to the
MCAP), from its start, and prints per frame set in the time window (s from the first set):
how many cameras see the hand, what the ground truth says it holds, the tracker nearest it
(``t<id> <phase> <mm>``; with ``--tracker``, that one) and its carry estimate
(``carry=<0|1> <confidence> <hue> since <s>``: the state, how sure, the object's hue, when
the oldest sample in its window was taken; ``-`` for a hand the carry stage did not analyse,
e.g. a lost one), and the activity engine's still episodes (``<rule>:t<id> rest <s> apart
<s>``). The questions it answers: whether a missed pick or place lost its carry evidence
(the hand hidden, its window aged or restarted) or its tracker (how session 92 traced
pick_place take 102).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from surveil.activity import load_rules
from surveil.eval.score import align_frames
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import Pipeline, load_pipeline_config, use_one_opencv_thread

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from pipeline_bench import render  # noqa: E402


def _s(t_ns: int | None, t0_ns: int) -> str:
    return "-" if t_ns is None else f"{(t_ns - t0_ns) * 1e-9:.2f}"


def timeline(
    rec_dir: Path,
    limb: str,
    seed: int,
    config: Path | None = None,
    from_s: float = 0.0,
    to_s: float = np.inf,
    every: int = 1,
    tracker: int | None = None,
) -> Iterator[str]:
    """The timeline's lines (module docstring); stops after ``to_s``."""
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    if limb not in gt.labels:
        raise SystemExit(f"{rec_dir.name}: no true limb {limb!r} (one of {', '.join(gt.labels)})")
    j = gt.labels.index(limb)
    cfg = dataclasses.replace(load_pipeline_config(config), seed=seed)
    pipeline = Pipeline.for_recording(rec, cfg, load_rules())
    t0_ns = None
    for k, fs in enumerate(rec.framesets()):
        result = pipeline.step(fs)
        t0_ns = fs.t_ns if t0_ns is None else t0_ns
        t_s = (fs.t_ns - t0_ns) * 1e-9
        if t_s > to_s:
            return
        if t_s < from_s or k % every:
            continue
        g = int(align_frames(gt.t_ns, np.array([fs.t_ns]), gt.fps)[0])
        if g < 0:
            continue  # no true frame within half a period
        x = gt.positions_m[g, j]
        if not np.isfinite(x).all():
            yield f"{t_s:6.2f} | not in the room"
            continue
        held = [o for o, by in zip(gt.object_names, gt.held_by[g], strict=True) if by == limb]
        targets = result.track.targets
        near = [t for t in targets if t.target_id == tracker] if tracker is not None else []
        if not near and targets:
            near = [min(targets, key=lambda t: float(np.linalg.norm(t.mean_m - x)))]
        if near:
            t = near[0]
            mm = 1000 * float(np.linalg.norm(t.mean_m - x))
            who = f"t{t.target_id} {t.label} {t.phase.value} {mm:.0f}mm"
            est = result.carry.get(t.target_id)
            carry = (
                "-"
                if est is None
                else f"carry={int(est.carrying)} {est.confidence:.2f} "
                f"{'-' if est.hue_deg is None else f'{est.hue_deg:.0f}deg'} "
                f"since {_s(est.since_ns, t0_ns)}"
            )
        else:
            who, carry = "-", "-"
        stills = " ".join(
            f"{rule.rsplit(':', 1)[-1]}:t{hand} rest {_s(rest, t0_ns)} apart {_s(apart, t0_ns)}"
            for rule, hand, rest, apart in pipeline.activity.open_stills
        )
        yield (
            f"{t_s:6.2f} | {gt.n_views[g, j]} views | holds {','.join(held) or '-'} | {who}"
            f" | {carry} | {stills or '-'}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", help="bundled scene, NAME@N for a held-out take")
    parser.add_argument("--limb", required=True, help="true hand, e.g. p1/right_hand")
    parser.add_argument("--from", dest="from_s", type=float, default=0.0)
    parser.add_argument("--to", dest="to_s", type=float, default=np.inf)
    parser.add_argument("--every", type=int, default=1, help="print every N-th frame set")
    parser.add_argument("--tracker", type=int, help="follow this tracker id, not the nearest")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML) of the run")
    args = parser.parse_args()
    use_one_opencv_thread()  # as `surveil run`
    rec_dir = render(args.name, args.out)
    print(
        f"{args.name}, {args.limb}, seed {args.seed}: time s | views | holds | tracker | "
        "its carry estimate | still episodes"
    )
    for line in timeline(
        rec_dir,
        args.limb,
        args.seed,
        args.config,
        args.from_s,
        args.to_s,
        max(args.every, 1),
        args.tracker,
    ):
        print(line)


if __name__ == "__main__":
    main()
