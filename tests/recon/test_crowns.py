"""Head candidates from silhouette crowns, on people drawn as convex solids (a head ellipsoid
on a torso box on two legs) seen by 640x480 cameras high in the corners of a 6 x 4 m room."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from surveil.camera import Camera, Rig, look_at
from surveil.config import from_table
from surveil.datatypes import BlobSet, CameraObservation, Silhouettes
from surveil.errors import ConfigError
from surveil.recon.candidates import make_candidates
from surveil.recon.crowns import (
    centre_lines,
    crown_heads,
    people_from_crowns,
    silhouette_crowns,
)
from surveil.recon.settings import CandidateConfig, CrownConfig
from surveil.rigs import make_corner_rig

W, H = 640, 480
CFG = CrownConfig()
HEAD_A, HEAD_B = 0.125, 0.09  # the head's vertical and horizontal semi-axes, m


def _rig() -> Rig:
    return make_corner_rig(4, room_m=(6.0, 4.0), height_m=2.8, size=(W, H), hfov_deg=80)


def _parts(head_m: np.ndarray) -> list[np.ndarray]:
    """Surface points of a person's convex parts: head (ellipsoid), torso, two legs."""
    t, p = np.meshgrid(np.linspace(0, np.pi, 24), np.linspace(0, 2 * np.pi, 48))
    sphere = np.column_stack(
        [(np.sin(t) * np.cos(p)).ravel(), (np.sin(t) * np.sin(p)).ravel(), np.cos(t).ravel()]
    )
    head = head_m + sphere * [HEAD_B, HEAD_B, HEAD_A]
    corners = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T

    def box(lo, hi):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        return (lo + hi) / 2 + corners * (hi - lo) / 2

    x, y, z = head_m
    neck = z - HEAD_A + 0.02  # the shoulders' top, overlapping the chin
    torso = box([x - 0.12, y - 0.22, neck - 0.6], [x + 0.12, y + 0.22, neck])
    legs = [
        box([x - 0.08, y + s - 0.07, 0.0], [x + 0.08, y + s + 0.07, neck - 0.6])
        for s in (-0.12, 0.12)
    ]
    return [head, torso, *legs]


def _silhouettes(cam: Camera, heads_m: list[np.ndarray], hide_head: bool = False) -> Silhouettes:
    """The people's silhouettes in one view (``hide_head``: their heads are camouflaged)."""
    mask = np.zeros((H, W), np.uint8)
    for head in heads_m:
        for k, part in enumerate(_parts(np.asarray(head, float))):
            if hide_head and k == 0:
                continue
            px = cam.project(part)[0]
            hull = cv2.convexHull(np.rint(px).astype(np.int32))
            cv2.fillConvexPoly(mask, hull, 255)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask)
    dist = cv2.distanceTransform((mask == 0).astype(np.uint8), cv2.DIST_L2, 5)
    return Silhouettes(
        labels.astype(np.int32),
        stats[1:, cv2.CC_STAT_TOP].astype(np.float64),
        (stats[1:, cv2.CC_STAT_TOP] + stats[1:, cv2.CC_STAT_HEIGHT] - 1).astype(np.float64),
        dist,
        boxes_px=stats[1:, :4].astype(np.int32),
    )


def _heads(views: dict[int, Silhouettes], rig: Rig, cfg: CrownConfig = CFG):
    crowns = {m: silhouette_crowns(sil, rig.cameras[m], cfg) for m, sil in views.items()}
    return crown_heads(views, crowns, rig, cfg)


def test_each_head_of_two_people_in_one_silhouette_is_a_crown_their_shoulders_are_not():
    cam = look_at(
        "c", np.array([0.0, 0, 2.6]), np.array([4.0, 0, 1.2]), width=W, height=H, hfov_deg=70
    )
    heads = [np.array([4.0, -0.2, 1.62]), np.array([4.6, 0.25, 1.78])]
    sil = _silhouettes(cam, heads)
    assert sil.n == 1  # they overlap: one silhouette
    crowns = silhouette_crowns(sil, cam, CFG)
    tops = [cam.project((h + [0, 0, HEAD_A])[None])[0][0] for h in heads]
    assert len(crowns) == 2
    for u, v in tops:
        nearest = crowns[np.argmin(np.abs(crowns[:, 0] - u))]
        assert abs(nearest[0] - u) < 3 and abs(nearest[1] - v) < 3


def test_a_flat_topped_silhouette_has_no_crown():
    cam = look_at(
        "c", np.array([0.0, 0, 2.6]), np.array([4.0, 0, 1.2]), width=W, height=H, hfov_deg=70
    )
    sil = _silhouettes(cam, [np.array([4.0, 0.0, 1.6])], hide_head=True)  # headless
    assert len(silhouette_crowns(sil, cam, CFG)) == 0


def test_a_line_of_sight_over_a_crown_moved_to_the_centre_passes_within_two_pixels_of_it():
    rig = _rig()
    head = np.array([3.2, 1.7, 1.65])
    for cam in rig:
        crown = silhouette_crowns(_silhouettes(cam, [head]), cam, CFG)
        assert len(crown) == 1
        o, d = centre_lines(cam, crown, HEAD_A, HEAD_B)
        off = head - o[0]
        miss = np.linalg.norm(off - (off @ d[0]) * d[0])
        assert miss < 2 * np.linalg.norm(off) / cam.K[0, 0]  # two pixels at its depth


