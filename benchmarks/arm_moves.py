"""How many blobs the bare-forearm option moves to a hand end, per scene (docs/blobs.md, "Bare
forearms").

    python benchmarks/arm_moves.py [--config TOML] [--sheet PNG] [--by-limb] [NAME ...]

Runs the front end (``benchmarks/front_end.py``, N_h the true number of people) with the given
settings (default: the defaults, ``[blobs] arm_length_rel = 0.17`` since session 101) and counts
the blobs whose point :func:`surveil.blobs.extract.hand_ends` moves off their centre of mass
(the blob's point or, with ``arm_hand_end = "report"``, its ``hand_px``), and
judges each move against the ground truth: the true head or hand (visible in that camera,
projected through the recording's rig) nearest to either point, within ``JUDGE_PX``, is the
blob's limb; the move is *toward* it when the new point lies nearer to it than the centre
of mass did, else *away*; with no limb that near, *no limb*. "gain px" is the median of (old
distance - new distance) over the judged moves. negative's p2 wears short sleeves; in
three_people most moves are hands joined to a colour fringe along a sleeve, moved onto the
hand (docs/blobs.md, "Bare forearms"); elsewhere a move is a blob taken for a forearm that is
not one. ``--by-limb`` adds the same per true limb. ``--sheet`` writes
a contact sheet of the first moves of the last scene (old point blue, new point red, the
blob green) to look at what moved.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np
from front_end import observe_recording
from pipeline_bench import add_scene_arguments, render, scene_names

import surveil.blobs.extract as extract
import surveil.pipeline as pipeline
from surveil.blobs.extract import blob_margin_px
from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import load_pipeline_config

ROOT = Path(__file__).resolve().parents[1]
TILE_PX = 120
JUDGE_PX = 40.0  # a blob's point this near a true limb's projection is that limb's


def judge_move(
    old_px: np.ndarray, new_px: np.ndarray, limbs_px: np.ndarray
) -> tuple[int, float] | None:
    """(index of the true limb the moved blob belongs to, old minus new distance to it, px)
    for a blob point moved from ``old_px`` to ``new_px`` ((2,) each), given the true limbs'
    projections ``limbs_px`` ((L, 2)); None when no limb lies within ``JUDGE_PX`` of either
    point.

    >>> judge_move(np.array([0.0, 0]), np.array([0.0, 10]), np.array([[0.0, 12], [50, 50]]))
    (0, 10.0)
    >>> judge_move(np.array([0.0, 0]), np.array([0.0, 10]), np.array([[90.0, 90]])) is None
    True
    """
    if not len(limbs_px):
        return None
    d_old = np.linalg.norm(limbs_px - old_px, axis=1)
    d_new = np.linalg.norm(limbs_px - new_px, axis=1)
    j = int(np.argmin(np.minimum(d_old, d_new)))
    if min(d_old[j], d_new[j]) > JUDGE_PX:
        return None
    return j, float(d_old[j] - d_new[j])


def count_moves(
    rec_dir: Path, cfg, sheet_tiles: int = 0
) -> tuple[int, int, dict[str, list[float]], list[np.ndarray]]:
    """Blobs seen, blobs moved, the judged moves' gains (px, :func:`judge_move`) by true
    limb label (``"no limb"``: no gain, one entry per move) and up to ``sheet_tiles`` crops
    of the moved ones."""
    pending: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # old, new, blob pixels
    by_blobset: dict[int, list] = {}  # id of a BlobSet -> its moves
    plain_ends, plain_extract = extract.hand_ends, pipeline.extract_blobs

    def ends_spy(pixels_px, blob_of, centroids_px, *args):
        out = plain_ends(pixels_px, blob_of, centroids_px, *args)
        for k in np.flatnonzero(np.linalg.norm(out - centroids_px, axis=1) > 0.5):
            pending.append((centroids_px[k], out[k], pixels_px[blob_of == k]))
        return out

    def extract_spy(*args, **kwargs):
        blobs = plain_extract(*args, **kwargs)
        by_blobset[id(blobs)] = pending.copy()
        pending.clear()
        return blobs

    gt = load_ground_truth(rec_dir)
    rec = open_recording(rec_dir)
    n_people = len({label.split("/")[0] for label in gt.labels})
    n_blobs = n_moved = 0
    gains: dict[str, list[float]] = {}
    tiles: list[np.ndarray] = []
    extract.hand_ends, pipeline.extract_blobs = ends_spy, extract_spy
    try:
        for fs, observations, _ in observe_recording(rec, cfg, n_people):
            row = int(np.searchsorted(gt.frames, fs.index))
            has_truth = row < len(gt.frames) and gt.frames[row] == fs.index
            for cam, obs in observations.items():
                n_blobs += len(obs.blobs)
                moves = by_blobset.pop(id(obs.blobs), [])
                n_moved += len(moves)
                # the spy saw the coordinates of the box around the people that the blob
                # stage works on (extract_blobs): shift them back to the frame's
                region = obs.silhouettes.region(blob_margin_px(cfg.blobs, obs.skin.shape[1]))
                shift = (
                    np.zeros(2) if region is None else np.array([region[1].start, region[0].start])
                )
                if has_truth and moves:
                    truth = gt.positions_m[row]
                    seen = gt.visible[row, :, gt.cameras.index(cam)] & np.isfinite(truth).all(1)
                    limbs_px = rec.rig[cam].project(truth[seen])[0] if seen.any() else np.zeros(0)
                    labels = [gt.labels[j] for j in np.flatnonzero(seen)]
                    for old, new, _ in moves:
                        judged = judge_move(old + shift, new + shift, limbs_px)
                        if judged is None:
                            gains.setdefault("no limb", []).append(np.nan)
                        else:
                            gains.setdefault(labels[judged[0]], []).append(judged[1])
                for old, new, px in moves[: max(sheet_tiles - len(tiles), 0)]:
                    tiles.append(_tile(fs.images[cam], old + shift, new + shift, px + shift))
                    cv2.putText(tiles[-1], f"{fs.index} {cam}", (3, 14), 0, 0.45, (255,) * 3)
            by_blobset.clear()
    finally:
        extract.hand_ends, pipeline.extract_blobs = plain_ends, plain_extract
    return n_blobs, n_moved, gains, tiles


def verdict_cells(gains: list[float]) -> str:
    """``toward | away | no limb | gain px`` cells of a table row from judged gains."""
    g = np.asarray(gains, dtype=np.float64)
    judged = g[np.isfinite(g)]
    median = f"{np.median(judged):+.1f}" if len(judged) else "-"
    toward, away = int((judged > 0).sum()), int((judged <= 0).sum())
    return f"{toward} | {away} | {int(np.isnan(g).sum())} | {median}"


def _tile(image: np.ndarray, old: np.ndarray, new: np.ndarray, px: np.ndarray) -> np.ndarray:
    img = image.copy()
    cols, rows = px[:, 0].astype(int), px[:, 1].astype(int)
    img[rows, cols] = (0.5 * img[rows, cols] + (0, 127, 0)).astype(np.uint8)
    cv2.circle(img, tuple(int(v) for v in old), 3, (255, 0, 0), -1)
    cv2.circle(img, tuple(int(v) for v in new), 3, (0, 0, 255), -1)
    u, v = (int(c) - TILE_PX // 2 for c in new)
    u, v = max(u, 0), max(v, 0)
    crop = img[v : v + TILE_PX, u : u + TILE_PX]
    crop = cv2.copyMakeBorder(
        crop, 0, TILE_PX - crop.shape[0], 0, TILE_PX - crop.shape[1], cv2.BORDER_CONSTANT
    )
    return cv2.resize(crop, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scene_arguments(parser)
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--config", type=Path, help="settings (default: the defaults)")
    parser.add_argument("--sheet", type=Path, help="contact sheet PNG of the last scene's moves")
    parser.add_argument("--by-limb", action="store_true", help="also a row per true limb")
    args = parser.parse_args(argv)
    cfg = load_pipeline_config(args.config)
    names = scene_names(args)
    print("| scenario | blobs | moved | share | toward | away | no limb | gain px |")
    print("|---|---|---|---|---|---|---|---|")
    for i, name in enumerate(names):
        last = i == len(names) - 1 and args.sheet is not None
        n_blobs, n_moved, gains, tiles = count_moves(
            render(name, args.out), cfg, 15 if last else 0
        )
        every = [g for limb_gains in gains.values() for g in limb_gains]
        print(
            f"| {name} | {n_blobs} | {n_moved} | {n_moved / max(n_blobs, 1):.4f} | "
            f"{verdict_cells(every)} |",
            flush=True,
        )
        if args.by_limb:
            for limb in sorted(gains):
                print(f"| {name} {limb} | | {len(gains[limb])} | | {verdict_cells(gains[limb])} |")
        if last and tiles:
            blank = np.zeros_like(tiles[0])
            rows = [
                tiles[j : j + 5] + [blank] * (5 - len(tiles[j : j + 5]))
                for j in range(0, len(tiles), 5)
            ]
            cv2.imwrite(str(args.sheet), np.vstack([np.hstack(r) for r in rows]))
            print(f"wrote {args.sheet}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
