import dataclasses
import math

import numpy as np
import pytest

from surveil.blobs import BlobConfig, extract_blobs, silhouettes_from_mask
from surveil.blobs.extract import REFERENCE_WIDTH_PX

H, W = 100, 120


def _one_person():
    m = np.zeros((H, W), bool)
    m[10:91, 20:80] = True  # top 10, bottom 90
    return silhouettes_from_mask(m, 10)


# every skin pixel inside the silhouette is a blob, as it is; a bare forearm's hand end is
# the blob's point (the option before session 101; the default keeps it for the report only)
BARE_ARMS = BlobConfig(
    min_blob_area_px=1,
    silhouette_dilate_px=0,
    open_px=0,
    max_blob_area_rel=0.0,
    arm_length_rel=0.17,
    arm_hand_end="point",
)


def test_keeps_ceil_lambda_3n_largest_and_drops_small():
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    sizes = [9, 8, 7, 6, 5, 4, 2]  # squares: areas 81..4 px
    for i, s in enumerate(sizes):
        skin[12 + 11 * i : 12 + 11 * i + s, 25 : 25 + s] = True
    cfg = BlobConfig(min_blob_area_px=10, blob_excess=1.5, silhouette_dilate_px=0, open_px=0)
    blobs = extract_blobs(skin, sil, cfg)
    assert len(blobs) == math.ceil(1.5 * 3 * 1) == 5
    assert blobs.areas_px.tolist() == [81, 64, 49, 36, 25]
    blobs = extract_blobs(skin, sil, cfg, n_people_hint=2)  # ceil(9) = 9: only the size cut
    assert blobs.areas_px.tolist() == [81, 64, 49, 36, 25, 16]
    assert blobs.labels.max() == 6 and (blobs.labels == 1).sum() == 81


def test_a_dark_head_on_a_skin_coloured_shirt_is_split_off_by_colour(rng):
    """A dark-skinned head sits on a beige shirt that the skin classifier also takes for
    skin; together they are too big for a head or hand and would be dropped whole. With the
    frame, the blob splits by chromaticity: the head stays a blob, the shirt (shaded on one
    side, same chromaticity) is still too big and goes."""
    sil = _one_person()
    img = np.zeros((H, W, 3), np.uint8)
    shirt = np.zeros((H, W), bool)
    shirt[26:70, 22:78] = True
    head = np.zeros((H, W), bool)
    head[12:26, 42:56] = True
    img[shirt] = (150, 180, 200)  # beige (BGR)
    img[40:70, 50:78] = (100, 120, 133)  # the shirt's shaded side
    img[head] = (40, 58, 92)  # dark skin
    img = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    skin = shirt | head
    cfg = BlobConfig(min_blob_area_px=10, silhouette_dilate_px=0, open_px=0)
    assert len(extract_blobs(skin, sil, cfg)) == 0
    blobs = extract_blobs(skin, sil, cfg, bgr=img)
    assert len(blobs) == 1
    assert blobs.centroids_px[0] == pytest.approx([48.5, 18.5], abs=1.0)
    assert (
        len(extract_blobs(skin, sil, dataclasses.replace(cfg, split_min_delta=0.0), bgr=img)) == 0
    )


def _head_and_hand_joined_by_a_rim(hand_px: int) -> tuple[np.ndarray, np.ndarray]:
    """A person's mask and skin in a 640-pixel-wide frame (the opening's kernel size is
    given for that width): a head and a hand_px x hand_px hand ending at (63, 63), joined by
    a two-pixel rim of colour fringe along the silhouette edge."""
    h, w = 100, REFERENCE_WIDTH_PX
    person = np.zeros((h, w), bool)
    person[10:91, 20:80] = True
    skin = np.zeros((h, w), bool)
    skin[15:27, 40:52] = True  # head
    skin[64 - hand_px : 64, 64 - hand_px : 64] = True
    skin[20:70, 21:23] = True  # the rim
    skin[20:22, 21:41] = True
    skin[68:70, 21:61] = True
    skin[62:69, 60:62] = True
    return person, skin


