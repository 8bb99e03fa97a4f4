import numpy as np
import pytest

from surveil.datatypes import ActivityEvent
from surveil.errors import InputError
from surveil.io.ground_truth import GroundTruth, load_ground_truth, write_ground_truth


def make_truth() -> GroundTruth:
    rng = np.random.default_rng(0)
    pos = rng.uniform(0, 3, (4, 3, 3))
    pos[3, 2] = np.nan  # a limb absent in the last frame
    vis = rng.random((4, 3, 2)) > 0.4
    vis[3, 2] = False
    ev = ActivityEvent(
        "exchange",
        0,
        100,
        200,
        ("p1/right_hand", "p1/left_hand"),
        ("p1",),
        "ground_truth",
        object_hue_deg=120.0,
        from_actor="p1/right_hand",
        to_actor="p1/left_hand",
        object_name="ball",
    )
    return GroundTruth(
        frames=np.arange(4),
        t_ns=np.arange(4) * 66_666_667,
        labels=("p1/head", "p1/left_hand", "p1/right_hand"),
        cameras=("a", "b"),
        positions_m=pos,
        visible=vis,
        object_names=("ball",),
        object_hue_deg=np.array([120.0]),
        object_positions_m=rng.uniform(0, 1, (4, 1, 3)),
        held_by=np.array([["p1/right_hand"]] * 2 + [[""]] * 2, dtype=object),
        events=(ev,),
        meta={"fps": 15.0, "objects": [{"name": "ball", "hue_deg": 120.0}]},
    )


def test_round_trip_keeps_positions_visibility_objects_and_events(tmp_path):
    gt = make_truth()
    write_ground_truth(tmp_path / "rec" / "ground_truth", gt)
    back = load_ground_truth(tmp_path / "rec")
    np.testing.assert_allclose(back.positions_m, gt.positions_m, atol=1e-5)
    np.testing.assert_array_equal(back.visible, gt.visible)
    assert back.labels == gt.labels and back.cameras == gt.cameras
    assert back.held_by.tolist() == gt.held_by.tolist()
    assert back.events == gt.events
    assert back.fps == 15.0


def test_missing_ground_truth_says_how_to_get_one(tmp_path):
    with pytest.raises(InputError, match="no ground truth.*surveil synth"):
        load_ground_truth(tmp_path)


def test_unknown_camera_in_visibility_is_reported_with_the_line(tmp_path):
    write_ground_truth(tmp_path / "ground_truth", make_truth())
    limbs = tmp_path / "ground_truth" / "limbs.csv"
    lines = limbs.read_text().splitlines()
    lines[1] = lines[1].rsplit(",", 1)[0] + ",zzz"
    limbs.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"limbs\.csv:2: camera 'zzz' is not in scene\.json"):
        load_ground_truth(tmp_path)
