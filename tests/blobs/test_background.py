import cv2
import numpy as np
import pytest

from surveil.blobs import BackgroundConfig, BackgroundModel
from surveil.blobs.background import (
    distance_to_polygon_m,
    distance_to_zero,
    floor_polygon_m,
    floor_view_mask,
    learning_frames_after,
    relative_gain,
    silhouettes_from_mask,
    upscale_twice,
)
from surveil.camera import look_at

H, W = 120, 160


def _scene(rng):
    base = np.full((H, W, 3), 120, np.uint8)
    base[:, W // 2 :] = (60, 140, 200)
    return base, lambda: np.clip(base + rng.normal(0, 2, base.shape), 0, 255).astype(np.uint8)


def _learn(model, frame, n=30):
    for _ in range(n):
        model.step(frame())


def test_moving_rectangle_gives_one_silhouette_in_place(rng):
    cfg = BackgroundConfig(learning_frames=20, min_person_area_px=100)
    model = BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)
    _learn(model, frame)
    for x in range(20, 60, 4):
        img = frame()
        img[30:90, x : x + 20] = (20, 200, 40)
        sil = model.step(img)
    assert sil.n == 1
    assert sil.top_v_px[0] == pytest.approx(30, abs=2)
    assert sil.bottom_v_px[0] == pytest.approx(89, abs=2)
    assert sil.labels[60, x + 10] == 1 and sil.labels[60, 130] == 0
    assert sil.dist_outside_px[60, x + 10] == 0
    assert sil.dist_outside_px[60, x + 40] == pytest.approx(20, abs=2)
    assert sil.labels.dtype == np.int32 and sil.dist_outside_px.dtype == np.float32


@pytest.mark.parametrize("scale", [1.0, 0.5, 0.3])
def test_silhouette_boxes_hold_every_silhouette_pixel(rng, scale):
    """Skin and blobs are computed inside these boxes only: a pixel outside would be lost.
    At model_scale < 1 the mask is resized back, so the boxes are scaled with slack."""
    cfg = BackgroundConfig(learning_frames=20, min_person_area_px=100, model_scale=scale)
    model = BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)
    _learn(model, frame)
    img = frame()
    img[30:90, 23:41] = (20, 200, 40)
    img[50:103, 101:133] = (200, 30, 160)
    sil = model.step(img)
    assert sil.n == 2 and sil.boxes_px is not None
    covered = np.zeros((H, W), bool)
    for x0, y0, x1, y1 in sil.boxes(0):
        covered[y0:y1, x0:x1] = True
    assert covered[sil.labels > 0].all()
    # and not much more than the people (the frame is 5.5 times their area)
    area = sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in sil.boxes(0))
    assert area < 1.5 * (60 * 18 + 53 * 32)


def test_thin_arm_held_out_stays_in_the_silhouette(rng):
    # a 3-px-wide arm (about 1.5 px in the half-size mask) reaching out of a body must stay
    # foreground: a 3-px opening erased such arms, and with them hands held against them
    model = BackgroundModel(BackgroundConfig(learning_frames=20, min_person_area_px=100), (H, W))
    _, frame = _scene(rng)
    _learn(model, frame)
    img = frame()
    img[30:100, 20:44] = (20, 200, 40)  # body
    img[50:53, 44:70] = (20, 200, 40)  # arm
    img[49:54, 70:74] = (60, 110, 200)  # hand
    sil = model.step(img)
    assert sil.n == 1
    assert sil.labels[51, 60] == 1 and sil.labels[51, 72] == 1


@pytest.mark.parametrize("mask", ["changed", "foreground"])
def test_raw_masks_mark_what_differs_from_the_background_not_what_the_closing_filled(rng, mask):
    # changed: foreground or shadow; foreground: without shadows -- both before the clean-up
    model = BackgroundModel(BackgroundConfig(learning_frames=20, min_person_area_px=100), (H, W))
    _, frame = _scene(rng)
    _learn(model, frame)
    assert getattr(model.step(frame()), mask) is None  # not asked for
    img = frame()
    img[30:100, 20:30] = (20, 200, 40)  # two legs 4 px apart: the closing joins them
    img[30:100, 34:44] = (20, 200, 40)
    sil = model.step(img, **{mask: True})
    raw = getattr(sil, mask)
    assert raw is not None and raw.shape == (H, W)
    assert sil.labels[60, 32] > 0, "the closing filled the gap"
    assert not raw[60, 32]
    assert raw[60, 25] and raw[60, 38]
    assert not raw[60, 100]