def test_opening_cuts_thin_rims_joining_blobs_and_keeps_small_hands():
    person, skin = _head_and_hand_joined_by_a_rim(4)
    sil = silhouettes_from_mask(person, 10)
    cfg = BlobConfig(min_blob_area_px=10, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    plain = dataclasses.replace(cfg, open_px=0)
    assert len(extract_blobs(skin, sil, plain)) == 1  # head, rim and hand in one blob
    blobs = extract_blobs(skin, sil, cfg)
    assert len(blobs) == 2
    assert blobs.centroids_px.ravel().tolist() == pytest.approx([45.5, 20.5, 61.5, 61.5], abs=0.3)
    # at half the width the kernel would be 1.5 px: no opening (a 2 x 2 hand survives)
    half = extract_blobs(
        skin[::2, ::2],
        silhouettes_from_mask(person[::2, ::2], 10),
        dataclasses.replace(cfg, min_blob_area_px=1),
    )
    assert len(half) == 1


def test_open_keeps_isolated_restores_a_hand_seen_edge_on_and_still_cuts_rims():
    """A hand hanging at the side, seen from the front, is a two-pixel sliver with a
    three-pixel-wide knuckle: the opening leaves a few pixels of it, too few for a blob, and
    the hand is lost. ``open_keeps_isolated`` keeps such a region whole; a rim joining a head
    and a hand (much of the region survives) is still cut, and a one-pixel fringe touching
    nothing (nothing survives) is still erased."""
    person, skin = _head_and_hand_joined_by_a_rim(6)
    sil = silhouettes_from_mask(person, 10)
    skin[40:56, 74:76] = True  # the other hand edge-on: 2 x 16 px ...
    skin[47:50, 73:76] = True  # ... with a 3 x 3 knuckle
    skin[30:50, 30] = True  # a one-pixel fringe, 20 px
    cfg = BlobConfig(
        min_blob_area_px=16,
        silhouette_dilate_px=0,
        max_blob_area_rel=0.0,
        open_keeps_isolated=False,
    )
    unopened = extract_blobs(skin, sil, dataclasses.replace(cfg, open_px=0))
    assert unopened.areas_px.tolist() == [399, 35, 20]  # head, rim and hand in one blob
    opened = extract_blobs(skin, sil, cfg)
    assert opened.areas_px.tolist() == [142, 34]  # the sliver is gone
    kept = extract_blobs(skin, sil, dataclasses.replace(cfg, open_keeps_isolated=True))
    assert kept.areas_px.tolist() == [142, 35, 34]
    assert kept.centroids_px[1] == pytest.approx([74.4, 47.5], abs=0.1)
    assert kept.centroids_px[[0, 2]] == pytest.approx(opened.centroids_px)
    assert kept.restored.tolist() == [False, True, False]
    assert opened.restored is None
    # restored regions only stand in for missing limbs: with a head and two hands in the
    # silhouette already, a fold of a shirt (or a third hand) has no place
    skin[75:81, 40:46] = True
    full = extract_blobs(skin, sil, dataclasses.replace(cfg, open_keeps_isolated=True))
    assert full.areas_px.tolist() == [142, 34, 32]
    assert full.restored.tolist() == [False, False, False]


def _edge_on_hand(skin: np.ndarray, top: int, col: int) -> None:
    """A 2 x 16 px sliver with a 3 x 3 knuckle, rows top..top+16 (an edge-on hand)."""
    skin[top : top + 16, col : col + 2] = True
    skin[top + 7 : top + 10, col - 1 : col + 2] = True


def test_restored_blobs_only_where_a_hanging_hand_can_be():
    """With a band [restore_min_rel_v, restore_max_rel_v], a region the opening would erase
    becomes a blob only at the height of a hand hanging at the side: a sliver by the shoulder
    (a fold, a sleeve's edge) stays erased, one by the hip is kept."""
    person, skin = _head_and_hand_joined_by_a_rim(6)
    sil = silhouettes_from_mask(person, 10)  # top row 10, bottom row 90
    _edge_on_hand(skin, 22, 74)  # centroid row ~30: rel_v 0.25
    cfg = BlobConfig(
        min_blob_area_px=16,
        silhouette_dilate_px=0,
        max_blob_area_rel=0.0,
        open_keeps_isolated=True,
        restore_min_rel_v=0.0,
        restore_max_rel_v=1.0,
    )
    anywhere = extract_blobs(skin, sil, cfg)
    assert anywhere.restored.tolist() == [False, True, False]
    assert anywhere.rel_v[1] == pytest.approx(0.25, abs=0.02)
    band = dataclasses.replace(cfg, restore_min_rel_v=0.4, restore_max_rel_v=0.7)
    high = extract_blobs(skin, sil, band)
    assert high.areas_px.tolist() == [142, 34]  # head and the plain hand only
    assert high.restored is None or not high.restored.any()
    _edge_on_hand(skin, 52, 70)  # centroid row ~60: rel_v 0.62
    low = extract_blobs(skin, sil, band)
    assert low.restored.tolist() == [False, True, False]
    assert low.rel_v[1] == pytest.approx(0.62, abs=0.02)
    assert low.centroids_px[1, 0] == pytest.approx(70.4, abs=0.2)


def test_ignores_skin_outside_silhouettes_and_computes_rel_v():
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    skin[48:53, 40:45] = True  # centre row 50 -> rel_v (50 - 10) / 80 = 0.5
    skin[40:60, 90:110] = True  # outside
    blobs = extract_blobs(skin, sil, BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0))
    assert len(blobs) == 1
    assert blobs.centroids_px[0] == pytest.approx([42.0, 50.0])
    assert blobs.rel_v[0] == pytest.approx(0.5)
    assert blobs.silhouette.tolist() == [1]
    assert blobs.bboxes_px[0].tolist() == [40, 48, 5, 5]


