"""Activity recognition (paper 004 §7, Table 1): rules as data, decision points, events.

``rules`` loads and validates TOML rule files into a :class:`RuleSet`; ``engine`` turns tracker
frames and carry estimates into :class:`~surveil.datatypes.ActivityEvent` online;
``predicates`` holds the pure checks they share. The rule language is in ``docs/rules.md``.
"""

from surveil.activity.engine import ActivityEngine, recognise
from surveil.activity.rules import Rule, RuleSet, Thresholds, default_rules_path, load_rules

__all__ = [
    "ActivityEngine",
    "Rule",
    "RuleSet",
    "Thresholds",
    "default_rules_path",
    "load_rules",
    "recognise",
]
