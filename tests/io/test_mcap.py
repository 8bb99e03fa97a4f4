"""Output MCAP: the formats.md contract (topics, schemas, fields, times) and reading it back,
including files cut short by a crash."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from mcap_protobuf.decoder import DecoderFactory
from scipy.spatial.transform import Rotation

from surveil.camera import Camera, Rig, look_at
from surveil.datatypes import ActivityEvent, CandidateSet, Limb, Phase, TargetSnapshot
from surveil.errors import InputError
from surveil.io.mcap_reader import decode_point_cloud, read_run
from surveil.io.mcap_writer import McapWriter, hue_name

S = 1_000_000_000
START = 1_700_000_000 * S
TOPIC_SCHEMAS = {
    "/events": "foxglove.Event",
    "/events/log": "foxglove.Log",
    "/targets": "foxglove.SceneUpdate",
    "/targets/points": "foxglove.PointCloud",
    "/candidates": "foxglove.PointCloud",
    "/tf": "foxglove.FrameTransforms",
    "/cameras/cam0/calibration": "foxglove.CameraCalibration",
    "/cameras/cam1/calibration": "foxglove.CameraCalibration",
}


@pytest.fixture
def rig() -> Rig:
    cam0 = look_at(
        "cam0", np.array([3.0, -3, 2.5]), np.array([0.0, 0, 1]), width=320, height=240, hfov_deg=70
    )
    cam1 = look_at(
        "cam1",
        np.array([-3.0, -3, 2.5]),
        np.array([0.0, 0, 1]),
        width=640,
        height=480,
        hfov_deg=60,
        dist=np.array([0.1, -0.05, 0.001, 0.002, 0.01, 0.0, 0.0, 0.0]),
    )
    return Rig((cam0, cam1))


def exchange() -> ActivityEvent:
    return ActivityEvent(
        "exchange",
        12 * S,
        int(12.4 * S),
        13 * S,
        ("p1/right_hand", "p2/left_hand"),
        ("p1", "p2"),
        "default.toml:exchange",
        0.912,
        118.0,
        "p1/right_hand",
        "p2/left_hand",
    )


def clap() -> ActivityEvent:
    return ActivityEvent(
        "clap",
        2 * S,
        int(2.5 * S),
        3 * S,
        ("p1/left_hand", "p1/right_hand"),
        ("p1",),
        "default.toml:clap",
        0.5,
    )


def targets() -> list[TargetSnapshot]:
    return [
        TargetSnapshot(4, 1, Limb.HEAD, Phase.NORMAL, np.array([0.1, 0.2, 1.6])),
        TargetSnapshot(5, 2, Limb.RIGHT_HAND, Phase.COMBINED, np.array([-0.5, 0.25, 1.0])),
        TargetSnapshot(6, 0, Limb.UNKNOWN, Phase.UNLABELLED, np.array([1.0, 1.0, 0.9])),
        TargetSnapshot(7, 1, Limb.LEFT_HAND, Phase.LOST, np.array([0.3, -0.2, 1.1])),
        TargetSnapshot(8, 0, Limb.UNKNOWN, Phase.UNINITIALISED, np.array([9.0, 9, 9])),
    ]


def candidates() -> CandidateSet:
    return CandidateSet(np.array([[0.1, 0.2, 1.6], [2.0, -1.0, 0.5]]), np.array([0.9, 0.25]))


def decoded(path: Path) -> dict[str, list]:
    """topic -> [(log_time, publish_time, decoded message)] via mcap's own reader."""
    out: dict[str, list] = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, message, msg in reader.iter_decoded_messages():
            out.setdefault(channel.topic, []).append((message.log_time, message.publish_time, msg))
    return out