def test_silhouettes_know_their_centres():
    sil = _one_person()
    assert sil.centres_px.tolist() == [[49.5, 50.0]]


def test_a_bare_forearm_stands_for_its_hand_end_and_a_face_for_its_centre():
    """Short sleeves: the forearm is skin too, and the centre of mass of forearm + hand lies
    halfway to the elbow. An arm-shaped blob (longer than arm_length_rel x the silhouette's
    height of 80 px, more than ARM_ASPECT times longer than wide) gives the centre of its last
    hand_length_rel x 80 px at the end away from the body's centre (49.5, 50); a face with
    its neck (not that elongated) and a hand alone (not that long) keep their centres."""
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    skin[50:74, 70:75] = True  # hanging arm beside the body: 24 x 5 px, 0.3 of the height
    skin[12:34, 40:50] = True  # face and neck: 22 x 10 px
    skin[50:60, 25:29] = True  # hand alone at the other side: 10 x 4 px
    cfg = BARE_ARMS
    tenth = dataclasses.replace(cfg, hand_length_rel=0.1)
    by_size = extract_blobs(skin, sil, tenth)
    face, arm, hand = by_size.centroids_px
    assert arm == pytest.approx([72.0, 69.0])  # rows 65..73: within 8 px of the lower tip
    assert face == pytest.approx([44.5, 22.5])
    assert hand == pytest.approx([26.5, 54.5])
    too_long = np.zeros((H, W), bool)
    too_long[20:50, 70:75] = True  # 30 px = 0.375 of the height: no bare arm is that long
    (point,) = extract_blobs(too_long, sil, cfg).centroids_px
    assert point == pytest.approx([72.0, 34.5])
    assert by_size.rel_v[1] == pytest.approx((69.0 - 10) / 80)
    off = extract_blobs(skin, sil, dataclasses.replace(cfg, arm_length_rel=0.0))
    assert off.centroids_px[1] == pytest.approx([72.0, 61.5])
    raised = np.zeros((H, W), bool)
    raised[12:36, 70:75] = True  # the same arm raised above the body's centre
    tenth = dataclasses.replace(cfg, hand_length_rel=0.1)
    (point,) = extract_blobs(raised, sil, tenth).centroids_px
    assert point == pytest.approx([72.0, 16.0])


