import pytest

from surveil.viz import paths


def test_camera_paths_nest_under_the_camera():
    assert paths.camera_path("cam0") == "world/cameras/cam0"
    for p in paths.camera_overlay_paths("cam0"):
        assert p.startswith("world/cameras/cam0/")
    assert len(set(paths.camera_overlay_paths("cam0"))) == 4


def test_target_paths_use_the_label_so_a_person_is_a_parent():
    assert paths.target_estimate_path("p1/right_hand") == "world/targets/p1/right_hand/estimate"
    assert paths.target_trail_path("t7") == "world/targets/t7/trail"
    assert paths.state_path("p2/head") == "states/p2/head"
    assert paths.carry_path("p2/left_hand") == "carry/p2/left_hand"


@pytest.mark.parametrize("bad", ["", "p1", "p0/head", "p1/foot", "world/x", "t"])
def test_bad_label_is_rejected_naming_it(bad):
    with pytest.raises(ValueError, match="label must look like"):
        paths.target_path(bad)
