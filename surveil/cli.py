"""Command-line interface: the only place where exceptions become messages and exit codes.

Subcommands: ``demo``, ``run``, ``synth``, ``info``, ``eval``, ``truth``, ``train-skin``,
``rig``, ``review``, ``rules-check``, ``events``.
"""

from __future__ import annotations

import argparse
import dataclasses
import enum
import json
import logging
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from surveil import __version__
from surveil.errors import SurveilError

log = logging.getLogger("surveil")

REPO_ROOT = Path(__file__).resolve().parent.parent


class ExitCode(enum.IntEnum):
    OK = 0
    FAILURE = 1  # the command ran but its check failed (e.g. a score below a threshold)
    USAGE = 2  # argparse's own code for bad arguments
    BAD_INPUT = 3  # a SurveilError: bad file, config, recording...
    INTERRUPTED = 130


def configure_logging(verbosity: int) -> None:
    level = {-1: logging.WARNING, 0: logging.INFO}.get(verbosity, logging.DEBUG)
    logging.basicConfig(
        level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr, force=True
    )


def progress_bar(desc: str, quiet: bool, unit: str = "frame") -> Callable[[int, int], None]:
    """An ``on_progress(done, total)`` callback drawing a tqdm bar on stderr (``unit``: what
    is counted)."""
    from tqdm import tqdm

    state: dict = {}

    def on_progress(done: int, total: int) -> None:
        if quiet:
            return
        if "bar" not in state:
            state["bar"] = tqdm(
                total=total,
                desc=desc,
                unit=unit,
                file=sys.stderr,
                dynamic_ncols=True,
                leave=False,
            )
        bar = state["bar"]
        bar.update(done - bar.n)
        if done >= total:
            bar.close()

    return on_progress


def demo_recording_dir() -> tuple[Path, Path]:
    """(scenario file, output directory) of the bundled demo."""
    return REPO_ROOT / "recordings" / "demo.toml", REPO_ROOT / "recordings" / "demo"


# ---------------------------------------------------------------------------------------------
# handlers: each takes the parsed args and returns an ExitCode


def cmd_synth(args: argparse.Namespace) -> ExitCode:
    from surveil.synth.scene import synthesise

    out = args.out or args.scenario.with_suffix("")
    t0 = time.perf_counter()
    summary = synthesise(
        args.scenario,
        out,
        preview=args.preview,
        preview_times_s=tuple(args.preview_at or ()),
        overwrite=args.force,
        on_progress=progress_bar(f"synth {args.scenario.stem}", args.quiet),
        scene_seed=args.seed,
        compression=args.compression,
    )
    elapsed = time.perf_counter() - t0
    print(summary.describe())
    print(
        f"rendered in {elapsed:.1f} s "
        f"({1000 * elapsed / max(summary.n_camera_frames, 1):.1f} ms per camera frame)"
    )
    return ExitCode.OK


def cmd_info(args: argparse.Namespace) -> ExitCode:
    from surveil.io.recording import describe_recording, open_recording

    rec = open_recording(args.recording)
    info = describe_recording(rec)
    print(json.dumps(info.to_dict(), indent=2) if args.json else info.format())
    return ExitCode.OK


def cmd_demo(args: argparse.Namespace) -> ExitCode:
    from surveil.synth.scene import synthesise

    scenario, out = demo_recording_dir()
    if args.out is not None:
        out = args.out
    summary = synthesise(
        scenario,
        out,
        preview=True,
        overwrite=True,  # the demo folder is ours: re-render it when the generator changed
        on_progress=progress_bar("synth demo", args.quiet),
    )
    print(summary.describe())
    print(f"contact sheet: {out / 'preview.png'}")
    mcap = out.with_suffix(".mcap")
    # the run command's own defaults, not a copy of them
    run_args = build_parser().parse_args(["run", str(out), "--out", str(mcap)])
    run_args.quiet = args.quiet
    code = cmd_run(run_args)
    print(
        f"next: surveil eval {out} {mcap}   (score against the ground truth)\n"
        f"      surveil events {mcap}        (the event timeline)\n"
        f"      surveil review {mcap}        (review in Rerun)"
    )
    return code


