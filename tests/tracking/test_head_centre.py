"""The head's centre from the silhouettes' crowns (surveil.tracking.head_centre)."""

from __future__ import annotations

import numpy as np

from surveil.camera import Rig
from surveil.tracking.head_centre import crown_heights_m, head_rises_m

HEAD_R = 0.11  # radius of the drawn heads, m


def test_the_crown_is_the_top_of_the_silhouette_straight_above_the_head(
    rig: Rig, draw_person_labels
):
    # two people, faces 5 cm below the centres of their heads, 1.2 m apart
    skins = np.array([[2.0, 2.0, 1.62], [3.2, 2.0, 1.52]])
    crowns = np.array([1.78, 1.68])
    for cam in rig.cameras:
        labels = draw_person_labels(cam, skins[0, :2], crowns[0], HEAD_R)
        draw_person_labels(cam, skins[1, :2], crowns[1], HEAD_R, label=2, labels=labels)
        # one pixel is about 1.6 cm at 3 m for these 320 x 240 cameras
        found = crown_heights_m(skins, cam, labels, span_m=0.4)
        assert np.all(np.abs(found - crowns) < 0.02), (cam.name, found)


def test_a_view_that_cannot_see_the_crown_says_nothing(rig: Rig, draw_person_labels):
    cam = rig.cameras[0]
    skin = np.array([2.0, 2.0, 1.62])
    labels = draw_person_labels(cam, skin[:2], 1.78, HEAD_R)

    def crown(head_m, labels):
        return crown_heights_m(np.array([head_m]), cam, labels, span_m=0.4)[0]

    # the head on background (a head tracker off its person)
    assert np.isnan(crown([3.5, 0.5, 1.62], labels))
    # the silhouette goes on above the head for longer than the span: a hand raised over it
    raised = labels.copy()
    top = cam.project(np.array([[2.0, 2.0, 1.78]]))[0][0]
    raised[: round(top[1]) + 1, round(top[0]) - 2 : round(top[0]) + 3] = 1
    assert np.isnan(crown(skin, raised))
    assert abs(crown(skin, labels) - 1.78) < 0.02  # without the hand
    # behind the camera
    assert np.isnan(crown(cam.centre_m - 0.5 * cam.R[2], labels))
    assert crown_heights_m(np.zeros((0, 3)), cam, labels, span_m=0.4).shape == (0,)


def test_the_rise_is_the_median_of_the_views_that_agree_with_a_head(rig: Rig, draw_person_labels):
    skin = np.array([2.0, 2.0, 1.55])  # a neck seen from behind, 12 cm below the centre
    crown = 1.55 + 0.12 + HEAD_R
    views = [(cam, draw_person_labels(cam, skin[:2], crown, HEAD_R)) for cam in rig.cameras]

    def rise(views):
        return head_rises_m(skin[None], views, top_to_centre_m=HEAD_R, max_rise_m=0.2)[0]

    assert abs(rise(views) - 0.12) < 0.015
    # camouflaged hair in one view (the crown at the forehead puts the centre below the skin
    # point) and another person's taller head merged on top in a second: both left out
    cam0, cam1 = rig.cameras[0], rig.cameras[1]
    low = draw_person_labels(cam0, skin[:2], 1.55 + HEAD_R - 0.03, HEAD_R)
    tall = draw_person_labels(cam1, skin[:2], crown, HEAD_R)
    draw_person_labels(cam1, skin[:2] + [0.05, 0.0], crown + 0.25, HEAD_R, labels=tall)
    odd = [(cam0, low), (cam1, tall)] + views[2:]
    assert abs(rise(odd) - 0.12) < 0.015
    # no view tells
    assert np.isnan(rise([(cam0, low)]))
    assert np.isnan(rise([]))
