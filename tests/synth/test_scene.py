"""End-to-end checks of `surveil synth` on the small shared recording (tests/conftest.py)."""

import json

import cv2
import numpy as np
import pytest

from surveil.cli import ExitCode, main
from surveil.errors import ConfigError
from surveil.eval.truth_checks import visible_hands_on_skin
from surveil.io.calibration import load_rig
from surveil.io.ground_truth import MaskClass, load_ground_truth
from surveil.io.recording import open_recording
from surveil.synth.actors import BodyShape
from surveil.synth.scenario import load_scenario
from surveil.synth.scene import synthesise
from surveil.synth.timeline import compile_scenario


@pytest.fixture(scope="module")
def gt(small_recording):
    return load_ground_truth(small_recording)


def test_projected_visible_hands_land_on_skin_pixels(small_recording):
    hits, total = visible_hands_on_skin(small_recording)
    assert total > 100
    assert hits / total >= 0.95


def test_nothing_is_visible_in_a_dropped_frame(small_recording, gt):
    masks = small_recording / "ground_truth" / "masks"
    dropped = [
        (i, c)
        for c, cam in enumerate(gt.cameras)
        for i, frame in enumerate(gt.frames)
        if not (masks / cam / f"{frame:06d}.png").exists()
    ]
    assert dropped  # late start and drops exist in this scene
    assert not any(gt.visible[i, :, c].any() for i, c in dropped)


def test_most_limbs_are_seen_by_two_or_more_cameras(gt):
    present = np.isfinite(gt.positions_m[..., 0])
    assert (gt.n_views[present] >= 2).mean() > 0.7


def test_empty_room_lead_in_has_no_people(gt):
    lead = gt.t_ns < 2_000_000_000  # the small scenario's empty_room_s = 2.0
    assert np.isnan(gt.positions_m[lead]).all() and not gt.visible[lead].any()
    assert np.isfinite(gt.positions_m[~lead]).all()
    assert min(ev.start_ns for ev in gt.events) >= 2_000_000_000
    # the empty frames are still frames of the ground truth (scored: no target expected)
    np.testing.assert_array_equal(gt.frames, np.arange(gt.meta["n_frames"]))


