"""Activity rules as data: the TOML rule language of ``docs/rules.md`` (paper 004 §7, Table 1).

A rule file holds an optional ``[defaults]`` table of thresholds shared by the file's rules and
one ``[rule.<name>]`` table per rule::

    [defaults]
    separation_m = 0.25

    [rule.touch_face]
    description = "a hand touches the head of the same person"
    limbs = ["hand", "head"]
    persons = "same"

Every key is checked when the file is loaded: unknown keys, unknown values and out-of-range
thresholds raise :class:`~surveil.errors.RuleError` naming the file, the rule and the field and
listing what is valid. Several files can be loaded into one :class:`RuleSet`; rule names must be
unique across them.

The default rules live in the repository's top-level ``rules/default.toml``. A wheel ships that
same file as a data file (``[tool.setuptools.data-files]`` in ``pyproject.toml`` installs it to
``<prefix>/share/surveil/rules/``), so there is one copy in the source tree and the build copies
it; :func:`default_rules_path` finds it in either place.
"""

from __future__ import annotations

import dataclasses
import re
import sys
import sysconfig
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from surveil.config import from_table, read_toml, setting
from surveil.datatypes import Limb, parse_label
from surveil.errors import ConfigError, RuleError

#: Limb kinds a rule can name. ``hand`` matches either hand; ``scene`` is the world (pick, place).
LIMB_KINDS = ("hand", "left_hand", "right_hand", "head", "scene")
#: Who the body limbs belong to.
PERSONS = ("same", "different", "any")
#: Whether the carried object moved between the two limbs (``a_to_b``: from the first to the
#: second limb of ``limbs``; the engine tries both orders for symmetric limb pairs).
TRANSFERS = ("a_to_b", "none", "any")
#: Values of ``carry_before``/``carry_after`` entries.
CARRY_VALUES = (0, 1, "any")

RULE_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")
DEFAULT_RULES_FILE = "default.toml"
_TOP_KEYS = ("defaults", "rule")


