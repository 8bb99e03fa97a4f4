import pytest
import rerun.blueprint as rrb

from surveil.viz.blueprint import build_blueprint, world_view


@pytest.mark.parametrize("cams", [[], ["cam0"], ["a", "b", "c", "d"], [f"c{i}" for i in range(7)]])
def test_blueprint_builds_for_any_camera_count(cams):
    assert isinstance(build_blueprint(cams), rrb.Blueprint)


def test_blueprint_with_an_eye():
    bp = build_blueprint(["cam0", "cam1"], eye=((0.0, -3.0, 3.0), (0.0, 0.0, 1.0)))
    assert isinstance(bp, rrb.Blueprint)


def test_world_view_keeps_the_frusta_but_not_the_image_plane_overlays():
    view = world_view(["cam0"])
    query = str(view.contents)
    assert "- world/cameras/cam0/image" in query
    assert "- world/cameras/cam0/targets" in query
    assert "- world/cameras/cam0/**" not in query  # would hide the pinhole itself
