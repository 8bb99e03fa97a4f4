"""What the per-camera stage and the candidate stage saw at one instant, as a picture and a table.

    python benchmarks/frame_overlay.py RECORDING --at SECONDS [--out PNG] [--config TOML]
        [--limb p1/left_hand ...] [--point X,Y,Z ...] [--people N]

Replays the recording's front end (background models, skin, blobs: ``front_end.py``) up to
the frame set nearest ``--at`` and writes a 2x2 (or larger) grid of its camera frames with:

- skin pixels tinted magenta (the whole frame: the classifier's verdict before the
  silhouette mask), silhouette outlines in green;
- every blob's box and point in yellow, numbered as in ``BlobSet`` (largest first);
- the silhouettes' crowns (``CameraObservation.crowns_px``) as blue triangles;
- the frame set's candidates (after explaining away, without tracker feedback) as red
  crosses (heads from the crowns among them: docs/candidates.md, "Crowns");
- the true heads and hands (ground truth, when the recording has one) as cyan rings,
  labelled; ``--limb`` restricts them;
- any ``--point X,Y,Z`` (world, metres: a tracker's estimate read from an MCAP, say) as a
  white cross.

It prints every candidate: position, prior, nearest true limb and distance, the two blobs
it was made of (camera c, blob b, and the true limb whose projection that blob's point lies
within 20 px of, ``?`` if none) and its support per camera (``view_support``; -1 none).
That is how a ghost (two blobs of different limbs) or a missed limb (no blob, a blob on a
sleeve) shows itself: docs/benchmarks.md, session 65.

Blobs are chosen for ``--people`` people (default: the ground truth's count, else the
silhouettes'), as in ``candidate_misses.py``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np
from front_end import observe_recording

from surveil.io.ground_truth import load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import load_pipeline_config
from surveil.recon.candidates import make_candidates, view_support

SKIN_TINT = np.array([127, 0, 127], dtype=np.float32)  # BGR magenta, added to half the pixel
OWNER_RADIUS_PX = 20.0


def _point(text: str) -> np.ndarray:
    try:
        xyz = np.array([float(v) for v in text.split(",")])
    except ValueError:
        xyz = np.empty(0)
    if xyz.shape != (3,):
        raise argparse.ArgumentTypeError(f"--point takes X,Y,Z in metres, got {text!r}")
    return xyz


def draw_camera(img, obs, cam, candidates_m, truth, points_m) -> np.ndarray:
    """The frame of one camera with its observation, the candidates, the true limbs
    (``{label: (3,) position}`` of the limbs this camera sees) and extra points drawn."""
    vis = img.copy()
    skin = obs.skin
    vis[skin] = (0.5 * vis[skin] + SKIN_TINT).astype(np.uint8)
    outline = (obs.silhouettes.labels > 0).astype(np.uint8)
    contours, _ = cv2.findContours(outline, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(vis, contours, -1, (0, 255, 0), 1)
    blobs = obs.blobs
    for k in range(len(blobs)):
        x, y, w, h = (int(v) for v in blobs.bboxes_px[k])
        cv2.rectangle(vis, (x, y), (x + w, y + h), (0, 255, 255), 1)
        u, v = (int(round(c)) for c in blobs.centroids_px[k])
        cv2.drawMarker(vis, (u, v), (0, 255, 255), cv2.MARKER_CROSS, 7)
        cv2.putText(vis, str(k), (x + w + 1, y + 8), 0, 0.35, (0, 255, 255), 1)
    for u, v in obs.crowns_px if obs.crowns_px is not None else ():
        cv2.drawMarker(
            vis, (int(round(u)), int(round(v))), (255, 128, 0), cv2.MARKER_TRIANGLE_UP, 9
        )

    def pixel(p_m) -> tuple[int, int] | None:
        uv, depth = cam.project(np.asarray(p_m)[None])
        return tuple(int(round(c)) for c in uv[0]) if cam.in_image(uv, depth)[0] else None

    for colour, size, pts in (((0, 0, 255), 9, candidates_m), ((255, 255, 255), 13, points_m)):
        for uv in filter(None, map(pixel, pts)):
            cv2.drawMarker(vis, uv, colour, cv2.MARKER_TILTED_CROSS, size)
    for label, p in truth.items():
        uv = pixel(p)
        if uv is not None:
            cv2.circle(vis, uv, 10, (255, 255, 0), 1)
            cv2.putText(vis, label, (uv[0] + 11, uv[1] + 4), 0, 0.35, (255, 255, 0), 1)
    cv2.putText(vis, cam.name, (5, 15), 0, 0.5, (255, 255, 255), 1)
    return vis


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", type=Path)
    parser.add_argument("--at", type=float, required=True, help="time, s from the first set")
    parser.add_argument("--out", type=Path, default=Path("frame_overlay.png"))
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML)")
    parser.add_argument("--limb", action="append", default=[], help="true limbs to draw")
    parser.add_argument("--point", action="append", type=_point, default=[])
    parser.add_argument("--people", type=int, help="N_h for the blob count")
    args = parser.parse_args(argv)

    rec = open_recording(args.recording)
    cfg = load_pipeline_config(args.config)
    gt = load_ground_truth(args.recording) if rec.ground_truth_dir is not None else None
    index = int(round(args.at * 1e9 / rec.period_ns))  # the grid index of the set
    last_s = rec.set_indices[-1] * rec.period_ns / 1e9
    if not 0 <= index <= rec.set_indices[-1]:
        sys.exit(f"{args.recording}: --at {args.at} s is outside its 0 to {last_s:.2f} s")
    n_people = args.people
    if n_people is None and gt is not None:
        n_people = len({label.split("/")[0] for label in gt.labels})
    labels = list(gt.labels) if gt is not None else []
    unknown = sorted(set(args.limb) - set(labels))
    if unknown:
        sys.exit(f"--limb {', '.join(unknown)}: not in the ground truth ({', '.join(labels)})")
    wanted = [lab for lab in labels if not args.limb or lab in args.limb]
    frame = None
    for fs, by_name, _ in observe_recording(rec, cfg, n_people, max_frames=index + 1):
        if fs.index == index and by_name:
            frame = fs, by_name
    if frame is None:
        sys.exit(f"{args.recording}: no camera has a frame at {args.at} s (a dropped set)")
    fs, by_name = frame
    observations = list(by_name.values())
    by_cam = {rec.rig.names.index(o.camera): o for o in observations}
    cands = make_candidates(observations, rec.rig, cfg.candidates)
    truth_f = None
    if gt is not None:
        truth_f = gt.frame_at(fs.t_ns)

    tiles = []
    for name, obs in by_name.items():
        m = rec.rig.names.index(name)
        truth = {}
        if truth_f is not None:
            truth = {
                lab: gt.positions_m[truth_f, labels.index(lab)]
                for lab in wanted
                if gt.visible[truth_f, labels.index(lab), gt.cameras.index(name)]
            }
        tiles.append(
            draw_camera(
                fs.images[name], obs, rec.rig.cameras[m], cands.points_m, truth, args.point
            )
        )
    cols = 2
    blank = np.zeros_like(tiles[0])
    tiles += [blank] * (-len(tiles) % cols)
    grid = np.vstack([np.hstack(tiles[i : i + cols]) for i in range(0, len(tiles), cols)])
    cv2.imwrite(str(args.out), grid)

    owners: dict[tuple[int, int], str] = {}
    if truth_f is not None:
        for m, obs in by_cam.items():
            uv = rec.rig.cameras[m].project(gt.positions_m[truth_f])[0]
            seen = gt.visible[truth_f, :, gt.cameras.index(rec.rig.names[m])]
            for b, c in enumerate(obs.blobs.centroids_px):
                d = np.where(seen, np.linalg.norm(uv - c, axis=1), np.inf)
                j = int(np.argmin(d))
                owners[(m, b)] = labels[j] if d[j] <= OWNER_RADIUS_PX else "?"
    support = view_support(
        cands.points_m,
        cands.cam_pairs,
        cands.blob_pairs,
        rec.rig,
        by_cam,
        cfg.candidates.support_radius_px,
    )
    print(
        f"{args.recording} at {fs.t_ns / 1e9:.2f} s (frame set {fs.index}): "
        f"{len(cands.points_m)} candidates; picture {args.out}"
    )
    print("| point m | prior | nearest true limb | pair (camera, blob: owner) | support |")
    print("|---|---|---|---|---|")
    for k, p in enumerate(cands.points_m):
        near = "-"
        if truth_f is not None:
            d = np.linalg.norm(gt.positions_m[truth_f] - p, axis=1)  # NaN: not in the room
            if np.isfinite(d).any():
                j = int(np.nanargmin(d))
                near = f"{labels[j]} {d[j] * 1000:.0f} mm"
        pair = ", ".join(
            f"c{c} b{b}: {owners.get((int(c), int(b)), '?')}"
            for c, b in zip(cands.cam_pairs[k], cands.blob_pairs[k], strict=True)
        )
        if (cands.cam_pairs[k] < 0).all():
            pair = "the silhouettes' crowns"
        print(
            f"| {np.round(p, 2).tolist()} | {cands.prior[k]:.2f} | {near} | {pair} "
            f"| {support[k].tolist()} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
