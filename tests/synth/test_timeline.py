"""The choreography's true events must describe what the bodies really do."""

import numpy as np
import pytest

from surveil.synth.scenario import load_scenario
from surveil.synth.timeline import compile_scenario

NS = 1e9
SCENE = """
[scene]
duration_s = 12.0
[[furniture]]
name = "table"
centre_m = [2.0, 1.0]
size_m = [1.0, 0.6, 0.92]
[[people]]
position_m = [2.0, 1.55]
facing_deg = -90
[[people]]
position_m = [2.0, 2.5]
facing_deg = 90
[[objects]]
name = "ball"
shape = "ball"
held_by = "p1/right_hand"
[[objects]]
name = "box"
on = "table"
position_m = [0.2, 0.2]
[[actions]]
at_s = 0.5
person = "p1"
do = "clap"
[[actions]]
at_s = 2.5
person = "p1"
do = "turn"
towards = "p2"
[[actions]]
at_s = 3.5
person = "p1"
do = "give"
object = "ball"
with = "p2"
[[actions]]
at_s = 6.5
person = "p1"
do = "turn"
facing_deg = -90
[[actions]]
at_s = 7.5
person = "p1"
do = "pick"
object = "box"
hand = "left"
"""


@pytest.fixture(scope="module")
def chor(tmp_path_factory):
    path = tmp_path_factory.mktemp("tl") / "s.toml"
    path.write_text(SCENE)
    return compile_scenario(load_scenario(path), np.random.default_rng(3))


def hands(chor, pid, t):
    return chor.actors[pid].pose(t, 0.0, 0.0).hands_m


def by_activity(chor, name):
    return [e for e in chor.events if e.activity == name]


def test_events_come_in_time_order_with_climax_inside(chor):
    assert [e.activity for e in chor.events] == ["clap", "exchange", "pick"]
    for e in chor.events:
        assert e.start_ns < e.climax_ns < e.end_ns


def test_clap_climax_is_when_the_two_hands_touch(chor):
    (clap,) = by_activity(chor, "clap")
    t = clap.climax_ns / NS
    gap_at_climax = np.linalg.norm(np.subtract(*hands(chor, "p1", t)))
    gap_before = np.linalg.norm(np.subtract(*hands(chor, "p1", clap.start_ns / NS)))
    assert gap_at_climax < 0.05 < 0.25 < gap_before


def test_exchange_moves_the_object_between_the_named_hands(chor):
    (ex,) = by_activity(chor, "exchange")
    assert (ex.from_actor, ex.to_actor) == ("p1/right_hand", "p2/left_hand")
    ball = chor.objects["ball"]
    assert ball.holder_at(ex.start_ns / NS) == "p1/right_hand"
    assert ball.holder_at(ex.end_ns / NS) == "p2/left_hand"
    t = ex.climax_ns / NS
    giver, receiver = hands(chor, "p1", t)[1], hands(chor, "p2", t)[0]
    assert np.linalg.norm(giver - receiver) < 0.12


def test_pick_climax_is_when_the_hand_stops_at_the_object(chor):
    (pick,) = by_activity(chor, "pick")
    t = pick.climax_ns / NS
    dt = 1 / 30
    speed = np.linalg.norm(hands(chor, "p1", t + dt)[0] - hands(chor, "p1", t - dt)[0]) / (2 * dt)
    peak = max(
        np.linalg.norm(hands(chor, "p1", s + dt)[0] - hands(chor, "p1", s)[0]) / dt
        for s in np.arange(pick.start_ns / NS, t, dt)
    )
    assert speed < 0.1 * peak
    box_rest = chor.objects["box"].state(pick.start_ns / NS)[1]
    assert np.linalg.norm(hands(chor, "p1", t)[0] - box_rest) < 0.12
    assert chor.objects["box"].holder_at(pick.end_ns / NS) == "p1/left_hand"
