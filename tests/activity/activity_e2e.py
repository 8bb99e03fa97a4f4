"""For the end-to-end test of a user rule on a synthetic scene (wired by the integrator once
tracking and carry exist): a scenario in which one person touches their face twice (the synth
ground truth has ``touch_face`` events), the rules to run (defaults + the example user rule
``rules/examples/touch_face.toml``), and an event matcher.

Intended use::

    rec = synthesise(scenario_path, out)        # TOUCH_FACE_SCENARIO written to a file
    results = Pipeline(cfg, rules=touch_face_rules()).run(rec)   # (whatever the API is)
    found = recognise(touch_face_rules(), ((r.track, r.carry) for r in results))
    assert_events_match(found, load_ground_truth(rec).events, "touch_face")
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from surveil.activity.rules import RuleSet, default_rules_path, load_rules
from surveil.datatypes import ActivityEvent

REPO = Path(__file__).resolve().parents[2]
TOUCH_FACE_RULE = REPO / "rules" / "examples" / "touch_face.toml"

TOUCH_FACE_SCENARIO = """
[scene]
name = "touch_face"
duration_s = 5.0
empty_room_s = 1.0
fps = 15.0
seed = 7

[rig]
n_cameras = 4
width = 320
height = 240

[[people]]
position_m = [3.0, 2.6]
facing_deg = 0
skin = "medium"

[[actions]]
at_s = 1.5
person = "p1"
do = "touch_face"
hand = "right"

[[actions]]
at_s = 3.3
person = "p1"
do = "touch_face"
hand = "left"
"""


def touch_face_rules() -> RuleSet:
    """The default rules plus the example user rule ``touch_face``."""
    return load_rules([default_rules_path(), TOUCH_FACE_RULE])


def assert_events_match(
    found: Sequence[ActivityEvent],
    truth: Sequence[ActivityEvent],
    activity: str,
    tolerance_s: float = 0.5,
) -> None:
    """Every true ``activity`` event has exactly one found event of that activity with the same
    actors (as a set) and a climax within ``tolerance_s``, and no found one is left over."""
    want = [e for e in truth if e.activity == activity]
    got = [e for e in found if e.activity == activity]
    unmatched = list(got)
    for t in want:
        hits = [
            g
            for g in unmatched
            if set(g.actors) == set(t.actors)
            and abs(g.climax_ns - t.climax_ns) <= tolerance_s * 1e9
        ]
        assert len(hits) == 1, f"{activity} at {t.climax_ns / 1e9:.2f} s {t.actors}: {hits}"
        unmatched.remove(hits[0])
    assert not unmatched, f"extra {activity} events: {unmatched}"
