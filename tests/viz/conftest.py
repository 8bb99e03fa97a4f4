"""Fixtures of the review tests: a tiny rig and a short stream of constructed FrameResults."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from surveil.camera import Rig, look_at
from surveil.datatypes import (
    ActivityEvent,
    BlobSet,
    CameraObservation,
    CandidateSet,
    CarryEstimate,
    FrameResult,
    FrameSet,
    Limb,
    Phase,
    Silhouettes,
    TargetSnapshot,
    TrackFrame,
    Transition,
)

PERIOD_NS = 66_666_667
W, H = 160, 120


@pytest.fixture(scope="session")
def tiny_rig() -> Rig:
    centre = np.array([2.0, 2.0, 1.0])
    return Rig(
        (
            look_at("camA", np.array([0.0, 0.0, 2.5]), centre, width=W, height=H, hfov_deg=70),
            look_at("camB", np.array([4.0, 0.0, 2.5]), centre, width=W, height=H, hfov_deg=70),
        )
    )


def _observation(cam: str, k: int) -> CameraObservation:
    labels = np.zeros((H, W), np.int32)
    labels[30:100, 60 + k : 90 + k] = 1
    sil = Silhouettes(labels, np.array([30.0]), np.array([99.0]), np.zeros((H, W), np.float32))
    blobs = BlobSet(
        np.array([[70.0 + k, 40.0]]),
        np.array([60], np.int64),
        np.array([[65 + k, 35, 10, 10]], np.int32),
        np.array([1], np.int32),
        np.array([0.1]),
        np.zeros((H, W), np.int32),
    )
    return CameraObservation(cam, sil, np.zeros((H, W), bool), blobs)


def make_results(n: int = 12) -> list[FrameResult]:
    """Two people's heads and hands moving; tracker 5 starts unlabelled and becomes
    p1/right_hand at frame 3, carries a green object from frame 4, joins tracker 6 at frame 6
    (an exchange decided at frame 7, climax at frame 6), is lost at frame 9 and gone at 10.
    camB drops its frame 2."""
    rng = np.random.default_rng(0)
    out = []
    for k in range(n):
        t = k * PERIOD_NS
        x = 1.5 + 0.05 * k
        images = {c: rng.integers(0, 255, (H, W, 3), dtype=np.uint8) for c in ("camA", "camB")}
        if k == 2:
            del images["camB"]
        targets = [
            TargetSnapshot(1, 1, Limb.HEAD, Phase.NORMAL, np.array([x, 2.0, 1.7])),
            TargetSnapshot(2, 2, Limb.HEAD, Phase.NORMAL, np.array([2.6, 2.0, 1.6])),
            TargetSnapshot(6, 2, Limb.LEFT_HAND, Phase.NORMAL, np.array([2.3, 2.0, 1.1])),
        ]
        if k < 10:
            phase = Phase.UNLABELLED if k < 3 else Phase.NORMAL
            phase = Phase.COMBINED if 6 <= k < 8 else phase
            phase = Phase.LOST if k == 9 else phase
            person, limb = (0, Limb.UNKNOWN) if k < 3 else (1, Limb.RIGHT_HAND)
            targets.append(
                TargetSnapshot(
                    5,
                    person,
                    limb,
                    phase,
                    np.array([x + 0.3, 2.0, 1.1]),
                    carried_hue_deg=120.0 if k >= 4 else None,
                )
            )
        transitions = ()
        if k == 6:
            transitions = (
                Transition(t, 5, Phase.NORMAL, Phase.COMBINED, "p1/right_hand", [2.1, 2, 1.1], 6),
            )
        carry = {}
        if 4 <= k < 9:
            carry[5] = CarryEstimate(5, "p1/right_hand", t, True, 120.0, 0.2 + 0.1 * (k - 4))
        events = ()
        if k == 7:
            events = (
                ActivityEvent(
                    "exchange",
                    5 * PERIOD_NS,
                    6 * PERIOD_NS,
                    7 * PERIOD_NS,
                    ("p1/right_hand", "p2/left_hand"),
                    ("p1", "p2"),
                    "default.toml:exchange",
                    0.9,
                    object_hue_deg=120.0,
                    from_actor="p1/right_hand",
                    to_actor="p2/left_hand",
                ),
            )
        particles = np.array([t.mean_m for t in targets for _ in range(3)], np.float32)
        owner = np.array([t.target_id for t in targets for _ in range(3)], np.int32)
        out.append(
            FrameResult(
                frameset=FrameSet(k, t, images),
                observations={c: _observation(c, k) for c in images},
                candidates=CandidateSet(
                    np.array([[x, 2.0, 1.7], [2.0, 2.5, 0.5]]), np.array([0.9, 0.2])
                ),
                track=TrackFrame(t, tuple(targets), transitions, particles, owner),
                carry=carry,
                events=events,
            )
        )
    return out


def entity_paths(rrd: Path) -> set[str]:
    """Entity paths with data in an .rrd, from ``rerun rrd print``."""
    from surveil.viz.viewer import rerun_executable

    text = subprocess.run(
        [rerun_executable(), "rrd", "print", str(rrd)], capture_output=True, text=True, check=True
    ).stdout
    found = set()
    for line in text.splitlines():
        if line.startswith("Chunk(") and " - /" in line:
            found.add(line.split(" - ")[1].strip())
    return found


@pytest.fixture(scope="session")
def sink_rrd(tiny_rig, tmp_path_factory) -> Path:
    from surveil.viz.rerun_log import RerunSink

    path = tmp_path_factory.mktemp("viz") / "tiny.rrd"
    with RerunSink(path, tiny_rig, recording_id="tiny") as sink:
        for result in make_results():
            sink.write(result)
    return path


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() not in ("", "0", "false", "no")


@pytest.fixture(name="make_results")
def make_results_fixture():
    """The :func:`make_results` helper (tests import nothing from conftest)."""
    return make_results


@pytest.fixture(name="entity_paths")
def entity_paths_fixture():
    return entity_paths


@pytest.fixture(name="in_ci")
def in_ci_fixture() -> bool:
    return in_ci()