def test_background_edges_are_the_learnt_scenes_edges_refreshed_every_few_frames(rng):
    cfg = BackgroundConfig(learning_frames=20, min_person_area_px=100, edges_every_frames=5)
    model = BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)  # grey left half, orange right half
    for _ in range(19):
        assert model.step(frame(), background_edges=True).background_edges is None  # learning
    edges = model.step(frame(), background_edges=True).background_edges
    assert edges.shape == (H, W) and edges.dtype == np.float32
    assert edges[60, W // 2 - 1] > 50 and edges[60, 20] < 5 and edges[60, 120] < 5
    img = frame()
    img[30:90, 20:40] = (20, 200, 40)  # a person: not in the background image
    assert model.step(img, background_edges=True).background_edges is edges  # shared
    assert model.step(frame()).background_edges is None  # not asked for
    for _ in range(2):
        assert model.step(frame(), background_edges=True).background_edges is edges
    refreshed = model.step(frame(), background_edges=True).background_edges
    assert refreshed is not edges and edges[60, 30] < 5


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_background_image_is_the_learnt_scene_at_frame_size_shared_until_read_again(rng, scale):
    cfg = BackgroundConfig(learning_frames=20, edges_every_frames=5, model_scale=scale)
    model = BackgroundModel(cfg, (H, W))
    base, frame = _scene(rng)  # grey left half, orange right half
    for _ in range(20):
        assert model.background_image() is None  # still learning
        model.step(frame())
    image = model.background_image()
    assert image.shape == (H, W, 3) and image.dtype == np.uint8 and not image.flags.writeable
    inner = np.s_[:, 10 : W // 2 - 10]  # away from the edge the downscale blurs
    assert np.abs(image[inner].astype(int) - base[inner]).max() <= 6
    img = frame()
    img[30:90, 20:40] = (20, 200, 40)  # a person walks in: not part of the background
    model.step(img)
    assert model.background_image() is image  # the same array until read again
    for _ in range(cfg.edges_every_frames):
        model.step(img)
    again = model.background_image()
    assert again is not image
    assert np.abs(again[50, 30].astype(int) - base[50, 30]).max() <= 6


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_shadow_is_background_only_inside_the_shadow_region(rng, scale):
    """A darkened patch of the same hue is a shadow where shadows may fall (the floor); in
    front of a wall it is a dark thing of the wall's hue (dark skin before a brown door)."""
    cfg = BackgroundConfig(learning_frames=20, model_scale=scale)
    floor = np.zeros((H, W), bool)
    floor[70:] = True  # the lower part of the image sees the floor
    model = BackgroundModel(cfg, (H, W), shadow_region=floor)
    _, frame = _scene(rng)
    _learn(model, frame)
    img = frame()
    img[75:115, 10:70] = (img[75:115, 10:70] * 0.65).astype(np.uint8)  # on the floor
    img[5:45, 90:150] = (img[5:45, 90:150] * 0.65).astype(np.uint8)  # on the wall
    sil = model.step(img, foreground=True)
    assert sil.n == 1
    assert sil.labels[25, 120] == 1 and sil.labels[95, 40] == 0
    assert sil.foreground[25, 120] and not sil.foreground[95, 40]
    # without a region, MOG2's shadows are shadows everywhere
    plain = BackgroundModel(cfg, (H, W))
    _learn(plain, frame)
    assert plain.step(img).n == 0


def test_shadow_region_must_match_the_frames():
    with pytest.raises(ValueError, match="shadow_region"):
        BackgroundModel(BackgroundConfig(), (H, W), shadow_region=np.ones((H, W + 1), bool))


def test_empty_scene_has_no_silhouette_and_large_distances(rng):
    model = BackgroundModel(BackgroundConfig(learning_frames=5), (H, W))
    _, frame = _scene(rng)
    for _ in range(10):
        sil = model.step(frame())
    assert sil.n == 0 and sil.top_v_px.shape == (0,)
    assert not sil.mask.any()
    assert (sil.dist_outside_px >= np.hypot(H, W) - 1).all()


def test_learning_phase_then_slow_rate_keeps_a_standing_person(rng):
    cfg = BackgroundConfig(learning_frames=10, learning_rate=0.001, min_person_area_px=100)
    model = BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)
    assert model.learning
    _learn(model, frame, 10)
    assert not model.learning
    for _ in range(40):  # the person stands still for 40 frames: not absorbed at rate 0.001
        img = frame()
        img[30:90, 40:60] = (20, 200, 40)
        sil = model.step(img)
    assert sil.n == 1
    model.reset()
    assert model.learning and model.n_frames == 0


HEAD_PX = np.array([[50.0, 35.0]])  # the standing person's head, as a tracker reports it


def _stand(model, frame, n, person_px=None, box=None):
    """n frames of a person standing at rows 30:90, cols 40:60 (and, with ``box``, a still
    object there), the person's head passed as ``people_px``."""
    for _ in range(n):
        img = frame()
        img[30:90, 40:60] = (20, 200, 40)
        if box is not None:
            img[box] = (200, 40, 200)
        sil = model.step(img, people_px=person_px)
    return sil


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_a_tracked_person_is_not_learnt_into_the_background_however_long_they_stand(rng, scale):
    # at rate 0.02 MOG2 absorbs a still colour within ~20 frames (weight 1 - 0.98^n > 0.3)
    cfg = BackgroundConfig(
        learning_frames=10, learning_rate=0.02, min_person_area_px=100, model_scale=scale
    )
    free, kept = BackgroundModel(cfg, (H, W)), BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)
    _learn(free, frame, 10)
    _learn(kept, frame, 10)
    assert _stand(free, frame, 80).n == 0  # absorbed
    sil = _stand(kept, frame, 80, person_px=HEAD_PX)
    assert sil.n == 1 and sil.mask[30:90, 40:60].mean() > 0.95
    # and when nobody is tracked the model learns everything again
    assert _stand(kept, frame, 80, person_px=np.zeros((0, 2))).n == 0


