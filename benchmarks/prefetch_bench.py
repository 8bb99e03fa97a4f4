"""What reading ahead saves: `surveil run` with and without the read-ahead thread, alternating.

    python benchmarks/prefetch_bench.py [--rounds 4] [RECORDING]

Each run is a fresh process (``surveil.cli.main(["-q", "run", RECORDING, ...])``, import
included); "off" replaces ``surveil.io.prefetch.prefetched`` by the identity, so frame sets are
decoded in the pipeline's thread as before session 89. Rounds alternate off / on, so that a
busy machine slows both alike. Prints each run's wall and CPU time (user + system of the child
process) and the medians; compare medians, the machine is shared. Default recording: the demo
(``recordings/demo``, rendered by ``surveil demo``).
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import sys
import surveil.io.prefetch as prefetch
if sys.argv[1] == "off":
    prefetch.prefetched = lambda items, depth=2: items
from surveil.cli import main
sys.exit(main(["-q", "run", sys.argv[2], "--out", sys.argv[3]]))
"""


def timed_run(mode: str, recording: Path, out: Path) -> tuple[float, float]:
    """Wall and CPU seconds of one run in a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-c", CHILD, mode, str(recording), str(out)],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", nargs="?", type=Path, default=ROOT / "recordings" / "demo")
    parser.add_argument("--rounds", type=int, default=4)
    args = parser.parse_args(argv)
    if not (args.recording / "recording.toml").is_file():
        parser.error(f"{args.recording} is not a recording (run `surveil demo` first)")
    times: dict[str, list[tuple[float, float]]] = {"off": [], "on": []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for mode in ("off", "on"):
                wall, cpu = timed_run(mode, args.recording, Path(tmp) / f"{mode}.mcap")
                times[mode].append((wall, cpu))
                print(f"round {r + 1} {mode}: wall {wall:.2f} s, cpu {cpu:.2f} s", flush=True)
    print("| read-ahead | wall s, median | cpu s, median | runs |")
    print("|---|---|---|---|")
    for mode, rows in times.items():
        wall = statistics.median(w for w, _ in rows)
        cpu = statistics.median(c for _, c in rows)
        print(f"| {mode} | {wall:.2f} | {cpu:.2f} | {len(rows)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
