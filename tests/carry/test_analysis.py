"""Hand regions, reliability (eq. 28) and the CarryAnalyser on constructed frames."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from surveil.blobs.background import silhouettes_from_mask
from surveil.blobs.extract import extract_blobs
from surveil.blobs.settings import BlobConfig
from surveil.camera import Rig, look_at
from surveil.carry import (
    CarryAnalyser,
    CarryConfig,
    analyse_hand_view,
    choose_radius,
    circle_box,
    find_hand_blob,
    hand_region,
    hand_view,
    locate_hand,
    locate_hands,
    rim_background_fraction,
)
from surveil.carry import analysis as carry_analysis
from surveil.datatypes import CameraObservation, Limb, Phase, TargetSnapshot

W, H = 320, 240
SKIN_BGR = (120, 160, 220)
GREEN_BGR = (30, 200, 30)
SHIRT_BGR = (110, 100, 100)  # greyish: no reliable hue
HAND_M = np.array([0.0, 0.0, 1.0])
NS = 66_666_667  # 15 fps


@pytest.fixture(scope="module")
def camera():
    return look_at("cam0", np.array([0.0, -3.0, 1.0]), HAND_M, width=W, height=H, hfov_deg=50)


def disc(mask_shape, centre, radius):
    yy, xx = np.ogrid[: mask_shape[0], : mask_shape[1]]
    return (xx - centre[0]) ** 2 + (yy - centre[1]) ** 2 <= radius**2


def make_frame(
    camera, hand_m=HAND_M, *, box=True, body_dx_px=-40, hand_r_px=5, shirt_bgr=SHIRT_BGR
):
    """A grey room, a person's body (rectangle) beside or behind the hand, a skin disc at the
    hand's projection and optionally a green box held next to it."""
    img = np.full((H, W, 3), 150, np.uint8)
    px, _ = camera.project(np.asarray(hand_m, float).reshape(1, 3))
    u, v = px[0]
    body = np.zeros((H, W), bool)
    bx = int(u) + body_dx_px
    body[int(v) - 60 : int(v) + 80, bx - 20 : bx + 20] = True
    arm = np.zeros((H, W), bool)
    lo, hi = sorted((bx, int(u)))
    arm[int(v) - 2 : int(v) + 3, lo : hi + 1] = True  # a sleeve from the body to the hand
    hand = disc((H, W), (u, v), hand_r_px)
    fg = body | arm | hand
    img[body | arm] = shirt_bgr
    if box:
        boxm = np.zeros((H, W), bool)
        boxm[int(v) - 5 : int(v) + 6, int(u) + 3 : int(u) + 13] = True
        boxm &= ~hand
        img[boxm] = GREEN_BGR
        fg |= boxm
    img[hand] = SKIN_BGR
    sil = silhouettes_from_mask(fg, 50)
    blobs = extract_blobs(hand, sil, BlobConfig(min_blob_area_px=5, silhouette_dilate_px=0))
    return img, CameraObservation(camera.name, sil, hand, blobs)


def hand_target(tid=1, person=1, limb=Limb.RIGHT_HAND, pos=HAND_M):
    return TargetSnapshot(tid, person, limb, Phase.NORMAL, np.asarray(pos, float))


def run(analyser, frames, targets, t0=0):
    out = None
    for k, (img, obs) in enumerate(frames):
        out = analyser.step(t0 + k * NS, {"cam0": img}, {"cam0": obs}, targets)
    return out


def test_rim_fraction_and_radius_choice():
    fg = np.zeros((60, 60), bool)
    fg[:, :30] = True
    bg = rim_background_fraction(fg, np.array([45.0, 30.0]), np.array([5.0, 10.0, 20.0]), 64)
    assert bg[0] == 1.0 and bg[1] == 1.0 and 0.6 < bg[2] < 0.9
    assert choose_radius(np.array([0.0, 0.05]), 0.5, 0.2) == 0  # inside: smallest
    with pytest.raises(ValueError, match="background_fractions"):
        choose_radius(np.zeros(0), 0.5, 0.2)


