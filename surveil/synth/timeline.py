"""Choreography: a scenario's action list compiled into smooth trajectories and true events.

Each person has a root track (floor position), a facing track and one track per hand. A
track is a sequence of moves; a move blends from wherever the track was to a new *target
function* of time (a fixed world point, or a body-relative pose such as "hands at rest" that
follows the body while it walks) with a minimum-jerk profile. Overlapping moves blend
smoothly. Small seeded variations (timing, end points, idle drift) keep repetitions from
looking identical.

The true event times come from the same compiled moves: the climax of a clap, handshake or
exchange is the instant the hands arrive together; of a pick or place the instant the hand
comes to rest at the object (paper 004, Table 1 and section 7).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from surveil.datatypes import ActivityEvent
from surveil.errors import ConfigError
from surveil.synth.actors import (
    UP,
    Appearance,
    BodyShape,
    Pose,
    body_axes,
    carry_hand_target,
    min_jerk,
    rest_hand_targets,
    solve_pose,
)
from surveil.synth.scenario import ActionSpec, Scenario, parse_rgb, person_ids

TargetFn = Callable[[float], np.ndarray]
SIDES = ("left", "right")
SIDE_SIGN = {"left": 1.0, "right": -1.0}
NS = 1_000_000_000


class Track:
    """Piecewise minimum-jerk blends between target functions of time."""

    def __init__(self, initial: TargetFn) -> None:
        self.moves = [(-np.inf, -np.inf, initial)]

    def move(self, t_start: float, t_arrive: float, target: TargetFn) -> None:
        self.moves.append((t_start, max(t_arrive, t_start + 1e-3), target))
        self.moves.sort(key=lambda m: m[0])

    def __call__(self, t: float, upto: int | None = None) -> np.ndarray:
        k = len(self.moves) - 1 if upto is None else upto
        while k > 0 and self.moves[k][0] > t:
            k -= 1
        t0, t1, target = self.moves[k]
        if t >= t1 or k == 0:
            return target(t)
        s = float(min_jerk((t - t0) / (t1 - t0)))
        before = self(t, k - 1)
        return before + s * (target(t) - before)


def const(value: np.ndarray) -> TargetFn:
    value = np.array(value, dtype=np.float64)
    return lambda t: value


@dataclass
class Actor:
    """One person's compiled motion."""

    pid: str
    number: int
    shape: BodyShape
    look: Appearance
    root: Track  # (3,) floor point
    yaw: Track  # (1,) radians, unwrapped
    hands: dict[str, Track]
    drift_phase: np.ndarray  # (2, 3) idle drift phases

    def yaw_at(self, t: float) -> float:
        return float(self.yaw(t)[0])

    def rest(self, side: str) -> TargetFn:
        i = SIDES.index(side)

        def fn(t: float) -> np.ndarray:
            drift = 0.008 * np.sin(np.array([0.7, 0.9, 0.5]) * t + self.drift_phase[i])
            return rest_hand_targets(self.shape, self.root(t), self.yaw_at(t))[i] + drift

        return fn

    def carry(self, side: str) -> TargetFn:
        i = SIDES.index(side)

        def fn(t: float) -> np.ndarray:
            drift = 0.006 * np.sin(np.array([0.8, 0.6, 0.7]) * t + self.drift_phase[i])
            return (
                carry_hand_target(self.shape, self.root(t), self.yaw_at(t), SIDE_SIGN[side])
                + drift
            )

        return fn

    def shoulder(self, side: str, t: float) -> np.ndarray:
        fwd, left = body_axes(self.yaw_at(t))
        return (
            self.root(t)
            + UP * self.shape.shoulder_height_m
            + SIDE_SIGN[side] * self.shape.shoulder_half_width_m * left
        )

    def pose(self, t: float, gait_phase: float, gait_amp: float) -> Pose:
        hands = np.stack([self.hands[s](t) for s in SIDES])
        bob = np.array([0.0, 0.0, 0.004 * np.sin(2 * np.pi * 0.25 * t + self.drift_phase[0, 0])])
        return solve_pose(
            self.shape,
            self.root(t),
            self.yaw_at(t),
            hands,
            gait_phase=gait_phase,
            gait_amp=gait_amp,
            head_offset_m=bob,
        )


