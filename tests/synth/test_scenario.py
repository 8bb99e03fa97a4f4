from pathlib import Path

import numpy as np
import pytest

from surveil.errors import ConfigError
from surveil.synth.scenario import load_scenario
from surveil.synth.timeline import compile_scenario

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings"
BASE = """
[scene]
duration_s = 5.0
[[people]]
position_m = [2.0, 2.0]
[[people]]
position_m = [2.9, 2.0]
facing_deg = 180
[[objects]]
name = "cup"
held_by = "p1/right_hand"
"""


def write(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(BASE + text)
    return path


@pytest.mark.parametrize("path", sorted(RECORDINGS.glob("*.toml")), ids=lambda p: p.stem)
def test_bundled_scenarios_load_and_compile(path):
    chor = compile_scenario(load_scenario(path), np.random.default_rng(0))
    assert chor.actors


def test_unknown_key_is_named_with_the_file(tmp_path):
    path = write(tmp_path, "[room]\ncolour = 3\n")
    with pytest.raises(ConfigError, match=r"s\.toml: room\.colour is not a known key"):
        load_scenario(path)


def test_bad_value_names_the_dotted_key_and_range(tmp_path):
    path = write(tmp_path, "[effects]\ndrop_rate = 0.9\n")
    with pytest.raises(ConfigError, match=r"effects\.drop_rate must be <= 0.5, got 0.9"):
        load_scenario(path)


def test_action_naming_an_unknown_person_fails(tmp_path):
    path = write(tmp_path, '[[actions]]\nat_s = 1.0\nperson = "p7"\ndo = "clap"\n')
    with pytest.raises(ConfigError, match=r"actions\[0\]\.person: unknown person 'p7'"):
        load_scenario(path)


def test_with_key_names_the_partner(tmp_path):
    path = write(
        tmp_path, '[[actions]]\nat_s = 1.0\nperson = "p1"\ndo = "handshake"\nwith = "p2"\n'
    )
    assert load_scenario(path).actions[0].partner == "p2"


def test_unreachable_pick_is_refused_with_a_hint(tmp_path):
    path = write(
        tmp_path,
        """
[[furniture]]
name = "table"
centre_m = [4.5, 4.0]
[[objects]]
name = "box"
on = "table"
[[actions]]
at_s = 1.0
person = "p2"
do = "pick"
object = "box"
""",
    )
    with pytest.raises(ConfigError, match="cannot reach object 'box'.*walk_to"):
        compile_scenario(load_scenario(path), np.random.default_rng(0))


def test_one_hand_cannot_do_two_things_at_once(tmp_path):
    path = write(
        tmp_path,
        """
[[actions]]
at_s = 1.0
person = "p1"
do = "clap"
[[actions]]
at_s = 1.3
person = "p1"
do = "touch_face"
""",
    )
    with pytest.raises(ConfigError, match="p1/right_hand is busy with p1 clap"):
        compile_scenario(load_scenario(path), np.random.default_rng(0))


def test_giving_an_object_one_does_not_hold_fails(tmp_path):
    path = write(
        tmp_path,
        '[[actions]]\nat_s = 1.0\nperson = "p2"\ndo = "give"\nobject = "cup"\nwith = "p1"\n',
    )
    with pytest.raises(ConfigError, match="p2 does not hold 'cup'"):
        compile_scenario(load_scenario(path), np.random.default_rng(0))