@pytest.mark.parametrize(
    ("centre", "radius"),
    [((20.3, 15.7), 6.2), ((0.4, 0.5), 9.0), ((39.9, 29.2), 5.0), ((10.0, 10.0), 10.0)],
)
def test_circle_box_holds_the_whole_circle_and_the_region_built_on_it(centre, radius):
    shape = (30, 40)
    centre = np.array(centre)
    box = circle_box(centre, radius, shape)
    circle = disc(shape, centre, radius)
    assert circle[box].sum() == circle.sum()
    # the region built on the box equals the region built on the whole image
    rng = np.random.default_rng(0)
    fg = rng.random(shape) < 0.7
    skin = rng.random(shape) < 0.2
    blob = disc(shape, centre, 2.5)
    full = hand_region(fg, skin, blob, centre, radius)
    origin = np.array([box[1].start, box[0].start], float)
    boxed = hand_region(fg[box], skin[box], blob[box], centre - origin, radius)
    assert full.any() and full[box].sum() == full.sum()
    np.testing.assert_array_equal(boxed, full[box])


def test_rim_fraction_reads_silhouette_labels_like_the_mask():
    rng = np.random.default_rng(1)
    labels = rng.integers(0, 3, (40, 50)).astype(np.int32)  # 0 background, 1-2 people
    radii = np.array([4.0, 9.5, 30.0])  # the largest circle leaves the image
    for centre in ([25.0, 20.0], [3.0, 37.0]):
        np.testing.assert_array_equal(
            rim_background_fraction(labels, np.array(centre), radii, 48),
            rim_background_fraction(labels > 0, np.array(centre), radii, 48),
        )


def test_find_hand_blob_returns_the_nearest_blob_pixel_within_reach():
    rng = np.random.default_rng(2)
    lab = np.where(rng.random((30, 30)) < 0.15, rng.integers(1, 5, (30, 30)), 0)
    rows, cols = np.nonzero(lab)
    for point in rng.uniform(-2.0, 31.0, (300, 2)):
        d2 = (cols - point[0]) ** 2 + (rows - point[1]) ** 2
        nearest = int(np.argmin(d2))
        expected = int(lab[rows[nearest], cols[nearest]]) if d2[nearest] <= 9.5 else 0
        assert find_hand_blob(lab, point, 3.0) == expected, point


def test_radius_steps_are_numpys_linspace_to_the_bit():
    rng = np.random.default_rng(3)
    for _ in range(2000):
        start = rng.uniform(1.0, 60.0)
        stop = start + rng.uniform(0.0, 60.0) * (rng.random() < 0.9)
        n = int(rng.integers(1, 9))
        np.testing.assert_array_equal(
            carry_analysis._linspace(start, stop, n), np.linspace(start, stop, n)
        )


def test_find_hand_blob_prefers_the_blob_under_the_point():
    lab = np.zeros((30, 30), np.int32)
    lab[10:14, 10:14] = 2
    lab[10:14, 15:19] = 1
    assert find_hand_blob(lab, np.array([12.0, 12.0]), 5) == 2
    assert find_hand_blob(lab, np.array([25.0, 25.0]), 5) == 0


def test_reliability_stretched_hand_beats_hand_inside_silhouette(camera):
    cfg = CarryConfig()
    img, obs = make_frame(camera, box=False, body_dx_px=-45)  # hand far from the body
    out = analyse_hand_view(img, obs, camera, HAND_M, cfg)
    img2, obs2 = make_frame(camera, box=False, body_dx_px=0)  # hand in front of the body
    inside = analyse_hand_view(img2, obs2, camera, HAND_M, cfg)
    assert out is not None and inside is not None
    assert out.rho > 0.8 and inside.rho < 0.3
    assert inside.rho >= cfg.rho_min  # eq. 28 floor
    radii = [out.radius_px, inside.radius_px]
    # inside the silhouette the circle shrinks to its smallest size
    r_small = camera.K[0, 0] * cfg.min_radius_m / 3.0
    assert radii[1] == pytest.approx(max(r_small, radii[1]), abs=1.0)
    assert radii[1] <= radii[0] + 1e-9