@dataclass
class ObjectTrack:
    """Who holds an object when; where it rests otherwise."""

    name: str
    hue_deg: float
    albedo: np.ndarray
    size_m: np.ndarray
    shape: str
    states: list[tuple[float, str, np.ndarray | None]]  # (from t, holder label | "", rest pos)

    def state(self, t: float) -> tuple[str, np.ndarray | None]:
        holder, pos = "", None
        for t0, h, p in self.states:
            if t0 <= t:
                holder, pos = h, p
        return holder, pos

    def holder_at(self, t: float) -> str:
        return self.state(t)[0]


@dataclass
class Choreography:
    actors: dict[str, Actor]
    objects: dict[str, ObjectTrack]
    events: list[ActivityEvent]
    furniture_tops: dict[str, tuple[np.ndarray, float]]  # name -> (centre xy, top z)


def hsv_albedo(hue_deg: float, sat: float, val: float) -> np.ndarray:
    """BGR albedo in [0, 1] of an HSV colour."""
    import cv2

    hsv = np.array([[[hue_deg / 2.0, sat * 255, val * 255]]], dtype=np.uint8)
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0].astype(np.float64) / 255.0


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 1e-9 else v


class Compiler:
    """Turns the validated action list into tracks and events, in time order."""

    def __init__(self, scenario: Scenario, rng: np.random.Generator) -> None:
        self.sc = scenario
        self.rng = rng
        self.actors: dict[str, Actor] = {}
        ids = person_ids(scenario)
        for n, (pid, spec) in enumerate(zip(ids, scenario.people, strict=False), start=1):
            where = f"people[{n - 1}]"
            shape = BodyShape.from_height(spec.height_m)
            look = Appearance(
                skin=parse_rgb(spec.skin, f"{where}.skin", skin=True),
                hair=parse_rgb(spec.hair, f"{where}.hair"),
                shirt=parse_rgb(spec.shirt, f"{where}.shirt"),
                trousers=parse_rgb(spec.trousers, f"{where}.trousers"),
                shoes=parse_rgb(spec.shoes, f"{where}.shoes"),
                long_sleeves=spec.sleeves == "long",
            )
            root = Track(const([*spec.position_m, 0.0]))
            yaw = Track(const([np.radians(spec.facing_deg)]))
            actor = Actor(pid, n, shape, look, root, yaw, {}, rng.uniform(0, 2 * np.pi, (2, 3)))
            actor.hands = {s: Track(actor.rest(s)) for s in SIDES}
            self.actors[pid] = actor
        self.tops: dict[str, tuple[np.ndarray, float]] = {}
        for f in scenario.furniture:
            self.tops[f.name] = (np.array(f.centre_m, dtype=np.float64), f.size_m[2])
        self.objects: dict[str, ObjectTrack] = {}
        for o in scenario.objects:
            size = np.array(o.size_m) if o.shape == "box" else np.full(3, max(o.size_m))
            if o.held_by:
                state = (o.held_by, None)
            else:
                base = np.array(o.position_m, dtype=np.float64)
                z = size[2] / 2
                if o.on:
                    centre, top = self.tops[o.on]
                    base, z = base + centre, top + size[2] / 2
                state = ("", np.array([base[0], base[1], z]))
            self.objects[o.name] = ObjectTrack(
                o.name,
                o.hue_deg,
                hsv_albedo(o.hue_deg, o.saturation, o.value),
                size,
                o.shape,
                [(-np.inf, *state)],
            )
        for _name, obj in self.objects.items():
            if obj.states[0][1]:
                pid, hand = obj.states[0][1].split("/")
                actor = self.actors[pid]
                side = hand.removesuffix("_hand")
                actor.hands[side] = Track(actor.carry(side))
        self.events: list[ActivityEvent] = []
        self.busy: dict[str, list[tuple[float, float, str]]] = {}

    # -- helpers ------------------------------------------------------------------------------

    def jitter(self, seconds: float) -> float:
        return seconds * float(1 + 0.06 * self.rng.standard_normal())

    def wobble(self, point: np.ndarray, sigma_m: float = 0.008) -> np.ndarray:
        return point + self.rng.normal(0, sigma_m, 3)

    def held_object(self, label: str, t: float) -> str | None:
        for name, obj in self.objects.items():
            if obj.holder_at(t) == label:
                return name
        return None

    def home(self, actor: Actor, side: str, t_after: float) -> TargetFn:
        """Where a hand goes back to: carrying pose if it holds an object then, else rest."""
        label = f"{actor.pid}/{side}_hand"
        return actor.carry(side) if self.held_object(label, t_after) else actor.rest(side)

    def claim(self, label: str, t0: float, t1: float, what: str) -> None:
        """Reserve a limb for [t0, t1]; two actions may not move one hand at once."""
        for b0, b1, other in self.busy.get(label, []):
            if t0 < b1 and b0 < t1:
                raise ConfigError(
                    f"actions: {label} is busy with {other} ({b0:.2f}-{b1:.2f} s) when "
                    f"{what} ({t0:.2f}-{t1:.2f} s) needs it; move one of them in time"
                )
        self.busy.setdefault(label, []).append((t0, t1, what))

    def event(
        self,
        activity: str,
        t0: float,
        climax: float,
        t_end: float,
        actors: tuple[str, ...],
        persons: tuple[str, ...],
        obj: str | None = None,
        frm: str | None = None,
        to: str | None = None,
    ) -> None:
        what = f"{persons[0]} {activity} at {t0:.2f} s"
        for label in actors:
            if label.endswith("_hand"):
                self.claim(label, t0, t_end, what)
        hue = self.objects[obj].hue_deg if obj else None
        self.events.append(
            ActivityEvent(
                activity=activity,
                start_ns=round(t0 * NS),
                climax_ns=round(climax * NS),
                end_ns=round(t_end * NS),
                actors=actors,
                persons=persons,
                rule="ground_truth",
                object_hue_deg=hue,
                from_actor=frm,
                to_actor=to,
                object_name=obj,
            )
        )

    def check_reach(
        self, act: ActionSpec, actor: Actor, side: str, t: float, target: np.ndarray, what: str
    ) -> None:
        reach = actor.shape.arm_reach_m
        dist = float(np.linalg.norm(target - actor.shoulder(side, t)))
        if dist > reach * 0.98:
            raise ConfigError(
                f"actions (at_s = {act.at_s}, {act.person} {act.do}): {act.person}'s "
                f"{side} hand cannot reach {what} ({dist:.2f} m from the shoulder, arm "
                f"{reach:.2f} m); move the people/objects closer or add a walk_to first"
            )

    # -- actions ------------------------------------------------------------------------------

    def compile(self) -> Choreography:
        order = sorted(enumerate(self.sc.actions), key=lambda ia: (ia[1].at_s, ia[0]))
        for _, act in order:
            getattr(self, f"do_{act.do}")(act, self.actors[act.person], act.at_s)
        self.events.sort(key=lambda e: e.climax_ns)
        return Choreography(self.actors, self.objects, self.events, self.tops)

    def do_idle(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        return None

    def do_walk_to(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        start = actor.root(t0)
        goal = np.array([*act.position_m, 0.0])
        dist = float(np.linalg.norm(goal - start))
        if dist > 0.05:
            heading = np.arctan2(*(goal - start)[[1, 0]])
            self.turn_to(actor, t0, heading, 0.5)
        dur = act.duration_s or max(0.8, 1.3 * dist / act.speed_mps)
        actor.root.move(t0 + 0.2, t0 + 0.2 + dur, const(goal))
        if act.facing_deg is not None:
            self.turn_to(actor, t0 + 0.2 + dur - 0.2, np.radians(act.facing_deg), 0.7)

    def turn_to(self, actor: Actor, t0: float, heading: float, dur: float) -> None:
        current = actor.yaw_at(t0)
        # unwrapped: turn the short way round
        target = current + (heading - current + np.pi) % (2 * np.pi) - np.pi
        actor.yaw.move(t0, t0 + dur, const([target]))

    def do_turn(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        if act.towards:
            d = self.actors[act.towards].root(t0) - actor.root(t0)
            heading = float(np.arctan2(d[1], d[0]))
        elif act.facing_deg is not None:
            heading = float(np.radians(act.facing_deg))
        else:
            raise ConfigError(
                f"actions (at_s = {act.at_s}, {act.person} turn): give facing_deg or towards"
            )
        self.turn_to(actor, t0, heading, act.duration_s or 0.8)

    def two_hands_together(
        self, actor: Actor, t0: float, reach: float, hold: float, back: float
    ) -> tuple[float, float, float]:
        """Both hands of one person meet in front of the chest. Returns climax, leave, end."""
        fwd, left = body_axes(actor.yaw_at(t0))
        centre = self.wobble(actor.root(t0) + fwd * 0.34 + UP * 0.70 * actor.shape.height_m)
        gap = 0.5 * actor.shape.hand_thickness_m + 0.002
        climax = t0 + reach
        for side in SIDES:
            actor.hands[side].move(t0, climax, const(centre + SIDE_SIGN[side] * gap * left))
        return climax, climax + hold, climax + hold + back

    def do_clap(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        scale = (act.duration_s or 1.3) / 1.3
        climax, leave, end = self.two_hands_together(
            actor, t0, self.jitter(0.55 * scale), 0.12 * scale, self.jitter(0.6 * scale)
        )
        for side in SIDES:
            actor.hands[side].move(leave, end, self.home(actor, side, end))
        self.event(
            "clap",
            t0,
            climax,
            end,
            (f"{actor.pid}/left_hand", f"{actor.pid}/right_hand"),
            (actor.pid,),
        )

    def meeting(
        self, a: Actor, b: Actor, t0: float, height_frac: float, act: ActionSpec
    ) -> tuple[np.ndarray, np.ndarray]:
        ra, rb = a.root(t0), b.root(t0)
        d = rb - ra
        dist = float(np.linalg.norm(d))
        max_dist = 2 * 0.9 * min(a.shape.arm_reach_m, b.shape.arm_reach_m) + 0.2
        if dist > max_dist or dist < 0.5:
            raise ConfigError(
                f"actions (at_s = {act.at_s}, {act.person} {act.do}): "
                f"{a.pid} and {b.pid} stand {dist:.2f} m apart; they must be "
                f"0.5-{max_dist:.2f} m apart to reach each other (walk_to first)"
            )
        h = height_frac * 0.5 * (a.shape.height_m + b.shape.height_m)
        return self.wobble(0.5 * (ra + rb) + UP * h), _unit(d)

    def do_handshake(self, act: ActionSpec, actor: Actor, t0: float, gap_m: float = 0.0) -> None:
        other = self.actors[act.partner]
        centre, d = self.meeting(actor, other, t0, 0.57, act)
        reach, hold, back = self.jitter(0.8), (act.duration_s or 2.6) - 1.6, self.jitter(0.7)
        climax = t0 + reach
        side_dir = np.cross(UP, d)  # actor's left
        touching = gap_m == 0.0
        for who, sgn in ((actor, -1.0), (other, 1.0)):
            base = centre + sgn * (0.5 * gap_m + 0.01) * d + sgn * 0.012 * side_dir
            if touching:

                def pump(t: float, base=base) -> np.ndarray:
                    amp = 0.025 * np.clip((t - climax) / 0.2, 0, 1)
                    return base + UP * amp * np.sin(2 * np.pi * 2.2 * (t - climax))

                who.hands["right"].move(t0, climax, pump)
            else:
                who.hands["right"].move(t0, climax, const(base))
            who.hands["right"].move(
                climax + hold, climax + hold + back, self.home(who, "right", climax + hold + back)
            )
        hands = (f"{actor.pid}/right_hand", f"{other.pid}/right_hand")
        if touching:
            self.event(
                "handshake", t0, climax, climax + hold + back, hands, (actor.pid, other.pid)
            )
        else:  # a near miss: no event, but the hands are still busy
            for label in hands:
                self.claim(label, t0, climax + hold + back, f"{actor.pid} approach")

    def do_approach(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        self.do_handshake(act, actor, t0, gap_m=act.gap_m)

    def _held(
        self, act: ActionSpec, actor: Actor, t0: float, verb: str, hint: str = ""
    ) -> tuple[ObjectTrack, str]:
        """The object an action needs the actor to hold at ``t0``, and the hand side holding
        it; a ConfigError naming the action otherwise."""
        obj = self.objects[act.object]
        holder = obj.holder_at(t0)
        if not holder.startswith(f"{actor.pid}/"):
            raise ConfigError(
                f"actions (at_s = {act.at_s}, {act.person} {verb}): "
                f"{act.person} does not hold {act.object!r} then "
                f"(holder: {holder or 'nobody'}){hint}"
            )
        return obj, holder.split("/")[1].removesuffix("_hand")

    def do_give(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        obj, side = self._held(act, actor, t0, "give", "; pick it first")
        if act.hand and act.hand != side:
            raise ConfigError(
                f"actions (at_s = {act.at_s}, give): {act.object!r} is in the "
                f"{side} hand, not the {act.hand} hand"
            )
        other = self.actors[act.partner]
        opposite = "left" if side == "right" else "right"
        to_side = act.to_hand or opposite
        giver, receiver = f"{actor.pid}/{side}_hand", f"{other.pid}/{to_side}_hand"
        if other is actor:
            if to_side == side:
                raise ConfigError(
                    f"actions (at_s = {act.at_s}, give): a hand-to-hand "
                    f"exchange needs the other hand (to_hand = {opposite!r})"
                )
            climax, leave, end = self.two_hands_together(
                actor, t0, self.jitter(0.6), 0.45, self.jitter(0.6)
            )
            transfer = climax + 0.2
            obj.states.append((transfer, receiver, None))
            actor.hands[side].move(leave, end, actor.rest(side))
            actor.hands[to_side].move(leave, end, actor.carry(to_side))
            persons = (actor.pid,)
        else:
            centre, d = self.meeting(actor, other, t0, 0.6, act)
            reach, hold, back = self.jitter(0.85), 0.5, self.jitter(0.75)
            climax = t0 + reach
            actor.hands[side].move(t0, climax, const(centre - 0.035 * d))
            other.hands[to_side].move(t0 + 0.1, climax, const(centre + 0.035 * d))
            transfer = climax + 0.25
            obj.states.append((transfer, receiver, None))
            end = climax + hold + back
            actor.hands[side].move(climax + hold, end, actor.rest(side))
            other.hands[to_side].move(climax + hold, end, other.carry(to_side))
            persons = (actor.pid, other.pid)
        self.event(
            "exchange", t0, climax, end, (giver, receiver), persons, act.object, giver, receiver
        )

    def surface_target(
        self, actor: Actor, side: str, t0: float, obj: ObjectTrack, point: np.ndarray
    ) -> np.ndarray:
        """Hand centre grasping an object whose centre is ``point``, from the near side."""
        toward = _unit((point - actor.root(t0)) * np.array([1.0, 1.0, 0.0]))
        offset = 0.5 * obj.size_m[:2].max() + 0.5 * actor.shape.hand_thickness_m + 0.006
        return point - toward * offset + UP * 0.25 * obj.size_m[2]

    def do_pick(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        obj = self.objects[act.object]
        holder, rest = obj.state(t0)
        if holder:
            raise ConfigError(
                f"actions (at_s = {act.at_s}, pick): {act.object!r} is held "
                f"by {holder} then; only a resting object can be picked"
            )
        side = act.hand or "right"
        label = f"{actor.pid}/{side}_hand"
        if self.held_object(label, t0):
            raise ConfigError(
                f"actions (at_s = {act.at_s}, pick): {label} already holds "
                f"{self.held_object(label, t0)!r}"
            )
        target = self.surface_target(actor, side, t0, obj, rest)
        self.check_reach(act, actor, side, t0 + 0.8, target, f"object {act.object!r}")
        dist = float(np.linalg.norm(target - actor.hands[side](t0)))
        climax = t0 + self.jitter(0.55 + 0.5 * dist)
        still = act.duration_s or 0.45
        actor.hands[side].move(t0, climax, const(target))
        obj.states.append((climax + 0.5 * still, label, None))
        end = climax + still + self.jitter(0.75)
        actor.hands[side].move(climax + still, end, actor.carry(side))
        self.event("pick", t0, climax, end, (label,), (actor.pid,), act.object)

    def do_place(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        obj, side = self._held(act, actor, t0, "place")
        if act.where:
            centre, top = self.tops[act.where]
            xy = centre + (np.array(act.position_m) if len(act.position_m) == 2 else 0.0)
        else:
            xy, top = np.array(act.position_m), 0.0
        rest = np.array([xy[0], xy[1], top + obj.size_m[2] / 2])
        target = self.surface_target(actor, side, t0, obj, rest)
        self.check_reach(act, actor, side, t0 + 0.8, target, "the place point")
        dist = float(np.linalg.norm(target - actor.hands[side](t0)))
        climax = t0 + self.jitter(0.55 + 0.5 * dist)
        still = act.duration_s or 0.45
        actor.hands[side].move(t0, climax, const(target))
        obj.states.append((climax + 0.5 * still, "", rest))
        end = climax + still + self.jitter(0.75)
        actor.hands[side].move(climax + still, end, actor.rest(side))
        hand = f"{actor.pid}/{side}_hand"
        self.event("place", t0, climax, end, (hand,), (actor.pid,), act.object)

    def do_touch_face(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        side = act.hand or "right"
        fwd, left = body_axes(actor.yaw_at(t0))
        head = actor.root(t0) + UP * actor.shape.head_centre_height_m + 0.02 * fwd
        target = (
            head
            + fwd * (actor.shape.head_radii_m[1] + 0.5 * actor.shape.hand_thickness_m + 0.004)
            - UP * 0.035
            + SIDE_SIGN[side] * 0.03 * left
        )
        climax = t0 + self.jitter(0.6)
        hold = act.duration_s or 0.5
        end = climax + hold + self.jitter(0.6)
        actor.hands[side].move(t0, climax, const(target))
        actor.hands[side].move(climax + hold, end, self.home(actor, side, end))
        self.event(
            "touch_face",
            t0,
            climax,
            end,
            (f"{actor.pid}/{side}_hand", f"{actor.pid}/head"),
            (actor.pid,),
        )

    def do_wave(self, act: ActionSpec, actor: Actor, t0: float) -> None:
        side = act.hand or "right"
        fwd, left = body_axes(actor.yaw_at(t0))
        up_point = (
            actor.shoulder(side, t0)
            + UP * 0.40 * actor.shape.height_m / 1.75
            + SIDE_SIGN[side] * 0.2 * left
            + 0.12 * fwd
        )
        reach = self.jitter(0.6)
        dur = act.duration_s or 1.6

        def wave(t: float) -> np.ndarray:
            return up_point + 0.1 * left * np.sin(2 * np.pi * 1.8 * (t - t0 - reach))

        actor.hands[side].move(t0, t0 + reach, wave)
        end = t0 + reach + dur + 0.6
        actor.hands[side].move(t0 + reach + dur, end, self.home(actor, side, end))
        self.event("wave", t0, t0 + reach, end, (f"{actor.pid}/{side}_hand",), (actor.pid,))


def compile_scenario(scenario: Scenario, rng: np.random.Generator) -> Choreography:
    """Compile a validated scenario into tracks and true events (see module docstring)."""
    return Compiler(scenario, rng).compile()
