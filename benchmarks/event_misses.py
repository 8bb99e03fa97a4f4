"""What happened to every true activity event in a run: recognised, or where it was lost.

    python benchmarks/event_misses.py [--out out/bench_synth] [--seed 0] [--rerun] [--config TOML]
        [--trace] [NAME ...]

Reads ``out/bench_synth/<name>[.<config stem>].seed<N>.mcap`` (written by
``benchmarks/pipeline_bench.py``; run here when missing or with ``--rerun``) and the ground
truth. For every true event, the trackers nearest to its true actors (hands, or a hand and a
head) are followed from 0.7 s before to 0.5 s after the climax; trackers are matched by
position (within ``--gate-m``), not by label, so a wrong label does not hide a good track.
Verdicts:

- ``recognised``: an output event of the same activity within 1 s of the climax;
- ``other event``: an output event of another activity within 1 s (named);
- ``combined``: (pair events) the actors' trackers were combined within 0.3 s of the
  climax, but no event followed (labels, carry states or rule thresholds);
- ``actor lost``: an actor had no tracker near it in more than 40 % of the window;
- ``one tracker``: (pair events) one tracker was nearest to both actors near the climax,
  never in the combined state: the other's tracker was lost or had drifted onto it;
- ``not combined``: both actors tracked, never combined;
- ``tracked``: (one-hand events) the hand was tracked, no event followed.

The "seen in 2+ views" column gives, per actor, the fraction of the true frames within
0.3 s of the climax in which two or more cameras see it unoccluded (the ground truth's
``visible_in``): a multi-view tracker has nothing to triangulate when it is low (a hand
hidden by the object it holds or by the body). It is a hint, not a verdict: the combined
state exists for hands that hide each other (a clap is recognised with its hands in two
views a third of that time).

``--trace`` adds, under every event that was not recognised, its window frame by frame: for
each actor the nearest tracker (label, state, error to the truth), the true distance between
the actors and the distance between their trackers.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import numpy as np

from surveil.datatypes import ActivityEvent, Phase
from surveil.io.ground_truth import GroundTruth, load_ground_truth
from surveil.io.mcap_reader import RunData, read_run

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from pipeline_bench import add_run_arguments, run_of, scene_names  # noqa: E402

BEFORE_S, AFTER_S, CLIMAX_S, MATCH_S = 0.7, 0.5, 0.3, 1.0


def seen_in_two_views(event: ActivityEvent, gt: GroundTruth) -> list[float]:
    """Per actor of ``event``: fraction of the true frames within CLIMAX_S of the climax in
    which two or more cameras see it."""
    near = np.abs(gt.t_ns - event.climax_ns) <= CLIMAX_S * 1e9
    out = []
    for a in event.actors:
        if a not in gt.labels or not near.any():
            out.append(float("nan"))
            continue
        views = gt.visible[near, gt.labels.index(a)].sum(axis=1)
        out.append(float(np.mean(views >= 2)))
    return out


def _actor_tracks(
    run: RunData, gt: GroundTruth, actor: str, frames: np.ndarray, gate_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per output frame: the tracker nearest to the true actor within ``gate_m`` (-1: none),
    its state code and its target row (-1: none)."""
    j = gt.labels.index(actor)
    trackers = np.full(len(frames), -1)
    states = np.full(len(frames), 255)
    target_rows = np.full(len(frames), -1)
    for k, f in enumerate(frames):
        g = gt.frame_at(run.frame_t_ns[f])
        truth = gt.positions_m[g, j]
        span = run.frame_rows(int(f))
        rows = np.arange(span.start, span.stop)
        rows = rows[run.target_state[rows] != Phase.LOST.code]
        if not np.isfinite(truth).all() or len(rows) == 0:
            continue
        d = np.linalg.norm(run.target_pos_m[rows] - truth, axis=1)
        if d.min() <= gate_m:
            r = rows[int(d.argmin())]
            trackers[k] = run.target_tracker[r]
            states[k] = run.target_state[r]
            target_rows[k] = r
    return trackers, states, target_rows


def _window(run: RunData, climax_ns: int) -> np.ndarray:
    """Output frames from BEFORE_S before to AFTER_S after a climax."""
    return np.flatnonzero(
        (run.frame_t_ns >= climax_ns - BEFORE_S * 1e9)
        & (run.frame_t_ns <= climax_ns + AFTER_S * 1e9)
    )


_STATE = {p.code: p.value for p in Phase}