@dataclass(frozen=True, slots=True)
class Thresholds:
    """Thresholds of one rule (SI units). A file's ``[defaults]`` table overrides these
    built-in values; a rule's own keys override the file's defaults.

    Times are seconds on the recording clock; the engine never counts frames.
    """

    coincidence_m: float = setting(
        0.12,
        "two body limbs whose estimates come closer than this coincide even if the tracker "
        "did not combine them (0 = only the tracker's combined state counts), metres",
        min=0.0,
        max=1.0,
    )
    min_coincidence_s: float = setting(
        0.1,
        "limbs that came within coincidence_m (and were not combined by the tracker) must "
        "stay there this long, or their meeting is dropped when they part: one frame set's "
        "blip of a tracker is no contact, s (0 = any)",
        min=0.0,
        max=10.0,
    )
    separation_m: float = setting(
        0.30,
        "the limbs are apart again (post-separation point) at this distance; also the "
        "approach distance that starts an event, metres",
        min=0.01,
        max=3.0,
    )
    separation_delay_s: float = setting(
        0.2,
        "wait this long after reaching separation_m before deciding (carry evidence), s",
        min=0.0,
        max=10.0,
    )
    separation_timeout_s: float = setting(
        2.0,
        "decide anyway this long after the separation (pick/place: after the hand last rested "
        "within coincidence_m of its still point), s",
        min=0.0,
        max=60.0,
    )
    max_coincidence_s: float = setting(
        10.0,
        "give up an episode whose limbs stay together (pick/place: whose hand rests) longer "
        "than this, s",
        min=0.1,
        max=600.0,
    )
    wait_for_lost_hand: bool = setting(
        True,
        "pick/place: a hand whose tracker is lost at its still point (before it left) is "
        "waited for: the timeout counts from the last moment it was lost there (up to "
        "max_coincidence_s from the stop); its return, not the evidence from before it was "
        "hidden, says what it holds after",
    )
    max_approach_s: float = setting(
        2.0,
        "look back at most this far before the climax for the approach start, s",
        min=0.0,
        max=30.0,
    )
    still_speed_mps: float = setting(
        0.2,
        "pick/place: a hand is still when it moves less than still_speed_mps * still_s "
        "(extent) during still_s, m/s",
        min=0.0,
        max=5.0,
    )
    still_s: float = setting(
        0.3, "pick/place: how long the hand must stay still, s", min=0.01, max=10.0
    )
    shoulder_drop_m: float = setting(
        0.24,
        "pick/place: the still hand must be below shoulder height = head height minus this, m",
        min=-1.0,
        max=1.0,
    )
    min_reach_m: float = setting(
        0.3,
        "pick/place: the still hand must be at least this far from its head horizontally, m",
        min=0.0,
        max=3.0,
    )
    max_meeting_drop_m: float = setting(
        0.0,
        "pair rules: the limbs must meet at most this far below the head of the person "
        "taking part (two people: the lower head), e.g. a clap happens in front of the chest, "
        "hands that meet at the hips while walking do not clap; 0 = anywhere, m",
        min=0.0,
        max=3.0,
    )
    seen_reach_m: float = setting(
        0.15,
        "pick/place: a hand whose track begins during the look-back (a tracker started or "
        "re-acquired late in the reach) needs only this much of the reach seen: its first "
        "sample this far from the still point (>= separation_m: the whole reach, always), m",
        min=0.0,
        max=3.0,
    )
    min_confidence: float = setting(
        0.3,
        "carry estimates less confident than this count as unknown (only 'any' matches)",
        min=0.0,
        max=1.0,
    )
    hue_tolerance_deg: float = setting(
        25.0,
        "two hues within this circular distance are the same object, degrees",
        min=0.0,
        max=180.0,
    )
    timeout_confidence_factor: float = setting(
        0.5,
        "an event decided by separation_timeout_s has its confidence multiplied by this",
        min=0.0,
        max=1.0,
    )
    min_repeat_s: float = setting(
        0.0,
        "the same activity of the same actors counts again only if its climax comes at least "
        "this long after the previous one's end (a tracker that parts a long handshake for a "
        "moment and joins it again would report it twice); 0 = every time, s",
        min=0.0,
        max=60.0,
    )
    conserve_objects: bool = setting(
        True,
        "two hands that meet and part hold as many objects after as before: when one of "
        "their four carry states is unknown, the other three decide it",
    )
    conserve_doubt_below: float = setting(
        0.75,
        "with conserve_objects: when the four carry states are known but break the count "
        "(an object appeared or vanished), the least confident state whose change would "
        "restore the count is decided by the other three if its confidence is below this; "
        "0 = never",
        min=0.0,
        max=1.0,
    )


_THRESHOLD_KEYS = tuple(f.name for f in dataclasses.fields(Thresholds))


@dataclass(frozen=True, slots=True)
class _RuleBody:
    """The non-threshold keys of a rule table (validated by :func:`surveil.config.from_table`)."""

    limbs: tuple[str, ...] = setting(doc="two limb kinds: hand/hand, hand/head or hand/scene")
    description: str = setting("", "one line for people")
    persons: str = setting("any", "same, different or any", choices=PERSONS)
    carry_before: tuple[int | str, ...] | None = setting(
        None, "carry state of each body limb at the first decision point: 0, 1 or 'any'"
    )
    carry_after: tuple[int | str, ...] | None = setting(
        None, "carry state of each body limb at the post-separation point: 0, 1 or 'any'"
    )
    transfer: str = setting("any", "a_to_b, none or any", choices=TRANSFERS)
    enabled: bool = setting(True, "false: load and validate the rule but never fire it")


_BODY_KEYS = tuple(f.name for f in dataclasses.fields(_RuleBody))


