"""Size of the Rerun review recording per minute (issue 6).

    python benchmarks/review_size.py [RECORDING] [--out DIR]

Builds the review .rrd of RECORDING (default: the demo, ``recordings/demo``, rendered by
``surveil demo``; 4 cameras, 640x480, 15 fps) from its ground-truth MCAP (a perfect tracker)
with several JPEG qualities and image scales, with blob boxes and silhouettes, and prints MB
per minute of recording and seconds to build. Camera frames dominate the size.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from surveil.eval.truth_mcap import write_truth_mcap
from surveil.io.recording import open_recording
from surveil.viz.review import build_review

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = ((70, 1.0), (50, 1.0), (85, 1.0), (70, 0.5))  # (jpeg_quality, image_scale)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", type=Path, nargs="?", default=ROOT / "recordings" / "demo")
    parser.add_argument("--out", type=Path, default=None, help="keep the .rrd files here")
    args = parser.parse_args(argv)
    rec = open_recording(args.recording)
    first = min(int(ts[0]) for ts in rec.timestamps_ns.values())
    last = max(int(ts[-1]) for ts in rec.timestamps_ns.values())
    minutes = (last - first + rec.period_ns) / 60e9
    size = {c.name: c.size for c in rec.rig}
    out = args.out or Path(tempfile.mkdtemp(prefix="review_size_"))
    out.mkdir(parents=True, exist_ok=True)
    mcap = out / "truth.mcap"
    write_truth_mcap(args.recording, mcap)
    print(
        f"{args.recording}: {len(rec.camera_names)} cameras {sorted(set(size.values()))}, "
        f"{rec.fps:g} fps, {60 * minutes:.1f} s"
    )
    print("| JPEG quality | image scale | MB per minute | MB per hour | build s per s |")
    print("|---:|---:|---:|---:|---:|")
    for quality, scale in SETTINGS:
        rrd = out / f"review_q{quality}_s{scale:g}.rrd"
        t0 = time.perf_counter()
        build_review(mcap, rrd, recording=args.recording, jpeg_quality=quality, image_scale=scale)
        elapsed = time.perf_counter() - t0
        mb_min = rrd.stat().st_size / 1e6 / minutes
        print(
            f"| {quality} | {scale:g} | {mb_min:.0f} | {60 * mb_min / 1000:.1f} GB | "
            f"{elapsed / (60 * minutes):.2f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