def test_hand_ends_for_the_report_only_leave_the_blobs_points_as_they_were():
    """``arm_hand_end = 'report'``: every blob keeps its centre of mass and rel_v (the
    candidates and the tracker see what they see with the option off); the hand ends the
    option would have made the points are in ``hand_px`` instead, and the default mode
    keeps none there."""
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    skin[50:74, 70:75] = True  # hanging bare forearm
    skin[12:34, 40:50] = True  # face and neck
    skin[50:60, 25:29] = True  # hand alone
    cfg = dataclasses.replace(BARE_ARMS, hand_length_rel=0.1)
    as_points = extract_blobs(skin, sil, cfg)
    report = extract_blobs(skin, sil, dataclasses.replace(cfg, arm_hand_end="report"))
    off = extract_blobs(skin, sil, dataclasses.replace(cfg, arm_length_rel=0.0))
    assert as_points.hand_px is None and off.hand_px is None
    np.testing.assert_array_equal(report.centroids_px, off.centroids_px)
    np.testing.assert_array_equal(report.rel_v, off.rel_v)
    np.testing.assert_array_equal(report.hand_px, as_points.centroids_px)
    assert report.hand_px[1] == pytest.approx([72.0, 69.0])  # the arm's; the others unmoved
    np.testing.assert_array_equal(report.hand_px[[0, 2]], off.centroids_px[[0, 2]])


def test_arm_zone_keeps_a_neck_and_a_shin_at_their_centres_and_still_moves_real_arms():
    """Seen from the side or behind, an ear or a face with its neck is a strip as long and
    thin as a forearm, and so is a shin in skin-coloured trousers; without ``arm_zone`` both
    move to a tip like a bare forearm. With it (the default) a blob that reaches into the
    head's zone (above row 10 + HEAD_ZONE_REL x 80) within HEAD_HALF_WIDTH_REL x 80 of the
    silhouette's centre column (49.5), or below KNEE_REL (row 10 + 64), keeps its centre; a
    hanging forearm ending at row 73 and one raised beside the head still move to their hand
    ends."""
    sil = _one_person()
    zoned = dataclasses.replace(BARE_ARMS, hand_length_rel=0.1)
    assert zoned.arm_zone
    anywhere = dataclasses.replace(zoned, arm_zone=False)
    neck = np.zeros((H, W), bool)
    neck[14:38, 47:52] = True  # from the ear (row 14, in the head's zone) down the neck
    shin = np.zeros((H, W), bool)
    shin[62:86, 40:45] = True  # below the knee
    for strip in (neck, shin):
        centre = np.argwhere(strip)[:, ::-1].mean(axis=0)
        assert extract_blobs(strip, sil, zoned).centroids_px[0] == pytest.approx(centre)
        moved = extract_blobs(strip, sil, anywhere).centroids_px[0]
        assert abs(moved[1] - centre[1]) > 5
    hanging = np.zeros((H, W), bool)
    hanging[50:74, 70:75] = True  # fingertips at row 73
    assert extract_blobs(hanging, sil, zoned).centroids_px[0] == pytest.approx([72.0, 69.0])
    raised = np.zeros((H, W), bool)
    raised[12:36, 70:75] = True  # beside the head, 22.5 px from the centre column
    assert extract_blobs(raised, sil, zoned).centroids_px[0] == pytest.approx([72.0, 16.0])


def test_a_hanging_forearm_level_with_the_hips_ends_in_its_lower_tip():
    """A silhouette's centre of mass is at hip height, level with a hanging hand: a forearm
    centred on that row is as far from it at both tips. The hand end is measured from the
    shoulder point (SHOULDER_DROP_REL x 80 px below the top row 10), so the lower tip wins."""
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    skin[38:62, 70:75] = True  # centroid row 49.5, the silhouette's centre row 50
    cfg = dataclasses.replace(BARE_ARMS, hand_length_rel=0.1)
    (point,) = extract_blobs(skin, sil, cfg).centroids_px
    assert point == pytest.approx([72.0, 57.0])  # rows 53..61: within 8 px of the lower tip