@dataclass(frozen=True, slots=True)
class Rule:
    """One activity rule.

    Attributes
    ----------
    name : str
        The activity name written to ``/events`` (``activity`` metadata).
    source : str
        File name the rule came from (``default.toml``); ``rule_id`` is ``source:name``.
    limbs : tuple of str
        Two entries of :data:`LIMB_KINDS`; ``scene`` only second (pick/place).
    persons : str
        ``same``, ``different`` or ``any``: who the body limbs belong to.
    carry_before, carry_after : tuple of (bool | None)
        One entry per body limb (``scene`` has none): True = carrying (1), False = empty (0),
        None = any. For a head always None (the carry stage analyses hands only).
    transfer : str
        ``a_to_b``: the object the first limb held before is held by the second after (hues
        within ``hue_tolerance_deg``); ``none``: no object moved either way; ``any``.
    thresholds : Thresholds
    description : str
    enabled : bool
    """

    name: str
    source: str
    limbs: tuple[str, ...]
    persons: str
    carry_before: tuple[bool | None, ...]
    carry_after: tuple[bool | None, ...]
    transfer: str
    thresholds: Thresholds
    description: str = ""
    enabled: bool = True

    @property
    def rule_id(self) -> str:
        """``<file name>:<rule name>``, the ``rule`` metadata of an event."""
        return f"{self.source}:{self.name}"

    @property
    def is_scene(self) -> bool:
        """True for hand/scene rules (decided from the hand's stillness, not a coincidence)."""
        return "scene" in self.limbs

    @property
    def is_symmetric(self) -> bool:
        """Whether the two limbs may be swapped (same kind)."""
        return self.limbs[0] == self.limbs[1]

    def describe(self) -> str:
        """A one-line summary, e.g. ``exchange: hand/hand any persons, carry 1,0 -> 0,1, ...``."""

        def fmt(states: tuple[bool | None, ...]) -> str:
            return ",".join("any" if s is None else str(int(s)) for s in states)

        parts = [f"{'/'.join(self.limbs)}"]
        if not self.is_scene:
            parts.append(f"persons {self.persons}")
        parts.append(f"carry {fmt(self.carry_before)} -> {fmt(self.carry_after)}")
        if self.transfer != "any":
            parts.append(f"transfer {self.transfer}")
        if not self.enabled:
            parts.append("DISABLED")
        text = f"{self.rule_id}: {', '.join(parts)}"
        return f"{text} -- {self.description}" if self.description else text

    def to_table(self) -> dict[str, Any]:
        """The rule as a TOML-like table (for metadata and ``rules-check --json``)."""

        def enc(states: tuple[bool | None, ...]) -> list[int | str]:
            return ["any" if s is None else int(s) for s in states]

        return {
            "name": self.name,
            "source": self.source,
            "description": self.description,
            "limbs": list(self.limbs),
            "persons": self.persons,
            "carry_before": enc(self.carry_before),
            "carry_after": enc(self.carry_after),
            "transfer": self.transfer,
            "enabled": self.enabled,
            **dataclasses.asdict(self.thresholds),
        }


def limb_matches(kind: str, limb: Limb) -> bool:
    """Whether a tracked limb fits a rule's limb kind.

    >>> limb_matches("hand", Limb.LEFT_HAND), limb_matches("right_hand", Limb.LEFT_HAND)
    (True, False)
    """
    if kind == "hand":
        return limb.is_hand
    if kind == "scene":
        return False
    return limb is not Limb.UNKNOWN and limb.key == kind


def label_matches(kind: str, label: str) -> bool:
    """Whether a target label (``p1/left_hand``, ``t7``) fits a limb kind; unlabelled
    trackers (``t7``) fit nothing."""
    try:
        _, limb = parse_label(label)
    except ValueError:
        return False
    return limb_matches(kind, limb)


@dataclass(frozen=True, slots=True)
class RuleSet:
    """Rules loaded from one or more files, in file order then rule order (the order in which
    simultaneous events are reported). Names are unique across the set."""

    rules: tuple[Rule, ...]
    sources: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        seen: dict[str, str] = {}
        for rule in self.rules:
            if rule.name in seen:
                raise RuleError(
                    f"{rule.source}: rule.{rule.name}: name already defined in {seen[rule.name]}; "
                    "rule names must be unique across rule files"
                )
            seen[rule.name] = rule.source

    def __iter__(self) -> Iterator[Rule]:
        return iter(self.rules)

    def __len__(self) -> int:
        return len(self.rules)

    def __getitem__(self, name: str) -> Rule:
        for rule in self.rules:
            if rule.name == name:
                return rule
        raise KeyError(f"no rule {name!r}; rules: {', '.join(r.name for r in self.rules)}")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.rules)

    def to_metadata(self) -> dict[str, str]:
        """One string per rule, ``rule_id -> describe()``-like JSON, for an MCAP ``rules``
        metadata record."""
        import json

        return {r.rule_id: json.dumps(r.to_table(), sort_keys=True) for r in self.rules}


# ---------------------------------------------------------------------------------------------
# loading


def _rule_error(exc: ConfigError) -> RuleError:
    return RuleError(str(exc))


