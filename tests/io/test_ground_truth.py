import dataclasses

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


def with_joints_and_facing(gt: GroundTruth) -> GroundTruth:
    rng = np.random.default_rng(1)
    joints = rng.uniform(0, 3, (4, 6, 3))
    joints[0] = np.nan  # the person is absent in the first frame
    facing = np.array([[np.nan], [0.0], [np.pi / 2], [-3.0]])
    return dataclasses.replace(
        gt,
        joint_labels=tuple(
            f"p1/{side}_{joint}"
            for side in ("left", "right")
            for joint in ("shoulder", "elbow", "wrist")
        ),
        joint_positions_m=joints,
        persons=("p1",),
        facing_yaw_rad=facing,
    )


def test_round_trip_keeps_arm_joints_and_facing(tmp_path):
    gt = with_joints_and_facing(make_truth())
    write_ground_truth(tmp_path / "ground_truth", gt)
    joints_csv = (tmp_path / "ground_truth" / "joints.csv").read_text().splitlines()
    assert joints_csv[0] == "frame,t_ns,label,x_m,y_m,z_m"
    assert len(joints_csv) == 1 + 3 * 6  # no rows for the absent first frame
    assert joints_csv[1].startswith("1,66666667,p1/left_shoulder,")
    facing_csv = (tmp_path / "ground_truth" / "facing.csv").read_text().splitlines()
    assert facing_csv[0] == "frame,t_ns,person,yaw_deg"
    assert [line.rsplit(",", 1)[1] for line in facing_csv[1:]] == [
        "0.0000",
        "90.0000",
        f"{np.degrees(-3.0):.4f}",
    ]
    back = load_ground_truth(tmp_path)
    assert back.joint_labels == gt.joint_labels and back.persons == ("p1",)
    assert back.joint_positions_m.shape == (4, 6, 3)
    np.testing.assert_allclose(back.joint_positions_m, gt.joint_positions_m, atol=1e-5)
    np.testing.assert_allclose(back.facing_yaw_rad, gt.facing_yaw_rad, atol=1e-5)


def test_facing_is_written_within_half_a_turn(tmp_path):
    gt = with_joints_and_facing(make_truth())
    gt = dataclasses.replace(gt, facing_yaw_rad=np.array([[np.nan], [2 * np.pi], [-4.0], [7.0]]))
    write_ground_truth(tmp_path / "ground_truth", gt)
    back = load_ground_truth(tmp_path).facing_yaw_rad[1:, 0]
    np.testing.assert_allclose(back, [0.0, 2 * np.pi - 4.0, 7.0 - 2 * np.pi], atol=1e-5)


def test_truth_without_joints_or_facing_loads_with_empty_defaults(tmp_path):
    gt = make_truth()
    assert gt.joint_labels == () and gt.joint_positions_m.shape == (0, 0, 3)
    assert gt.persons == () and gt.facing_yaw_rad.shape == (0, 0)
    write_ground_truth(tmp_path / "ground_truth", gt)
    assert not (tmp_path / "ground_truth" / "joints.csv").exists()
    assert not (tmp_path / "ground_truth" / "facing.csv").exists()
    back = load_ground_truth(tmp_path)
    assert back.joint_labels == () and back.joint_positions_m.shape == (0, 0, 3)
    assert back.persons == () and back.facing_yaw_rad.shape == (0, 0)
    np.testing.assert_allclose(back.positions_m, gt.positions_m, atol=1e-5)


def test_joints_with_a_missing_column_name_the_file_and_the_header(tmp_path):
    write_ground_truth(tmp_path / "ground_truth", with_joints_and_facing(make_truth()))
    joints = tmp_path / "ground_truth" / "joints.csv"
    lines = joints.read_text().splitlines()
    lines[0] = "frame,t_ns,label,x_m,y_m,height_m"
    joints.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        InputError,
        match=r"joints\.csv: missing column\(s\) z_m; expected header "
        r"frame,t_ns,label,x_m,y_m,z_m",
    ):
        load_ground_truth(tmp_path)


def test_facing_at_an_unknown_frame_is_reported_with_the_line(tmp_path):
    write_ground_truth(tmp_path / "ground_truth", with_joints_and_facing(make_truth()))
    facing = tmp_path / "ground_truth" / "facing.csv"
    lines = facing.read_text().splitlines()
    lines[2] = "99," + lines[2].split(",", 1)[1]
    facing.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"facing\.csv:3: frame 99 is not a frame"):
        load_ground_truth(tmp_path)


def test_frame_at_picks_the_truth_frame_nearest_in_time():
    gt = make_truth()  # frames every 66.7 ms from 0
    assert [gt.frame_at(t) for t in (-5, 30_000_000, 40_000_000, 10**12)] == [0, 0, 1, 3]