def test_view_of_a_hand_with_a_green_box(camera):
    img, obs = make_frame(camera)
    view = analyse_hand_view(img, obs, camera, HAND_M, CarryConfig())
    assert view is not None and view.pdf.shape == (180,)
    assert np.min(np.abs(view.modes_deg - 120.0)) < 6.0
    assert view.pdf.sum() > 0.2


def test_no_blob_near_the_hand_means_not_visible(camera):
    img, obs = make_frame(camera)
    far = HAND_M + np.array([0.0, 0.0, 0.5])
    assert analyse_hand_view(img, obs, camera, far, CarryConfig()) is None
    behind = np.array([0.0, -4.0, 1.0])
    assert analyse_hand_view(img, obs, camera, behind, CarryConfig()) is None


def test_located_together_or_one_at_a_time_the_views_are_the_same(camera):
    img, obs = make_frame(camera)
    hands = np.array([HAND_M, HAND_M + [0.0, 0.0, 0.5], [0.0, -4.0, 1.0], HAND_M + [0.02, 0, 0]])
    cfg = CarryConfig()
    together = locate_hands(obs, camera, hands, cfg)
    alone = [locate_hand(obs, camera, h, cfg) for h in hands]
    assert [s is None for s in together] == [False, True, True, False]
    for a, b in zip(together, alone, strict=True):
        assert (a is None and b is None) or (
            a.blob_label == b.blob_label
            and a.roi == b.roi
            and np.array_equal(a.centre_px, b.centre_px)
            and (a.radius_px, a.rho, a.depth_m) == (b.radius_px, b.rho, b.depth_m)
        )
    view = hand_view(img, obs, together[0], cfg)
    ref = analyse_hand_view(img, obs, camera, HAND_M, cfg)
    assert np.array_equal(view.pdf, ref.pdf) and view.rho == ref.rho


def test_a_blob_two_hands_claim_feeds_only_the_nearer_one(camera, monkeypatch):
    """A hand hidden behind another in this camera projects onto the other's blob: the blob
    and its box belong to the nearer hand, and the hidden one is not colour-analysed."""
    calls = []

    def counting_view(*args, **kwargs):
        calls.append(args[2].depth_m)
        return hand_view(*args, **kwargs)

    monkeypatch.setattr(carry_analysis, "hand_view", counting_view)
    behind = camera.centre_m + 1.4 * (HAND_M - camera.centre_m)  # same pixel, farther
    analyser = CarryAnalyser(CarryConfig(), Rig((camera,)))
    targets = [hand_target(1, 1, Limb.RIGHT_HAND), hand_target(2, 2, Limb.LEFT_HAND, behind)]
    out = run(analyser, [make_frame(camera)] * 5, targets)
    assert out[1].carrying and abs(out[1].hue_deg - 120.0) < 5.0
    assert not out[2].carrying and out[2].confidence == 0.0
    assert len(calls) == 5 and max(calls) < 3.5  # the nearer hand's view, once per frame set


def test_end_to_end_green_box_is_carried_and_bare_hand_is_not(camera):
    rig = Rig((camera,))
    analyser = CarryAnalyser(CarryConfig(), rig)
    with_box = run(analyser, [make_frame(camera)] * 5, [hand_target()])
    est = with_box[1]
    assert est.carrying and abs(est.hue_deg - 120.0) < 5.0
    assert est.since_ns == 0 and est.t_ns == 4 * NS  # the window holds all five frame sets
    assert est.label == "p1/right_hand" and 0.0 < est.confidence <= 1.0
    assert est.hue_pdf.sum() == pytest.approx(1.0)
    analyser.reset()
    bare = run(analyser, [make_frame(camera, box=False)] * 5, [hand_target()])
    assert not bare[1].carrying and bare[1].hue_deg is None


def test_heads_and_high_unknown_targets_are_not_analysed(camera):
    analyser = CarryAnalyser(CarryConfig(), Rig((camera,)))
    img, obs = make_frame(camera)
    targets = [
        hand_target(1, 1, Limb.HEAD, [0.0, 0.0, 1.7]),
        hand_target(2, 0, Limb.UNKNOWN, [0.0, 0.0, 1.6]),
        hand_target(3, 0, Limb.UNKNOWN, HAND_M),
    ]
    out = analyser.step(0, {"cam0": img}, {"cam0": obs}, targets)
    assert set(out) == {3} and out[3].label == "t3"


