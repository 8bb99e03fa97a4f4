"""Shared fixtures of the tracking tests."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.camera import Rig, look_at


@pytest.fixture(scope="session")
def rig() -> Rig:
    """Four 320x240 cameras at the corners of a 5 x 4 m room, 2.5 m up."""
    corners = [(0.0, 0.0), (5.0, 0.0), (5.0, 4.0), (0.0, 4.0)]
    return Rig(
        tuple(
            look_at(
                f"cam{i}",
                np.array([x, y, 2.5]),
                np.array([2.5, 2.0, 1.0]),
                width=320,
                height=240,
                hfov_deg=80,
            )
            for i, (x, y) in enumerate(corners)
        )
    )
