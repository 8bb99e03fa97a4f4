"""Skin classifier, leave one scene out, and on a real photograph (issue 3).

    python benchmarks/skin_bench.py [--out out/bench_synth] [--test handshake] [--every 3]

Trains a generic model (as the shipped default: ``build_default_skin_model``, seed 0) on every
bundled scene except ``--test``, then reports pixel precision and recall of skin *inside true
person pixels* of the held-out scene (silhouettes remove the rest later), and the fraction of
pixels flagged in regions of ``skimage.data.astronaut()`` that training never saw: the right
half of the face (skin), the grey backdrop and the flag (not skin). The shipped default
(trained on all scenes) is scored the same way for comparison.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from surveil.blobs.skin import SkinModel, default_skin_model
from surveil.io.skin_model import build_default_skin_model, training_pixels_from_recording
from surveil.synth.scene import synthesise

ROOT = Path(__file__).resolve().parents[1]


def person_scores(model: SkinModel, pixels: np.ndarray, skin: np.ndarray) -> tuple[float, float]:
    pred = model.classify(pixels[None])[0]
    tp = int(np.count_nonzero(pred & skin))
    return tp / max(int(pred.sum()), 1), tp / max(int(skin.sum()), 1)


def photo_flags(model: SkinModel) -> dict[str, float]:
    from skimage import data

    bgr = np.ascontiguousarray(data.astronaut()[..., ::-1])
    regions = {
        "face right half": bgr[90:170, 225:265],
        "backdrop": bgr[0:80, 0:150],
        "flag": bgr[0:200, 380:512],
    }
    return {name: float(model.classify(img).mean()) for name, img in regions.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "out" / "bench_synth")
    parser.add_argument("--test", default="handshake")
    parser.add_argument("--every", type=int, default=3)
    args = parser.parse_args(argv)
    names = sorted(p.stem for p in (ROOT / "recordings").glob("*.toml"))
    for name in names:
        synthesise(ROOT / "recordings" / f"{name}.toml", args.out / name)
    train = [args.out / n for n in names if n != args.test]
    held_out = build_default_skin_model(train, np.random.default_rng(0), every=args.every)
    rng = np.random.default_rng(1)
    pixels, skin = training_pixels_from_recording(
        args.out / args.test, args.every, background_fraction=0.0, rng=rng
    )
    print(f"| model | {args.test}: P in people | R in people | astronaut face (right) "
          "| backdrop | flag |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for label, model in (
        (f"trained without {args.test}", held_out),
        ("shipped default (all scenes)", default_skin_model()),
    ):
        p, r = person_scores(model, pixels, skin)
        f = photo_flags(model)
        print(
            f"| {label} | {p:.3f} | {r:.3f} | {f['face right half']:.3f} "
            f"| {f['backdrop']:.3f} | {f['flag']:.3f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