def _carry_states(
    value: tuple[int | str, ...] | None, limbs: tuple[str, ...], key: str
) -> tuple[bool | None, ...]:
    body = [k for k in limbs if k != "scene"]
    if value is None:
        return (None,) * len(body)
    if len(value) != len(body):
        raise RuleError(
            f"{key} must have one entry per body limb ({len(body)}: {', '.join(body)}; the "
            f"scene has none), got {list(value)!r}"
        )
    states: list[bool | None] = []
    for i, (v, kind) in enumerate(zip(value, body, strict=True)):
        if isinstance(v, bool) or v not in CARRY_VALUES:
            raise RuleError(f"{key}[{i}] must be one of 0, 1, 'any', got {v!r}")
        state = None if v == "any" else bool(v)
        if kind == "head" and state is not None:
            raise RuleError(
                f"{key}[{i}] must be 'any' for a head (only hands are analysed), got {v!r}"
            )
        states.append(state)
    return tuple(states)


def parse_rule(name: str, table: Any, defaults: Thresholds, source: str, where: str) -> Rule:
    """Build one :class:`Rule` from its TOML table.

    Parameters
    ----------
    name : str
        The rule's name (the key of ``[rule.<name>]``).
    table : dict
        The rule's keys.
    defaults : Thresholds
        The file's defaults (thresholds the rule does not set).
    source : str
        File name recorded in ``rule_id``.
    where : str
        Message prefix naming the file, e.g. ``"rules/my.toml"``.

    Raises
    ------
    RuleError
        Naming ``where``, ``rule.<name>`` and the bad field, with the valid names or range.
    """
    prefix = f"{where}: rule.{name}"
    if not RULE_NAME_RE.match(name):
        raise RuleError(
            f"{prefix}: a rule name must start with a letter and hold only letters, digits, "
            "'_' and '-'"
        )
    if not isinstance(table, dict):
        raise RuleError(f"{prefix} must be a table, got {table!r}")
    unknown = sorted(set(table) - set(_BODY_KEYS) - set(_THRESHOLD_KEYS))
    if unknown:
        raise RuleError(
            f"{prefix}.{unknown[0]} is not a known key; valid keys: "
            f"{', '.join(sorted(_BODY_KEYS + _THRESHOLD_KEYS))}"
        )
    try:
        body = from_table(_RuleBody, {k: v for k, v in table.items() if k in _BODY_KEYS}, prefix)
        overrides = {k: v for k, v in table.items() if k in _THRESHOLD_KEYS}
        base = dataclasses.asdict(defaults)
        thresholds = from_table(Thresholds, {**base, **overrides}, prefix)
    except RuleError:
        raise
    except ConfigError as exc:
        raise _rule_error(exc) from None
    limbs = body.limbs
    for i, kind in enumerate(limbs):
        if kind not in LIMB_KINDS:
            raise RuleError(
                f"{prefix}.limbs[{i}]: unknown limb {kind!r}; valid limbs: {', '.join(LIMB_KINDS)}"
            )
    if len(limbs) != 2:
        raise RuleError(
            f"{prefix}.limbs must name two limbs (hand/hand, hand/head or hand/scene), "
            f"got {list(limbs)!r}"
        )
    if limbs[0] == "scene":
        raise RuleError(f"{prefix}.limbs: put 'scene' second (e.g. ['hand', 'scene'])")
    if "scene" in limbs and limbs[0] not in ("hand", "left_hand", "right_hand"):
        raise RuleError(f"{prefix}.limbs: the scene pairs with a hand, got {list(limbs)!r}")
    if limbs[0] == "head" and limbs[1] == "head":
        raise RuleError(f"{prefix}.limbs: head/head is not supported; use a hand")
    if "scene" in limbs and body.persons != "any":
        raise RuleError(
            f"{prefix}.persons must be 'any' for a hand/scene rule, got {body.persons!r}"
        )
    before = _carry_states(body.carry_before, limbs, f"{prefix}.carry_before")
    after = _carry_states(body.carry_after, limbs, f"{prefix}.carry_after")
    if body.transfer != "any":
        if "scene" in limbs:
            raise RuleError(
                f"{prefix}.transfer must be 'any' for a hand/scene rule, got {body.transfer!r}"
            )
        if "head" in limbs:
            raise RuleError(
                f"{prefix}.transfer needs two hands; must be 'any' with a head, "
                f"got {body.transfer!r}"
            )
    if body.transfer == "a_to_b" and (before[0] is False or after[1] is False):
        raise RuleError(
            f"{prefix}.transfer = 'a_to_b' contradicts carry_before[0] = 0 or carry_after[1] = 0"
        )
    return Rule(
        name=name,
        source=source,
        limbs=limbs,
        persons=body.persons,
        carry_before=before,
        carry_after=after,
        transfer=body.transfer,
        thresholds=thresholds,
        description=body.description,
        enabled=body.enabled,
    )


