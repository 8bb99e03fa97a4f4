"""One true limb through a run, frame set by frame set: the trackers and candidates nearest it.

    python benchmarks/limb_timeline.py NAME --limb p2/left_hand [--from 3.5] [--to 5.0]
        [--every 1] [--near 3] [--out out/bench_synth] [--seed 0] [--rerun] [--config TOML]

Reads ``out/bench_synth/<name>[.<config stem>].seed<N>.mcap`` (written by
``benchmarks/pipeline_bench.py``; run here when missing or with ``--rerun``) and the ground
truth. Per frame set in the time window (s from the first set) it prints how many cameras
see the limb, the ``--near`` trackers nearest it (``t<id>:<label>:<phase>@<mm>``) and the
candidates nearest it (``<mm> (<prior>, dz <mm>)``, dz the candidate's height above the
limb). The questions it answers: when a tracker left the limb, what it followed instead, and
whether the limb had a candidate meanwhile (how ``benchmarks/id_switches.py``'s switches
and the hand errors of docs/benchmarks.md were traced, sessions 75-76).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from surveil.datatypes import Phase
from surveil.eval.score import align_frames
from surveil.io.ground_truth import GroundTruth, load_ground_truth
from surveil.io.mcap_reader import RunData, read_run

PHASE_OF_CODE = {p.code: p.value for p in Phase}
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from pipeline_bench import add_run_arguments, run_of  # noqa: E402


def timeline_rows(
    gt: GroundTruth,
    run: RunData,
    limb: str,
    from_s: float = 0.0,
    to_s: float = np.inf,
    every: int = 1,
    near: int = 3,
) -> list[str]:
    """The timeline's lines (module docstring), one per frame set with ground truth."""
    j = gt.labels.index(limb)
    truth_of = align_frames(gt.t_ns, run.frame_t_ns, gt.fps)
    t0_ns = run.frame_t_ns[0] if len(run.frame_t_ns) else 0
    rows = []
    for m, t_ns in enumerate(run.frame_t_ns[::every]):
        m *= every
        t_s = (t_ns - t0_ns) * 1e-9
        g = truth_of[m]
        if not from_s <= t_s <= to_s or g < 0:
            continue
        x = gt.positions_m[g, j]
        if not np.isfinite(x).all():
            rows.append(f"{t_s:6.2f} | not in the room")
            continue
        here = run.frame_rows(m)
        d = np.linalg.norm(run.target_pos_m[here] - x, axis=1)
        ids, labels = run.target_tracker[here], run.target_label[here]
        phases = [PHASE_OF_CODE.get(int(c), "?") for c in run.target_state[here]]
        trackers = " ".join(
            f"t{ids[k]}:{labels[k]}:{phases[k]}@{1000 * d[k]:.0f}" for k in np.argsort(d)[:near]
        )
        # /candidates messages are matched by time: a set may have targets and no candidates
        c = int(np.searchsorted(run.candidate_t_ns, t_ns))
        cand = (
            run.candidate_rows(c)
            if c < len(run.candidate_t_ns) and run.candidate_t_ns[c] == t_ns
            else slice(0, 0)
        )
        c_pos, c_prior = run.candidate_pos_m[cand], run.candidate_prior[cand]
        dc = np.linalg.norm(c_pos - x, axis=1)
        cands = " ".join(
            f"{1000 * dc[k]:.0f} ({c_prior[k]:.2f}, dz {1000 * (c_pos[k, 2] - x[2]):+.0f})"
            for k in np.argsort(dc)[:near]
        )
        rows.append(f"{t_s:6.2f} | {gt.n_views[g, j]} views | {trackers or '-'} | {cands or '-'}")
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_run_arguments(parser)
    parser.add_argument("--limb", required=True, help="true limb, e.g. p2/left_hand")
    parser.add_argument("--from", dest="from_s", type=float, default=0.0, help="s")
    parser.add_argument("--to", dest="to_s", type=float, default=np.inf, help="s")
    parser.add_argument("--every", type=int, default=1, help="every N-th frame set")
    parser.add_argument("--near", type=int, default=3, help="trackers and candidates shown")
    args = parser.parse_args(argv)
    if len(args.names) != 1:
        parser.error("name one scene (NAME or NAME@N)")
    if args.every < 1 or args.near < 1:
        parser.error("--every and --near take 1 or more")
    name = args.names[0]
    gt = load_ground_truth(args.out / name)
    if args.limb not in gt.labels:
        parser.error(f"--limb {args.limb}: not in {name}'s ground truth ({', '.join(gt.labels)})")
    run = read_run(run_of(name, args))
    print(f"{name}, {args.limb}: time s | views | trackers nearest | candidates nearest")
    rows = timeline_rows(gt, run, args.limb, args.from_s, args.to_s, args.every, args.near)
    print("\n".join(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