def _joints(gt, pid: str, side: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(F, 3) shoulder, elbow and wrist of one arm."""
    return tuple(
        gt.joint_positions_m[:, gt.joint_labels.index(f"{pid}/{side}_{joint}")]
        for joint in ("shoulder", "elbow", "wrist")
    )


def test_arm_joints_have_the_body_s_lengths_and_reach_the_hands(gt):
    lead = gt.t_ns < 2_000_000_000
    assert gt.joint_positions_m.shape == (len(gt.frames), 12, 3)
    assert np.isnan(gt.joint_positions_m[lead]).all()
    assert np.isfinite(gt.joint_positions_m[~lead]).all()
    for person in gt.meta["persons"]:
        pid = person["id"]
        shape = BodyShape.from_height(person["height_m"])
        for side in ("left", "right"):
            shoulder, elbow, wrist = (a[~lead] for a in _joints(gt, pid, side))
            hand = gt.positions_m[~lead, gt.labels.index(f"{pid}/{side}_hand")]
            np.testing.assert_allclose(
                np.linalg.norm(elbow - shoulder, axis=1), shape.upper_arm_m, atol=1e-3
            )
            np.testing.assert_allclose(
                np.linalg.norm(wrist - elbow, axis=1), shape.forearm_m, atol=1e-3
            )
            # the wrist lies on the line from the elbow to the hand centre, half a hand short
            np.testing.assert_allclose(
                np.linalg.norm(hand - wrist, axis=1), 0.5 * shape.hand_length_m, atol=1e-3
            )
            np.testing.assert_allclose(
                np.linalg.norm(hand - elbow, axis=1),
                shape.forearm_m + 0.5 * shape.hand_length_m,
                atol=1e-3,
            )


def test_facing_is_the_actor_s_yaw_and_the_shoulders_agree(small_scenario, gt):
    lead = gt.t_ns < 2_000_000_000
    assert gt.persons == ("p1", "p2") and gt.facing_yaw_rad.shape == (len(gt.frames), 2)
    assert np.isnan(gt.facing_yaw_rad[lead]).all()
    assert np.isfinite(gt.facing_yaw_rad[~lead]).all()
    scenario = load_scenario(small_scenario)
    # the choreography's generator: the first of the seed's five streams (scene._render)
    rng_chor = np.random.default_rng(np.random.SeedSequence(scenario.scene.seed).spawn(5)[0])
    chor = compile_scenario(scenario, rng_chor)
    t_s = gt.t_ns[~lead] / 1e9 - 2.0  # choreography time starts after the lead-in
    for p, pid in enumerate(gt.persons):
        true = np.array([chor.actors[pid].yaw_at(t) for t in t_s])
        diff = np.angle(np.exp(1j * (gt.facing_yaw_rad[~lead, p] - true)))
        assert np.abs(diff).max() < 1e-4
        # the body's left axis, from the right shoulder to the left, is the facing + 90 deg
        left_sh, right_sh = (_joints(gt, pid, side)[0][~lead] for side in ("left", "right"))
        across = left_sh - right_sh
        from_shoulders = np.arctan2(across[:, 1], across[:, 0]) - np.pi / 2
        diff = np.angle(np.exp(1j * (gt.facing_yaw_rad[~lead, p] - from_shoulders)))
        assert np.abs(diff).max() < 1e-3
    # the scenario's facing_deg: p1 faces +X, p2 faces -X at the start
    first = gt.facing_yaw_rad[~lead][0]
    assert np.abs(np.angle(np.exp(1j * (first - np.radians([0.0, 180.0]))))).max() < 0.02


def test_rendered_skin_pixels_look_like_skin(small_recording, gt):
    """The masks and the video agree: pixels labelled skin have skin hue in the frame."""
    rec = open_recording(small_recording)
    fs = next(iter(rec.framesets(start=40, stop=41)))
    cam = sorted(fs.images)[0]
    mask = cv2.imread(str(small_recording / "ground_truth" / "masks" / cam / "000040.png"))
    hsv = cv2.cvtColor(fs.images[cam], cv2.COLOR_BGR2HSV)
    skin = mask[..., 0] == MaskClass.SKIN
    assert skin.sum() > 50
    hue_deg = hsv[..., 0][skin].astype(float) * 2
    assert np.median(np.minimum(hue_deg, 360 - hue_deg)) < 40  # reddish-orange


def test_recording_is_readable_with_drops_and_late_start(small_recording, gt):
    rec = open_recording(small_recording)
    assert rec.camera_names == gt.cameras
    meta = json.loads((small_recording / "ground_truth" / "scene.json").read_text())
    assert meta["missing_frames"]["cam3"] >= 7  # 0.5 s late start at 15 fps
    sets = list(rec.framesets())
    assert len(sets) == len(gt.frames)
    early = [fs for fs in sets if fs.t_ns < 0.45e9]
    assert early and all("cam3" not in fs.images for fs in early)
    assert all(fs.images[c].shape == (240, 320, 3) for fs in sets for c in fs.images)


def test_written_rig_carries_a_small_calibration_error(small_recording):
    true = load_rig(small_recording / "ground_truth" / "rig_true.yaml")
    written = load_rig(small_recording / "rig.yaml")
    for cam in true:
        shift = np.linalg.norm(cam.centre_m - written[cam.name].centre_m)
        assert 0 < shift < 0.05


def test_true_events_are_written(gt):
    assert [e.activity for e in gt.events] == ["exchange", "touch_face"]
    ex = gt.events[0]
    assert (ex.from_actor, ex.to_actor, ex.object_hue_deg) == (
        "p1/right_hand",
        "p2/left_hand",
        120.0,
    )


def test_same_seed_gives_identical_ground_truth_and_reuses_up_to_date_output(
    small_scenario, small_recording, tmp_path
):
    out = tmp_path / "again"
    synthesise(small_scenario, out)
    for name in ("limbs.csv", "joints.csv", "facing.csv", "objects.csv", "events.json"):
        assert (out / "ground_truth" / name).read_bytes() == (
            small_recording / "ground_truth" / name
        ).read_bytes()
    assert (out / "cam0.csv").read_bytes() == (small_recording / "cam0.csv").read_bytes()
    assert synthesise(small_scenario, out).reused


def test_a_rendering_finished_meanwhile_by_another_process_is_kept_for_its_readers(
    small_scenario, small_recording, tmp_path, monkeypatch
):
    """Two benchmark processes that render the same missing take at once: the one that
    finishes second must not delete the files the first is already reading (session 95:
    frames of three_people read as missing in one of two parallel seed_spread runs)."""
    import shutil

    from surveil.synth import scene

    out = tmp_path / "shared"
    render = scene._render
    theirs = []

    def render_while_another_finishes(*args, **kwargs):
        summary = render(*args, **kwargs)
        shutil.copytree(small_recording, out)  # the other process's rename
        theirs.append((out / "cam0.csv").stat().st_ino)
        return summary

    monkeypatch.setattr(scene, "_render", render_while_another_finishes)
    synthesise(small_scenario, out)
    assert (out / "cam0.csv").stat().st_ino == theirs[0]
    assert [p.name for p in tmp_path.iterdir()] == ["shared"]  # no temporary left


def test_another_scene_seed_is_another_take_of_the_same_script(
    small_scenario, small_recording, tmp_path
):
    """`surveil synth --seed N`: the same people and actions, but other timing variations,
    calibration error and noise; the bundled take is not reused for it, nor it for the
    bundled take."""
    out = tmp_path / "take"
    assert main(["synth", str(small_scenario), "--out", str(out), "--seed", "5"]) == ExitCode.OK
    bundled, take = load_ground_truth(small_recording), load_ground_truth(out)
    assert take.meta["seed"] == 5 != bundled.meta["seed"]
    assert take.labels == bundled.labels
    assert [e.activity for e in take.events] == [e.activity for e in bundled.events]
    assert not np.array_equal(take.positions_m, bundled.positions_m, equal_nan=True)
    assert (out / "rig.yaml").read_bytes() != (small_recording / "rig.yaml").read_bytes()
    assert synthesise(small_scenario, out, scene_seed=5).reused
    assert not synthesise(small_scenario, out, overwrite=True).reused
    assert load_ground_truth(out).meta["seed"] == bundled.meta["seed"]


def test_another_codec_stores_the_same_take_another_way(small_scenario, small_recording, tmp_path):
    """`surveil synth --compression png`: the bundled take's frames, pixel for pixel before
    encoding, as lossless PNG folders (the codec as a held-out condition); not reused for
    the bundled take's codec."""
    out = tmp_path / "png"
    args = ["synth", str(small_scenario), "--out", str(out), "--compression", "png"]
    assert main(args) == ExitCode.OK
    png, bundled = open_recording(out), open_recording(small_recording)
    assert sorted(p.name for p in (out / "cam0").iterdir())[0].endswith(".png")
    assert (out / "cam0.csv").read_bytes() == (small_recording / "cam0.csv").read_bytes()
    first_png = next(iter(png.framesets())).images["cam0"]
    first = next(iter(bundled.framesets())).images["cam0"]
    # the bundled take is lossy: the two differ by its coding error only
    assert np.abs(first_png.astype(int) - first.astype(int)).mean() < 6
    assert synthesise(small_scenario, out, compression="png").reused
    assert not synthesise(small_scenario, out, compression="jpeg", overwrite=True).reused
    # naming the scenario's own codec is the bundled take, already rendered
    own = load_scenario(small_scenario).effects.compression
    assert synthesise(small_scenario, small_recording, compression=own).reused


def test_an_unknown_codec_is_refused(small_scenario, tmp_path):
    with pytest.raises(ConfigError, match="compression must be one of mp4v, jpeg, png, got 'gif'"):
        synthesise(small_scenario, tmp_path / "x", compression="gif")
    assert not (tmp_path / "x").exists()


def test_a_negative_scene_seed_is_refused(small_scenario, tmp_path, capsys):
    code = main(["synth", str(small_scenario), "--out", str(tmp_path / "x"), "--seed", "-1"])
    assert code == ExitCode.BAD_INPUT
    assert "scene seed must be >= 0, got -1" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_synth_refuses_to_overwrite_a_foreign_directory(small_scenario, tmp_path, capsys):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep me")
    code = main(["synth", str(small_scenario), "--out", str(tmp_path / "mine")])
    assert code == ExitCode.BAD_INPUT
    assert "is not a recording made by `surveil synth`" in capsys.readouterr().err
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep me"


def test_synth_cli_reports_a_bad_scenario(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene]\nfps = -3\n")
    assert main(["synth", str(bad)]) == ExitCode.BAD_INPUT
    assert "scene.fps must be >= 1.0, got -3" in capsys.readouterr().err


def test_preview_contact_sheet_is_written(small_recording):
    sheet = cv2.imread(str(small_recording / "preview.png"))
    assert sheet is not None and sheet.shape[1] == 4 * 320 and sheet.std() > 10


def test_preview_at_chosen_times_has_one_row_per_time(small_scenario, tmp_path):
    out = tmp_path / "rec"
    code = main(
        [
            "-q",
            "synth",
            str(small_scenario),
            "--out",
            str(out),
            "--preview-at",
            "0.5",
            "--preview-at",
            "2.0",
        ]
    )
    assert code == ExitCode.OK
    sheet = cv2.imread(str(out / "preview.png"))
    tile_h = 240  # 320x240 tiles at full size
    assert sheet.shape[0] == 28 + 2 * tile_h
