"""Labelling cues: head / hand, person, left / right, angle rule (section 7.1)."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.datatypes import Limb
from surveil.tracking import LabellingConfig
from surveil.tracking import labelling as lab

CFG = LabellingConfig()


def test_head_log_odds_orders_head_above_hands():
    pos = np.array([[0.0, 0.0, 1.7], [0.05, 0.25, 0.8], [0.05, -0.25, 0.8]])
    below = lab.below_another(pos, CFG)
    llr = lab.head_log_odds(pos[:, 2], np.zeros(3), below, np.full(3, np.nan), CFG)
    assert below.tolist() == [False, True, True]
    assert llr[0] > CFG.decide_llr and np.all(llr[1:] < -CFG.decide_llr)


def test_silhouette_and_speed_cues():
    z = np.full(3, CFG.head_z_mid_m)  # height neutral
    llr = lab.head_log_odds(
        z, np.array([0.0, 0.0, 2.0]), np.zeros(3, bool), np.array([0.02, 0.4, np.nan]), CFG
    )
    assert llr[0] > 0 > llr[1] and llr[2] == pytest.approx(-CFG.speed_llr)


def test_hand_joins_the_clearly_nearest_person_with_a_free_slot():
    heads = np.array([[0.0, 0, 1.7], [1.2, 0, 1.7]])
    hand = np.array([0.3, 0.2, 1.0])
    assert lab.nearest_person(hand, heads, np.array([0, 0]), CFG) == 0
    assert lab.nearest_person(hand, heads, np.array([2, 0]), CFG) == -1  # both hands taken
    assert lab.nearest_person(np.array([0.6, 0, 1.0]), heads, np.array([0, 0]), CFG) == -1
    assert lab.nearest_person(np.array([5.0, 0, 1.0]), heads, np.array([0, 0]), CFG) == -1


@pytest.mark.parametrize("facing_deg", [0, 90, 200, 300])
def test_left_right_follows_facing(facing_deg):
    f = np.radians(facing_deg)
    facing = np.array([np.cos(f), np.sin(f)])
    left = np.array([-facing[1], facing[0]])
    head = np.array([1.0, 2.0, 1.7])
    hands = np.array([[*(head[:2] - 0.25 * left), 0.8], [*(head[:2] + 0.25 * left), 0.8]])
    assert lab.decide_left_right(hands, head, facing) == (Limb.RIGHT_HAND, Limb.LEFT_HAND)
    assert lab.decide_left_right(hands[1:], head, facing) == (Limb.LEFT_HAND,)


def test_facing_cues_walking_and_social():
    head = np.array([0.0, 0.0, 1.7])
    walk = lab.facing_cues(head, np.array([0.0, 1.0, 0]), np.zeros((0, 3)), np.zeros((0, 3)), CFG)
    assert walk[1] > 0 and walk[0] == 0
    social = lab.facing_cues(head, np.zeros(3), np.zeros((0, 3)), np.array([[-1.0, 0, 1.6]]), CFG)
    assert social[0] < 0 and social[1] == 0
    # hands hanging at the sides give no evidence
    rest = np.array([[0.0, 0.25, 0.8], [0.0, -0.25, 0.8]])
    assert np.allclose(lab.facing_cues(head, np.zeros(3), rest, np.zeros((0, 3)), CFG), 0)


def test_angle_rule_keeps_or_swaps():
    before = np.array([0.4, 0.0, 0.0])  # B was 40 cm to the +x of A
    back = lab.angle_rule(before, np.array([-0.2, 0, 0]), np.array([0.2, 0, 0]))
    crossed = lab.angle_rule(before, np.array([0.2, 0, 0]), np.array([-0.2, 0, 0]))
    assert back[0] == (0, 1) and back[1] == pytest.approx(0.0)
    assert crossed[0] == (1, 0) and crossed[1] == pytest.approx(np.pi)
    # 60 degrees off is still "the same side"
    tilted = lab.angle_rule(before, np.zeros(3), np.array([0.1, 0.17, 0]))
    assert tilted[0] == (0, 1)
