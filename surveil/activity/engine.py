"""The activity engine: decision points over a stream of tracker frames (paper 004 §7, Table 1).

Two kinds of episode, one per (rule, limbs) pair:

*Coincidence episodes* (hand/hand, hand/head rules). Opened at the **climax**: the two
trackers enter the combined state together (a ``Transition`` with ``new is COMBINED``), or their
estimates come closer than the rule's ``coincidence_m`` (so hand/head contacts count even when
the tracker keeps them apart; if the tracker combines them later, its join becomes the climax).
The limbs' labels from before the join and the carry estimates at the first contact ("before";
the carry stage freezes estimates while hands overlap; a hand whose estimate there is not
confident takes its latest confident one of the ``max_approach_s`` before) are kept. The
episode is separated by the combined -> unlabelled transition (or, if it never combined, when
the distance exceeds ``coincidence_m`` again); a separation at which the tracker found that the
two never met (``Transition.met`` False) drops the episode. The **post-separation point** is
the first frame set at least ``separation_delay_s`` after the two targets are ``separation_m``
apart at which the carry estimates the rule looks at are confident (``min_confidence``), or
``separation_timeout_s`` after the separation, whichever comes first; the carry estimates there
are "after". After the separation the trackers are unlabelled; a tracker that has been relabelled
by then is matched to the pre-join labels by label, otherwise by tracker id.

*Still episodes* (hand/scene rules: pick, place). A labelled hand in the normal state that
stays within ``still_speed_mps * still_s`` for ``still_s`` (:func:`~.predicates.still_since`),
below its shoulder and at least ``min_reach_m`` from its head horizontally
(:func:`~.predicates.away_from_body`; heads are taken from the same person's ``pN/head``
target), with no other target within ``coincidence_m``, after a reach (it was ``separation_m``
or more from the still point at most ``max_approach_s`` before): the ballistic reach-stop of
§7.3.1. Climax = the contact, the first moment the resting hand is lowest
(:func:`_contact_ns`); "before" = the carry estimate at the start of the reach; "after" =
the estimate ``separation_delay_s`` after the hand is ``separation_m`` from the still point
again (the return), or at ``separation_timeout_s`` after the hand was last within
``coincidence_m`` of its still point (a hand resting there longer delays the decision, which
has no "after" to go on yet), at most ``max_coincidence_s`` after the stop was detected.
When the hand's tracker is lost and another takes its label, the episode goes on with that
tracker.
At the step where the hand is ``separation_m`` from the still point, its id is listed in
:attr:`ActivityEngine.released_hands`: the pipeline
restarts its carry window (:meth:`~surveil.carry.CarryAnalyser.restart`), as the carry stage
itself does when two hands separate, so "after" holds only frames from the return, not the
object the hand left or took up a moment before.

At the post-separation point every enabled rule whose limbs, persons, carry states and transfer
match fires an :class:`~surveil.datatypes.ActivityEvent`, emitted by that :meth:`step`:
``start_ns`` = the approach start (the last time the limbs were ``separation_m`` apart before
the climax, at most ``max_approach_s`` earlier), ``end_ns`` = the post-separation point.
``confidence`` is the mean confidence of the carry estimates the rule looked at (1 if it looked
at none), times ``timeout_confidence_factor`` when the decision was forced by a timeout or by
:meth:`finish`.

The engine uses only ``t_ns``, never frame counts; it keeps a history of recent frames no
longer than any rule needs (``max_approach_s + still_s`` plus a margin) and drops episodes when
they are decided or given up.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from surveil.activity.predicates import (
    away_from_body,
    carry_satisfies,
    carry_state,
    conserve_objects,
    object_moved,
    still_since,
)
from surveil.activity.rules import Rule, RuleSet, label_matches
from surveil.datatypes import (
    ActivityEvent,
    CarryEstimate,
    Limb,
    Phase,
    TargetSnapshot,
    TrackFrame,
    parse_label,
)

log = logging.getLogger(__name__)

_NS = 1_000_000_000
_HISTORY_MARGIN_S = 0.5  # extra history beyond what the rules look back (rounding, jitter)


def _ns(seconds: float) -> int:
    return int(round(seconds * _NS))


@dataclass(frozen=True, slots=True)
class _Frame:
    t_ns: int
    targets: dict[int, TargetSnapshot]
    carry: dict[int, CarryEstimate]


@dataclass(slots=True)
class _PairEpisode:
    rule: Rule
    ids: list[int]  # tracker ids, in the order of labels
    labels: tuple[str, str]  # labels before the join
    climax_ns: int
    start_ns: int
    before: tuple[CarryEstimate | None, CarryEstimate | None]
    combined: bool
    separated_ns: int | None = None
    apart_ns: int | None = None
    meeting_drop_m: float | None = None  # least depth below the head while together


@dataclass(slots=True)
class _StillEpisode:
    rule: Rule
    hand_id: int
    label: str
    climax_ns: int
    start_ns: int
    detected_ns: int
    point_m: np.ndarray
    before: CarryEstimate | None
    apart_ns: int | None = None
    resting_ns: int = 0  # the last time the hand was within coincidence_m of the point
    hidden_ns: int = 0  # the last time its tracker was lost before it left (wait_for_lost_hand)
    # (t_ns, height m) of the hand while it rests there: the contact is where it is lowest
    rest_heights: list[tuple[int, float]] = field(default_factory=list)


def _contact_ns(st: _StillEpisode, smooth: int = 3, tolerance_m: float = 0.01) -> int:
    """The climax of a pick or place: the first moment the resting hand is lowest (its
    height averaged over ``smooth`` frame sets, within ``tolerance_m`` of the least), when it
    touches the object or puts it down. A hand that stops above the table and then lowers the
    object (the demo's place: 4-5 cm) touches the table later than it stops; one that rests
    at one height touches it when it stops. The rest is the hand's samples within
    ``coincidence_m`` of its point, less the last ``still_s``: a sample is at rest only if
    the hand stayed for ``still_s`` after it, and a hand that leaves downwards (pick_place's
    place) dips as it goes."""
    end_ns = st.resting_ns - _ns(st.rule.thresholds.still_s)
    heights = [(t, z) for t, z in st.rest_heights if t <= end_ns]
    if len(heights) < smooth:
        return st.climax_ns
    ts = np.array([t for t, _ in heights], dtype=np.int64)
    z = np.convolve([h for _, h in heights], np.ones(smooth) / smooth, mode="valid")
    first = int(np.flatnonzero(z <= z.min() + tolerance_m)[0])
    return st.climax_ns if first == 0 else max(st.climax_ns, int(ts[first + smooth // 2]))


def _heir(cur: _Frame, label: str, lost_id: int) -> TargetSnapshot | None:
    """The tracker other than ``lost_id`` that holds ``label`` in the normal state now."""
    for snap in cur.targets.values():
        if snap.target_id != lost_id and snap.phase is Phase.NORMAL and snap.label == label:
            return snap
    return None


def _person(label: str) -> int:
    return parse_label(label)[0]


def _persons(labels: tuple[str, ...]) -> tuple[str, ...]:
    out: list[str] = []
    for lab in labels:
        p = _person(lab)
        if p > 0 and f"p{p}" not in out:
            out.append(f"p{p}")
    return tuple(out)


def _persons_ok(rule: Rule, labels: tuple[str, str]) -> bool:
    if rule.persons == "any":
        return True
    pa, pb = _person(labels[0]), _person(labels[1])
    if pa == 0 or pb == 0:
        return False
    return (pa == pb) if rule.persons == "same" else (pa != pb)


def _orders(rule: Rule, labels: tuple[str, str]) -> list[tuple[int, int]]:
    """Assignments (a, b) of the episode's two limbs to the rule's limbs (A, B) that fit the
    limb kinds, the lexicographically smaller label first as A (deterministic actors)."""
    orders = sorted([(0, 1), (1, 0)], key=lambda ab: (labels[ab[0]], labels[ab[1]]))
    return [
        (a, b)
        for a, b in orders
        if label_matches(rule.limbs[0], labels[a]) and label_matches(rule.limbs[1], labels[b])
    ]


def _distance(a: TargetSnapshot | None, b: TargetSnapshot | None) -> float | None:
    if a is None or b is None:
        return None
    return float(np.linalg.norm(a.mean_m - b.mean_m))


class ActivityEngine:
    """Recognises activities online from tracker frames and carry estimates.

    Parameters
    ----------
    rules : RuleSet
        The rules to apply (disabled rules are ignored).

    Examples
    --------
    >>> from surveil.activity.rules import load_rules
    >>> engine = ActivityEngine(load_rules())
    >>> engine.step(TrackFrame(0, ()), {})
    []

    References
    ----------
    Paper 004 §7.1 (coincidence and separation from the tracker FSM), §7.3.1 (decision points,
    ballistic pick/place), Table 1.
    """

    def __init__(self, rules: RuleSet) -> None:
        self.rules = rules
        active = [r for r in rules if r.enabled]
        self._pair_rules = [r for r in active if not r.is_scene]
        self._scene_rules = [r for r in active if r.is_scene]
        look_back = max(
            (r.thresholds.max_approach_s + r.thresholds.still_s for r in active), default=0.0
        )
        self._history_ns = _ns(look_back + _HISTORY_MARGIN_S)
        # how long an event's end matters for min_repeat_s: an event is decided up to
        # max_coincidence_s + separation_timeout_s after its climax
        self._repeat_horizon_ns = _ns(
            max(
                (
                    r.thresholds.min_repeat_s
                    + r.thresholds.max_coincidence_s
                    + r.thresholds.separation_timeout_s
                    for r in rules
                ),
                default=0.0,
            )
        )
        self.reset()

    def reset(self) -> None:
        """Forget every frame and episode (start of a new stream)."""
        self._frames: deque[_Frame] = deque()
        self._pairs: dict[tuple[str, frozenset[int]], _PairEpisode] = {}
        self._stills: dict[tuple[str, int], _StillEpisode] = {}
        # (rule, pair) -> disarmed until the pair is separation_m apart again
        self._pair_disarmed: set[tuple[str, frozenset[int]]] = set()
        # (rule, hand) -> last still point; re-armed when the hand is separation_m from it
        self._still_disarmed: dict[tuple[str, int], np.ndarray] = {}
        self._last_t_ns: int | None = None
        self._released: list[int] = []
        # (activity, actors) -> end of the last such event, ns (for min_repeat_s)
        self._last_end: dict[tuple[str, frozenset[str]], int] = {}

    @property
    def released_hands(self) -> tuple[int, ...]:
        """Hand tracker ids that left a still point (pick / place) at the last :meth:`step`:
        what they hold from now on is "after"; their carry windows should restart."""
        return tuple(self._released)

    @property
    def open_stills(self) -> tuple[tuple[str, int, int, int | None], ...]:
        """The pick/place episodes not yet decided, for diagnostics: (rule id, hand tracker
        id, the last time the hand rested at its point, the time it left it or None), ns."""
        return tuple(
            (st.rule.rule_id, st.hand_id, st.resting_ns, st.apart_ns)
            for st in self._stills.values()
        )

    # -----------------------------------------------------------------------------------------
    # public API

    def step(self, frame: TrackFrame, carry: Mapping[int, CarryEstimate]) -> list[ActivityEvent]:
        """Feed one frame set; return the events decided at it (climaxes may lie earlier).

        Parameters
        ----------
        frame : TrackFrame
            Targets and transitions of this frame set.
        carry : Mapping[int, CarryEstimate]
            Per hand tracker id, what it carries now (hands not analysed may be absent).

        Returns
        -------
        list of ActivityEvent
            In climax order (then rule order).

        Raises
        ------
        ValueError
            If ``frame.t_ns`` is earlier than the previous frame's.
        """
        t = int(frame.t_ns)
        if self._last_t_ns is not None and t < self._last_t_ns:
            raise ValueError(
                f"frame.t_ns must not decrease: got {t} after {self._last_t_ns}; "
                "call reset() to start a new stream"
            )
        self._last_t_ns = t
        self._released = []
        cur = _Frame(
            t,
            {s.target_id: s for s in frame.targets},
            {int(k): v for k, v in carry.items()},
        )
        self._frames.append(cur)
        while self._frames and self._frames[0].t_ns < t - self._history_ns:
            self._frames.popleft()

        events: list[ActivityEvent] = []
        events += self._on_transitions(frame, cur)
        self._open_by_proximity(cur)
        events += self._advance_pairs(cur)
        self._open_stills(cur)
        events += self._advance_stills(cur)
        self._rearm(cur)
        return self._ordered(self._not_repeats(events))

    def finish(self) -> list[ActivityEvent]:
        """Decide the pending episodes at the end of the stream with the latest estimates.

        Coincidence episodes that never separated, and still moments whose hand never left
        its point, are dropped: all Table 1 activities are decided after a separation, and a
        stream that ends first has not shown one (a hand still at the table when the
        recording stops may yet take the object back). Decisions made here count as timeouts
        for the confidence.
        """
        events: list[ActivityEvent] = []
        if self._frames:
            cur = self._frames[-1]
            for key, ep in list(self._pairs.items()):
                if ep.separated_ns is not None:
                    ev = self._decide_pair(ep, cur, timed_out=True)
                    events += [ev] if ev else []
                del self._pairs[key]
            for key, st in list(self._stills.items()):
                if st.apart_ns is not None:
                    ev = self._decide_still(st, cur, timed_out=True)
                    events += [ev] if ev else []
                else:
                    log.debug("%s: %s never left its still point", st.rule.rule_id, st.label)
                del self._stills[key]
        events = self._not_repeats(events)
        self.reset()
        return self._ordered(events)

    # -----------------------------------------------------------------------------------------
    # history helpers

    def _label_before(self, target_id: int, given: str | None) -> str | None:
        if given is not None:
            return given
        for fr in reversed(self._frames):
            snap = fr.targets.get(target_id)
            if snap is not None and snap.phase is not Phase.COMBINED:
                return snap.label
        return None

    def _latest_carry(self, target_id: int, t_ns: int) -> CarryEstimate | None:
        for fr in reversed(self._frames):
            if fr.t_ns <= t_ns and target_id in fr.carry:
                return fr.carry[target_id]
        return None

    def _confident_carry(
        self, target_id: int, t_ns: int, since_ns: int, min_confidence: float
    ) -> CarryEstimate | None:
        """The latest estimate at or before ``t_ns`` that is confident, looking back to
        ``since_ns``; else the latest one. A hand's estimate can lose confidence in the last
        half second before contact (its tracker lags the fast approach and the region misses
        the object; the other hand's circle crowds it); what it held confidently on the
        approach is what it carried."""
        for fr in reversed(self._frames):
            if fr.t_ns > t_ns:
                continue
            if fr.t_ns < since_ns:
                break
            est = fr.carry.get(target_id)
            if est is not None and est.confidence >= min_confidence:
                return est
        return self._latest_carry(target_id, t_ns)

    def _surest_carry(self, target_id: int, since_ns: int, t_ns: int) -> CarryEstimate | None:
        """The most confident estimate from ``since_ns`` to ``t_ns`` (the latest of equals),
        else None."""
        best: CarryEstimate | None = None
        for fr in self._frames:
            est = fr.carry.get(target_id) if since_ns <= fr.t_ns <= t_ns else None
            if est is not None and (best is None or est.confidence >= best.confidence):
                best = est
        return best

    def _carry_since(self, target_id: int, t_ns: int, since_ns: int) -> CarryEstimate | None:
        """The latest estimate at or before ``t_ns`` if its evidence all dates from
        ``since_ns`` or later (else None): after a pick or place the fusion window still
        holds the frames from before the hand let go for up to its length."""
        est = self._latest_carry(target_id, t_ns)
        if est is None or est.since_ns is None or est.since_ns < since_ns:
            return None
        return est

    def _approach_start(self, ids: tuple[int, int], climax_ns: int, rule: Rule) -> int:
        """The last time before the climax at which the two targets were ``separation_m``
        apart, looking back at most ``max_approach_s``; else the earliest time both were seen
        in that window; else the climax."""
        th = rule.thresholds
        earliest = climax_ns - _ns(th.max_approach_s)
        start = climax_ns
        for fr in reversed(self._frames):
            if fr.t_ns > climax_ns:
                continue
            if fr.t_ns < earliest:
                break
            d = _distance(fr.targets.get(ids[0]), fr.targets.get(ids[1]))
            if d is None:
                continue
            start = fr.t_ns
            if d >= th.separation_m:
                break
        return start

    def _head_of(self, person: int) -> np.ndarray | None:
        label = f"p{person}/head"
        for fr in reversed(self._frames):
            for snap in fr.targets.values():
                if snap.label == label and snap.phase is not Phase.LOST:
                    return snap.mean_m
        return None

    # -----------------------------------------------------------------------------------------
    # coincidence episodes

    def _open_pair(
        self,
        rule: Rule,
        ids: tuple[int, int],
        labels: tuple[str, str],
        t_ns: int,
        combined: bool,
    ) -> None:
        key = (rule.name, frozenset(ids))
        if not _orders(rule, labels) or not _persons_ok(rule, labels):
            return
        th = rule.thresholds
        start = self._approach_start(ids, t_ns, rule)
        since = t_ns - _ns(th.max_approach_s)
        before = tuple(self._confident_carry(i, t_ns, since, th.min_confidence) for i in ids)
        self._pairs[key] = _PairEpisode(
            rule=rule,
            ids=list(ids),
            labels=labels,
            climax_ns=t_ns,
            start_ns=start,
            before=before,
            combined=combined,
            meeting_drop_m=self._meeting_drop_m(ids, labels) if th.max_meeting_drop_m else None,
        )
        log.debug("%s: climax of %s at %d ns", rule.rule_id, "+".join(labels), t_ns)

    def _meeting_drop_m(self, ids: tuple[int, int], labels: tuple[str, str]) -> float | None:
        """How far below the lower head of the persons in ``labels`` the two limbs (the mean
        of their estimates now) are, metres; None when a limb or every head is unknown. A
        pair episode keeps the least of these from its climax to its separation: trackers
        join while the hands still rise to a clap."""
        now = self._frames[-1].targets
        if any(i not in now for i in ids):
            return None
        meet_z = 0.5 * (now[ids[0]].mean_m[2] + now[ids[1]].mean_m[2])
        heads = [self._head_of(_person(lab)) for lab in labels]
        heads_z = [h[2] for h in heads if h is not None]
        return float(min(heads_z) - meet_z) if heads_z else None

    def _on_transitions(self, frame: TrackFrame, cur: _Frame) -> list[ActivityEvent]:
        """Open episodes at joins, mark separations. A join of a pair whose previous episode
        is still waiting for its post-separation point (quick repeated claps) decides that one
        first, as a timeout."""
        events: list[ActivityEvent] = []
        for tr in frame.transitions:
            if tr.partner_id is None:
                continue
            if tr.new is Phase.COMBINED and tr.old is not Phase.COMBINED:
                ids = (tr.target_id, tr.partner_id)
                partner_label = self._label_before(tr.partner_id, tr.partner_label)
                if partner_label is None:
                    continue
                labels = (tr.label, partner_label)
                if _person(labels[0]) == 0 or _person(labels[1]) == 0:
                    # rejoined before being relabelled: keep the labels of the pending episode
                    labels = self._pending_labels(ids) or labels
                for rule in self._pair_rules:
                    key = (rule.name, frozenset(ids))
                    ep = self._pairs.get(key)
                    if ep is not None and ep.separated_ns is not None:
                        ev = self._decide_pair(ep, cur, timed_out=True)
                        events += [ev] if ev else []
                        del self._pairs[key]
                        ep = None
                    if ep is not None:
                        if not ep.combined:
                            # opened by proximity: the tracker's join is the climax (§7.1)
                            ep.climax_ns = cur.t_ns
                        ep.combined = True
                        continue
                    self._open_pair(rule, ids, labels, cur.t_ns, combined=True)
            elif tr.old is Phase.COMBINED and not tr.met:
                # the tracker found that the two never met: the join was no coincidence
                for key, ep in list(self._pairs.items()):
                    if tr.target_id in ep.ids and ep.separated_ns is None:
                        log.debug("%s: %s never met", ep.rule.rule_id, "+".join(ep.labels))
                        del self._pairs[key]
            elif tr.old is Phase.COMBINED and tr.new in (Phase.UNLABELLED, Phase.NORMAL):
                for ep in self._pairs.values():
                    if tr.target_id not in ep.ids or ep.separated_ns is not None:
                        continue
                    other = ep.ids[1 - ep.ids.index(tr.target_id)]
                    if tr.partner_id != other and tr.partner_id not in ep.ids:
                        # the tracker that separated from it is a new one: it takes the place
                        # of the partner that is gone
                        ep.ids[ep.ids.index(other)] = tr.partner_id
                    ep.separated_ns = cur.t_ns
        return events

    def _pending_labels(self, ids: tuple[int, int]) -> tuple[str, str] | None:
        for ep in self._pairs.values():
            if set(ep.ids) == set(ids) and ep.separated_ns is not None:
                by_id = dict(zip(ep.ids, ep.labels, strict=True))
                return by_id[ids[0]], by_id[ids[1]]
        return None

    def _open_by_proximity(self, cur: _Frame) -> None:
        live = [
            s
            for s in cur.targets.values()
            if s.phase is Phase.NORMAL and s.limb is not Limb.UNKNOWN
        ]
        for rule in self._pair_rules:
            th = rule.thresholds
            if th.coincidence_m <= 0:
                continue
            for i, a in enumerate(live):
                for b in live[i + 1 :]:
                    key = (rule.name, frozenset((a.target_id, b.target_id)))
                    if key in self._pairs or key in self._pair_disarmed:
                        continue
                    d = _distance(a, b)
                    if d is not None and d < th.coincidence_m:
                        self._open_pair(
                            rule, (a.target_id, b.target_id), (a.label, b.label), cur.t_ns, False
                        )

    def _advance_pairs(self, cur: _Frame) -> list[ActivityEvent]:
        events = []
        t = cur.t_ns
        for key, ep in list(self._pairs.items()):
            th = ep.rule.thresholds
            d = _distance(cur.targets.get(ep.ids[0]), cur.targets.get(ep.ids[1]))
            if ep.separated_ns is None:
                if th.max_meeting_drop_m > 0:
                    drop = self._meeting_drop_m((ep.ids[0], ep.ids[1]), ep.labels)
                    if drop is not None and (
                        ep.meeting_drop_m is None or drop < ep.meeting_drop_m
                    ):
                        ep.meeting_drop_m = drop
                if not ep.combined and d is None:
                    del self._pairs[key]  # a limb vanished while close: nothing to decide
                    continue
                if not ep.combined and d > th.coincidence_m:
                    if t - ep.climax_ns < _ns(th.min_coincidence_s):
                        log.debug("%s: %s too brief to meet", ep.rule.rule_id, ep.labels)
                        del self._pairs[key]
                        continue
                    ep.separated_ns = t
                elif t - ep.climax_ns > _ns(th.max_coincidence_s):
                    log.debug("%s: gave up %s (no separation)", ep.rule.rule_id, ep.labels)
                    del self._pairs[key]
                    self._pair_disarmed.add(key)
                    continue
                else:
                    continue
            if ep.apart_ns is None and d is not None and d >= th.separation_m:
                ep.apart_ns = t
            ready = (
                ep.apart_ns is not None
                and t - ep.apart_ns >= _ns(th.separation_delay_s)
                and self._after_known(ep.rule, self._after(ep, cur))
            )
            timed_out = t - ep.separated_ns >= _ns(th.separation_timeout_s)
            if ready or timed_out:
                ev = self._decide_pair(ep, cur, timed_out=not ready)
                events += [ev] if ev else []
                del self._pairs[key]
                self._pair_disarmed.add((key[0], frozenset(ep.ids)))
        return events

    def _after(
        self, ep: _PairEpisode, cur: _Frame
    ) -> tuple[CarryEstimate | None, CarryEstimate | None]:
        """The latest carry estimates of the two limbs, in the order of ``ep.labels``: the
        tracker holding each pre-join label now, by label if relabelled, else by id."""
        now = {i: cur.targets[i].label for i in ep.ids if i in cur.targets}
        holders = [
            next((i for i in ep.ids if now.get(i) == lab), ep.ids[k])
            for k, lab in enumerate(ep.labels)
        ]
        return self._latest_carry(holders[0], cur.t_ns), self._latest_carry(holders[1], cur.t_ns)

    @staticmethod
    def _after_known(rule: Rule, after: Iterable[CarryEstimate | None]) -> bool:
        """Whether the carry evidence after a separation is decided (confident for every limb
        whose state the rule looks at): a window restarted at the separation holds only a
        few, often ambiguous, frames when ``separation_delay_s`` has passed."""
        if all(req is None for req in rule.carry_after):
            return True
        return all(carry_state(est, rule.thresholds.min_confidence) is not None for est in after)

    def _decide_pair(self, ep: _PairEpisode, cur: _Frame, timed_out: bool) -> ActivityEvent | None:
        rule, th, t = ep.rule, ep.rule.thresholds, cur.t_ns
        drop = ep.meeting_drop_m
        if th.max_meeting_drop_m > 0 and drop is not None and drop > th.max_meeting_drop_m:
            log.debug(
                "%s: %s met no higher than %.2f m below the head",
                rule.rule_id,
                "+".join(ep.labels),
                drop,
            )
            return None
        before, after = ep.before, self._after(ep, cur)
        if th.conserve_objects and all(limb.endswith("hand") for limb in rule.limbs):
            before, after, inferred = conserve_objects(
                before, after, th.min_confidence, th.hue_tolerance_deg, th.conserve_doubt_below
            )
            if inferred is not None:
                log.debug(
                    "%s: %s carry %s of %s inferred: %s",
                    rule.rule_id,
                    "+".join(ep.labels),
                    "before" if inferred < 2 else "after",
                    ep.labels[inferred % 2],
                    _describe((*before, *after)[inferred], th.min_confidence),
                )
        for a, b in _orders(rule, ep.labels):
            bef = (before[a], before[b])
            aft = (after[a], after[b])
            used: list[CarryEstimate | None] = []
            ok = True
            for k in (0, 1):
                for req, est in ((rule.carry_before[k], bef[k]), (rule.carry_after[k], aft[k])):
                    if req is None:
                        continue
                    used.append(est)
                    ok &= carry_satisfies(req, carry_state(est, th.min_confidence))
            if not ok:
                continue
            moved_ab = object_moved(
                bef[0], aft[0], aft[1], th.min_confidence, th.hue_tolerance_deg
            )
            moved_ba = object_moved(
                bef[1], aft[1], aft[0], th.min_confidence, th.hue_tolerance_deg
            )
            if rule.transfer == "a_to_b" and not moved_ab:
                continue
            if rule.transfer == "none" and (moved_ab or moved_ba):
                continue
            if rule.transfer != "any":
                used += [bef[0], aft[1]] if rule.transfer == "a_to_b" else [*bef, *aft]
            labels = (ep.labels[a], ep.labels[b])
            hue = None
            if moved_ab:
                hue = bef[0].hue_deg  # type: ignore[union-attr]
            elif moved_ba:
                hue = bef[1].hue_deg  # type: ignore[union-attr]
            else:
                hue = _first_hue([e for e in used if e is not None], th.min_confidence)
            return ActivityEvent(
                activity=rule.name,
                start_ns=min(ep.start_ns, ep.climax_ns),
                climax_ns=ep.climax_ns,
                end_ns=max(t, ep.climax_ns),
                actors=labels,
                persons=_persons(labels),
                rule=rule.rule_id,
                confidence=_confidence(used, timed_out, th.timeout_confidence_factor),
                object_hue_deg=hue,
                from_actor=labels[0] if moved_ab else labels[1] if moved_ba else None,
                to_actor=labels[1] if moved_ab else labels[0] if moved_ba else None,
            )
        if log.isEnabledFor(logging.DEBUG):
            log.debug(
                "%s: %s did not match (carry before %s, after %s)",
                rule.rule_id,
                "+".join(ep.labels),
                [_describe(e, th.min_confidence) for e in before],
                [_describe(e, th.min_confidence) for e in after],
            )
        return None

    # -----------------------------------------------------------------------------------------
    # still episodes (pick / place)

    def _hand_track(self, hand_id: int, since_ns: int) -> tuple[np.ndarray, np.ndarray, bool]:
        """(t_ns (T,), points_m (T, 3), all normal) of a hand since ``since_ns``, or since it
        last left the combined or lost state if that is later: while combined the estimate is
        the pair's and while lost it is stale, so neither shows the hand's own reach (and its
        carry estimates then are from before the join, not from the start of the reach)."""
        ts, ps, normal = [], [], True
        for fr in self._frames:
            if fr.t_ns < since_ns:
                continue
            snap = fr.targets.get(hand_id)
            if snap is None:
                continue
            if snap.phase in (Phase.COMBINED, Phase.LOST):
                ts, ps, normal = [], [], True
                continue
            ts.append(fr.t_ns)
            ps.append(snap.mean_m)
            normal &= snap.phase is Phase.NORMAL
        return (
            np.array(ts, dtype=np.int64),
            np.array(ps, dtype=np.float64).reshape(-1, 3),
            normal,
        )

    def _open_stills(self, cur: _Frame) -> None:
        for rule in self._scene_rules:
            th = rule.thresholds
            for hand in cur.targets.values():
                key = (rule.name, hand.target_id)
                if (
                    hand.phase is not Phase.NORMAL
                    or not label_matches(rule.limbs[0], hand.label)
                    or key in self._stills
                    or key in self._still_disarmed
                ):
                    continue
                head = self._head_of(hand.person)
                if head is None or not away_from_body(
                    hand.mean_m, head, th.shoulder_drop_m, th.min_reach_m
                ):
                    continue  # cheap test first: most hands are at the body
                since = cur.t_ns - _ns(th.max_approach_s + th.still_s)
                ts, ps, _ = self._hand_track(hand.target_id, since)
                first = still_since(ts, ps, th.still_s, th.still_speed_mps)
                if first is None:
                    continue
                _, _, normal = self._hand_track(hand.target_id, int(ts[first]))
                point = ps[first:].mean(axis=0)
                if not normal or not away_from_body(
                    point, head, th.shoulder_drop_m, th.min_reach_m
                ):
                    continue
                if th.coincidence_m > 0 and any(
                    o.target_id != hand.target_id
                    and o.phase is not Phase.LOST
                    and float(np.linalg.norm(o.mean_m - hand.mean_m)) < th.coincidence_m
                    for o in cur.targets.values()
                ):
                    continue
                climax = int(ts[first])
                far = np.linalg.norm(ps[:first] - point, axis=1) >= th.separation_m
                if far.any():
                    start = int(ts[:first][far][-1])
                    before = self._latest_carry(hand.target_id, start)
                    if carry_state(before, th.min_confidence) is None:
                        # the window restarted as the hand left an earlier still point
                        # just before this reach and holds too little yet: the surest
                        # estimate of the reach tells what the hand brought
                        before = self._surest_carry(hand.target_id, start, climax) or before
                elif ts[0] > since and np.linalg.norm(ps[0] - point) >= th.seen_reach_m:
                    # the track begins late in the reach (the hand was unseen before): what
                    # it held on the part seen is what it brought, and the estimate that is
                    # surest of it tells (the window restarted when the hand was seen again,
                    # so the first estimates rest on a few samples and flicker)
                    start = int(ts[0])
                    before = self._surest_carry(hand.target_id, start, climax)
                else:
                    continue  # no reach: the hand did not come from separation_m away
                self._stills[key] = _StillEpisode(
                    rule=rule,
                    hand_id=hand.target_id,
                    label=hand.label,
                    climax_ns=climax,
                    start_ns=start,
                    detected_ns=cur.t_ns,
                    point_m=point,
                    before=before,
                    resting_ns=cur.t_ns,
                    rest_heights=[
                        (int(t), float(z)) for t, z in zip(ts[first:], ps[first:, 2], strict=True)
                    ],
                )
                log.debug("%s: %s still at %d ns", rule.rule_id, hand.label, climax)

    def _advance_stills(self, cur: _Frame) -> list[ActivityEvent]:
        events = []
        t = cur.t_ns
        for key, st in list(self._stills.items()):
            th = st.rule.thresholds
            snap = cur.targets.get(st.hand_id)
            if snap is None or snap.phase is Phase.LOST:
                heir = _heir(cur, st.label, st.hand_id)
                if heir is not None:
                    # the tracker passed its hand's slot on (the hand came back elsewhere):
                    # the label is the hand, so its new tracker carries the episode on
                    log.debug(
                        "%s: %s goes on with t%d (t%d lost)",
                        st.rule.rule_id,
                        st.label,
                        heir.target_id,
                        st.hand_id,
                    )
                    del self._stills[key]
                    key = (key[0], heir.target_id)
                    self._stills[key] = st
                    st.hand_id, snap = heir.target_id, heir
            if (
                st.apart_ns is None
                and snap is not None
                and snap.phase is Phase.COMBINED
                and any(
                    o.phase is Phase.COMBINED
                    and o.person not in (0, snap.person)
                    and o.limb.is_hand
                    and float(np.linalg.norm(o.mean_m - snap.mean_m)) < th.separation_m
                    for o in cur.targets.values()
                )
            ):
                # another person's hand met it at the still point before it left: a handover
                # whose taker came after the giver's hand had stopped, not the scene
                log.debug("%s: %s met another person's hand", st.rule.rule_id, st.label)
                del self._stills[key]
                self._still_disarmed[key] = st.point_m
                continue
            if st.apart_ns is None and snap is not None:
                gap_m = float(np.linalg.norm(snap.mean_m - st.point_m))
                if gap_m >= th.separation_m:
                    st.apart_ns = t
                    if st.hand_id not in self._released:
                        self._released.append(st.hand_id)
                elif gap_m < th.coincidence_m and snap.phase is not Phase.LOST:
                    st.resting_ns = t
                    st.rest_heights.append((t, float(snap.mean_m[2])))
            ready = (
                st.apart_ns is not None
                and t - st.apart_ns >= _ns(th.separation_delay_s)
                and self._after_known(st.rule, [self._carry_since(st.hand_id, t, st.apart_ns)])
            )
            # the carry state "after" exists only once the hand has left: while it rests at
            # the point (a careful place, demo seed 1: about 2.1 s) the timeout waits, up to
            # max_coincidence_s from the stop
            # a hand hidden at its still point (the box it took hides it, pick_place@102)
            # may come back with the object: the evidence from before it was lost cannot say,
            # so the timeout counts from its return. One lost after it left is not waited for
            # (negative@101: back at the face, its circle read the face's rim as an object).
            if (
                th.wait_for_lost_hand
                and st.apart_ns is None
                and snap is not None
                and snap.phase is Phase.LOST
            ):
                st.hidden_ns = t
            timed_out = t - max(st.resting_ns, st.hidden_ns) >= _ns(th.separation_timeout_s) or (
                t - st.detected_ns >= _ns(th.max_coincidence_s)
            )
            if ready or timed_out:
                ev = self._decide_still(st, cur, timed_out=not ready)
                events += [ev] if ev else []
                del self._stills[key]
                self._still_disarmed[key] = st.point_m
        return events

    def _decide_still(
        self, st: _StillEpisode, cur: _Frame, timed_out: bool
    ) -> ActivityEvent | None:
        rule, th = st.rule, st.rule.thresholds
        after = None
        if st.apart_ns is not None:
            after = self._carry_since(st.hand_id, cur.t_ns, st.apart_ns)
        if after is None:  # timed out before a clean window: the latest there is
            after = self._latest_carry(st.hand_id, cur.t_ns)
        used: list[CarryEstimate | None] = []
        for req, est in ((rule.carry_before[0], st.before), (rule.carry_after[0], after)):
            if req is None:
                continue
            used.append(est)
            if not carry_satisfies(req, carry_state(est, th.min_confidence)):
                log.debug(
                    "%s: %s did not match (carry before %s, after %s%s; left the still point "
                    "at %s ns, decided at %d ns)",
                    rule.rule_id,
                    st.label,
                    _describe(st.before, th.min_confidence),
                    _describe(after, th.min_confidence),
                    ", timed out" if timed_out else "",
                    st.apart_ns,
                    cur.t_ns,
                )
                return None
        return ActivityEvent(
            activity=rule.name,
            start_ns=min(st.start_ns, st.climax_ns),
            climax_ns=_contact_ns(st),
            end_ns=max(cur.t_ns, st.climax_ns),
            actors=(st.label,),
            persons=_persons((st.label,)),
            rule=rule.rule_id,
            confidence=_confidence(used, timed_out, th.timeout_confidence_factor),
            object_hue_deg=_first_hue([e for e in used if e is not None], th.min_confidence),
        )

    # -----------------------------------------------------------------------------------------

    def _rearm(self, cur: _Frame) -> None:
        """Re-arm pairs and hands that are far enough apart again; forget absent trackers."""
        for key in list(self._pair_disarmed):
            rule = self.rules[key[0]]
            a, b = sorted(key[1])
            if a not in cur.targets or b not in cur.targets:
                self._pair_disarmed.discard(key)
                continue
            d = _distance(cur.targets[a], cur.targets[b])
            if d is not None and d >= rule.thresholds.separation_m:
                self._pair_disarmed.discard(key)
        for key, point in list(self._still_disarmed.items()):
            snap = cur.targets.get(key[1])
            rule = self.rules[key[0]]
            if snap is None or np.linalg.norm(snap.mean_m - point) >= rule.thresholds.separation_m:
                del self._still_disarmed[key]

    def _not_repeats(self, events: list[ActivityEvent]) -> list[ActivityEvent]:
        """``events`` without those whose rule's ``min_repeat_s`` has not passed since the
        end of the same activity of the same actors (they continue it), in climax order."""
        kept = []
        for ev in sorted(events, key=lambda e: e.climax_ns):
            key = (ev.activity, frozenset(ev.actors))
            gap_s = self.rules[ev.activity].thresholds.min_repeat_s
            last = self._last_end.get(key)
            if gap_s > 0 and last is not None and ev.climax_ns - last < _ns(gap_s):
                log.debug(
                    "%s: %s at %d ns continues the one that ended at %d ns (min_repeat_s)",
                    ev.rule,
                    "+".join(ev.actors),
                    ev.climax_ns,
                    last,
                )
            else:
                kept.append(ev)
            self._last_end[key] = ev.end_ns if last is None else max(ev.end_ns, last)
        if self._last_t_ns is not None:
            for key, end in list(self._last_end.items()):
                if self._last_t_ns - end > self._repeat_horizon_ns:
                    del self._last_end[key]
        return kept

    def _ordered(self, events: list[ActivityEvent]) -> list[ActivityEvent]:
        order = {r.name: i for i, r in enumerate(self.rules)}
        return sorted(events, key=lambda e: (e.climax_ns, order.get(e.activity, 0), e.actors))


def _confidence(used: list[CarryEstimate | None], timed_out: bool, factor: float) -> float:
    confs = [e.confidence for e in used if e is not None]
    conf = float(np.mean(confs)) if confs else 1.0
    conf = min(max(conf, 0.0), 1.0)
    return conf * factor if timed_out else conf


def _describe(est: CarryEstimate | None, min_confidence: float) -> str:
    """A carry estimate for the debug log: ``1 (0.82, 120 deg)``, ``0 (0.64)``, ``? (0.12)``."""
    if est is None:
        return "none"
    state = carry_state(est, min_confidence)
    mark = "?" if state is None else str(int(state))
    hue = f", {est.hue_deg:.0f} deg" if est.hue_deg is not None else ""
    return f"{mark} ({est.confidence:.2f}{hue})"


def _first_hue(estimates: list[CarryEstimate], min_confidence: float) -> float | None:
    for est in estimates:
        if carry_state(est, min_confidence) is True and est.hue_deg is not None:
            return float(est.hue_deg)
    return None


def recognise(
    rules: RuleSet, stream: Iterable[tuple[TrackFrame, Mapping[int, CarryEstimate]]]
) -> list[ActivityEvent]:
    """Every event of a whole stream: :meth:`ActivityEngine.step` on each frame, then
    :meth:`ActivityEngine.finish`. For offline use and tests, e.g. on pipeline results:
    ``recognise(rules, ((r.track, r.carry) for r in results))``.

    >>> from surveil.activity.rules import load_rules
    >>> recognise(load_rules(), [(TrackFrame(0, ()), {}), (TrackFrame(10, ()), {})])
    []
    """
    engine = ActivityEngine(rules)
    events: list[ActivityEvent] = []
    for frame, carry in stream:
        events += engine.step(frame, carry)
    return events + engine.finish()
