"""The whole pipeline on the small synthetic recording: output contract, accuracy, determinism."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from surveil.activity import load_rules
from surveil.blobs.extract import SceneryMask
from surveil.blobs.settings import BlobConfig
from surveil.blobs.skin import SkinModel
from surveil.datatypes import Limb, Phase, Silhouettes
from surveil.errors import ConfigError
from surveil.eval.score import EvalConfig, evaluate
from surveil.io.mcap_reader import read_run
from surveil.io.mcap_writer import McapSink, McapWriter
from surveil.io.recording import open_recording
from surveil.pipeline import (
    OPENCV_THREADS_ENV,
    Pipeline,
    PipelineConfig,
    load_pipeline_config,
    observe_cameras,
    run_recording,
    use_one_opencv_thread,
)
from surveil.recon.settings import CandidateConfig
from surveil.rigs import make_corner_rig
from surveil.tracking import LabellingConfig, TrackingConfig


def _run(recording_dir, out, seed=0):
    rec = open_recording(recording_dir)
    pipeline = Pipeline(PipelineConfig(seed=seed), rec.rig, load_rules())
    sink = McapSink(McapWriter(out, rec.rig, start_time_ns=rec.start_time_ns))
    summary = run_recording(rec.framesets, rec.n_framesets, pipeline, [sink])
    return summary, read_run(out)


@pytest.fixture(scope="module")
def first_run(small_recording, tmp_path_factory):
    return _run(small_recording, tmp_path_factory.mktemp("run") / "a.mcap")


def test_run_writes_every_frame_set_and_finds_both_people(first_run, small_recording):
    summary, run = first_run
    rec = open_recording(small_recording)
    assert summary.n_framesets == rec.n_framesets == run.n_frames
    assert run.complete and "/events" in run.channels
    assert len(summary.persons) >= 2
    stages = summary.median_ms()
    assert {"background", "skin", "blobs", "candidates", "tracking", "carry"} <= set(stages)


def test_run_tracks_heads_and_hands_against_the_ground_truth(first_run, small_recording, tmp_path):
    _, run = first_run
    report = evaluate(small_recording, run.path, EvalConfig())
    t = report.targets
    # 320x240 frames (hands ~6 px wide): a coarse bar; the full-size figures are benchmarks.
    # Explaining ghost candidates away trades recall here (0.56 -> 0.49, CLEAR MOT matching)
    # for far fewer false targets (1.9 -> 0.3 per frame): both are held.
    assert t.recall > 0.45
    assert t.false_targets_per_frame < 1.0
    assert t.head_error_mm_mean < 120 and t.hand_error_mm_median < 120


def test_same_seed_gives_the_same_output_whatever_opencvs_thread_count(
    first_run, small_recording, tmp_path
):
    # machines differ in cores, and OpenCV parallelises some calls (connected components,
    # resizes): the events must not depend on it
    _, a = first_run
    before = cv2.getNumThreads()
    cv2.setNumThreads(2 if before == 1 else 1)
    try:
        _, b = _run(small_recording, tmp_path / "b.mcap")
    finally:
        cv2.setNumThreads(before)
    np.testing.assert_array_equal(a.target_pos_m, b.target_pos_m)
    np.testing.assert_array_equal(a.target_label, b.target_label)
    np.testing.assert_array_equal(a.candidate_pos_m, b.candidate_pos_m)
    assert a.events == b.events


def test_one_opencv_thread_unless_the_environment_says_otherwise(monkeypatch):
    before = cv2.getNumThreads()
    try:
        cv2.setNumThreads(2)
        monkeypatch.setenv(OPENCV_THREADS_ENV, "2")
        assert use_one_opencv_thread() == 2
        monkeypatch.delenv(OPENCV_THREADS_ENV)
        assert use_one_opencv_thread() == 1 == cv2.getNumThreads()
    finally:
        cv2.setNumThreads(before)


def test_config_file_overrides_and_rejects_unknown_keys(tmp_path):
    good = tmp_path / "run.toml"
    good.write_text("seed = 5\n[tracking.filter]\nn_particles = 120\n")
    cfg = load_pipeline_config(good)
    assert cfg.seed == 5 and cfg.tracking.filter.n_particles == 120
    bad = tmp_path / "bad.toml"
    bad.write_text("[candidates]\nsigma_gap = 0.02\n")
    with pytest.raises(ConfigError, match=r"bad.toml: candidates.sigma_gap is not a known key"):
        load_pipeline_config(bad)


def test_the_background_learns_around_people_tracked_for_protect_after_s(small_recording):
    # the background model is told about a person's head and hands only once the person has
    # been tracked for protect_after_s (MOG2 needs far longer to absorb a still person);
    # unlabelled and lost targets never count, and a person gone that long starts again
    from surveil.datatypes import Limb, Phase, TargetSnapshot

    rec = open_recording(small_recording)
    pipe = Pipeline(PipelineConfig(), rec.rig, load_rules())
    after = pipe.cfg.background.protect_after_s
    s = 1_000_000_000

    def snap(tid, person, limb, phase=Phase.NORMAL):
        return TargetSnapshot(tid, person, limb, phase, np.array([1.0, 2.0, 1.0 + tid]))

    first = [snap(1, 1, Limb.HEAD), snap(2, 0, Limb.UNKNOWN), snap(3, 1, Limb.LEFT_HAND)]
    assert len(pipe._protected_people(0, first)) == 0
    assert len(pipe._protected_people(int((after - 1) * s), first)) == 0
    later = [*first, snap(4, 1, Limb.RIGHT_HAND, Phase.LOST), snap(5, 2, Limb.HEAD)]
    got = pipe._protected_people(int(after * s), later)
    assert sorted(got[:, 2]) == [2.0, 4.0]  # person 1's head and left hand only
    gone = int((2 * after + 1) * s)
    assert len(pipe._protected_people(gone, [snap(1, 1, Limb.HEAD)])) == 0


def test_clipped_silhouette_distances_leave_candidates_and_tracks_unchanged(
    small_recording, monkeypatch
):
    # the run clips dist_outside_px where p_b and the head body check no longer read it
    # (silhouette_distance_cap_px): the same candidates and tracks as with exact distances
    import surveil.pipeline as pipeline_module

    rec = open_recording(small_recording)
    clipped = Pipeline(PipelineConfig(), rec.rig, load_rules())
    exact = Pipeline(PipelineConfig(), rec.rig, load_rules())
    n_candidates = 0
    for fs in rec.framesets():
        a = clipped.step(fs)
        with monkeypatch.context() as m:  # models made in this step measure exactly
            m.setattr(pipeline_module, "silhouette_distance_cap_px", lambda cfg: None)
            b = exact.step(fs)
        np.testing.assert_array_equal(a.candidates.points_m, b.candidates.points_m)
        np.testing.assert_array_equal(a.candidates.prior, b.candidates.prior)
        assert [(t.target_id, t.label, t.phase) for t in a.track.targets] == [
            (t.target_id, t.label, t.phase) for t in b.track.targets
        ]
        n_candidates += len(a.candidates.points_m)
    assert n_candidates > 0
    cap = pipeline_module.silhouette_distance_cap_px(PipelineConfig())
    assert all(bg.distance_cap_px == cap for bg in clipped.backgrounds.values())
    assert all(bg.distance_cap_px is None for bg in exact.backgrounds.values())
    clipped_dist = next(iter(a.observations.values())).silhouettes.dist_outside_px
    assert clipped_dist.max() <= cap + 1e-4


def test_the_distance_cap_follows_the_settings_that_read_the_distances():
    from surveil.pipeline import silhouette_distance_cap_px
    from surveil.recon.settings import CandidateConfig

    cfg = PipelineConfig()
    wider = PipelineConfig(candidates=CandidateConfig(sigma_silhouette_px=12.0))
    assert silhouette_distance_cap_px(wider) == 2 * silhouette_distance_cap_px(cfg)
    lax = PipelineConfig(candidates=CandidateConfig(term_threshold=1e-6, prior_threshold=1e-6))
    # p_b rejects only from sigma sqrt(2 ln 1e6) = 5.3 sigma: the cap moves out with it
    assert silhouette_distance_cap_px(lax) > 6 * cfg.candidates.sigma_silhouette_px
    never = PipelineConfig(candidates=CandidateConfig(term_threshold=0, prior_threshold=0))
    assert silhouette_distance_cap_px(never) is None


def test_the_changed_mask_is_asked_for_only_by_the_blob_tests_that_read_it():
    from surveil.blobs.settings import BlobConfig

    def wants(blobs: BlobConfig) -> bool:
        return PipelineConfig(blobs=blobs).background_requests()["changed"]

    assert wants(BlobConfig())  # the scenery test, on by default, reads it
    off = BlobConfig(scenery_share=0.0)
    assert not wants(off)  # the others are off by default: no mask, no cost
    assert wants(dataclasses.replace(off, min_changed_share=0.3))
    assert wants(dataclasses.replace(off, change_dilate_px=1))


def test_the_foreground_mask_is_asked_for_by_whichever_stage_reads_it(small_recording):
    from surveil.blobs.settings import BlobConfig
    from surveil.recon.settings import CandidateConfig

    def wants(cfg: PipelineConfig) -> bool:
        return cfg.background_requests()["foreground"]

    pairs = CandidateConfig(min_pair_foreground_share=0.2)
    assert not wants(PipelineConfig())  # both tests are off by default: no mask, no cost
    assert wants(PipelineConfig(candidates=pairs))  # the candidate stage's pair test
    assert wants(PipelineConfig(blobs=BlobConfig(min_foreground_share=0.1)))
    # and the blobs of such a run carry their shares
    rec = open_recording(small_recording)
    pipeline = Pipeline.for_recording(rec, PipelineConfig(candidates=pairs), load_rules())
    shares = [
        obs.blobs.foreground_share
        for fs in rec.framesets(stop=40)
        for obs in pipeline.step(fs).observations.values()
        if len(obs.blobs)
    ]
    assert shares and all(s is not None and np.all((s >= 0) & (s <= 1)) for s in shares)


def test_arm_trackers_feed_the_hands_no_two_views_see(small_recording):
    """With ``[arms] enabled`` and ``feed_candidates`` the arms run before the candidates,
    one pose per tracked person, and their hands join the candidates only where no camera
    pair gave one (rows of -1 camera pairs)."""
    from surveil.armpose import ArmPoseConfig
    from surveil.io.ground_truth import load_ground_truth

    rec = open_recording(small_recording)
    gt = load_ground_truth(small_recording)
    # the arms follow the tracker's hands by side; on this 320x240 recording the face cue
    # sides them otherwise and the fed hands' median error is 0.35 m, not 0.17 (session 50,
    # docs/armpose.md): the feed is tested on the sides it was tuned with, and on the fixed
    # head rise it was tuned with (the measured one moves the heads by millimetres and this
    # median to 0.34 m: docs/armpose.md, "Sensitive to the head's height"), and on the
    # silhouettes' own tops in p_o it was tuned with (tops_from_heads, the default since
    # session 78, gives 0.31 m), and on the pairs' midpoints it was tuned with (candidates
    # refined from all their views, the default since session 87, give 0.27 m)
    no_face = TrackingConfig(labelling=LabellingConfig(face_weight=0.0), head_top_to_centre_m=0.0)
    cfg = PipelineConfig(
        tracking=no_face,
        candidates=CandidateConfig(tops_from_heads=False, refine_min_views=0),
        arms=ArmPoseConfig(enabled=True, feed_candidates=True),
    )
    pipe = Pipeline(cfg, rec.rig, load_rules())
    n_fed, n_poses, errors = 0, 0, []
    hands = [j for j, lab in enumerate(gt.labels) if lab.endswith("hand")]
    for fs in rec.framesets():
        result = pipe.step(fs)
        cand = result.candidates
        fed = cand.cam_pairs[:, 0] < 0 if cand.cam_pairs is not None else np.zeros(0, bool)
        n_fed += int(fed.sum())
        if fed.any():
            # a fed hand is at least feed_radius_m from every camera-pair candidate
            d = np.linalg.norm(cand.points_m[fed][:, None] - cand.points_m[~fed][None], axis=2)
            assert d.size == 0 or d.min() > cfg.arms.feed_radius_m
            # and near a true hand
            f = int(np.argmin(np.abs(gt.t_ns - fs.t_ns)))
            true = gt.positions_m[f, hands]
            errors += list(np.linalg.norm(cand.points_m[fed][:, None] - true[None], axis=2).min(1))
        n_poses += len(result.arms)
        if result.arms:
            assert "arms" in result.timings_ms
    assert n_poses > 0
    assert n_fed > 0, "no arm hand was ever fed on a recording with hands hidden in views"
    # near a hand, not anywhere: 0.17 m median on this 320x240 recording, 0.08-0.10 m on the
    # 640x480 scenes (docs/benchmarks.md); a pose far off its hand would be metres away
    assert np.median(errors) < 0.25, np.round(errors, 2)


class _OneSilhouette:
    """A background model whose every frame shows one silhouette: two people merged."""

    def step(self, img, **_):
        labels = np.zeros(img.shape[:2], np.int32)
        labels[100:400, 200:440] = 1
        return Silhouettes(
            labels, np.array([100.0]), np.array([399.0]), np.zeros(img.shape[:2], np.float32)
        )


@pytest.mark.parametrize(
    ("from_crowns", "hint", "kept"), [(True, 0, 6), (False, 0, 5), (False, 2, 6)]
)
def test_a_view_where_people_merged_keeps_blobs_for_as_many_as_the_crowns_count(
    monkeypatch, from_crowns, hint, kept
):
    # two faces and four hands, all skin (white), in one silhouette of every view; each view's
    # crowns show two heads. N_h = 1 keeps ceil(1.5 * 3 * 1) = 5 blobs, N_h = 2 keeps 9.
    monkeypatch.setattr("surveil.pipeline.silhouette_crowns", lambda *_: np.zeros((2, 2)))
    rig = make_corner_rig(3, room_m=(6.0, 4.0), height_m=2.8, size=(640, 480), hfov_deg=80)
    img = np.zeros((480, 640, 3), np.uint8)
    for k, side in enumerate((20, 18, 16, 14, 12, 10)):
        img[150 : 150 + side, 210 + 36 * k : 210 + 36 * k + side] = 255
    lut = np.zeros((32, 32, 32), bool)
    lut[31, 31, 31] = True
    skin = SkinModel(lut, 5)
    cfg = PipelineConfig(
        people_hint=hint,
        blobs=dataclasses.replace(BlobConfig(), people_from_crowns=from_crowns, scenery_share=0.0),
    )
    observations, seconds = observe_cameras(
        cfg,
        rig,
        {cam.name: img for cam in rig},
        {cam.name: _OneSilhouette() for cam in rig},
        {cam.name: skin for cam in rig},
        {cam.name: SceneryMask(skin) for cam in rig},
        cfg.people_hint or None,
    )
    assert list(observations) == [cam.name for cam in rig]
    for obs in observations.values():
        assert obs.silhouettes.n == 1
        assert len(obs.blobs.areas_px) == kept
    assert all(set(s) == {"background", "skin", "crowns", "blobs"} for s in seconds.values())


def test_hands_pulled_onto_their_blobs_move_only_the_reported_hands(small_recording):
    """``[tracking] blob_pull_sigma_px``: the reported points of labelled hands move (onto
    their blobs' lines of sight, tests/tracking/test_blob_pull.py); the trackers (ids,
    labels, phases), the heads and combined pairs stay the filter's, and an unlabelled
    tracker moves only in a frame set where some blob is a bare forearm (its hand end pulls
    it). Whether the moves bring the hands
    nearer the true ones is measured on the bundled 640x480 takes, where 67 % of the demo's
    do (docs/tracking.md, "Hands pulled onto their blobs"): this 3 s, 320x240 take has too
    few moves (about 70) to tell, and its mean hand error went either way with changes
    elsewhere in the pipeline (docs/benchmarks.md, session 100)."""
    rec = open_recording(small_recording)
    off = TrackingConfig(blob_pull_sigma_px=0.0)
    on = TrackingConfig(blob_pull_sigma_px=4.0, blob_pull_gate_px=12.0)  # 320x240: half size
    pipes = {
        k: Pipeline(PipelineConfig(tracking=c), rec.rig, load_rules())
        for k, c in (("off", off), ("on", on))
    }
    moved = 0
    for fs in rec.framesets():
        a, b = (pipes[k].step(fs) for k in ("off", "on"))
        assert [(t.target_id, t.label, t.phase) for t in a.track.targets] == [
            (t.target_id, t.label, t.phase) for t in b.track.targets
        ]
        forearm = any(
            o.blobs.hand_px is not None and (o.blobs.hand_px != o.blobs.centroids_px).any()
            for o in b.observations.values()
        )
        for s, p in zip(a.track.targets, b.track.targets, strict=True):
            if s.phase is Phase.UNLABELLED and s.limb is not Limb.HEAD and forearm:
                continue
            if s.limb is Limb.HEAD or s.phase is not Phase.NORMAL:
                np.testing.assert_array_equal(s.mean_m, p.mean_m)
            else:
                moved += not np.array_equal(s.mean_m, p.mean_m)
    assert moved > 20
