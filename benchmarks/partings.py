"""Every separation of a combined pair in a run, judged against the ground truth.

    python benchmarks/partings.py [--out out/bench_synth] [--seeds 0] [--config TOML]
        [--rerun] [--list] [NAME ...]

Reads ``out/bench_synth/<name>[.<config stem>].seed<N>.mcap`` (written by
``benchmarks/pipeline_bench.py``; run here when missing or with ``--rerun``) and the ground
truth. A parting is a frame set in which two trackers that were combined in the previous one
(the same estimate) both leave the combined phase (not lost); their estimates then are the
modes they took. Each is judged:

- ``kept``: both modes lie within ``--radius`` of true limbs, two different ones, and each
  tracker took the limb it followed before the pair joined (its nearest true limb in its
  last frame set outside the pair);
- ``swapped``: both on true limbs, but the trackers took each other's (or another) limb;
- ``ghost``: a mode is off every true limb (a candidate where no limb is: the pair parted
  onto something that was not one of its targets), or both modes are on one limb.

Ghost partings are what the tracker's separation rules are about (docs/tracking.md,
"Separation"); ``--list`` prints each parting: time, trackers, the limb and distance of each
mode.

``--routes`` runs the pipeline again (the MCAPs are rewritten, the same runs) with a spy on
the tracker's separation, and the listing also says how each pair parted (``modes``: its
modes moved ``separate_gain_m`` apart; ``far apart``: they stayed ``separate_far_m`` apart;
``seeds``: it parted onto seeds, ``fixed`` when the parting gave each tracker its mode;
``never met``), how far apart its modes first appeared (m) and the prior and supporting views
of the far mode's candidate then (where the modes were measured, not set by a parting onto
seeds): the figures of docs/benchmarks.md, session 99.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from collections import Counter, defaultdict
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from surveil.datatypes import Phase
from surveil.io.ground_truth import GroundTruth, load_ground_truth
from surveil.io.mcap_reader import RunData, read_run

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from pipeline_bench import (  # noqa: E402
    add_run_arguments,
    parse_seeds,
    print_kind_counts,
    run_of,
    scene_names,
)

VERDICTS = ("kept", "swapped", "ghost")


@dataclass(frozen=True)
class Route:
    """How the tracker parted a pair (``--routes``): the route, the distance (m) between its
    modes when they first appeared, and the far mode's candidate then: prior and views (-1
    when unknown)."""

    route: str
    first_m: float
    far_prior: float
    far_views: int


class RouteSpy:
    """Records, while active, how every combined pair the tracker separates parted, by (time
    of the frame set, ns; the two tracker ids)."""

    def __init__(self) -> None:
        self.routes: dict[tuple[int, frozenset[int]], Route] = {}
        self._first: dict[tuple[int, int], tuple[float, int]] = {}

    def __enter__(self) -> RouteSpy:
        from surveil.tracking import manager

        self._cls = manager.MultiTargetTracker
        self._measure, self._separate = self._cls._measure_separation, self._cls._separate
        spy = self

        def measure(trk, pts, prior, dt_s, t_ns):
            spy._measure(trk, pts, prior, dt_s, t_ns)
            for tr, _ in trk._combined_pairs():
                if tr.split_m is not None and tr.apart_frames == 1 and len(pts):
                    k = int(np.argmin(np.linalg.norm(pts - tr.split_m[1], axis=1)))
                    views = int(trk._views[k]) if len(trk._views) == len(pts) else -1
                    spy._first[(id(trk), tr.id)] = (float(prior[k]), views)

        def separate(trk, a, b, t_ns, met=True):
            if a.split_m is not None:
                lc = trk.cfg.lifecycle
                if a.split_fixed is not None and b.split_fixed is not None:
                    route = "fixed"
                elif not met:
                    route = "never met"
                elif not np.isfinite(a.split_gain_m):
                    route = "seeds"
                elif a.split_gain_m >= lc.separate_gain_m:
                    route = "modes"
                else:
                    route = "far apart"
                # a parting onto seeds sets the modes itself (infinite gain): nothing of them
                # was measured as they appeared
                measured = bool(np.isfinite(a.split_gain_m))
                prior, views = (
                    spy._first.get((id(trk), a.id), (np.nan, -1)) if measured else (np.nan, -1)
                )
                first = float(a.split_first_m) if measured else np.nan
                spy.routes[(int(t_ns), frozenset((a.id, b.id)))] = Route(
                    route, first, prior, views
                )
            spy._separate(trk, a, b, t_ns, met)

        self._cls._measure_separation, self._cls._separate = measure, separate
        return self

    def __exit__(self, *exc) -> None:
        self._cls._measure_separation, self._cls._separate = self._measure, self._separate


def _nearest_limb(gt: GroundTruth, t_ns: int, point_m: np.ndarray) -> tuple[int, float]:
    """Index and distance (m) of the true limb nearest ``point_m`` at the ground-truth frame
    nearest ``t_ns``."""
    f = gt.frame_at(t_ns)
    d = np.linalg.norm(gt.positions_m[f] - point_m, axis=1)
    d = np.where(np.isfinite(d), d, np.inf)
    k = int(np.argmin(d))
    return k, float(d[k])


@dataclass(frozen=True)
class Parting:
    """One parting: when (s from the first frame set), the two trackers, the true limb
    nearest each one's mode with its distance (m), and the verdict (``VERDICTS``)."""

    t_s: float
    trackers: tuple[int, int]
    modes: tuple[tuple[int, float], tuple[int, float]]
    verdict: str


