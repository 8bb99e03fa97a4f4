"""What the skin blobs lie on: every blob by the ground-truth class of most of its pixels.

    python benchmarks/blob_classes.py [--out out/bench_synth] [--config X.toml] [NAME ...]

For every blob after the learning phase, in frames with ground-truth masks, the mask class
(:class:`surveil.io.ground_truth.MaskClass`) under most of its pixels: ``SKIN`` (a real head
or hand), ``CLOTHING``, ``HAIR``, ``OBJECT``, ``SKIN_DISTRACTOR`` (skin-coloured scenery such
as a wooden table) or ``BACKGROUND`` (floor, walls: skin-coloured background that the
silhouette clean-up took in). Prints the share of each class per scene, and of the
background blobs the share per camera. Blobs are extracted with the true number of people,
as in ``candidate_misses.py``.

``--changed-shares`` adds a table: per class, the fraction of its blobs with less than
0.2 / 0.3 / 0.4 / 0.5 of their pixels changed to the background model (foreground or
shadow): what ``[blobs] min_changed_share`` at that value would drop.

``--flat-cores`` adds a table: per class, the fraction of its blobs with fewer than
``FLAT_MIN_PX`` pixels whose chroma is flat (the magnitude of the 3x3 Sobel gradient of
YCrCb's Cr and Cb below 30 / 40 / 50): what a test that asks a blob for a flat core
would drop. Colour fringes (a shirt blended with the wall, JPEG chroma bleeding) lie on
chroma edges across their whole width; a hand has a flat inside.

``--face-chroma`` adds a table: per class, the fraction of its blobs whose mean chroma
(YCrCb's Cr, Cb) lies more than 6 / 8 / 10 / 12 from that of every face in the same view
(the blob under a true head's projection, the face blobs themselves not counted): what a
test asking a hand to have the colour of a face in its view would weaken or drop. A
person's hands and face share a skin tone; a fringe on a red or olive shirt does not.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import cv2
import numpy as np
from front_end import observe_recording

from surveil.blobs.extract import pixel_share
from surveil.camera import Camera
from surveil.datatypes import CameraObservation, FrameSet
from surveil.io.ground_truth import GroundTruth, MaskClass, load_ground_truth
from surveil.io.recording import open_recording
from surveil.pipeline import load_pipeline_config
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]


SHARE_LIMITS = (0.2, 0.3, 0.4, 0.5)
FLAT_LIMITS = (30.0, 40.0, 50.0)
FLAT_MIN_PX = 3
FACE_CHROMA_LIMITS = (6.0, 8.0, 10.0, 12.0)
FACE_SEARCH_PX = 6  # a face blob: the most common blob within this of a head's projection


def blob_chroma(img: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    """(n + 1, 2) mean Cr, Cb (YCrCb, 0..255) of each blob ``labels == k`` (row 0 unused)."""
    inside = labels > 0
    ycc = cv2.cvtColor(img[inside][None], cv2.COLOR_BGR2YCrCb)[0].astype(np.float64)
    lab = labels[inside]
    area = np.maximum(np.bincount(lab, minlength=n + 1), 1)
    return np.column_stack([np.bincount(lab, ycc[:, k], n + 1) / area for k in (1, 2)])


def face_blobs(labels: np.ndarray, heads_px: np.ndarray) -> list[int]:
    """Blob labels (1-based) of the faces: the most common blob within ``FACE_SEARCH_PX``
    of each head projection ((H, 2) u, v in the image)."""
    h, w = labels.shape
    r = FACE_SEARCH_PX
    faces = set()
    for u, v in np.rint(heads_px).astype(int):
        ids = labels[max(v - r, 0) : min(v + r + 1, h), max(u - r, 0) : min(u + r + 1, w)]
        ids = ids[ids > 0]
        if len(ids):
            faces.add(int(np.bincount(ids).argmax()))
    return sorted(faces)


def flat_pixels(img: np.ndarray, labels: np.ndarray, box: np.ndarray, blob: int) -> np.ndarray:
    """(len(FLAT_LIMITS),) how many of blob ``blob``'s pixels (``labels == blob + 1``,
    bounding box ``box`` x, y, w, h) have a chroma gradient below each limit."""
    x, y, w, h = (int(v) for v in box)
    x0, y0 = max(0, x - 2), max(0, y - 2)
    sub = cv2.cvtColor(img[y0 : y + h + 2, x0 : x + w + 2], cv2.COLOR_BGR2YCrCb)
    sub = sub[..., 1:].astype(np.float32)
    gx = cv2.Sobel(sub, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(sub, cv2.CV_32F, 0, 1, ksize=3)
    grad = np.sqrt((gx**2 + gy**2).sum(axis=-1))
    inside = labels[y0 : y + h + 2, x0 : x + w + 2] == blob + 1
    return (grad[inside][:, None] < np.array(FLAT_LIMITS)).sum(axis=0)


def blob_classes(
    rec_dir: Path,
    config,
    shares: dict[str, list[float]] | None = None,
    flat: dict[str, list[np.ndarray]] | None = None,
    face: dict[str, list[float]] | None = None,
) -> tuple[Counter, Counter]:
    """(blobs per mask class name, background blobs per camera) over a recording; with
    ``shares``, each blob's changed share is appended to its class's list; with ``flat``,
    its :func:`flat_pixels`; with ``face``, the chroma distance from it to the nearest face
    of its view (:func:`blob_chroma`, :func:`face_blobs`; views without a face blob are
    skipped)."""
    rec = open_recording(rec_dir)
    gt = load_ground_truth(rec_dir)
    n_people = len({lab.split("/")[0] for lab in gt.labels})
    heads = [i for i, lab in enumerate(gt.labels) if lab.endswith("/head")]
    by_class: Counter = Counter()
    background_by_cam: Counter = Counter()
    for fs, by_name, _ in observe_recording(rec, config, n_people, changed=shares is not None):
        if fs.index < config.background.learning_frames:
            continue
        for cam, obs in by_name.items():
            path = rec_dir / "ground_truth" / "masks" / cam / f"{fs.index:06d}.png"
            if not path.is_file() or not len(obs.blobs):
                continue
            classes = cv2.imread(str(path))[..., 0]
            labels = obs.blobs.labels
            inside = labels > 0
            # (blob, class) pixel counts in one pass
            counts = np.zeros((len(obs.blobs) + 1, len(MaskClass)), np.int64)
            np.add.at(counts, (labels[inside], classes[inside]), 1)
            changed = None
            if shares is not None:
                changed = pixel_share(labels, obs.silhouettes.changed, len(obs.blobs) + 1)
            to_face = None
            if face is not None:
                to_face = _chroma_to_faces(fs, cam, obs, gt, heads, rec.rig[cam])
            for b in np.flatnonzero(counts[1:].sum(axis=1) > 0):
                k = int(counts[b + 1].argmax())
                if to_face is not None and np.isfinite(to_face[b]):
                    face.setdefault(MaskClass(k).name, []).append(float(to_face[b]))
                by_class[MaskClass(k).name] += 1
                if k == MaskClass.BACKGROUND:
                    background_by_cam[cam] += 1
                if changed is not None:
                    shares.setdefault(MaskClass(k).name, []).append(float(changed[b + 1]))
                if flat is not None:
                    got = flat_pixels(fs.images[cam], labels, obs.blobs.bboxes_px[b], int(b))
                    flat.setdefault(MaskClass(k).name, []).append(got)
    return by_class, background_by_cam


def _chroma_to_faces(
    fs: FrameSet,
    cam: str,
    obs: CameraObservation,
    gt: GroundTruth,
    heads: list[int],
    camera: Camera,
) -> np.ndarray | None:
    """(B,) chroma distance of each blob of ``obs`` to the nearest face of the view (inf for
    the faces themselves), or None when no true head projects onto a blob."""
    f = gt.frame_at(fs.t_ns)
    head_m = gt.positions_m[f, heads]
    head_m = head_m[np.isfinite(head_m).all(axis=1)]
    if not len(head_m):
        return None
    px, depth = camera.project(head_m)
    faces = face_blobs(obs.blobs.labels, px[camera.in_image(px, depth)])
    if not faces:
        return None
    chroma = blob_chroma(fs.images[cam], obs.blobs.labels, len(obs.blobs))
    d = np.linalg.norm(chroma[1:, None] - chroma[faces][None], axis=2).min(axis=1)
    d[np.array(faces) - 1] = np.inf
    return d


def _class_rows(stem: str, names: list[str], by_class: dict | None, shares_below) -> list[str]:
    """Table rows, one per class with values in ``by_class`` (None: no rows): the class's
    blob count and ``shares_below`` of its values (one share per limit)."""
    rows = []
    for name in names if by_class is not None else ():
        got = np.array(by_class.get(name, []))
        if len(got):
            cells = " | ".join(f"{v:.3f}" for v in shares_below(got))
            rows.append(f"| {stem} | {name} | {len(got)} | {cells} |")
    return rows


def _print_class_table(what: str, limits: list[str], rows: list[str]) -> None:
    """A Markdown table of :func:`_class_rows` rows under "Share of each class's blobs
    ``what``:", one column per limit; nothing when there are no rows."""
    if not rows:
        return
    print(f"\nShare of each class's blobs {what}:\n")
    print("| scenario | class | blobs | " + " | ".join(limits) + " |")
    print("|---|---|---|" + "---|" * len(limits))
    print("\n".join(rows))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*")
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--config", type=Path, help="pipeline settings (TOML)")
    parser.add_argument(
        "--changed-shares",
        action="store_true",
        help="also the share of each class's blobs below changed-share limits",
    )
    parser.add_argument(
        "--flat-cores",
        action="store_true",
        help="also the share of each class's blobs without a flat-chroma core",
    )
    parser.add_argument(
        "--face-chroma",
        action="store_true",
        help="also the share of each class's blobs whose chroma is far from every face's",
    )
    args = parser.parse_args(argv)
    config = load_pipeline_config(args.config)
    paths = [ROOT / "recordings" / f"{n}.toml" for n in args.names] or sorted(
        (ROOT / "recordings").glob("*.toml")
    )
    names = [c.name for c in MaskClass]
    print("Share of the blobs by the ground-truth class under most of their pixels:\n")
    print("| scenario | blobs | " + " | ".join(names) + " | background blobs by camera |")
    print("|---|---|" + "---|" * len(names) + "---|")
    share_rows, flat_rows, face_rows = [], [], []
    for path in paths:
        rec_dir = args.out / path.stem
        synthesise(path, rec_dir)
        shares: dict[str, list[float]] | None = {} if args.changed_shares else None
        flat: dict[str, list[np.ndarray]] | None = {} if args.flat_cores else None
        face: dict[str, list[float]] | None = {} if args.face_chroma else None
        by_class, by_cam = blob_classes(rec_dir, config, shares, flat, face)
        face_rows += _class_rows(
            path.stem, names, face, lambda got: [np.mean(got > lim) for lim in FACE_CHROMA_LIMITS]
        )
        share_rows += _class_rows(
            path.stem, names, shares, lambda got: [np.mean(got < lim) for lim in SHARE_LIMITS]
        )
        flat_rows += _class_rows(
            path.stem, names, flat, lambda got: np.mean(got < FLAT_MIN_PX, axis=0)
        )
        total = max(sum(by_class.values()), 1)
        cells = " | ".join(f"{by_class[n] / total:.3f}" for n in names)
        cams = ", ".join(f"{c} {by_cam[c]}" for c in sorted(by_cam))
        print(f"| {path.stem} | {sum(by_class.values())} | {cells} | {cams} |", flush=True)
    _print_class_table(
        "with less than this share of changed pixels",
        [f"< {lim}" for lim in SHARE_LIMITS],
        share_rows,
    )
    _print_class_table(
        f"with fewer than {FLAT_MIN_PX} pixels of flat chroma (Sobel magnitude of Cr, Cb "
        "below the limit)",
        [f"< {lim:g}" for lim in FLAT_LIMITS],
        flat_rows,
    )
    _print_class_table(
        "whose mean chroma (Cr, Cb) is farther than the limit from every face's in the view",
        [f"> {lim:g}" for lim in FACE_CHROMA_LIMITS],
        face_rows,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
