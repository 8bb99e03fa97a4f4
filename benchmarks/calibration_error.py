"""What each camera pair's calibration error does to triangulation, per bundled scene.

    python benchmarks/calibration_error.py [--out out/bench_synth] [--every 7] [NAME ...]

Renders (or reuses) the bundled recordings named, all by default, into ``--out``.

A synthetic recording ships the rig it was rendered with (``ground_truth/rig_true.yaml``)
beside the calibration a user would have (``rig.yaml``, with the scene's calibration error).
Every ``--every``-th true head and hand position (``ground_truth/limbs.csv``, absent people
left out) is projected through the true rig and triangulated back through the written one,
for every camera pair, whether or not the cameras see it. Printed per pair: the median half
gap between the two lines of sight (what the candidate prior p_t reads; its width
``sigma_gap_m`` is 20 mm) and the median distance of the triangulated point from the true
one, mm. No image is read: this is the calibration alone, before any blob noise.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from pipeline_bench import ROOT, scene_names

from surveil.io.calibration import load_rig
from surveil.io.ground_truth import load_ground_truth
from surveil.recon.triangulate import closest_points
from surveil.synth.scene import synthesise


def true_points(recording: Path, every: int) -> np.ndarray:
    """(N, 3) every ``every``-th true limb position of a recording (frames by limbs), m."""
    positions = load_ground_truth(recording).positions_m.reshape(-1, 3)
    positions = positions[np.isfinite(positions).all(axis=1)]
    return positions[::every]


def pair_errors(recording: Path, every: int) -> dict[str, tuple[float, float]]:
    """Per camera pair ``"cam0-cam1"``: (median half gap, median 3-D error), mm."""
    written = load_rig(recording / "rig.yaml")
    true = load_rig(recording / "ground_truth" / "rig_true.yaml")
    points = true_points(recording, every)
    out = {}
    names = written.names
    projected = {name: true[name].project(points) for name in names}
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            (px_a, depth_a), (px_b, depth_b) = projected[a], projected[b]
            seen = (depth_a > 0) & (depth_b > 0)
            o_a, d_a = written[a].backproject(px_a[seen])
            o_b, d_b = written[b].backproject(px_b[seen])
            z, half_gap = closest_points(
                np.broadcast_to(o_a, d_a.shape), d_a, np.broadcast_to(o_b, d_b.shape), d_b
            )
            error = np.linalg.norm(z - points[seen], axis=1)
            out[f"{a}-{b}"] = (1000 * float(np.median(half_gap)), 1000 * float(np.median(error)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    ap.add_argument("--every", type=int, default=7, help="use every n-th ground-truth row")
    args = ap.parse_args()
    table = {}
    for name in scene_names(args):
        synthesise(ROOT / "recordings" / f"{name}.toml", args.out / name)
        table[name] = pair_errors(args.out / name, args.every)
    pairs = sorted({p for errs in table.values() for p in errs})
    print("median half gap / median 3-D error per camera pair, mm (written rig vs true rig)\n")
    print("| scenario | " + " | ".join(pairs) + " |")
    print("|---|" + "---|" * len(pairs))
    for name, errs in table.items():
        cells = [f"{errs[p][0]:.0f} / {errs[p][1]:.0f}" if p in errs else "-" for p in pairs]
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