def test_every_channel_is_present_without_messages(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "empty.mcap"
    with McapWriter(out, rig, metadata={"config": {"tracking.n_particles": "200"}}):
        pass
    with open(out, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        topics = {ch.topic: ch for ch in summary.channels.values()}
        assert set(topics) == set(TOPIC_SCHEMAS)
        for topic, ch in topics.items():
            schema = summary.schemas[ch.schema_id]
            assert schema.name == TOPIC_SCHEMAS[topic]
            assert schema.encoding == "protobuf" and ch.message_encoding == "protobuf"
            assert len(schema.data) > 100  # an embedded FileDescriptorSet
        counts = summary.statistics.channel_message_counts
        assert counts.get(topics["/events"].id, 0) == 0
        assert counts[topics["/tf"].id] == 1
        assert counts[topics["/cameras/cam1/calibration"].id] == 1
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    assert metadata["config"] == {"tracking.n_particles": "200"}
    assert metadata["surveil"]["start_time_ns"] == "0"
    run = read_run(out)
    assert run.channels == TOPIC_SCHEMAS and run.complete
    assert run.n_frames == 0 and run.events == () and run.target_pos_m.shape == (0, 3)


def test_targets_scene_update(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "t.mcap"
    with McapWriter(out, rig, start_time_ns=START) as w:
        w.write_frame(S // 15, targets(), candidates())
    ((log_time, publish_time, msg),) = decoded(out)["/targets"]
    assert log_time == publish_time == START + S // 15
    assert [e.id for e in msg.entities] == ["p1/head", "p2/right_hand", "t6", "p1/left_hand"]
    assert msg.deletions[0].type == 1  # ALL: ended targets disappear
    ent = msg.entities[1]
    assert ent.frame_id == "world"
    assert ent.timestamp.seconds * S + ent.timestamp.nanos == START + S // 15
    assert {kv.key: kv.value for kv in ent.metadata} == {"state": "combined", "tracker": "5"}
    (sphere,) = ent.spheres
    p = sphere.pose.position
    assert (p.x, p.y, p.z) == (-0.5, 0.25, 1.0)
    assert 0.05 <= sphere.size.x == sphere.size.y == sphere.size.z <= 0.1


def test_point_clouds_decode_to_the_written_numbers(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "p.mcap"
    with McapWriter(out, rig) as w:
        w.write_frame(0, targets(), candidates())
    msgs = decoded(out)
    ((_, _, points),) = msgs["/targets/points"]
    assert points.frame_id == "world" and points.point_stride == 15
    assert [(f.name, f.offset, f.type) for f in points.fields] == [
        ("x", 0, 7),
        ("y", 4, 7),
        ("z", 8, 7),
        ("person", 12, 1),
        ("limb", 13, 1),
        ("state", 14, 1),
    ]
    cols = decode_point_cloud(points)
    live = targets()[:4]
    np.testing.assert_array_equal(
        np.column_stack([cols["x"], cols["y"], cols["z"]]),
        np.array([tg.mean_m for tg in live], dtype=np.float32),
    )
    assert cols["person"].tolist() == [1, 2, 0, 1]
    assert cols["limb"].tolist() == [0, 2, 255, 1]
    assert cols["state"].tolist() == [1, 2, 0, 3]
    ((_, _, cands),) = msgs["/candidates"]
    assert cands.point_stride == 16 and [f.name for f in cands.fields] == ["x", "y", "z", "prior"]
    cols = decode_point_cloud(cands)
    np.testing.assert_array_equal(cols["prior"], np.float32([0.9, 0.25]))
    np.testing.assert_array_equal(cols["x"], np.float32([0.1, 2.0]))
    run = read_run(out)
    np.testing.assert_allclose(run.candidate_pos_m, candidates().points_m, atol=1e-6)
    np.testing.assert_allclose(run.candidate_prior, [0.9, 0.25], atol=1e-7)


def test_event_metadata_and_log_line(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "e.mcap"
    with McapWriter(out, rig, start_time_ns=START) as w:
        w.write_event(exchange())
        w.write_event(clap())
    msgs = decoded(out)
    by_activity = {}
    for log_time, _, msg in msgs["/events"]:
        meta = {kv.key: kv.value for kv in msg.metadata}
        by_activity[meta["activity"]] = (log_time, msg, meta)
    log_time, msg, meta = by_activity["exchange"]
    assert meta == {
        "activity": "exchange",
        "climax_ns": str(START + int(12.4 * S)),
        "actors": "p1/right_hand,p2/left_hand",
        "persons": "p1,p2",
        "object_hue_deg": "118.0",
        "from": "p1/right_hand",
        "to": "p2/left_hand",
        "confidence": "0.912",
        "rule": "default.toml:exchange",
    }
    assert log_time == START + int(12.4 * S)
    assert msg.start_time.seconds * S + msg.start_time.nanos == START + 12 * S
    assert msg.end_time.seconds * S + msg.end_time.nanos == START + 13 * S
    _, _, meta = by_activity["clap"]
    assert set(meta) == {"activity", "climax_ns", "actors", "persons", "confidence", "rule"}
    lines = sorted(m.message for _, _, m in msgs["/events/log"])
    assert lines == [
        "12.40 s exchange p1/right_hand -> p2/left_hand (green, 0.91)",
        "2.50 s clap p1/left_hand, p1/right_hand (0.50)",
    ]
    assert all(m.level == 2 and m.name == "surveil" for _, _, m in msgs["/events/log"])
    run = read_run(out)
    assert run.events == (clap(), exchange())  # ns from t = 0 again; climax order


def test_calibration_and_transforms(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "c.mcap"
    with McapWriter(out, rig, start_time_ns=START):
        pass
    msgs = decoded(out)
    for cam in rig:
        ((log_time, _, cal),) = msgs[f"/cameras/{cam.name}/calibration"]
        assert log_time == START and cal.frame_id == cam.name
        assert (cal.width, cal.height) == (cam.width, cam.height)
        np.testing.assert_allclose(np.reshape(cal.K, (3, 3)), cam.K)
        np.testing.assert_allclose(np.reshape(cal.P, (3, 4)), np.hstack([cam.K, np.zeros((3, 1))]))
        np.testing.assert_allclose(np.reshape(cal.R, (3, 3)), np.eye(3))
    cal0 = msgs["/cameras/cam0/calibration"][0][2]
    cal1 = msgs["/cameras/cam1/calibration"][0][2]
    assert cal0.distortion_model == "plumb_bob" and len(cal0.D) == 5
    assert cal1.distortion_model == "rational_polynomial" and len(cal1.D) == 8
    np.testing.assert_allclose(cal1.D, rig["cam1"].dist)
    ((_, _, tf),) = msgs["/tf"]
    assert [t.child_frame_id for t in tf.transforms] == ["cam0", "cam1"]
    for t, cam in zip(tf.transforms, rig, strict=True):
        assert t.parent_frame_id == "world"
        np.testing.assert_allclose(
            [t.translation.x, t.translation.y, t.translation.z], cam.centre_m, atol=1e-12
        )
        q = [t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]
        # world_from_cam maps the camera's optical axis (+z) to its viewing direction
        forward = Rotation.from_quat(q).apply([0.0, 0.0, 1.0])
        np.testing.assert_allclose(forward, cam.R[2], atol=1e-9)


def test_four_coefficient_distortion_is_padded(tmp_path: Path) -> None:
    cam = Camera(
        "c",
        64,
        48,
        np.array([[50.0, 0, 32], [0, 50, 24], [0, 0, 1]]),
        np.array([0.1, 0.2, 0.0, 0.0]),
        np.eye(3),
        np.zeros(3),
    )
    out = tmp_path / "d.mcap"
    with McapWriter(out, Rig((cam,))):
        pass
    ((_, _, cal),) = decoded(out)["/cameras/c/calibration"]
    assert cal.distortion_model == "plumb_bob"
    np.testing.assert_allclose(cal.D, [0.1, 0.2, 0, 0, 0])


def test_read_run_round_trip(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "r.mcap"
    with McapWriter(out, rig, start_time_ns=START, metadata={"rules": {"a": "b"}}) as w:
        for i in range(3):
            w.write_frame(i * S // 15, targets()[: i + 1], candidates())
        w.write_event(exchange())
    run = read_run(out)
    assert run.start_time_ns == START and run.complete
    assert run.frame_t_ns.tolist() == [0, S // 15, 2 * S // 15]
    assert run.target_frame.tolist() == [0, 1, 1, 2, 2, 2]
    assert run.target_label.tolist() == [
        "p1/head",
        "p1/head",
        "p2/right_hand",
        "p1/head",
        "p2/right_hand",
        "t6",
    ]
    assert run.target_tracker.tolist() == [4, 4, 5, 4, 5, 6]
    assert run.target_person.tolist() == [1, 1, 2, 1, 2, 0]
    assert run.target_limb.tolist() == [0, 0, 2, 0, 2, 255]
    assert run.target_state.tolist() == [1, 1, 2, 1, 2, 0]
    np.testing.assert_array_equal(
        run.target_pos_m[run.frame_rows(2)], [tg.mean_m for tg in targets()[:3]]
    )
    assert run.candidate_frame.tolist() == [0, 0, 1, 1, 2, 2]
    assert run.candidate_rows(1) == slice(2, 4)
    assert run.metadata["rules"] == {"a": "b"}
    assert run.events == (exchange(),)


def write_many_frames(path: Path, rig: Rig, n: int) -> McapWriter:
    w = McapWriter(path, rig, start_time_ns=START, chunk_size=4096)
    for i in range(n):
        w.write_frame(i * S // 15, targets(), candidates())
    return w


def test_truncated_file_is_read_up_to_the_last_chunk(rig: Rig, tmp_path: Path) -> None:
    full = tmp_path / "full.mcap"
    write_many_frames(full, rig, 200).close()
    data = full.read_bytes()
    n_full = read_run(full).n_frames
    assert n_full == 200
    for cut in (len(data) // 2, len(data) - 40):
        part = tmp_path / f"cut{cut}.mcap"
        part.write_bytes(data[:cut])
        run = read_run(part)
        assert not run.complete
        assert 10 < run.n_frames <= 200
        assert run.frame_t_ns.tolist() == [i * S // 15 for i in range(run.n_frames)]
        assert set(run.channels) == set(TOPIC_SCHEMAS)
        assert run.metadata["surveil"]["start_time_ns"] == str(START)
    # only the closing magic lost: the footer was read, nothing is missing
    part = tmp_path / "nomagic.mcap"
    part.write_bytes(data[:-1])
    run = read_run(part)
    assert run.complete and run.n_frames == 200


def test_a_crashed_writer_leaves_a_readable_file(rig: Rig, tmp_path: Path) -> None:
    out = tmp_path / "crash.mcap"
    w = write_many_frames(out, rig, 199)  # not closed: no summary, last chunk unwritten
    try:
        run = read_run(out)
        assert not run.complete and 100 < run.n_frames < 199
    finally:
        w.close()
    assert read_run(out).n_frames == 199


def test_unreadable_files_are_input_errors(rig: Rig, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="not found"):
        read_run(tmp_path / "missing.mcap")
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"PK\x03\x04 this is a zip file")
    with pytest.raises(InputError, match="junk.mcap: not an MCAP file"):
        read_run(junk)
    (tmp_path / "empty.mcap").write_bytes(b"")
    with pytest.raises(InputError, match="not an MCAP file"):
        read_run(tmp_path / "empty.mcap")
    other = tmp_path / "other.mcap"
    with open(other, "wb") as f:
        writer = Writer(f)
        writer.start()
        writer.register_channel("/imu", "json", 0)
        writer.finish()
    with pytest.raises(InputError, match="other.mcap: no /targets channel"):
        read_run(other)


def test_writer_rejects_bad_arguments(rig: Rig, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="start_time_ns"):
        McapWriter(tmp_path / "a.mcap", rig, start_time_ns=-1)
    with pytest.raises(ValueError, match="reserved"):
        McapWriter(tmp_path / "b.mcap", rig, metadata={"surveil": {}})
    w = McapWriter(tmp_path / "c.mcap", rig)
    with pytest.raises(ValueError, match="t_ns"):
        w.write_frame(-5, [], CandidateSet.empty())
    w.close()
    w.close()  # idempotent
    with pytest.raises(ValueError, match="closed"):
        w.write_frame(0, [], CandidateSet.empty())


@pytest.mark.parametrize(
    ("hue", "name"),
    [
        (0, "red"),
        (359.9, "red"),
        (40, "orange"),
        (60, "yellow"),
        (118, "green"),
        (180, "cyan"),
        (230, "blue"),
        (275, "purple"),
        (310, "magenta"),
    ],
)
def test_hue_name(hue: float, name: str) -> None:
    assert hue_name(hue) == name