def test_a_fringe_as_long_as_a_forearm_but_thin_or_sparse_keeps_its_centre():
    """A wooden table's edge inside a silhouette is a skin-coloured strip as long as a
    forearm: thinner than a wrist (arm_min_width_rel x 81 px = 2.8 px), or, where the edge is
    slanted and noisy, with fewer pixels than a bar of arm_length_rel x 81 by that width
    (39). Its point stays its centre of mass; a forearm 4 px wide still moves to its hand
    end."""
    sil = _one_person()
    cfg = dataclasses.replace(BARE_ARMS, hand_length_rel=0.1)
    thin = np.zeros((H, W), bool)
    thin[50:74, 70:72] = True  # 24 x 2 px
    (point,) = extract_blobs(thin, sil, cfg).centroids_px
    assert point == pytest.approx([70.5, 61.5])
    sparse = np.zeros((H, W), bool)
    rows = np.arange(50, 74)
    sparse[rows, 70 + np.abs((rows % 6) - 3)] = True  # a zigzag 24 px long, 4 px wide: 24 px
    (point,) = extract_blobs(sparse, sil, cfg).centroids_px
    assert point == pytest.approx(np.argwhere(sparse)[:, ::-1].mean(axis=0))
    # wide enough (3.3 px): only the pixel count turned it away; a lower bound (22 px) lets it
    lower = dataclasses.replace(cfg, arm_min_width_rel=0.02)
    assert extract_blobs(sparse, sil, lower).centroids_px[0][1] == pytest.approx(69.0)
    wrist_wide = np.zeros((H, W), bool)
    wrist_wide[50:74, 70:74] = True  # 24 x 4 px
    (point,) = extract_blobs(wrist_wide, sil, cfg).centroids_px
    assert point == pytest.approx([71.5, 69.0])
    no_width_bound = dataclasses.replace(cfg, arm_min_width_rel=0.0)
    assert extract_blobs(thin, sil, no_width_bound).centroids_px[0] == pytest.approx([70.5, 69.0])


def test_dilation_takes_in_skin_just_outside_the_silhouette():
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    skin[40:45, 80:83] = True  # just right of the silhouette (last column 79)
    cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=3)
    assert len(extract_blobs(skin, sil, cfg)) == 1
    no_dilation = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0)
    assert len(extract_blobs(skin, sil, no_dilation)) == 0


def test_skin_coloured_background_inside_the_silhouette_is_not_a_blob():
    # the clean-up's closing fills the gap between an arm and the body with background; where
    # that background is skin-coloured (a warm floor), it is no blob when the background model
    # says it did not change, while a hand (changed) still is
    sil = _one_person()
    changed = sil.labels > 0
    changed[30:40, 50:60] = False  # the closed gap
    sil = dataclasses.replace(sil, changed=changed)
    skin = np.zeros((H, W), bool)
    skin[30:40, 50:60] = True  # skin-coloured background in the gap
    skin[60:66, 30:36] = True  # a hand
    cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    kept = extract_blobs(skin, sil, dataclasses.replace(cfg, change_dilate_px=0))
    assert kept.centroids_px.tolist() == [[32.5, 62.5]]
    assert len(extract_blobs(skin, sil, dataclasses.replace(cfg, change_dilate_px=-1))) == 2
    # a radius around the changed pixels takes in the rim of the gap again
    grown = extract_blobs(skin, sil, dataclasses.replace(cfg, change_dilate_px=2))
    assert grown.areas_px.sum() > kept.areas_px.sum()


def test_a_blob_mostly_not_foreground_is_scenery_and_dropped():
    # a wooden table's edge that the closing took into the silhouette: skin-coloured, but the
    # background model saw no change there; a hand on the table is foreground only in part
    # (where it is darker than the wood) and stays whole
    sil = _one_person()
    foreground = sil.labels > 0
    foreground[30:40, 40:60] = False  # the table's edge
    foreground[60:70, 30:40] = False  # the hand's half in the colour of the wood
    foreground[60:70, 30:35] = True
    sil = dataclasses.replace(sil, foreground=foreground)
    skin = np.zeros((H, W), bool)
    skin[30:40, 40:60] = True
    skin[60:70, 30:40] = True
    cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    kept = extract_blobs(skin, sil, dataclasses.replace(cfg, min_foreground_share=0.2))
    assert kept.centroids_px.tolist() == [[34.5, 64.5]] and kept.areas_px.tolist() == [100]
    every = extract_blobs(skin, sil, cfg)  # 0: no such test
    assert len(every) == 2
    # each blob's share is reported for the candidate stage (table edge 200 px, hand 100 px)
    assert every.foreground_share.tolist() == [0.0, 0.5]
    assert len(extract_blobs(skin, sil, dataclasses.replace(cfg, min_foreground_share=0.6))) == 0
    unmeasured = extract_blobs(skin, dataclasses.replace(sil, foreground=None), cfg)
    assert unmeasured.foreground_share is None