def cmd_eval(args: argparse.Namespace) -> ExitCode:
    from surveil.eval.score import EvalConfig, evaluate, format_report

    cfg = EvalConfig(
        gate_m=args.gate,
        min_views=args.min_views,
        climax_tolerance_s=args.climax_tolerance,
        activities=tuple(args.activity) if args.activity else None,
    )
    report = evaluate(args.recording, args.mcap, cfg)
    print(json.dumps(report.to_dict(), indent=2) if args.json else format_report(report))
    return ExitCode.OK


def cmd_run(args: argparse.Namespace) -> ExitCode:
    from surveil.activity import load_rules
    from surveil.io.mcap_writer import McapSink, McapWriter
    from surveil.io.prefetch import prefetched
    from surveil.io.recording import open_recording
    from surveil.pipeline import (
        Pipeline,
        config_as_dict,
        load_pipeline_config,
        run_recording,
        use_one_opencv_thread,
    )

    log.debug("OpenCV threads: %d", use_one_opencv_thread())
    cfg = load_pipeline_config(args.config)
    if args.seed is not None:
        cfg = dataclasses.replace(cfg, seed=args.seed)
    rules = load_rules(args.rules or None)
    rec = open_recording(args.recording)
    out = args.out or args.recording.with_suffix(".mcap")
    if out.is_dir():
        raise SurveilError(f"--out {out} is a directory; give a file name ending in .mcap")
    pipeline = Pipeline.for_recording(rec, cfg, rules)
    metadata = {
        "run": {
            "recording": str(Path(args.recording).resolve()),
            "config": json.dumps(config_as_dict(cfg), sort_keys=True),
            "rules": json.dumps(rules.to_metadata(), sort_keys=True),
            "skin_models": json.dumps(
                {c: m.meta for c, m in pipeline.skin_models.items()}, default=str
            ),
        }
    }
    sinks: list = [
        McapSink(McapWriter(out, rec.rig, metadata=metadata, start_time_ns=rec.start_time_ns))
    ]
    if args.rrd is not None:
        from surveil.viz.rerun_log import RerunSink

        sinks.append(
            RerunSink(args.rrd, rec.rig, rec.camera_names, start_time_ns=rec.start_time_ns)
        )
    stop = args.max_frames
    summary = run_recording(
        lambda: prefetched(rec.framesets(0, stop)),
        rec.count_framesets(0, stop),
        pipeline,
        sinks,
        on_progress=progress_bar(f"run {args.recording.name}", args.quiet),
    )
    print(summary.format())
    if summary.events:
        from surveil.activity.timeline import format_event_table
        from surveil.io.mcap_writer import hue_name

        print(format_event_table(sorted(summary.events, key=lambda e: e.climax_ns), hue_name))
    print(f"wrote {out}" + (f" and {args.rrd}" if args.rrd else ""))
    return ExitCode.OK


def cmd_truth(args: argparse.Namespace) -> ExitCode:
    from surveil.eval.truth_mcap import write_truth_mcap

    write_truth_mcap(args.recording, args.out)
    print(f"wrote {args.out}")
    return ExitCode.OK


def cmd_rig_import(args: argparse.Namespace) -> ExitCode:
    from surveil.io.calibration import import_rig, save_rig

    rig = import_rig(args.source, fmt=args.format, units=args.units, extri=args.extri)
    save_rig(rig, args.out)
    print(f"wrote {args.out}: {len(rig)} cameras ({', '.join(rig.names)})")
    return ExitCode.OK


def cmd_rig_export(args: argparse.Namespace) -> ExitCode:
    from surveil.io.calibration import export_aniposelib, load_rig

    rig = load_rig(args.rig)
    export_aniposelib(rig, args.out)
    print(f"wrote {args.out} (aniposelib TOML, metres)")
    return ExitCode.OK


