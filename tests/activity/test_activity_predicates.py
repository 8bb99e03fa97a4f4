"""conserve_objects: which unknown carry state two meeting hands' other three decide."""

from __future__ import annotations

import pytest

from surveil.activity.predicates import conserve_objects
from surveil.datatypes import CarryEstimate


def est(carrying: bool | None, hue: float | None = None, conf: float = 0.9, tid: int = 1):
    """An estimate; ``carrying=None`` gives an unconfident (unknown) one."""
    if carrying is None:
        return CarryEstimate(tid, "p1/left_hand", 0, False, None, 0.05)
    return CarryEstimate(tid, "p1/left_hand", 0, carrying, hue, conf)


def infer(before, after):
    return conserve_objects(before, after, min_confidence=0.3, hue_tolerance_deg=25.0)


@pytest.mark.parametrize(
    ("before", "after", "which", "carrying", "hue"),
    [
        ((est(False), est(None)), (est(False), est(False)), 1, False, None),
        ((est(True, 120.0), est(False)), (est(False), None), 3, True, 120.0),
        ((None, est(False)), (est(False), est(True, 120.0)), 0, True, 120.0),
        ((est(True, 120.0), est(False)), (est(True, 118.0), est(None)), 3, False, None),
        # two objects before, one hand keeps its own: the other took the second
        ((est(True, 120.0), est(True, 10.0)), (est(True, 12.0), None), 3, True, 120.0),
    ],
)
def test_one_unknown_state_is_decided_by_the_count(before, after, which, carrying, hue):
    bef, aft, k = infer(before, after)
    assert k == which
    got = (*bef, *aft)[k]
    assert got.carrying is carrying
    assert got.hue_deg == hue
    assert 0.3 <= got.confidence <= 0.9


def test_the_inferred_confidence_is_the_least_of_the_evidence():
    bef, aft, k = infer((est(False, conf=0.95), None), (est(False, conf=0.4), est(False)))
    assert k == 1 and bef[1].confidence == pytest.approx(0.4)


@pytest.mark.parametrize(
    ("before", "after"),
    [
        # nothing unknown, or two unknown: nothing to infer / too little evidence
        ((est(False), est(False)), (est(False), est(False))),
        ((est(None), est(False)), (est(False), est(None))),
        # the count leaves no 0-or-1 answer: two objects after, none before
        ((est(False), None), (est(True, 120.0), est(True, 10.0))),
        # a carrying state to infer, but no single unaccounted hue to give it
        ((est(True, None), est(False)), (est(False), None)),
    ],
)
def test_nothing_is_inferred_without_a_unique_answer(before, after):
    bef, aft, k = infer(before, after)
    assert k is None
    assert (bef, aft) == (before, after)


def doubt(before, after, doubt_below):
    return conserve_objects(before, after, 0.3, 25.0, doubt_below=doubt_below)


def test_a_weak_state_that_breaks_the_count_is_decided_by_the_other_three():
    """three_people's missed exchanges: the giver confidently held the ball and is
    confidently empty after, the taker reads empty after with little confidence; the ball
    cannot vanish, so the taker's weak reading is the wrong one."""
    before = (est(True, 50.0, conf=1.0), est(False, conf=0.95))
    after = (est(False, conf=0.97), est(False, conf=0.4))
    bef, aft, k = doubt(before, after, doubt_below=0.75)
    assert k == 3
    assert aft[1].carrying is True and aft[1].hue_deg == 50.0
    assert aft[1].confidence == pytest.approx(0.95)  # the least of the other three
    assert bef == before and aft[0] == after[0]


@pytest.mark.parametrize("doubt_below", [0.0, 0.4])
def test_a_state_at_or_above_the_doubt_level_stands(doubt_below):
    before = (est(True, 50.0, conf=1.0), est(False, conf=0.95))
    after = (est(False, conf=0.97), est(False, conf=0.4))
    assert doubt(before, after, doubt_below) == (before, after, None)


def test_only_the_least_confident_state_is_doubted():
    """Here the weakest is the giver's 'carrying' before (a false carry): flipping it to
    empty makes the count agree (a clap or handshake), and the taker's state stands."""
    before = (est(True, 56.0, conf=0.5), est(False, conf=0.85))
    after = (est(False, conf=0.95), est(False, conf=0.6))
    bef, aft, k = doubt(before, after, doubt_below=0.75)
    assert k == 0 and bef[0].carrying is False and aft == after


def test_the_doubted_state_is_one_whose_change_restores_the_count():
    """three_people, seed 1: the taker's "empty" before (0.49) is the weakest, but the ball
    it did not hold before cannot explain a vanished ball; its "empty" after (0.72) can."""
    before = (est(True, 51.0, conf=1.0), est(False, conf=0.49))
    after = (est(False, conf=0.98), est(False, conf=0.72))
    bef, aft, k = doubt(before, after, doubt_below=0.75)
    assert k == 3 and aft[1].carrying is True and aft[1].hue_deg == 51.0


def test_a_count_that_holds_is_not_doubted():
    before = (est(True, 50.0, conf=0.35), est(False, conf=0.35))
    after = (est(False, conf=0.35), est(True, 52.0, conf=0.35))
    assert doubt(before, after, doubt_below=1.0) == (before, after, None)