def test_window_freezes_while_hands_overlap_and_restarts_after(camera):
    cfg = CarryConfig()
    analyser = CarryAnalyser(cfg, Rig((camera,)))
    far = HAND_M + np.array([0.0, 2.0, 0.0])  # another person's hand, 2 m behind
    near = HAND_M + np.array([0.15, 0.0, 0.0])  # within overlap_distance_m
    apart = HAND_M + np.array([0.6, 0.0, 0.0])
    box, bare = make_frame(camera), make_frame(camera, box=False)
    a = hand_target(1, 1, Limb.RIGHT_HAND)

    def b(pos):
        return hand_target(2, 2, Limb.LEFT_HAND, pos)

    before = run(analyser, [box] * 5, [a, b(far)])[1]
    assert before.carrying
    # the hands meet; the box disappears from the image (it is being handed over)
    during = run(analyser, [bare] * 20, [a, b(near)], t0=5 * NS)[1]
    assert analyser.is_frozen(1) and analyser.is_frozen(2)
    assert during.carrying and during.hue_deg == before.hue_deg
    assert during.t_ns == 24 * NS
    np.testing.assert_array_equal(during.hue_pdf, before.hue_pdf)
    # they separate: the window restarts, so the old box does not linger
    after = run(analyser, [bare] * 2, [a, b(apart)], t0=25 * NS)[1]
    assert not after.carrying and not analyser.is_frozen(1)
    assert after.since_ns == 25 * NS  # its evidence starts at the separation


def test_restart_drops_what_the_window_held(camera):
    """A hand that put its box down and moved away: restarted, its window holds only the
    frames from then on, so the box it held a moment ago no longer counts."""
    analyser = CarryAnalyser(CarryConfig(), Rig((camera,)))
    a = hand_target()
    assert run(analyser, [make_frame(camera)] * 5, [a])[1].carrying
    stale = run(analyser, [make_frame(camera, box=False)] * 2, [a], t0=5 * NS)[1]
    assert stale.carrying and stale.since_ns == 0  # the 1 s window still holds the box
    analyser.restart(1)
    analyser.restart(99)  # unknown ids are ignored
    fresh = run(analyser, [make_frame(camera, box=False)] * 2, [a], t0=7 * NS)[1]
    assert not fresh.carrying and fresh.since_ns == 7 * NS


@pytest.mark.parametrize("pause", [True, False])
def test_a_hand_lost_longer_than_the_window_comes_back_with_what_it_held(camera, pause):
    """pick_place@102: the hand carrying the box was lost for 1.6 s; re-acquired, its window
    had aged empty and the first frames there (the box out of its circle) read it as empty,
    so the place that followed had no object before it."""
    cfg = dataclasses.replace(CarryConfig(), pause_hidden=pause)
    analyser = CarryAnalyser(cfg, Rig((camera,)))
    a = hand_target()
    assert run(analyser, [make_frame(camera)] * 5, [a])[1].carrying
    lost = dataclasses.replace(a, phase=Phase.LOST)
    assert run(analyser, [make_frame(camera)] * 30, [lost], t0=5 * NS) == {}  # 2 s hidden
    back = run(analyser, [make_frame(camera, box=False)] * 2, [a], t0=35 * NS)[1]
    if pause:
        assert back.carrying and back.since_ns == 0  # the five frames before it was lost
    else:
        assert not back.carrying and back.since_ns == 35 * NS


