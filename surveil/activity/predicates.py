"""Pure predicates the activity engine evaluates: carry states, object identity by hue,
stillness and reach (paper 004 §7.1, §7.3.1, Table 1). No state, no I/O."""

from __future__ import annotations

from collections.abc import Sequence
from typing import cast

import numpy as np

from surveil.datatypes import CarryEstimate


def hue_distance_deg(a_deg: float, b_deg: float) -> float:
    """Circular distance between two hues, degrees in ``[0, 180]``.

    >>> hue_distance_deg(350.0, 10.0), hue_distance_deg(120.0, 100.0)
    (20.0, 20.0)
    """
    d = abs(float(a_deg) - float(b_deg)) % 360.0
    return min(d, 360.0 - d)


def carry_state(est: CarryEstimate | None, min_confidence: float) -> bool | None:
    """What a hand carries as far as a rule can tell: True / False, or None (unknown) when
    there is no estimate or it is less confident than ``min_confidence``.

    >>> est = CarryEstimate(3, "p1/left_hand", 0, True, 120.0, 0.8)
    >>> carry_state(est, 0.5), carry_state(est, 0.9), carry_state(None, 0.5)
    (True, None, None)
    """
    if est is None or est.confidence < min_confidence:
        return None
    return bool(est.carrying)


def carry_satisfies(required: bool | None, state: bool | None) -> bool:
    """A rule's carry requirement (True = 1, False = 0, None = any) against a state; an
    unknown state satisfies only 'any'.

    >>> carry_satisfies(None, None), carry_satisfies(False, False), carry_satisfies(False, None)
    (True, True, False)
    """
    return required is None or state is required


def conserve_objects(
    before: tuple[CarryEstimate | None, CarryEstimate | None],
    after: tuple[CarryEstimate | None, CarryEstimate | None],
    min_confidence: float,
    hue_tolerance_deg: float,
    doubt_below: float = 0.0,
) -> tuple[tuple[CarryEstimate | None, ...], tuple[CarryEstimate | None, ...], int | None]:
    """Two meeting hands' carry estimates with one unknown state filled from the other three.

    Two hands that meet and part neither create nor destroy objects: they hold as many
    after as before. When exactly one of the four states is unknown (no estimate, or one
    below ``min_confidence``), that count decides it; an inferred carrying state takes the
    hue of the object the other side has and this side does not account for. The inferred
    estimate's confidence is the least of the three it came from. Nothing is inferred when
    zero or several states are unknown, when the count leaves no 0-or-1 answer, or when an
    inferred carrying state has no single hue to take.

    When all four states are known but break the count by one (an object appeared or
    vanished), one of them is wrong: of those whose change would restore the count (a hand
    that carried before or is empty after, for an object that vanished), the least confident
    is taken as unknown and inferred from the others if its confidence is below
    ``doubt_below`` (0: never).

    Returns ``(before, after, which)``: ``which`` is the index 0-3 (before a, before b,
    after a, after b) of the inferred state, or None.

    >>> a0 = CarryEstimate(1, "p1/right_hand", 0, True, 120.0, 0.9)
    >>> b0 = CarryEstimate(2, "p2/left_hand", 0, False, None, 0.8)
    >>> a1 = CarryEstimate(1, "p1/right_hand", 9, False, None, 0.7)
    >>> bef, aft, which = conserve_objects((a0, b0), (a1, None), 0.3, 25.0)
    >>> which, aft[1].carrying, aft[1].hue_deg, aft[1].confidence
    (3, True, 120.0, 0.7)
    """
    four = [*before, *after]
    unknown = [j for j, e in enumerate(four) if carry_state(e, min_confidence) is None]
    surplus = 0 if unknown else _count(before) - _count(after)
    if abs(surplus) == 1:
        known = cast("list[CarryEstimate]", four)
        # an object vanished: a carrying state before or an empty one after is wrong; one
        # appeared: an empty one before or a carrying one after
        suspects = [j for j, e in enumerate(known) if e.carrying == ((j < 2) == (surplus > 0))]
        weakest = min(suspects, key=lambda j: known[j].confidence)
        if known[weakest].confidence < doubt_below:
            unknown = [weakest]
    if len(unknown) != 1:
        return before, after, None
    k = unknown[0]
    other = 2 if k < 2 else 0
    # every estimate but the k-th is known (present and confident)
    beside = four[k ^ 1]  # the other hand at the same decision point
    there = four[other : other + 2]
    carrying = _count(there) - beside.carrying
    if carrying not in (0, 1):
        return before, after, None
    hue = None
    if carrying:
        held_here = [beside.hue_deg] if beside.carrying and beside.hue_deg is not None else []
        unaccounted = [
            e.hue_deg
            for e in there
            if e.carrying
            and e.hue_deg is not None
            and all(hue_distance_deg(h, e.hue_deg) > hue_tolerance_deg for h in held_here)
        ]
        if len(unaccounted) != 1:
            return before, after, None
        hue = unaccounted[0]
    template = four[k] or four[k ^ 2]  # the same hand at the other decision point
    four[k] = CarryEstimate(
        template.target_id,
        template.label,
        template.t_ns,
        bool(carrying),
        hue,
        min(e.confidence for j, e in enumerate(four) if j != k),
    )
    return (four[0], four[1]), (four[2], four[3]), k