def test_a_blob_that_hardly_changed_is_scenery_and_dropped_shadows_count_as_change():
    # the table's edge taken into the silhouette did not change; a dark hand in front of a
    # light wall is a "shadow" to MOG2 (changed, not foreground) and must stay; a hand on the
    # wooden table changed only where it is unlike the wood, and stays whole
    sil = _one_person()
    changed = sil.labels > 0
    changed[30:40, 40:60] = False  # the table's edge: 200 px, none changed
    changed[60:70, 30:40] = False  # the hand on the table: 100 px, 40 changed
    changed[60:70, 30:34] = True
    foreground = np.zeros_like(changed)  # the dark hand and the table hand: no foreground
    sil = dataclasses.replace(sil, changed=changed, foreground=foreground)
    skin = np.zeros((H, W), bool)
    skin[30:40, 40:60] = True
    skin[60:70, 30:40] = True
    skin[10:16, 62:68] = True  # the dark hand, changed as a shadow
    cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    kept = extract_blobs(skin, sil, dataclasses.replace(cfg, min_changed_share=0.3))
    assert sorted(kept.areas_px.tolist()) == [36, 100]
    assert len(extract_blobs(skin, sil, cfg)) == 3  # 0: no such test
    assert len(extract_blobs(skin, sil, dataclasses.replace(cfg, min_changed_share=0.5))) == 1
    # the foreground share test would drop the dark hand with the table's edge
    fg_test = extract_blobs(skin, sil, dataclasses.replace(cfg, min_foreground_share=0.3))
    assert len(fg_test) == 0
    # without a changed mask (the background model was not asked for it) nothing is dropped
    unmeasured = dataclasses.replace(sil, changed=None)
    assert (
        len(extract_blobs(skin, unmeasured, dataclasses.replace(cfg, min_changed_share=0.3))) == 3
    )


def _table_with_ghost_and_hand():
    """A skin-coloured table seen whole; an object just taken off it at rows 20-39, cols
    20-39 (a ghost: foreground, skin, its outline an edge of the background image only) and
    a darker hand resting on it at rows 60-71, cols 60-69."""
    img = np.full((H, W, 3), (90, 140, 190), np.uint8)
    img[60:72, 60:70] = (50, 80, 130)
    mask = np.zeros((H, W), bool)
    mask[20:40, 20:40] = True
    mask[60:72, 60:70] = True
    edges = np.zeros((H, W), np.float32)
    edges[18:42, 18:42] = 200.0  # the object's outline in the background image
    edges[22:38, 22:38] = 0.0
    sil = dataclasses.replace(silhouettes_from_mask(mask, 10), background_edges=edges)
    return img, mask.copy(), sil


def test_revealed_skin_coloured_table_is_no_blob_but_a_hand_on_it_is():
    img, skin, sil = _table_with_ghost_and_hand()
    cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    blobs = extract_blobs(skin, sil, cfg, 1, img)
    assert blobs.centroids_px.tolist() == [[64.5, 65.5]]
    # the test is off at ratio 0, without the frame, and while the background is learnt
    assert len(extract_blobs(skin, sil, dataclasses.replace(cfg, ghost_edge_ratio=0.0), 1, img))
    assert len(extract_blobs(skin, sil, cfg, 1)) == 2
    learning = dataclasses.replace(sil, background_edges=None)
    assert len(extract_blobs(skin, learning, cfg, 1, img)) == 2


def test_ghost_test_leaves_a_hand_in_front_of_an_edge_of_the_background():
    # a hand held over the object's former outline: the background edge is there, but so is
    # the hand's own edge in the frame
    img, skin, sil = _table_with_ghost_and_hand()
    edges = np.array(sil.background_edges)
    edges[55:77, 55:75] = 60.0
    sil = dataclasses.replace(sil, background_edges=edges)
    cfg = BlobConfig(min_blob_area_px=1, silhouette_dilate_px=0, max_blob_area_rel=0.0)
    assert extract_blobs(skin, sil, cfg, 1, img).centroids_px.tolist() == [[64.5, 65.5]]


