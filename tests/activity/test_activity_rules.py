"""Rule files: the default rules, user rules, and validation messages naming file, rule, field."""

from __future__ import annotations

from pathlib import Path

import pytest

from surveil.activity.rules import (
    LIMB_KINDS,
    Thresholds,
    default_rules_candidates,
    default_rules_path,
    load_rules,
)
from surveil.errors import ConfigError, RuleError

REPO = Path(__file__).resolve().parents[2]


def write(tmp_path: Path, text: str, name: str = "mine.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_default_rules_are_table_1():
    rules = load_rules()
    assert rules.names == ("clap", "handshake", "exchange", "pick", "place")
    assert rules["clap"].persons == "same" and rules["handshake"].persons == "different"
    assert rules["exchange"].carry_before == (True, False)
    assert rules["exchange"].carry_after == (False, True)
    assert rules["exchange"].transfer == "a_to_b"
    assert rules["pick"].limbs == ("hand", "scene") and rules["pick"].carry_before == (False,)
    assert rules["place"].carry_after == (False,)
    assert all(r.rule_id == f"default.toml:{r.name}" for r in rules)


def test_default_rules_come_from_the_top_level_rules_dir():
    assert default_rules_path() == REPO / "rules" / "default.toml"
    assert default_rules_candidates()[0] == REPO / "rules" / "default.toml"


def test_pyproject_ships_the_default_rules_as_data_files():
    import tomllib

    meta = tomllib.loads((REPO / "pyproject.toml").read_text())
    data_files = meta["tool"]["setuptools"]["data-files"]
    assert "rules/default.toml" in data_files["share/surveil/rules"]
    installed = [str(p) for p in default_rules_candidates()[1:]]
    assert all(p.endswith("share/surveil/rules/default.toml") for p in installed)


def test_file_defaults_and_rule_overrides(tmp_path):
    path = write(
        tmp_path,
        """
[defaults]
separation_m = 0.5
[rule.a]
limbs = ["hand", "head"]
[rule.b]
limbs = ["left_hand", "right_hand"]
separation_m = 0.4
""",
    )
    rules = load_rules([path])
    assert rules["a"].thresholds.separation_m == 0.5
    assert rules["b"].thresholds.separation_m == 0.4
    assert rules["a"].thresholds.still_s == Thresholds().still_s
    assert rules["a"].carry_before == (None, None) and rules["a"].persons == "any"


def test_rule_metadata_round_trips_through_json():
    import json

    meta = load_rules().to_metadata()
    table = json.loads(meta["default.toml:exchange"])
    assert table["carry_before"] == [1, 0] and table["limbs"] == ["hand", "hand"]


@pytest.mark.parametrize(
    ("body", "field", "hint"),
    [
        ('limbs = ["hand", "hand"]\ncolour = 3', "rule.bad.colour", "valid keys: carry_after"),
        ('limbs = ["hand", "foot"]', "rule.bad.limbs[1]", ", ".join(LIMB_KINDS)),
        ('limbs = ["hand"]', "rule.bad.limbs", "two limbs"),
        ('limbs = ["scene", "hand"]', "rule.bad.limbs", "second"),
        ('limbs = ["hand", "hand"]\npersons = "both"', "rule.bad.persons", "'same', 'different'"),
        ('limbs = ["hand", "hand"]\ntransfer = "up"', "rule.bad.transfer", "'a_to_b', 'none'"),
        ('limbs = ["hand", "hand"]\nseparation_m = -1', "rule.bad.separation_m", ">= 0.01"),
        ('limbs = ["hand", "hand"]\nmin_confidence = 2', "rule.bad.min_confidence", "<= 1.0"),
        (
            'limbs = ["hand", "hand"]\nmax_meeting_drop_m = -0.1',
            "rule.bad.max_meeting_drop_m",
            ">= 0",
        ),
        ('limbs = ["hand", "hand"]\nstill_s = "long"', "rule.bad.still_s", "number"),
        (
            'limbs = ["hand", "hand"]\nconserve_objects = "yes"',
            "rule.bad.conserve_objects",
            "true or false",
        ),
        ('limbs = ["hand", "hand"]\ncarry_before = [0]', "rule.bad.carry_before", "one entry"),
        (
            'limbs = ["hand", "hand"]\ncarry_after = [0, 2]',
            "rule.bad.carry_after[1]",
            "0, 1, 'any'",
        ),
        ('limbs = ["hand", "head"]\ncarry_after = [0, 1]', "rule.bad.carry_after[1]", "head"),
        ('limbs = ["hand", "scene"]\ncarry_after = [1, 0]', "rule.bad.carry_after", "scene"),
        ('limbs = ["hand", "scene"]\npersons = "same"', "rule.bad.persons", "hand/scene"),
        ('limbs = ["hand", "head"]\ntransfer = "none"', "rule.bad.transfer", "two hands"),
        ('description = "no limbs"', "rule.bad.limbs", "required"),
        (
            'limbs = ["hand", "hand"]\ncarry_before = [0, 0]\ntransfer = "a_to_b"',
            "rule.bad.transfer",
            "contradicts",
        ),
    ],
)
def test_invalid_rule_names_file_rule_and_field(tmp_path, body, field, hint):
    path = write(tmp_path, f"[rule.ok]\nlimbs = ['hand', 'head']\n\n[rule.bad]\n{body}\n")
    with pytest.raises(RuleError) as info:
        load_rules([path])
    msg = str(info.value)
    assert str(path) in msg
    assert field in msg
    assert hint in msg


def test_rule_error_is_a_config_error():
    assert issubclass(RuleError, ConfigError)


def test_unknown_top_level_key_and_defaults_key(tmp_path):
    path = write(tmp_path, "[rules.clap]\nlimbs = ['hand', 'hand']\n")
    with pytest.raises(RuleError, match=r"mine.toml: rules is not a known top-level key.*rule"):
        load_rules([path])
    path = write(tmp_path, "[defaults]\nspeed = 1\n[rule.a]\nlimbs = ['hand', 'head']\n")
    with pytest.raises(RuleError, match=r"mine.toml: defaults.speed is not a known key"):
        load_rules([path])


def test_bad_rule_name(tmp_path):
    path = write(tmp_path, "[rule.'touch face']\nlimbs = ['hand', 'head']\n")
    with pytest.raises(RuleError, match=r"mine.toml: rule.touch face: a rule name"):
        load_rules([path])


def test_file_without_rules_and_missing_or_broken_files(tmp_path):
    with pytest.raises(RuleError, match="no rules"):
        load_rules([write(tmp_path, "[defaults]\n")])
    with pytest.raises(RuleError, match="file not found"):
        load_rules([tmp_path / "absent.toml"])
    with pytest.raises(RuleError, match="invalid TOML"):
        load_rules([write(tmp_path, "[rule.a\n")])


def test_rule_names_unique_across_files(tmp_path):
    a = write(tmp_path, "[rule.touch]\nlimbs = ['hand', 'head']\n", "a.toml")
    b = write(tmp_path, "[rule.touch]\nlimbs = ['hand', 'hand']\n", "b.toml")
    with pytest.raises(RuleError) as info:
        load_rules([a, b])
    assert "b.toml: rule.touch" in str(info.value) and str(a) in str(info.value)
    clash = write(tmp_path, "[rule.clap]\nlimbs = ['hand', 'hand']\n", "c.toml")
    with pytest.raises(RuleError, match="clap: name already defined"):
        load_rules([default_rules_path(), clash])


def test_example_user_rules_load():
    examples = sorted((REPO / "rules" / "examples").glob("*.toml"))
    assert examples
    rules = load_rules([default_rules_path(), *examples])
    assert "touch_face" in rules.names


def test_end_to_end_helper_scenario_and_rules_load(tmp_path):
    from activity_e2e import TOUCH_FACE_SCENARIO, assert_events_match, touch_face_rules

    from surveil.synth.scenario import load_scenario

    path = tmp_path / "touch_face.toml"
    path.write_text(TOUCH_FACE_SCENARIO)
    load_scenario(path)
    assert touch_face_rules().names[-1] == "touch_face"
    assert_events_match([], [], "touch_face")