def test_what_no_tracked_person_holds_is_still_learnt_at_the_usual_rate(rng):
    # a bag put down (not a person: nothing tracked on it) is absorbed as without protection,
    # while the person beside it stays
    cfg = BackgroundConfig(learning_frames=10, learning_rate=0.02, min_person_area_px=100)
    model = BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)
    _learn(model, frame, 10)
    bag = (slice(70, 100), slice(100, 130))
    sil = _stand(model, frame, 8, person_px=HEAD_PX, box=bag)
    assert sil.n == 2  # the bag is new
    sil = _stand(model, frame, 80, person_px=HEAD_PX, box=bag)
    assert sil.n == 1 and sil.labels[60, 50] == 1 and sil.labels[85, 115] == 0


def test_protection_is_off_during_learning_and_when_disabled(rng):
    # people present from the start are learnt (the learning phase assumes an empty room),
    # and protect_people = false gives MOG2's own behaviour
    _, frame = _scene(rng)
    cfg = BackgroundConfig(learning_frames=30, learning_rate=0.02, min_person_area_px=100)
    learning = BackgroundModel(cfg, (H, W))
    assert _stand(learning, frame, 30, person_px=HEAD_PX).n == 0
    off = BackgroundModel(
        BackgroundConfig(
            learning_frames=10, learning_rate=0.02, min_person_area_px=100, protect_people=False
        ),
        (H, W),
    )
    _learn(off, frame, 10)
    assert _stand(off, frame, 80, person_px=HEAD_PX).n == 0


def test_a_camera_starting_late_learns_only_what_is_left_of_the_learning_phase(rng):
    # the run learns for 30 frame sets; a camera whose first frame comes 15 sets late learns
    # for the remaining 15 (people walk in when the run's learning ends), one that comes
    # after the end for the shortest phase
    cfg = BackgroundConfig(learning_frames=30, late_learning_frames=4)
    _, frame = _scene(rng)
    late = BackgroundModel(cfg, (H, W), learning_frames_after(cfg, 15))
    _learn(late, frame, 14)
    assert late.learning
    late.step(frame())
    assert not late.learning
    very_late = BackgroundModel(cfg, (H, W), learning_frames_after(cfg, 100))
    _learn(very_late, frame, 4)
    assert not very_late.learning
    assert BackgroundModel(cfg, (H, W)).learning_frames == 30


def test_wrong_frame_shape_names_argument():
    model = BackgroundModel(BackgroundConfig(), (H, W))
    with pytest.raises(ValueError, match="bgr"):
        model.step(np.zeros((H + 1, W, 3), np.uint8))


