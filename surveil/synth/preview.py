"""Contact sheets: all cameras at a few instants, with the ground truth drawn on top, so a
person can check a synthetic recording at a glance."""

from __future__ import annotations

import cv2
import numpy as np

from surveil.camera import Rig
from surveil.io.ground_truth import GroundTruth

TILE_W = 320
LIMB_COLOURS = {"head": (255, 255, 255), "left_hand": (60, 220, 60), "right_hand": (40, 40, 240)}


def contact_sheet(
    images: dict[int, dict[str, np.ndarray]], gt: GroundTruth, rig: Rig, title: str
) -> np.ndarray:
    """(H, W, 3) uint8 grid: one row per frame in ``images``, one column per camera.

    Each tile shows the rendered frame with the true heads and hands as rings (white head,
    green left hand, red right hand; dashed when occluded in that camera) and the time.
    """
    cams = list(rig.names)
    cam0 = rig.cameras[0]
    scale = TILE_W / cam0.width
    tile_h = int(round(cam0.height * scale))
    rows = []
    for k in sorted(images):
        tiles = []
        for c, name in enumerate(cams):
            img = images[k].get(name)
            if img is None:
                tile = np.full((tile_h, TILE_W, 3), 40, np.uint8)
                cv2.putText(
                    tile,
                    "dropped",
                    (TILE_W // 3, tile_h // 2),
                    cv2.FONT_HERSHEY_SIMPLEX,
                    0.6,
                    (200, 200, 200),
                    1,
                    cv2.LINE_AA,
                )
            else:
                tile = cv2.resize(img, (TILE_W, tile_h), interpolation=cv2.INTER_AREA)
                i = int(np.searchsorted(gt.frames, k))
                px, depth = rig[name].project(np.nan_to_num(gt.positions_m[i]))
                for j, label in enumerate(gt.labels):
                    if depth[j] <= 0 or not np.isfinite(gt.positions_m[i, j]).all():
                        continue
                    colour = LIMB_COLOURS[label.split("/")[1]]
                    centre = tuple(int(round(x)) for x in px[j] * scale)
                    if gt.visible[i, j, c]:
                        cv2.circle(tile, centre, 9, colour, 1, cv2.LINE_AA)
                    else:
                        cv2.circle(tile, centre, 2, colour, -1, cv2.LINE_AA)
            t_s = k / gt.fps
            _outlined_text(tile, f"{name}  t={t_s:.2f}s", (6, 16))
            tiles.append(tile)
        rows.append(np.hstack(tiles))
    sheet = np.vstack(rows) if rows else np.zeros((tile_h, TILE_W * len(cams), 3), np.uint8)
    header = np.full((28, sheet.shape[1], 3), 30, np.uint8)
    cv2.putText(
        header,
        f"{title}: rings = true head (white), left hand (green), right hand "
        f"(red); dots = occluded",
        (8, 19),
        cv2.FONT_HERSHEY_SIMPLEX,
        0.5,
        (230, 230, 230),
        1,
        cv2.LINE_AA,
    )
    return np.vstack([header, sheet])


def _outlined_text(image: np.ndarray, text: str, origin: tuple[int, int]) -> None:
    """White text with a dark outline, readable on any background."""
    for colour, thickness in (((0, 0, 0), 3), ((255, 255, 255), 1)):
        cv2.putText(
            image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, thickness, cv2.LINE_AA
        )