def test_four_views_of_two_people_give_their_head_centres():
    rig = _rig()
    heads = [np.array([2.4, 1.5, 1.62]), np.array([3.8, 2.4, 1.75])]
    points, gap, n_views = _heads({m: _silhouettes(cam, heads) for m, cam in enumerate(rig)}, rig)
    assert len(points) == 2
    err = np.linalg.norm(points[:, None] - np.array(heads)[None], axis=2).min(axis=0)
    assert (err < 0.03).all()
    assert (n_views >= 3).all() and (gap <= CFG.max_gap_m).all()


def test_three_people_close_together_count_three_where_their_silhouettes_merge():
    rig = _rig()
    heads = [np.array([2.2, 2.0, 1.62]), np.array([3.0, 2.0, 1.75]), np.array([3.8, 2.0, 1.85])]
    views = {m: _silhouettes(cam, heads) for m, cam in enumerate(rig)}
    crowns = [len(silhouette_crowns(views[m], rig.cameras[m], CFG)) for m in views]
    assert max(sil.n for sil in views.values()) == 1  # one silhouette in every view
    assert people_from_crowns(crowns) == 3
    # one view's stray crown (a raised fist) or hidden head is outvoted
    assert people_from_crowns([*crowns[:3], crowns[3] + 1]) == 3
    assert people_from_crowns([*crowns[:3], 2]) == 3


@pytest.mark.parametrize(("hidden", "found"), [(1, True), (2, False)])
def test_a_head_hidden_in_one_view_is_found_in_two_it_is_not(hidden, found):
    rig = _rig()
    head = np.array([3.0, 2.0, 1.7])
    views = {m: _silhouettes(cam, [head], hide_head=m < hidden) for m, cam in enumerate(rig)}
    points, _, _ = _heads(views, rig)
    assert (len(points) == 1) is found
    if found:
        assert np.linalg.norm(points[0] - head) < 0.03


def test_two_views_alone_do_not_make_a_head():
    rig = _rig()
    head = np.array([3.0, 2.0, 1.7])
    two = {m: _silhouettes(rig.cameras[m], [head]) for m in (0, 1)}
    assert len(_heads(two, rig)[0]) == 0
    assert len(_heads(two, rig, dataclasses.replace(CFG, min_views=2))[0]) == 1


def _observation(cam: Camera, heads_m: list[np.ndarray], blobs_m: np.ndarray) -> CameraObservation:
    sil = _silhouettes(cam, heads_m)
    px = cam.project(np.asarray(blobs_m, float).reshape(-1, 3))[0]
    n = len(px)
    u = np.clip(np.rint(px).astype(int), 0, [W - 1, H - 1])
    blobs = BlobSet(
        px,
        np.full(n, 60, np.int64),
        np.column_stack([u - 4, np.full((n, 2), 8)]).astype(np.int32),  # 8 x 8 px boxes
        sil.labels[u[:, 1], u[:, 0]].astype(np.int32),
        np.full(n, 0.5),
        np.zeros((H, W), np.int32),
    )
    return CameraObservation(cam.name, sil, np.zeros((H, W), bool), blobs)


@pytest.mark.parametrize("face_blob", [False, True])
def test_a_crown_head_is_added_only_where_no_skin_candidate_is(face_blob):
    rig = _rig()
    head = np.array([3.0, 2.0, 1.7])
    hands = np.array([[3.0, 1.65, 1.0], [3.0, 2.35, 1.0]])
    blobs = np.vstack([hands, head + [0, 0, -0.05]]) if face_blob else hands
    obs = [_observation(cam, [head], blobs) for cam in rig]
    cands = make_candidates(obs, rig, CandidateConfig())
    from_crowns = cands.head_only  # and no hand's: the tracker gives it to no hand
    np.testing.assert_array_equal(from_crowns, (cands.cam_pairs == -1).all(axis=1))
    assert from_crowns.sum() == (0 if face_blob else 1)
    if not face_blob:
        assert np.linalg.norm(cands.points_m[from_crowns][0] - head) < 0.03
        assert cands.prior[from_crowns][0] == CFG.prior
        assert (cands.blob_pairs[from_crowns] == -1).all()
        assert cands.views[from_crowns][0] == 2  # where two views' crowns meet
    at_hand = np.linalg.norm(cands.points_m[:, None] - hands[None], axis=2).min(axis=1) < 1e-3
    np.testing.assert_array_equal(cands.views[at_hand], 4)  # every camera sees both hands
    # the crowns a run finds in its per-camera stage give the same candidates
    given = [
        dataclasses.replace(o, crowns_px=silhouette_crowns(o.silhouettes, cam, CFG))
        for o, cam in zip(obs, rig, strict=True)
    ]
    again = make_candidates(given, rig, CandidateConfig())
    np.testing.assert_array_equal(again.points_m, cands.points_m)
    off = CandidateConfig(crowns=CrownConfig(enabled=False))
    assert not (make_candidates(obs, rig, off).cam_pairs == -1).any()


def test_crown_settings_are_checked_by_key():
    with pytest.raises(ConfigError, match="min_width_m"):
        from_table(CandidateConfig, {"crowns": {"min_width_m": 0.5}}, "run.toml")
    with pytest.raises(ConfigError, match="min_views"):
        from_table(CandidateConfig, {"crowns": {"min_views": 1}}, "run.toml")