def partings(gt: GroundTruth, run: RunData, radius_m: float) -> list[Parting]:
    """Every parting of the run (see the module docstring), oldest first."""
    combined, lost = Phase.COMBINED.code, Phase.LOST.code
    frame, tracker = run.target_frame, run.target_tracker
    state, pos = run.target_state, run.target_pos_m
    row_of = {(int(f), int(t)): r for r, (f, t) in enumerate(zip(frame, tracker, strict=True))}
    # frame set -> (row in the pair, row outside it) of each tracker that left a pair there
    leaving: dict[int, list[tuple[int, int]]] = defaultdict(list)
    for r in np.flatnonzero(state == combined):
        now = row_of.get((int(frame[r]) + 1, int(tracker[r])))
        if now is not None and state[now] not in (combined, lost):
            leaving[int(frame[r]) + 1].append((int(r), now))
    out = []
    for f in sorted(leaving):
        t_ns = int(run.frame_t_ns[f])
        for (ra, na), (rb, nb) in itertools.combinations(leaving[f], 2):
            if np.linalg.norm(pos[ra] - pos[rb]) > 1e-3:  # not partners: not one estimate
                continue
            modes = (_nearest_limb(gt, t_ns, pos[na]), _nearest_limb(gt, t_ns, pos[nb]))
            before = [_before_limb(gt, run, int(tracker[r]), f) for r in (ra, rb)]
            if not all(d <= radius_m for _, d in modes) or modes[0][0] == modes[1][0]:
                verdict = "ghost"
            elif before == [m[0] for m in modes]:
                verdict = "kept"
            else:
                verdict = "swapped"
            t_s = (t_ns - int(run.frame_t_ns[0])) * 1e-9
            out.append(Parting(t_s, (int(tracker[ra]), int(tracker[rb])), modes, verdict))
    return out


def _route_at(
    routes: dict[tuple[int, frozenset[int]], Route], t_ns: int, trackers: tuple[int, int]
) -> Route | None:
    """The route recorded for the pair ``trackers`` at the frame set nearest ``t_ns`` (within
    1 ms: the listing's time is rounded)."""
    pair = frozenset(trackers)
    near = [(abs(t - t_ns), r) for (t, ids), r in routes.items() if ids == pair]
    near = [(dt, r) for dt, r in near if dt <= 1_000_000]
    return min(near, key=lambda x: x[0])[1] if near else None


def _cell(x: float, digits: int) -> str:
    return "-" if not np.isfinite(x) else f"{x:.{digits}f}"


def _before_limb(gt: GroundTruth, run: RunData, tid: int, frame: int) -> int | None:
    """The true limb nearest tracker ``tid`` in its last frame set before ``frame`` outside a
    combined pair (None if it has none)."""
    mine = np.flatnonzero(
        (run.target_tracker == tid)
        & (run.target_frame < frame)
        & (run.target_state != Phase.COMBINED.code)
        & (run.target_state != Phase.LOST.code)
    )
    if not len(mine):
        return None
    last = mine[np.argmax(run.target_frame[mine])]
    t_ns = int(run.frame_t_ns[run.target_frame[last]])
    return _nearest_limb(gt, t_ns, run.target_pos_m[last])[0]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser)
    parser.add_argument(
        "--seeds", type=parse_seeds, default=None, help="e.g. 0-2 (default --seed)"
    )
    parser.add_argument("--radius", type=float, default=0.12, help="on a limb within this, m")
    parser.add_argument("--list", action="store_true", help="print every parting")
    parser.add_argument(
        "--routes", action="store_true", help="run again and list how each pair parted"
    )
    args = parser.parse_args(argv)
    seeds = args.seeds or [args.seed]
    args.rerun = args.rerun or args.routes
    rows, listing = [], []
    totals: Counter = Counter()
    for name in scene_names(args):
        counts: Counter = Counter()
        for seed in seeds:
            args.seed = seed
            with RouteSpy() if args.routes else nullcontext() as spy:
                mcap = run_of(name, args)
            gt = load_ground_truth(args.out / name)
            run = read_run(mcap)
            for p in partings(gt, run, args.radius):
                counts[p.verdict] += 1
                (a, da), (b, db) = p.modes
                ta, tb = p.trackers
                line = (
                    f"| {name} | {seed} | {p.t_s:.2f} | t{ta} / t{tb} "
                    f"| {gt.labels[a]} {1000 * da:.0f} | {gt.labels[b]} {1000 * db:.0f} "
                    f"| {p.verdict} |"
                )
                if args.routes:
                    t_ns = int(run.frame_t_ns[0]) + round(p.t_s * 1e9)
                    r = _route_at(spy.routes, t_ns, p.trackers)
                    line += (
                        " - | - | - | - |"
                        if r is None
                        else f" {r.route} | {_cell(r.first_m, 3)} | {_cell(r.far_prior, 2)} "
                        f"| {r.far_views if r.far_views >= 0 else '-'} |"
                    )
                listing.append(line)
        totals.update(counts)
        n = sum(counts.values())
        rows.append(f"| {name} | {n} | " + " | ".join(str(counts[v]) for v in VERDICTS) + " |")
    print(f"seeds {', '.join(map(str, seeds))}, a mode on a limb within {args.radius:.2f} m\n")
    print_kind_counts(
        "partings",
        VERDICTS,
        rows,
        totals,
        (
            "scenario | seed | t s | trackers | mode 1: limb mm | mode 2: limb mm | verdict"
            + (" | route | first apart m | far prior | far views" if args.routes else "")
        )
        if args.list
        else None,
        listing,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