def test_empty_input_gives_empty_blobset():
    sil = silhouettes_from_mask(np.zeros((H, W), bool), 10)
    blobs = extract_blobs(np.zeros((H, W), bool), sil, BlobConfig())
    assert len(blobs) == 0
    assert blobs.centroids_px.shape == (0, 2) and blobs.bboxes_px.shape == (0, 4)
    assert blobs.labels.shape == (H, W) and blobs.labels.dtype == np.int32


def test_wrong_skin_shape_names_argument():
    with pytest.raises(ValueError, match="skin"):
        extract_blobs(np.zeros((H, W + 1), bool), _one_person(), BlobConfig())


def test_blobs_found_near_people_are_those_of_the_whole_frame(small_recording):
    """extract_blobs works on the box around the silhouettes (plus blob_margin_px) and the
    skin model classifies only there; on rendered frames (upscaled to 640 px wide so that
    the opening acts) this gives exactly the blobs of the whole frame with all its skin."""
    import cv2

    from surveil.blobs import BackgroundConfig, BackgroundModel, blob_margin_px
    from surveil.blobs.extract import _extract, _open_radius_px
    from surveil.blobs.skin import default_skin_model
    from surveil.io.recording import open_recording

    rec = open_recording(small_recording)
    cfg = BlobConfig()
    skin_model = default_skin_model()
    models: dict[str, BackgroundModel] = {}
    compared = 0
    for fs in rec.framesets():
        for cam, small in fs.images.items():
            img = cv2.resize(small, (640, 480), interpolation=cv2.INTER_LINEAR)
            bg = models.setdefault(cam, BackgroundModel(BackgroundConfig(), img.shape[:2]))
            sil = bg.step(img, **cfg.background_requests())
            if bg.learning or sil.n == 0:
                continue
            skin_near = skin_model.classify(img, sil.boxes(blob_margin_px(cfg, 640)))
            got = extract_blobs(skin_near, sil, cfg, None, img)
            want = _extract(
                skin_model.classify(img), sil, cfg, None, img, _open_radius_px(cfg, 640)
            )
            np.testing.assert_allclose(got.centroids_px, want.centroids_px, atol=1e-9)
            for field in ("areas_px", "bboxes_px", "silhouette", "labels"):
                np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
            np.testing.assert_allclose(got.rel_v, want.rel_v, atol=1e-12)
            compared += len(want)
    assert compared > 100  # blobs, not empty frames, were compared


def test_an_empty_restore_band_is_a_config_error_naming_the_table(tmp_path):
    from surveil.errors import ConfigError
    from surveil.pipeline import load_pipeline_config

    path = tmp_path / "band.toml"
    path.write_text("[blobs]\nrestore_min_rel_v = 0.7\nrestore_max_rel_v = 0.4\n")
    with pytest.raises(ConfigError, match="blobs: restore_min_rel_v .* must not exceed"):
        load_pipeline_config(path)
    path.write_text("[blobs]\nrestore_max_rel_v = 1.5\n")
    with pytest.raises(ConfigError, match="restore_max_rel_v must be <= 1"):
        load_pipeline_config(path)


def _table_scene():
    """A person's silhouette that the closing has grown over the edge of a skin-coloured
    table (columns 65-79, rows 60-69: skin in the frame and in the background image,
    unchanged to the background model), with a hand (rows 20-29) that changed the pixels
    it covers."""
    sil = _one_person()
    skin = np.zeros((H, W), bool)
    skin[20:30, 30:40] = True  # the hand
    skin[60:70, 65:80] = True  # the table's edge
    scenery = np.zeros((H, W), bool)
    scenery[55:100, 55:120] = True  # the table in the background image
    changed = np.zeros((H, W), bool)
    changed[10:91, 20:60] = True  # the person; the table's edge is unchanged
    sil = dataclasses.replace(sil, changed=changed)
    return skin, sil, scenery


