"""The review file renders in a headless viewer (needs mesa-vulkan-drivers + libvulkan1, which
.ci/run installs: under CI a viewer that cannot start fails the test instead of skipping)."""

import cv2
import numpy as np
import pytest

from surveil.viz.viewer import ViewerError, screenshot


def test_headless_screenshot_is_not_blank(sink_rrd, tmp_path, in_ci):
    png = tmp_path / "shot.png"
    try:
        screenshot(sink_rrd, png, at_s=0.45, size=(1200, 800), settle_s=1.0)
    except ViewerError as exc:
        if in_ci or "exited" not in str(exc):
            raise
        pytest.skip(f"the rerun viewer cannot start here (no Vulkan driver?): {exc}")
    img = cv2.imread(str(png))
    assert img is not None and img.shape[0] >= 800 and img.shape[1] >= 1200
    assert img.std() > 10.0
    # the random camera frames and the coloured targets give many distinct colours;
    # a blank or error screen has a handful
    colours = np.unique(img.reshape(-1, 3), axis=0)
    assert len(colours) > 2000
