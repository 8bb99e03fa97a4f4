"""Self-checks of a synthetic recording's ground truth against its own masks."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from surveil.io.calibration import load_rig
from surveil.io.ground_truth import GT_DIR, MaskClass, load_ground_truth


def visible_hands_on_skin(recording_dir: Path) -> tuple[int, int]:
    """(hits, total): of the (camera, frame) pairs where the ground truth calls a hand visible
    and a mask exists, how many project the hand centre (through the true rig, with
    distortion) onto a pixel the mask labels as person skin."""
    recording_dir = Path(recording_dir)
    gt = load_ground_truth(recording_dir)
    rig = load_rig(recording_dir / GT_DIR / "rig_true.yaml")
    is_hand = np.array([label.endswith("hand") for label in gt.labels])
    hits = total = 0
    for c, cam in enumerate(gt.cameras):
        for i, frame in enumerate(gt.frames):
            path = recording_dir / GT_DIR / "masks" / cam / f"{frame:06d}.png"
            check = is_hand & gt.visible[i, :, c]
            if not check.any() or not path.exists():
                continue
            mask = cv2.imread(str(path))
            px, _ = rig[cam].project(gt.positions_m[i][check])
            u, v = np.round(px).astype(int).T
            total += int(check.sum())
            hits += int(np.count_nonzero(mask[v, u, 0] == MaskClass.SKIN))
    return hits, total