def test_skin_coloured_scenery_that_the_closing_took_in_is_not_a_blob():
    skin, sil, scenery = _table_scene()
    cfg = BlobConfig(min_blob_area_px=10, silhouette_dilate_px=0, open_px=0)
    assert cfg.scenery_share == 0.5  # on by default
    kept = extract_blobs(skin, sil, cfg, scenery=scenery)
    assert kept.centroids_px.tolist() == [[34.5, 24.5]]  # the hand alone
    assert len(extract_blobs(skin, sil, cfg)) == 2  # no scenery mask: no test
    off = dataclasses.replace(cfg, scenery_share=0.0)
    assert len(extract_blobs(skin, sil, off, scenery=scenery)) == 2
    # a hand held in front of the table changes what it covers: it stays a blob
    changed = sil.changed.copy()
    changed[60:70, 65:80] = True
    held = dataclasses.replace(sil, changed=changed)
    assert len(extract_blobs(skin, held, cfg, scenery=scenery)) == 2


def test_a_camouflaged_head_at_the_silhouette_top_is_not_taken_for_scenery():
    """A dark head in front of a skin-coloured board on the wall: skin in the frame and in
    the background image, and unchanged to the model where it blends in. It sits at the
    top of its silhouette, above scenery_min_rel_v, where the closing takes nothing in."""
    skin, sil, scenery = _table_scene()
    skin[11:19, 45:53] = True  # the head, rel_v 0.05
    scenery[0:25, 40:60] = True  # the board behind it
    cfg = BlobConfig(min_blob_area_px=10, silhouette_dilate_px=0, open_px=0)
    changed = sil.changed.copy()
    changed[11:19, 45:53] = False  # camouflaged: unchanged
    sil = dataclasses.replace(sil, changed=changed)
    kept = extract_blobs(skin, sil, cfg, scenery=scenery)
    assert sorted(kept.centroids_px.tolist()) == [[34.5, 24.5], [48.5, 14.5]]  # hand, head
    low = dataclasses.replace(cfg, scenery_min_rel_v=0.0)  # no head band: the head goes
    assert extract_blobs(skin, sil, low, scenery=scenery).centroids_px.tolist() == [[34.5, 24.5]]


def test_scenery_mask_classifies_each_background_image_once():
    from surveil.blobs.extract import SceneryMask
    from surveil.blobs.skin import default_skin_model

    class Model:  # a background model whose image changes when it is read again
        image = None

        def background_image(self):
            return self.image

    class Counting:  # the default skin model, counting its calls
        calls = 0

        def classify(self, bgr):
            self.calls += 1
            return default_skin_model().classify(bgr)

    skin, model = Counting(), Model()
    scenery = SceneryMask(skin)
    assert scenery.mask(model) is None  # learning: no background image yet
    model.image = np.full((H, W, 3), (90, 120, 190), np.uint8)  # wood-coloured, BGR
    first = scenery.mask(model)
    assert first.shape == (H, W) and first.all() and not first.flags.writeable
    assert scenery.mask(model) is first and skin.calls == 1
    model.image = np.full((H, W, 3), 128, np.uint8)  # read again: a grey wall
    assert not scenery.mask(model).any() and skin.calls == 2


def test_observe_drops_the_scenery_a_person_frames_with_the_cameras_scenery_mask(rng):
    """A person whose arm and body frame a gap through which a wooden table shows: the
    closing fills the gap, the table there is skin-coloured and unchanged, and ``observe``
    with the camera's SceneryMask drops its blob, as a run does; without the mask the table
    stays a blob (the review used to show it)."""
    from surveil.blobs import BackgroundConfig, BackgroundModel, SceneryMask, observe
    from surveil.blobs.skin import default_skin_model

    h, w = 240, 320
    room = np.full((h, w, 3), 110, np.uint8)
    room[100:200, 120:240] = (90, 120, 190)  # the wooden table, BGR

    def frame(img):
        return np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)

    person = room.copy()
    person[60:220, 130:190] = (40, 60, 30)  # dark green clothes
    person[140:146, 157:163] = room[140:146, 157:163]  # the gap: table seen through it
    skin = default_skin_model()
    cfg = BlobConfig()
    kept = {}
    for name, scenery in (("with mask", SceneryMask(skin)), ("without", None)):
        model = BackgroundModel(BackgroundConfig(learning_frames=20), (h, w))
        for _ in range(20):
            observe(frame(room), model, skin, cfg, "cam0", 1, scenery)
        obs = observe(frame(person), model, skin, cfg, "cam0", 1, scenery)
        gap = obs.blobs.labels[140:146, 157:163]
        kept[name] = bool(gap.any())
    assert kept == {"with mask": False, "without": True}
