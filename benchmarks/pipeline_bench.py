"""End-to-end benchmark: `surveil run` + `surveil eval` on every bundled scenario (issues 4, 5).

    python benchmarks/pipeline_bench.py [--out out/bench_synth] [--seed 0] [--config TOML]
        [NAME ...]

Renders (or reuses) each scenario, runs the whole pipeline with default settings and rules on
the recording's own (deliberately slightly wrong) calibration, scores the output MCAP against
the ground truth, and prints one Markdown table for tracking and one for events, plus the
processing rate (frame sets per second, wall clock, one process).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager, nullcontext
from pathlib import Path

from surveil.activity import load_rules
from surveil.eval.score import EvalConfig, evaluate
from surveil.io.mcap_writer import McapSink, McapWriter
from surveil.io.recording import open_recording
from surveil.pipeline import (
    Pipeline,
    RunSummary,
    load_pipeline_config,
    run_recording,
    use_one_opencv_thread,
)
from surveil.synth.scenario import COMPRESSIONS
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]


def cell(x, digits=3):
    """A metric for a Markdown table cell: ``-`` where it is undefined (None)."""
    return "-" if x is None else f"{x:.{digits}f}"


def output_path(out_dir: Path, name: str, config: Path | None, seed: int) -> Path:
    """Where a run of ``name`` goes: ``<name>.seed<N>.mcap``, or
    ``<name>.<config stem>.seed<N>.mcap``. The seed is in the name so that runs of other
    seeds (side by side, or one after the other) never overwrite a run that a later
    ``--seed N`` without ``--rerun`` reads back."""
    stem = f"{name}.{config.stem}" if config else name
    return out_dir / f"{stem}.seed{seed}.mcap"


def parse_seeds(text: str) -> list[int]:
    """Seeds from ``"0-5"``, ``"0,2,7"`` or a mix (``"0-2,9"``).

    >>> parse_seeds("0-2,9")
    [0, 1, 2, 9]
    """
    seeds: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.strip().partition("-")
        try:
            first, last = int(lo), int(hi or lo)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"seeds must look like 0-5 or 0,2,7, got {text!r}"
            ) from None
        if last < first:
            raise argparse.ArgumentTypeError(f"empty seed range {part!r} in {text!r}")
        seeds.extend(range(first, last + 1))
    return seeds


def scenario_of(name: str) -> tuple[Path, int | None, str | None]:
    """The bundled scenario file, scene seed and codec of a scene name: ``demo`` is the
    bundled take, ``demo@11`` the take rendered with ``[scene] seed = 11`` (held out: the
    settings were tuned on the bundled takes), ``demo~png`` or ``demo@11~png`` that take
    stored with ``[effects] compression = "png"`` (the codec held out).

    >>> [(p.name, s, c) for p, s, c in map(scenario_of, ["demo", "demo@11", "demo@11~png"])]
    [('demo.toml', None, None), ('demo.toml', 11, None), ('demo.toml', 11, 'png')]
    """
    take, tilde, codec = name.partition("~")
    base, at, seed = take.partition("@")
    path = ROOT / "recordings" / f"{base}.toml"
    if not path.is_file():
        raise SystemExit(f"no bundled scenario {base!r} (recordings/{base}.toml)")
    if tilde and codec not in COMPRESSIONS:
        raise SystemExit(
            f"scene {name!r}: the codec after '~' must be one of {', '.join(COMPRESSIONS)}"
        )
    if at and not seed.isdigit():
        raise SystemExit(f"scene {name!r}: the scene seed after '@' must be a number >= 0")
    return path, int(seed) if at else None, codec if tilde else None


def render(name: str, out_dir: Path) -> Path:
    """Render scene ``name`` (:func:`scenario_of`) into ``out_dir / name`` unless it is
    there and up to date; returns that recording directory."""
    rec_dir = out_dir / name
    scenario, scene_seed, codec = scenario_of(name)
    synthesise(scenario, rec_dir, scene_seed=scene_seed, compression=codec)
    return rec_dir


def run_to(
    rec_dir: Path,
    mcap: Path,
    seed: int,
    config: Path | None = None,
    around: Callable[[Pipeline], AbstractContextManager] = lambda _pipeline: nullcontext(),
) -> RunSummary:
    """Run the pipeline on ``rec_dir`` as `surveil run` does, writing ``mcap``; the run
    happens inside ``around(pipeline)`` (a benchmark's change to the pipeline, e.g.
    ``oracle_candidates.py``'s)."""
    use_one_opencv_thread()  # as `surveil run`
    rec = open_recording(rec_dir)
    cfg = dataclasses.replace(load_pipeline_config(config), seed=seed)
    pipeline = Pipeline.for_recording(rec, cfg, load_rules())
    sink = McapSink(McapWriter(mcap, rec.rig, start_time_ns=rec.start_time_ns))
    with around(pipeline):
        return run_recording(rec.framesets, rec.n_framesets, pipeline, [sink])


def bench(
    name: str, out_dir: Path, seed: int, config: Path | None = None
) -> tuple[object, object, float]:
    rec_dir = render(name, out_dir)
    mcap = output_path(out_dir, name, config, seed)
    summary = run_to(rec_dir, mcap, seed, config)
    report = evaluate(rec_dir, mcap, EvalConfig())
    return report, summary, summary.n_framesets / summary.wall_s


def add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    """Scene names (``NAME``, ``NAME@SCENE_SEED``, ``NAME~CODEC``), ``--scene-seeds`` and
    ``--codec``."""
    parser.add_argument(
        "names",
        nargs="*",
        help="bundled scenes (default: all); NAME@N is the take with scene seed N, NAME~CODEC "
        "(NAME@N~CODEC) that take stored with another [effects] compression",
    )
    parser.add_argument(
        "--scene-seeds",
        default=None,
        help="held-out takes instead of the bundled ones: every scene rendered with each of "
        "these scene seeds (e.g. 101-102), named NAME@N",
    )
    parser.add_argument(
        "--codec",
        choices=COMPRESSIONS,
        default=None,
        help="every scene stored with this [effects] compression instead of its own, named "
        "NAME~CODEC (the same pixels before encoding)",
    )


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of a script that reads the runs this script writes: scenes, output
    folder, seed, settings, and whether to run again."""
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--rerun", action="store_true", help="run the pipeline again")
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML) of the run")


def scene_names(args: argparse.Namespace) -> list[str]:
    """The scenes named, or every bundled recording; with ``--scene-seeds``, each of them
    as every take named there; with ``--codec``, each stored with that codec."""
    names = args.names or sorted(p.stem for p in (ROOT / "recordings").glob("*.toml"))
    if getattr(args, "scene_seeds", None) is not None:
        names = [f"{n}@{s}" for n in names for s in parse_seeds(args.scene_seeds)]
    if getattr(args, "codec", None) is not None:
        names = [f"{n}~{args.codec}" for n in names]
    return names


def run_of(name: str, args: argparse.Namespace) -> Path:
    """The output MCAP of scene ``name`` (:func:`add_run_arguments`), run first when it is
    missing or ``--rerun`` asks."""
    mcap = output_path(args.out, name, args.config, args.seed)
    if args.rerun or not mcap.exists():
        bench(name, args.out, args.seed, args.config)
    return mcap


def print_kind_counts(
    what: str,
    kinds: tuple[str, ...],
    rows: list[str],
    totals: Mapping[str, int],
    listing_header: str | None = None,
    listing: Sequence[str] = (),
) -> None:
    """A Markdown table of counts by kind per scenario (``rows``, already formatted), its
    total row from ``totals``, and, with ``listing_header`` (its columns, ``"a | b"``),
    the ``listing`` rows under it: the summary of ``id_switches.py`` and ``partings.py``."""
    print(f"| scenario | {what} | " + " | ".join(kinds) + " |")
    print("|---|---|" + "---|" * len(kinds))
    print("\n".join(rows))
    total = sum(totals.get(k, 0) for k in kinds)
    print(f"| all | {total} | " + " | ".join(str(totals.get(k, 0)) for k in kinds) + " |")
    if listing_header is not None:
        print(f"\n| {listing_header} |")
        print("|" + "---|" * (listing_header.count("|") + 1))
        print("\n".join(listing))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--config", type=Path, help="pipeline settings (TOML); output <name>.<stem>.mcap"
    )
    args = parser.parse_args(argv)
    names = scene_names(args)
    track_rows, event_rows = [], []
    n_true = n_pred = n_matched = n_dir = n_dir_ok = 0
    for name in names:
        report, summary, rate = bench(name, args.out, args.seed, args.config)
        t, e = report.targets, report.events
        stages = summary.median_ms()
        track_rows.append(
            f"| {name} | {cell(t.recall)} | {cell(t.head_error_mm_mean, 0)} / "
            f"{cell(t.head_error_mm_median, 0)} | {cell(t.hand_error_mm_mean, 0)} / "
            f"{cell(t.hand_error_mm_median, 0)} | {cell(t.false_targets_per_frame, 2)} "
            f"| {cell(t.limb_type_accuracy)} | {cell(t.left_right_accuracy)} "
            f"| {cell(t.person_consistency)} | {cell(t.label_accuracy)} "
            f"| {cell(t.id_switches_per_min, 1)} | {rate:.1f} "
            f"| {stages.get('carry', 0):.1f} |"
        )
        for a in e.activities:
            if a.n_true or a.n_pred:
                event_rows.append(
                    f"| {name} | {a.activity} | {a.n_true} | {a.n_pred} | {a.n_matched} "
                    f"| {cell(a.precision)} | {cell(a.recall)} | {cell(a.f1)} "
                    f"| {cell(a.climax_error_ms_median, 0)} | {cell(a.direction_accuracy)} |"
                )
            if a.direction_accuracy is not None:  # matched events with a true giver
                n_dir += a.n_matched
                n_dir_ok += round(a.direction_accuracy * a.n_matched)
        n_true, n_pred, n_matched = n_true + e.n_true, n_pred + e.n_pred, n_matched + e.n_matched
        event_rows.append(
            f"| {name} | all (micro) | {e.n_true} | {e.n_pred} | {e.n_matched} "
            f"| {cell(e.precision)} | {cell(e.recall)} | {cell(e.f1)} | | |"
        )
        print(track_rows[-1], file=sys.stderr, flush=True)
    print(
        "| scenario | recall | head mm mean / median | hand mm mean / median | false / frame "
        "| limb type acc | left/right acc | person consistency | label acc | ID switches / min "
        "| sets/s | carry ms |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(track_rows))
    print()
    print(
        "| scenario | activity | true | predicted | matched | P | R | F1 | climax ms median "
        "| direction |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(event_rows))
    print()
    print(
        f"Over the scenarios above: {n_matched} of {n_true} true events recognised, "
        f"{n_pred} predicted; "
        f"P {cell(n_matched / n_pred if n_pred else None)}, "
        f"R {cell(n_matched / n_true if n_true else None)}, "
        f"F1 {cell(2 * n_matched / (n_true + n_pred) if n_true + n_pred else None)}; "
        f"exchange direction right in {n_dir_ok} of {n_dir} recognised exchanges."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