def cmd_train_skin(args: argparse.Namespace) -> ExitCode:
    import numpy as np

    from surveil.blobs.settings import SkinConfig
    from surveil.io.recording import open_recording
    from surveil.io.skin_model import (
        build_default_skin_model,
        save_skin_model,
        skin_models_dir,
        train_camera_skin_models,
    )

    rng = np.random.default_rng(args.seed)
    if args.generic:
        if args.unbounded:
            raise SurveilError("--unbounded is for per-camera models; --generic has no bound")
        if args.out is None:
            raise SurveilError("train-skin --generic needs --out FILE.npz")
        model = build_default_skin_model(args.recordings, rng, every=args.every)
        save_skin_model(model, args.out)
        print(f"wrote {args.out} (generic model, {model.lut.mean():.1%} of colours are skin)")
        return ExitCode.OK
    if len(args.recordings) != 1:
        raise SurveilError("train-skin trains per-camera models from one recording at a time")
    rec_dir = args.recordings[0]
    rec = open_recording(rec_dir)
    out_dir = args.out or skin_models_dir(rec.rig_path)
    cfg = SkinConfig(bound_by_generic=not args.unbounded)
    models = train_camera_skin_models(
        rec_dir,
        rng,
        cfg,
        every=args.every,
        on_progress=progress_bar("train-skin", args.quiet, unit="camera"),
    )
    for cam, model in models.items():
        path = out_dir / f"{cam}.npz"
        save_skin_model(model, path)
        bound = ", bounded by the generic model" if "bounded_by" in model.meta else ""
        print(f"wrote {path} ({model.lut.mean():.1%} of colours are skin{bound})")
    return ExitCode.OK


def cmd_rules_check(args: argparse.Namespace) -> ExitCode:
    from surveil.activity.rules import load_rules

    rules = load_rules(args.files or None)
    if args.json:
        for rule in rules:
            print(json.dumps(rule.to_table()))
        return ExitCode.OK
    for rule in rules:
        print(rule.describe())
    print(f"{len(rules)} rules OK ({', '.join(rules.sources)})")
    return ExitCode.OK


def cmd_events(args: argparse.Namespace) -> ExitCode:
    from surveil.activity.timeline import event_json, format_event_table
    from surveil.io.mcap_reader import read_run
    from surveil.io.mcap_writer import hue_name

    run = read_run(args.mcap)
    if args.json:
        for ev in run.events:
            print(event_json(ev, hue_name))
    elif run.events:
        print(format_event_table(run.events, hue_name))
    else:
        print(f"{args.mcap}: no events")
    if not run.complete:
        log.warning("%s is truncated: events up to its last complete chunk", args.mcap)
    return ExitCode.OK


def cmd_review(args: argparse.Namespace) -> ExitCode:
    from surveil.viz import viewer
    from surveil.viz.review import build_review

    out = args.out or args.mcap.with_suffix(".rrd")
    build_review(
        args.mcap,
        out,
        recording=args.recording,
        jpeg_quality=args.jpeg_quality,
        image_scale=args.image_scale,
        observations=not args.no_blobs,
        on_progress=progress_bar(f"review {args.mcap.name}", args.quiet),
    )
    print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB)")
    try:
        if args.screenshot is not None:
            viewer.screenshot(out, args.screenshot, at_s=args.at)
            print(f"wrote {args.screenshot}")
        if args.web:
            print(f"serving the web viewer at http://127.0.0.1:{args.web_port} (Ctrl-C stops)")
            viewer.serve_web(out, port=args.web_port)
        elif not args.save and args.screenshot is None:
            if viewer.display_available():
                viewer.open_viewer(out)
            else:
                print(f"no display: open it elsewhere with `rerun {out}`, or use --web")
    except viewer.ViewerError as exc:
        log.error("%s", exc)
        return ExitCode.FAILURE
    return ExitCode.OK


