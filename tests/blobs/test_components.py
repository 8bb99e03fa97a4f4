"""components_with_stats agrees with OpenCV's full-frame labelling."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from surveil.blobs.components import components_with_stats


def _masks():
    rng = np.random.default_rng(4)
    for k in range(12):
        m = np.zeros((120, 160), np.uint8)
        for _ in range(k):  # 0 .. 11 random rectangles and discs, some on the border
            x, y = rng.integers(-5, 160), rng.integers(-5, 120)
            if rng.random() < 0.5:
                m[max(y, 0) : y + rng.integers(1, 30), max(x, 0) : x + rng.integers(1, 30)] = 1
            else:
                cv2.circle(m, (int(x), int(y)), int(rng.integers(1, 12)), 1, -1)
        yield m
    yield (np.random.default_rng(5).random((120, 160)) < 0.3).astype(np.uint8)  # speckle
    yield np.ones((120, 160), np.uint8)


@pytest.mark.parametrize("mask", list(_masks()))
def test_same_components_as_opencv_on_the_whole_frame(mask):
    n0, labels0, stats0, cents0 = cv2.connectedComponentsWithStats(mask, connectivity=8)
    n, labels, stats, cents = components_with_stats(mask.astype(bool))
    assert n == n0
    np.testing.assert_array_equal(labels, labels0)
    np.testing.assert_array_equal(stats[1:], stats0[1:])
    np.testing.assert_allclose(cents[1:], cents0[1:], atol=1e-9)
    assert stats[0, cv2.CC_STAT_AREA] == stats0[0, cv2.CC_STAT_AREA]
    if stats0[0, cv2.CC_STAT_AREA] > 0:
        np.testing.assert_allclose(cents[0], cents0[0], atol=1e-6)