def trace(event: ActivityEvent, run: RunData, gt: GroundTruth, gate_m: float) -> list[str]:
    """The event's window frame by frame (lines of text, see the module docstring)."""
    frames = _window(run, event.climax_ns)
    actors = [a for a in event.actors if a in gt.labels]
    rows = [_actor_tracks(run, gt, a, frames, gate_m)[2] for a in actors]
    lines = []
    for k, f in enumerate(frames):
        g = gt.frame_at(run.frame_t_ns[f])
        cells = [f"{(run.frame_t_ns[f] - event.climax_ns) / 1e9:+.2f}s"]
        for a, r in zip(actors, rows, strict=True):
            if r[k] < 0:
                cells.append(f"{a}: -")
                continue
            err = np.linalg.norm(run.target_pos_m[r[k]] - gt.positions_m[g, gt.labels.index(a)])
            state = _STATE.get(int(run.target_state[r[k]]), "?")
            cells.append(
                f"{a}: t{run.target_tracker[r[k]]} {run.target_label[r[k]]} {state} "
                f"{err * 1000:.0f}mm"
            )
        if len(actors) == 2:
            true_d = np.linalg.norm(
                gt.positions_m[g, gt.labels.index(actors[0])]
                - gt.positions_m[g, gt.labels.index(actors[1])]
            )
            cells.append(f"apart {true_d * 1000:.0f}mm")
            if rows[0][k] >= 0 and rows[1][k] >= 0:
                d = np.linalg.norm(run.target_pos_m[rows[0][k]] - run.target_pos_m[rows[1][k]])
                cells.append(f"trackers {d * 1000:.0f}mm")
        lines.append("    " + " | ".join(cells))
    return lines


def verdict(event: ActivityEvent, run: RunData, gt: GroundTruth, gate_m: float) -> tuple[str, str]:
    """(verdict, detail) of one true event (see the module docstring)."""
    climax = event.climax_ns  # the run's times and the ground truth's share one clock
    near = [e for e in run.events if abs(e.climax_ns - climax) <= MATCH_S * 1e9]
    if any(e.activity == event.activity for e in near):
        return "recognised", ""
    if near:
        return "other event", ", ".join(sorted({e.activity for e in near}))
    frames = _window(run, climax)
    hands = [a for a in event.actors if a in gt.labels]
    tracks = [_actor_tracks(run, gt, a, frames, gate_m)[:2] for a in hands]
    tracked = [float(np.mean(t >= 0)) for t, _ in tracks]
    detail = ", ".join(f"{a} {f:.0%}" for a, f in zip(hands, tracked, strict=True))
    if min(tracked, default=0.0) < 0.6:
        return "actor lost", detail
    if len(tracks) < 2:
        return "tracked", detail
    at_climax = np.abs(run.frame_t_ns[frames] - climax) <= CLIMAX_S * 1e9
    (ta, sa), (tb, sb) = tracks[:2]
    both = (sa == Phase.COMBINED.code) & (sb == Phase.COMBINED.code)
    if (at_climax & (ta >= 0) & both).any():
        return "combined", detail
    if (at_climax & (ta >= 0) & (ta == tb)).any():
        return "one tracker", detail
    return "not combined", detail


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser)
    parser.add_argument("--gate-m", type=float, default=0.15, help="tracker-actor gate, m")
    parser.add_argument(
        "--trace", action="store_true", help="print each missed event's window frame by frame"
    )
    args = parser.parse_args(argv)
    names = scene_names(args)
    totals: Counter = Counter()
    print("| scenario | activity | climax s | actors | seen in 2+ views | verdict | detail |")
    print("|---|---|---|---|---|---|---|")
    for name in names:
        mcap = run_of(name, args)
        run = read_run(mcap)
        gt = load_ground_truth(args.out / name)
        for event in gt.events:
            v, detail = verdict(event, run, gt, args.gate_m)
            totals[v] += 1
            seen = seen_in_two_views(event, gt)
            climax_s = event.climax_ns / 1e9
            print(
                f"| {name} | {event.activity} | {climax_s:.2f} | {', '.join(event.actors)} "
                f"| {', '.join(f'{f:.0%}' for f in seen)} | {v} | {detail} |"
            )
            if args.trace and v != "recognised":
                print("\n".join(trace(event, run, gt, args.gate_m)))
    print("\n" + ", ".join(f"{k}: {n}" for k, n in totals.most_common()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