def test_clipped_distances_are_the_exact_ones_up_to_the_clip():
    # the distance transform runs only near the silhouettes; beyond the clip every pixel is
    # farther than it, so min(exact, clip) is what comes out everywhere
    mask = np.zeros((H, W), bool)
    mask[20:70, 30:45] = True
    mask[60:110, 100:120] = True
    exact = silhouettes_from_mask(mask, 10).dist_outside_px
    clipped = silhouettes_from_mask(mask, 10, max_distance_px=9.5).dist_outside_px
    np.testing.assert_allclose(clipped, np.minimum(exact, 9.5), atol=1e-5)
    assert (exact > 30).any()  # the clip matters somewhere
    empty = silhouettes_from_mask(np.zeros((H, W), bool), 10, max_distance_px=9.5)
    assert (empty.dist_outside_px == 9.5).all()


def test_a_distance_cap_changes_no_distance_below_it(rng):
    cfg = BackgroundConfig(learning_frames=20, min_person_area_px=100)
    exact, capped = BackgroundModel(cfg, (H, W)), BackgroundModel(cfg, (H, W), distance_cap_px=12)
    _, frame = _scene(rng)
    for _ in range(30):
        img = frame()
        exact.step(img)
        capped.step(img)
    img = frame()
    img[30:90, 40:60] = (20, 200, 40)
    a, b = exact.step(img), capped.step(img)
    assert a.n == b.n == 1 and (a.labels == b.labels).all()
    assert b.dist_outside_px.max() <= 12 + 1e-5
    near = a.dist_outside_px < 10  # the model's half-size pixels: one of slack for the scaling
    np.testing.assert_allclose(b.dist_outside_px[near], a.dist_outside_px[near], atol=1e-4)
    with pytest.raises(ValueError, match="distance_cap_px"):
        BackgroundModel(cfg, (H, W), distance_cap_px=0)


