import cv2
import numpy as np
import pytest

from surveil.viz.rerun_log import RerunSink, hue_rgb, silhouette_outlines
from surveil.viz.viewer import verify


def test_rrd_verify_accepts_the_file(sink_rrd):
    verify(sink_rrd)


def test_everything_is_logged_where_paths_says(sink_rrd, entity_paths):
    found = entity_paths(sink_rrd)
    expected = {
        "/world",
        "/world/floor",
        "/world/cameras/camA",
        "/world/cameras/camA/image",
        "/world/cameras/camB/blobs",
        "/world/cameras/camB/silhouettes",
        "/world/cameras/camA/targets",
        "/world/candidates",
        "/world/targets/p1/head/estimate",
        "/world/targets/p1/head/trail",
        "/world/targets/p1/head/particles",
        "/world/targets/p1/right_hand/carried",
        "/world/targets/t5",  # cleared when relabelled
        "/world/event",
        "/events",
        "/transitions",
        "/states/p1/right_hand",
        "/states/t5",
        "/carry/p1/right_hand",
    }
    assert expected <= found, sorted(expected - found)


def test_constructor_checks_its_arguments(tiny_rig, tmp_path):
    with pytest.raises(ValueError, match="camera_names"):
        RerunSink(tmp_path / "a.rrd", tiny_rig, ["camA", "nope"])
    with pytest.raises(ValueError, match="jpeg_quality"):
        RerunSink(tmp_path / "b.rrd", tiny_rig, jpeg_quality=0)
    with pytest.raises(ValueError, match="image_scale"):
        RerunSink(tmp_path / "c.rrd", tiny_rig, image_scale=2.0)


def test_frames_out_of_order_are_refused(tiny_rig, tmp_path, make_results):
    results = make_results(3)
    with RerunSink(tmp_path / "x.rrd", tiny_rig, blueprint=False) as sink:
        sink.write(results[1])
        with pytest.raises(ValueError, match="time order"):
            sink.write(results[0])


def test_downscaled_images_and_overlays(tiny_rig, tmp_path, make_results):
    path = tmp_path / "half.rrd"
    with RerunSink(path, tiny_rig, image_scale=0.5, jpeg_quality=50) as sink:
        for r in make_results(4):
            sink.write(r)
    verify(path)


def test_hue_rgb_primaries():
    assert hue_rgb(0) == (255, 0, 0)
    assert hue_rgb(240) == (0, 0, 255)
    assert hue_rgb(360 + 120) == (0, 255, 0)


def test_silhouette_outlines_are_closed_and_scaled():
    lab = np.zeros((50, 60), np.int32)
    cv2.circle(lab, (20, 25), 10, 1, -1)
    lab[5:10, 40:55] = 2
    outlines = silhouette_outlines(lab, scale=0.5)
    assert len(outlines) == 2
    for o in outlines:
        assert o.dtype == np.float32 and o.shape[1] == 2
        assert np.array_equal(o[0], o[-1])
        assert o.max() <= 30.0
    assert silhouette_outlines(np.zeros((5, 5), np.int32)) == []
