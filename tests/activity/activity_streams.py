"""Constructed tracker/carry streams for activity tests: scripted limb paths, joins and carry
states turned into the ``TrackFrame`` / ``CarryEstimate`` sequences the tracking and carry
stages produce (including their behaviour at joins: one combined position, frozen carry
estimates, unlabelled trackers after a separation, optional label swap)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from surveil.activity.engine import recognise
from surveil.activity.rules import RuleSet
from surveil.datatypes import (
    ActivityEvent,
    CarryEstimate,
    Limb,
    Phase,
    TargetSnapshot,
    TrackFrame,
    Transition,
    make_label,
)

S = 1_000_000_000
Path3 = Callable[[float], np.ndarray]
# t (s) -> (carrying, hue_deg, confidence)
CarryFn = Callable[[float], tuple[bool, float | None, float]]


def still(*p: float) -> Path3:
    point = np.array(p, dtype=float)
    return lambda t: point


def keyframes(*keys: tuple[float, Sequence[float]]) -> Path3:
    """Piecewise-linear path through (t_s, (x, y, z)) keyframes, constant outside."""
    ts = np.array([k[0] for k in keys], dtype=float)
    ps = np.array([k[1] for k in keys], dtype=float)
    return lambda t: np.array([np.interp(t, ts, ps[:, i]) for i in range(3)])


def empty(conf: float = 0.9) -> CarryFn:
    return lambda t: (False, None, conf)


def holding(hue: float, conf: float = 0.9) -> CarryFn:
    return lambda t: (True, hue, conf)


def switch(at_s: float, before: CarryFn, after: CarryFn) -> CarryFn:
    return lambda t: before(t) if t < at_s else after(t)


@dataclass
class Track:
    tid: int
    person: int
    limb: Limb
    path: Path3
    carry: CarryFn | None = None  # hands only
    from_s: float = 0.0  # the tracker exists from this time on (started or re-acquired late)

    @property
    def label(self) -> str:
        return make_label(self.person, self.limb, self.tid)


@dataclass
class Join:
    """Trackers ``a`` and ``b`` are combined from ``t_join_s`` to ``t_sep_s``; afterwards they
    are unlabelled for ``relabel_s``. With ``swap``, tracker a follows b's limb after the
    separation (and gets its label), as when the tracker's identities cross. With ``met``
    False the tracker reports at the separation that the two never met."""

    a: int
    b: int
    t_join_s: float
    t_sep_s: float
    relabel_s: float = 0.3
    swap: bool = False
    met: bool = True


@dataclass
class Script:
    tracks: list[Track]
    joins: list[Join] = field(default_factory=list)
    duration_s: float = 4.0
    window_s: float = 0.0  # each carry estimate's evidence spans this long before it

    def _identity(self, tid: int, t: float) -> Track:
        """The physical limb tracker ``tid`` follows at time t (swaps after a separation)."""
        by_id = {tr.tid: tr for tr in self.tracks}
        for j in self.joins:
            if j.swap and t >= j.t_sep_s and tid in (j.a, j.b):
                return by_id[j.b if tid == j.a else j.a]
        return by_id[tid]

    def _state(self, tid: int, t: float) -> tuple[Phase, Join | None]:
        for j in self.joins:
            if tid in (j.a, j.b):
                if j.t_join_s <= t < j.t_sep_s:
                    return Phase.COMBINED, j
                if j.t_sep_s <= t < j.t_sep_s + j.relabel_s:
                    return Phase.UNLABELLED, j
        return Phase.NORMAL, None

    def frame(self, t: float) -> tuple[tuple[TargetSnapshot, ...], dict[int, CarryEstimate]]:
        targets, carry = [], {}
        by_id = {tr.tid: tr for tr in self.tracks}
        for tr in self.tracks:
            if t < tr.from_s:
                continue
            phase, j = self._state(tr.tid, t)
            limb_of = self._identity(tr.tid, t)
            if phase is Phase.COMBINED:
                pos = 0.5 * (by_id[j.a].path(t) + by_id[j.b].path(t))
            else:
                pos = limb_of.path(t)
            person, limb = (
                (0, Limb.UNKNOWN)
                if phase is Phase.UNLABELLED
                else (
                    limb_of.person,
                    limb_of.limb,
                )
            )
            snap = TargetSnapshot(tr.tid, person, limb, phase, pos)
            targets.append(snap)
            if limb_of.carry is not None:
                t_eval = j.t_join_s if phase is Phase.COMBINED else t  # frozen while combined
                carrying, hue, conf = limb_of.carry(t_eval)
                carry[tr.tid] = CarryEstimate(
                    tr.tid,
                    snap.label,
                    int(round(t * S)),
                    carrying,
                    hue,
                    conf,
                    since_ns=int(round((t - self.window_s) * S)),
                )
        return tuple(targets), carry

    def stream(self, fps: float = 15.0) -> list[tuple[TrackFrame, dict[int, CarryEstimate]]]:
        out = []
        prev: dict[int, TargetSnapshot] = {}
        n = int(self.duration_s * fps) + 1
        for i in range(n):
            t = i / fps
            t_ns = int(round(t * S))
            targets, carry = self.frame(t)
            transitions = []
            for snap in targets:
                old = prev.get(snap.target_id)
                if old is None or old.phase is snap.phase:
                    continue
                partner, met = None, True
                for j in self.joins:
                    if snap.target_id in (j.a, j.b):
                        partner = j.b if snap.target_id == j.a else j.a
                        met = j.met or old.phase is not Phase.COMBINED
                pairing = snap.phase is Phase.COMBINED or old.phase is Phase.COMBINED
                transitions.append(
                    Transition(
                        t_ns,
                        snap.target_id,
                        old.phase,
                        snap.phase,
                        old.label,
                        snap.mean_m,
                        partner if pairing else None,
                        prev[partner].label if pairing and partner is not None else None,
                        met,
                    )
                )
            out.append((TrackFrame(t_ns, targets, tuple(transitions)), carry))
            prev = {s.target_id: s for s in targets}
        return out


def run(
    rules: RuleSet, stream: Sequence[tuple[TrackFrame, Mapping[int, CarryEstimate]]]
) -> list[ActivityEvent]:
    """All events of a stream (online steps, then finish)."""
    return recognise(rules, stream)


# ---- people: heads and hands at rest ---------------------------------------------------------


def head(tid: int, person: int, x: float) -> Track:
    return Track(tid, person, Limb.HEAD, still(x, 0.0, 1.65))


def hand(tid: int, person: int, limb: Limb, path: Path3, carry: CarryFn | None = None) -> Track:
    return Track(tid, person, limb, path, carry if carry is not None else empty())
