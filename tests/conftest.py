"""Shared fixtures: a seeded rng and one small synthetic recording rendered once per session."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

SMALL_SCENARIO = """
[scene]
name = "small"
duration_s = 3.0
empty_room_s = 2.0
fps = 15.0
seed = 42

[rig]
n_cameras = 4
width = 320
height = 240

[effects]
mask_every = 1
drop_rate = 0.05
late_start_s = { cam3 = 0.5 }

[[furniture]]
name = "table"
centre_m = [4.4, 1.2]
size_m = [1.2, 0.7, 0.92]

[[people]]
position_m = [2.5, 2.6]
facing_deg = 0
skin = "dark"

[[people]]
position_m = [3.45, 2.6]
facing_deg = 180
skin = "light"
shirt = "red"

# 14 cm: at 320x240 a 9 cm ball shows too few pixels for the carry analysis
[[objects]]
name = "ball"
shape = "ball"
hue_deg = 120
size_m = [0.14, 0.14, 0.14]
held_by = "p1/right_hand"

[[actions]]
at_s = 0.2
person = "p1"
do = "give"
object = "ball"
with = "p2"

[[actions]]
at_s = 1.4
person = "p2"
do = "touch_face"
hand = "right"
"""


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture(scope="session")
def small_scenario(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("scenario") / "small.toml"
    path.write_text(SMALL_SCENARIO)
    return path


@pytest.fixture(scope="session")
def small_recording(small_scenario, tmp_path_factory) -> Path:
    """A 3 s, 4-camera 320x240 recording with masks on every frame."""
    from surveil.synth.scene import synthesise

    out = tmp_path_factory.mktemp("recordings") / "small"
    synthesise(small_scenario, out, preview=True)
    return out