def _count(pair: Sequence[CarryEstimate | None]) -> int:
    """How many objects two hands' known (not None) carry estimates hold."""
    return sum(bool(e is not None and e.carrying) for e in pair)


def object_moved(
    giver_before: CarryEstimate | None,
    giver_after: CarryEstimate | None,
    taker_after: CarryEstimate | None,
    min_confidence: float,
    hue_tolerance_deg: float,
) -> bool:
    """Whether the object the giver held before is held by the taker after (Table 1 exchange).

    Moved means: the giver carried an object of hue h before; the taker carries an object of
    hue within ``hue_tolerance_deg`` of h after; and the giver does not still carry that hue
    after (so two hands that each keep an object of the same colour do not count).

    >>> a0 = CarryEstimate(1, "p1/right_hand", 0, True, 120.0, 0.9)
    >>> a1 = CarryEstimate(1, "p1/right_hand", 9, False, None, 0.9)
    >>> b1 = CarryEstimate(2, "p2/left_hand", 9, True, 128.0, 0.9)
    >>> object_moved(a0, a1, b1, 0.3, 20.0), object_moved(a0, a1, b1, 0.3, 5.0)
    (True, False)
    """
    if carry_state(giver_before, min_confidence) is not True or giver_before.hue_deg is None:
        return False
    if carry_state(taker_after, min_confidence) is not True or taker_after.hue_deg is None:
        return False
    if hue_distance_deg(giver_before.hue_deg, taker_after.hue_deg) > hue_tolerance_deg:
        return False
    if carry_state(giver_after, min_confidence) is True and giver_after.hue_deg is not None:
        return hue_distance_deg(giver_before.hue_deg, giver_after.hue_deg) > hue_tolerance_deg
    return True


def still_since(
    t_ns: np.ndarray, points_m: np.ndarray, still_s: float, still_speed_mps: float
) -> int | None:
    """Index of the first sample of the trailing still stretch of a trajectory, or None.

    The hand is still over a stretch when every pair of its positions there is closer than
    ``still_speed_mps * still_s`` (the extent allowed in ``still_s`` at that speed). The
    trailing stretch (ending at the last sample) must span at least ``still_s``; it is then
    grown backwards as far as the extent allows, so its first sample is the moment the hand
    stopped (the pick/place climax). Only times matter, not the frame rate.

    Parameters
    ----------
    t_ns : (T,) int64, ascending, ns
    points_m : (T, 3) float64, metres
    still_s : float, seconds
    still_speed_mps : float, m/s

    Returns
    -------
    int or None
        None when the trailing ``still_s`` is not still or the samples do not span it.

    >>> t = np.arange(10) * 100_000_000  # 10 samples, 0.1 s apart
    >>> p = np.zeros((10, 3)); p[:4, 0] = [0.6, 0.4, 0.2, 0.01]
    >>> still_since(t, p, 0.3, 0.2)
    3
    >>> still_since(t, p, 0.9, 0.2) is None
    True
    """
    t_ns = np.asarray(t_ns, dtype=np.int64)
    points_m = np.asarray(points_m, dtype=np.float64)
    if len(t_ns) < 2:
        return None
    extent = still_speed_mps * still_s
    need_ns = int(round(still_s * 1e9))
    first = len(t_ns) - 1
    while first > 0:
        cand = points_m[first - 1]
        if np.any(np.linalg.norm(points_m[first:] - cand, axis=1) > extent):
            break
        first -= 1
    if t_ns[-1] - t_ns[first] < need_ns:
        return None
    return first


def away_from_body(
    hand_m: np.ndarray, head_m: np.ndarray, shoulder_drop_m: float, min_reach_m: float
) -> bool:
    """Whether a hand is out at the scene rather than at the body: below shoulder height
    (head height minus ``shoulder_drop_m``) and at least ``min_reach_m`` from the head
    horizontally (world Z up).

    >>> away_from_body(np.array([0.5, 0, 0.9]), np.array([0, 0, 1.6]), 0.2, 0.3)
    True
    >>> away_from_body(np.array([0.1, 0, 0.9]), np.array([0, 0, 1.6]), 0.2, 0.3)
    False
    """
    below = hand_m[2] <= head_m[2] - shoulder_drop_m
    reach = float(np.hypot(hand_m[0] - head_m[0], hand_m[1] - head_m[1]))
    return bool(below and reach >= min_reach_m)