@pytest.mark.parametrize("where", ["middle", "corner", "none"])
def test_silhouettes_scaled_back_near_people_only_equal_the_whole_frame_resizes(where):
    """At model_scale 0.5 labels and clipped distances are resized back to frame size only
    around the silhouettes: the same arrays, to the bit, as resizing the whole frame."""
    cfg = BackgroundConfig(model_scale=0.5, min_person_area_px=40)
    model = BackgroundModel(cfg, (H, W), distance_cap_px=12)
    mask = np.zeros((H // 2, W // 2), bool)
    if where == "middle":
        mask[10:50, 20:30] = True
        mask[25:55, 50:58] = True
        mask[28:40, 47:50] = True  # an arm held out of the second silhouette widens its box
    elif where == "corner":
        mask[0:30, 70:80] = True  # touches the frame border
    cap = 12 / 2.0
    small = silhouettes_from_mask(mask, 10, max_distance_px=cap)
    labels, dist = model._upscale(small, cap)
    whole = (W, H)
    np.testing.assert_array_equal(
        labels, cv2.resize(small.labels, whole, interpolation=cv2.INTER_NEAREST)
    )
    np.testing.assert_array_equal(
        dist, cv2.resize(small.dist_outside_px, whole, interpolation=cv2.INTER_LINEAR)
    )
    assert (dist < cap).sum() > 0 if where != "none" else (dist == cap).all()


def test_upscale_twice_outside_the_box_is_the_given_value():
    image = np.zeros((6, 8), np.int32)
    image[2:4, 3:5] = 7
    out = upscale_twice(image, (3, 2, 5, 4), -1, cv2.INTER_NEAREST)
    assert out.shape == (12, 16) and out.dtype == np.int32
    assert (out[4:8, 6:10] == 7).all() and (out == 7).sum() == 16 and (out == -1).sum() == 176
    assert (upscale_twice(image, None, 5, cv2.INTER_NEAREST) == 5).all()


def test_outside_distances_do_not_depend_on_where_the_array_lands_in_memory():
    """OpenCV's precise distance transform rounds some pixels' last bit differently with
    its output's alignment (16-byte steps for numpy's arrays): the same mask gave two
    different results over 64 calls whose outputs were kept alive. Ours give one."""
    mask = np.ones((48, 37), np.uint8)
    cv2.ellipse(mask, (18, 24), (7, 16), 20, 0, 360, 0, -1)
    kept = [distance_to_zero(mask) for _ in range(64)]
    assert len({d.tobytes() for d in kept}) == 1
    assert {d.ctypes.data % 64 for d in kept} == {0}
    np.testing.assert_allclose(
        kept[0], cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE), atol=1e-5
    )


@pytest.mark.parametrize("shape", [(480, 640), (240, 320)])
def test_floor_view_mask_is_where_lines_of_sight_meet_the_floor_inside_the_room(shape):
    cam = look_at(
        "c",
        np.array([0.25, 0.25, 2.6]),
        np.array([3.0, 2.5, 0.8]),
        width=640,
        height=480,
        hfov_deg=78,
    )
    room = floor_polygon_m(np.array([[0, 0, 2.6], [6, 0, 2.6], [6, 5, 2.6], [0, 5, 2.6]]))
    mask = floor_view_mask(cam, room, 0.1, shape)
    assert mask.shape == shape
    scale = shape[1] / 640

    def seen(point_m):
        px, depth = cam.project(np.array([point_m]))
        assert depth[0] > 0 and cam.in_image(px, depth)[0]
        u, v = np.round((px[0] + 0.5) * scale - 0.5).astype(int)
        return mask[v, u]

    assert seen([3.0, 2.5, 0.0]) and seen([4.0, 4.5, 0.0])
    assert seen([3.0, 2.5, 0.8])  # a hand at hip height has the floor behind it ...
    assert not seen([3.0, 2.5, 1.7])  # ... a head in the middle of the room the far wall
    assert not seen([3.0, 5.0, 1.2])  # the far wall, its line of sight meets z = 0 beyond
    assert not seen([6.0, 5.0, 2.6])  # level with the camera: never meets the floor


def test_distance_to_a_degenerate_polygon_is_to_its_segment():
    # two cameras: the "hull" is the segment between them, grown by the margin
    line = floor_polygon_m(np.array([[0.0, 0, 2.5], [4.0, 0, 2.5]]))
    d = distance_to_polygon_m(np.array([[2.0, 0.0], [2.0, 1.0], [5.0, 0.0]]), line)
    assert d.round(6).tolist() == [0.0, 1.0, 1.0]


def _lit(frame, level):
    return np.clip(np.rint(frame.astype(np.float32) * level), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_illumination_drift_is_undone_not_taken_for_foreground(rng, scale):
    """The light brightens by 8 % after learning while a person walks in, large enough to
    hold a quarter of the frame: the person is the only silhouette, and the model's gain is
    the drift's inverse (estimated every third frame). Without the compensation the whole
    frame turns foreground."""
    found = {}
    for compensate in (True, False):
        cfg = BackgroundConfig(
            learning_frames=20,
            min_person_area_px=100,
            model_scale=scale,
            gain_compensation=compensate,
        )
        model = BackgroundModel(cfg, (H, W))
        _, frame = _scene(rng)
        _learn(model, frame)
        for k in range(23):  # 20 frames of drift, then 3 at the new level
            img = frame()
            img[10:110, 30 + k : 80 + k] = (20, 200, 40)
            sil = model.step(_lit(img, 1.0 + 0.004 * min(k + 1, 20)))
        found[compensate] = sil
        if compensate:
            assert model.gain == pytest.approx(np.full(3, 1 / 1.08), abs=0.01)
    sil = found[True]
    assert sil.n == 1
    assert sil.mask.sum() == pytest.approx(100 * 50, rel=0.1)
    assert found[False].mask.mean() > 0.9


def test_relative_gain_ignores_what_is_not_usable_and_clipped_pixels():
    bg = np.full((10, 10, 3), 100, np.uint8)
    frame = np.full((10, 10, 3), 125, np.uint8)  # 25 % brighter
    frame[:6] = 30  # someone dark in front of most of the background
    frame[6:, :2] = 255  # and saturated highlights
    usable = np.zeros((10, 10), bool)
    usable[6:] = True
    assert relative_gain(frame, bg, usable).tolist() == pytest.approx([0.8] * 3)
    assert relative_gain(frame, bg, np.zeros((10, 10), bool)).tolist() == [1.0] * 3


def test_a_person_appearing_at_once_does_not_move_the_gain(rng):
    """A person who appears in one frame covers pixels that were background in the last: the
    gain, a median, stays 1 and only the person is foreground."""
    cfg = BackgroundConfig(learning_frames=20, min_person_area_px=100)
    model = BackgroundModel(cfg, (H, W))
    _, frame = _scene(rng)
    _learn(model, frame)
    img = frame()
    img[10:110, 20:70] = (250, 250, 250)  # a quarter of the frame, bright
    sil = model.step(img)
    assert model.gain == pytest.approx(np.ones(3), abs=0.01)
    assert sil.n == 1 and sil.mask.sum() == pytest.approx(100 * 50, rel=0.1)