# ---------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    from surveil.synth.scenario import COMPRESSIONS  # light: numpy and the config schema

    parser = argparse.ArgumentParser(
        prog="surveil",
        description="Multi-camera 3D tracking of heads and hands, carried objects and "
        "activity events.",
    )
    parser.add_argument("--version", action="version", version=f"surveil {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more logging")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    parser.add_argument(
        "--traceback", action="store_true", help="show the Python traceback of errors"
    )
    sub = parser.add_subparsers(dest="name", required=True, metavar="COMMAND")

    p = sub.add_parser("demo", help="synthesise (once) and process the bundled demo recording")
    p.add_argument("--out", type=Path, default=None, help="where to put the demo recording")
    p.set_defaults(command=cmd_demo)

    p = sub.add_parser("run", help="track heads and hands, recognise activities, write MCAP")
    p.add_argument("recording", type=Path, help="recording directory (with recording.toml)")
    p.add_argument(
        "--out", type=Path, default=None, help="output MCAP [<recording>.mcap beside it]"
    )
    p.add_argument("--rrd", type=Path, default=None, help="also write a Rerun review file")
    p.add_argument(
        "--rules",
        type=Path,
        action="append",
        help="activity rule file (repeatable; default: the default rules)",
    )
    p.add_argument("--config", type=Path, default=None, help="settings TOML (docs/pipeline.md)")
    p.add_argument("--seed", type=int, default=None, help="override the config's seed")
    p.add_argument(
        "--max-frames", type=int, default=None, help="process only the first N frame sets"
    )
    p.set_defaults(command=cmd_run)

    p = sub.add_parser("synth", help="render a synthetic recording with ground truth")
    p.add_argument("scenario", type=Path, help="scenario TOML (see recordings/*.toml)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output recording directory (default: scenario path without .toml)",
    )
    p.add_argument(
        "--preview",
        action="store_true",
        help="also write preview.png, a contact sheet of all cameras",
    )
    p.add_argument(
        "--preview-at",
        type=float,
        action="append",
        metavar="SECONDS",
        help="contact sheet at this time (repeatable; default: event climaxes)",
    )
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        help="replace the scenario's [scene] seed: another take of the same script (its own "
        "timing variations, calibration error, noise, dropped frames)",
    )
    p.add_argument(
        "--compression",
        choices=COMPRESSIONS,
        default=None,
        help="replace the scenario's [effects] compression: the same take stored another way",
    )
    p.set_defaults(command=cmd_synth)

    p = sub.add_parser("info", help="describe a recording: cameras, frames, sync statistics")
    p.add_argument("recording", type=Path, help="recording directory (with recording.toml)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(command=cmd_info)

    p = sub.add_parser("eval", help="score an output MCAP against a recording's ground truth")
    p.add_argument("recording", type=Path, help="recording directory with ground_truth/")
    p.add_argument("mcap", type=Path, help="output MCAP of `surveil run`")
    p.add_argument(
        "--gate",
        type=float,
        default=0.25,
        help="max distance (m) for a target to match a true limb [0.25]",
    )
    p.add_argument(
        "--min-views",
        type=int,
        default=2,
        help="a true limb counts for recall when seen by this many cameras [2]",
    )
    p.add_argument(
        "--climax-tolerance",
        type=float,
        default=1.0,
        help="max climax time difference (s) for an event match [1.0]",
    )
    p.add_argument(
        "--activity",
        action="append",
        help="score only these activities (repeatable; default: clap, handshake, "
        "exchange, pick, place and any activity in the MCAP)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(command=cmd_eval)

    p = sub.add_parser("truth", help="write a recording's ground truth as an output MCAP")
    p.add_argument("recording", type=Path)
    p.add_argument("--out", type=Path, required=True)
    p.set_defaults(command=cmd_truth)

    p = sub.add_parser(
        "review", help="a Rerun review recording (.rrd) of an output MCAP, and open it"
    )
    p.add_argument("mcap", type=Path, help="output MCAP of `surveil run` (or `surveil truth`)")
    p.add_argument(
        "--recording",
        type=Path,
        default=None,
        help="the recording the MCAP was made from (default: the one named in the MCAP)",
    )
    p.add_argument("--out", type=Path, default=None, help="the .rrd to write [MCAP.rrd]")
    how = p.add_mutually_exclusive_group()
    how.add_argument("--save", action="store_true", help="only write the .rrd")
    how.add_argument("--web", action="store_true", help="serve the web viewer")
    p.add_argument("--web-port", type=int, default=9090, help="web viewer port [9090]")
    p.add_argument(
        "--screenshot",
        type=Path,
        default=None,
        metavar="PNG",
        help="render the layout headlessly into this image (needs a Vulkan driver)",
    )
    p.add_argument(
        "--at", type=float, default=None, metavar="SECONDS", help="screenshot time [the end]"
    )
    p.add_argument("--jpeg-quality", type=int, default=70, help="camera frame quality [70]")
    p.add_argument(
        "--image-scale",
        type=float,
        default=1.0,
        help="scale of the stored camera frames, (0, 1] [1]; 0.5 makes the file ~3x smaller",
    )
    p.add_argument(
        "--no-blobs",
        action="store_true",
        help="do not recompute silhouettes, skin blobs and carry estimates (faster)",
    )
    p.set_defaults(command=cmd_review)

    p = sub.add_parser(
        "train-skin",
        help="train per-camera skin classifiers from an annotated recording, saved beside its rig",
    )
    p.add_argument(
        "recordings",
        type=Path,
        nargs="+",
        help="recording(s) with ground_truth/masks (synthetic, or annotated by hand)",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder [<rig dir>/<rig stem>_skin/], or the .npz with --generic",
    )
    p.add_argument(
        "--generic",
        action="store_true",
        help="one model for all cameras of all recordings (+ a photo), like the default",
    )
    p.add_argument("--every", type=int, default=2, help="use every N-th annotated frame [2]")
    p.add_argument(
        "--unbounded",
        action="store_true",
        help="per-camera models may call skin what the generic model does not (default: they "
        "only narrow it; docs/blobs.md)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the pixel subsample [0]")
    p.set_defaults(command=cmd_train_skin)

    p = sub.add_parser("rig", help="import, export calibration rigs")
    rig_sub = p.add_subparsers(dest="rig_command", required=True, metavar="ACTION")
    q = rig_sub.add_parser("import", help="convert another tool's calibration to a rig YAML")
    q.add_argument(
        "source",
        type=Path,
        help="OpenCV multiview file, aniposelib/Pose2Sim TOML, or EasyMocap "
        "intri.yml (with --extri)",
    )
    q.add_argument("--out", type=Path, required=True, help="rig YAML to write")
    q.add_argument(
        "--format",
        choices=["surveil", "opencv-multiview", "aniposelib", "easymocap"],
        default=None,
        help="source format (default: detected from the file)",
    )
    q.add_argument(
        "--units",
        choices=["m", "mm", "cm"],
        default=None,
        help="length unit of the source's translations (required where the format does not say)",
    )
    q.add_argument("--extri", type=Path, default=None, help="EasyMocap extri.yml")
    q.set_defaults(command=cmd_rig_import)
    q = rig_sub.add_parser("export", help="write a rig as aniposelib TOML (anipose, Pose2Sim)")
    q.add_argument("rig", type=Path)
    q.add_argument("--out", type=Path, required=True)
    q.set_defaults(command=cmd_rig_export)

    p = sub.add_parser("rules-check", help="validate activity rule files and list their rules")
    p.add_argument(
        "files", type=Path, nargs="*", help="rule TOML files (default: the default rules)"
    )
    p.add_argument("--json", action="store_true", help="one JSON object per rule")
    p.set_defaults(command=cmd_rules_check)

    p = sub.add_parser("events", help="print the event timeline of an output MCAP")
    p.add_argument("mcap", type=Path, help="output MCAP of `surveil run`")
    p.add_argument("--json", action="store_true", help="JSON lines instead of a table")
    p.set_defaults(command=cmd_events)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(-1 if args.quiet else args.verbose)
    try:
        return int(args.command(args))
    except SurveilError as exc:
        log.error("%s", exc)
        if args.traceback:
            raise
        return int(ExitCode.BAD_INPUT)
    except KeyboardInterrupt:
        return int(ExitCode.INTERRUPTED)
    except BrokenPipeError:
        # the reader of our output went away (`surveil events --json | head`): not an error
        # of ours; stop writing and keep the interpreter from complaining at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return int(ExitCode.OK)


if __name__ == "__main__":
    sys.exit(main())