def parse_rules(doc: dict[str, Any], source: str, where: str) -> tuple[Rule, ...]:
    """Rules of one parsed TOML document (see :func:`load_rule_file`)."""
    unknown = sorted(set(doc) - set(_TOP_KEYS))
    if unknown:
        raise RuleError(
            f"{where}: {unknown[0]} is not a known top-level key; valid keys: "
            f"{', '.join(_TOP_KEYS)} (write rules as [rule.<name>] tables)"
        )
    try:
        defaults = from_table(Thresholds, doc.get("defaults", {}), f"{where}: defaults")
    except ConfigError as exc:
        raise _rule_error(exc) from None
    rules = doc.get("rule", {})
    if not isinstance(rules, dict):
        raise RuleError(f"{where}: rule must be a table of [rule.<name>] tables")
    if not rules:
        raise RuleError(f"{where}: no rules; add at least one [rule.<name>] table")
    return tuple(parse_rule(name, table, defaults, source, where) for name, table in rules.items())


def load_rule_file(path: Path) -> tuple[Rule, ...]:
    """Load and validate one rule file.

    Raises
    ------
    RuleError
        The file is missing, not TOML, or a rule is invalid; the message names the file, the
        rule and the field.
    """
    path = Path(path)
    try:
        doc = read_toml(path)
    except ConfigError as exc:
        raise _rule_error(exc) from None
    return parse_rules(doc, path.name, str(path))


def load_rules(paths: Iterable[Path] | Path | None = None) -> RuleSet:
    """Load rule files into one :class:`RuleSet`.

    Parameters
    ----------
    paths : path or iterable of paths, optional
        Rule files in order; default: the default rules (:func:`default_rules_path`).

    Raises
    ------
    RuleError
        An invalid file, or a rule name defined twice (naming both files).
    """
    if paths is None:
        paths = [default_rules_path()]
    elif isinstance(paths, str | Path):
        paths = [Path(paths)]
    paths = [Path(p) for p in paths]
    rules: list[Rule] = []
    where: dict[str, str] = {}
    for path in paths:
        for rule in load_rule_file(path):
            if rule.name in where:
                raise RuleError(
                    f"{path}: rule.{rule.name}: name already defined in {where[rule.name]}; "
                    "rule names must be unique across rule files"
                )
            where[rule.name] = str(path)
            rules.append(rule)
    return RuleSet(tuple(rules), tuple(str(p) for p in paths))


def default_rules_candidates() -> Sequence[Path]:
    """Where :func:`default_rules_path` looks, in order: the source tree's ``rules/`` (a
    checkout or an editable install), then the installed data directory of the running
    interpreter (``<prefix>/share/surveil/rules``, system then user scheme)."""
    here = Path(__file__).resolve().parent.parent.parent  # the directory holding surveil/
    dirs = [here / "rules"]
    for scheme in (None, f"{'nt' if sys.platform == 'win32' else 'posix'}_user"):
        try:
            data = sysconfig.get_path("data", scheme) if scheme else sysconfig.get_path("data")
        except KeyError:
            continue
        dirs.append(Path(data) / "share" / "surveil" / "rules")
    dirs.append(Path(sys.prefix) / "share" / "surveil" / "rules")
    return [d / DEFAULT_RULES_FILE for d in dirs]


def default_rules_path() -> Path:
    """The default rule file (``rules/default.toml``).

    Raises
    ------
    RuleError
        If no copy is found (a broken installation); the message lists where it looked.
    """
    candidates = default_rules_candidates()
    for path in candidates:
        if path.is_file():
            return path
    raise RuleError(
        f"default rules not found; looked in {', '.join(str(p) for p in candidates)}; "
        "pass rule files explicitly"
    )