def make_two_hands(camera, left_m, right_m):
    """One person, both hands stretched out and each next to a green patch (a green dress
    seen around both hands)."""
    img = np.full((H, W, 3), 150, np.uint8)
    px, _ = camera.project(np.stack([left_m, right_m]))
    fg = np.zeros((H, W), bool)
    skin = np.zeros((H, W), bool)
    u_mid = int(px[:, 0].mean())
    v = int(px[0, 1])
    fg[v - 60 : v + 80, u_mid - 10 : u_mid + 10] = True
    img[fg] = SHIRT_BGR
    for u, vv in px:
        lo, hi = sorted((u_mid, int(u)))
        arm = np.zeros((H, W), bool)
        arm[int(vv) - 2 : int(vv) + 3, lo : hi + 1] = True
        img[arm] = SHIRT_BGR
        patch = np.zeros((H, W), bool)
        patch[int(vv) - 5 : int(vv) + 6, int(u) - 8 : int(u) + 9] = True
        img[patch] = GREEN_BGR
        hand = disc((H, W), (u, vv), 5)
        img[hand] = SKIN_BGR
        fg |= arm | patch | hand
        skin |= hand
    sil = silhouettes_from_mask(fg, 50)
    blobs = extract_blobs(skin, sil, BlobConfig(min_blob_area_px=5, silhouette_dilate_px=0))
    return img, CameraObservation(camera.name, sil, skin, blobs)


@pytest.mark.parametrize("subtract", [False, True])
def test_clothing_subtraction_removes_what_both_hands_see(camera, subtract):
    left_m, right_m = HAND_M - [0.3, 0.0, 0.0], HAND_M + [0.3, 0.0, 0.0]
    frame = make_two_hands(camera, left_m, right_m)
    cfg = dataclasses.replace(CarryConfig(), subtract_clothing=subtract)
    targets = [
        hand_target(1, 1, Limb.RIGHT_HAND, right_m),
        hand_target(2, 1, Limb.LEFT_HAND, left_m),
    ]
    out = run(CarryAnalyser(cfg, Rig((camera,))), [frame] * 3, targets)
    assert out[1].carrying is (not subtract) and out[2].carrying is (not subtract)
    # a different person's hand is never subtracted
    other = [targets[0], hand_target(2, 2, Limb.LEFT_HAND, left_m)]
    out = run(CarryAnalyser(cfg, Rig((camera,))), [frame] * 3, other)
    assert out[1].carrying and out[2].carrying


@pytest.mark.parametrize("box", [False, True])
def test_dress_subtraction_removes_the_shirt_beside_a_hand_but_not_what_it_holds(camera, box):
    """A bare hand against a red shirt sees red; the dress regions below the head (chest)
    see the same red, so with dress subtraction the hand is empty. A green box in the hand
    is still carried: the hand's circle is left out of the dress regions."""
    f = camera.K[0, 0]
    head_m = HAND_M + [-25 * 3.0 / f, 0.0, 0.65]  # above the body's centre line
    frame = make_frame(camera, box=box, body_dx_px=-25, shirt_bgr=(40, 30, 160))
    targets = [hand_target(1, 1, Limb.RIGHT_HAND), hand_target(2, 1, Limb.HEAD, head_m)]

    def estimate(subtract_dress: bool):
        # without the extent test, which removes a shirt this large on its own (not one
        # broken up by shading and folds, as on the exchange scene)
        cfg = CarryConfig(subtract_dress=subtract_dress, max_mode_extent=0.0)
        analyser = CarryAnalyser(cfg, Rig((camera,)))
        return run(analyser, [frame] * 5, targets)[1], analyser

    plain, _ = estimate(False)
    dressed, analyser = estimate(True)
    dress = analyser.dress(1)
    assert dress is not None and dress.sum() == pytest.approx(1.0)
    assert abs(((np.argmax(dress) * 2.0 + 180.0) % 360.0) - 180.0) < 10.0  # red, ~0 deg
    if box:
        assert plain.carrying and dressed.carrying
        assert abs(dressed.hue_deg - 120.0) < 5.0
    else:
        assert plain.carrying and abs(((plain.hue_deg + 180.0) % 360.0) - 180.0) < 10.0
        assert not dressed.carrying
    assert analyser.dress(7) is None


def test_memory_is_bounded(camera):
    cfg = dataclasses.replace(CarryConfig(), max_window_samples=4)
    analyser = CarryAnalyser(cfg, Rig((camera,)))
    run(analyser, [make_frame(camera)] * 12, [hand_target()])
    assert len(analyser._hands[1].window) == 4
    analyser.step(13 * NS, {}, {}, [])
    assert analyser._hands == {}
