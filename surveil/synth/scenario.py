"""The scenario file of ``surveil synth``: a validated, frozen description of a scene.

See docs/synth.md for the user documentation and ``recordings/*.toml`` for examples. Loading
goes through :func:`surveil.config.from_table`, so unknown keys and bad values fail with the
file and dotted key named.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from surveil.config import from_table, read_toml, setting
from surveil.errors import ConfigError

ACTIONS = (
    "idle",
    "walk_to",
    "turn",
    "clap",
    "handshake",
    "approach",
    "give",
    "pick",
    "place",
    "touch_face",
    "wave",
)

SKIN_TONES_RGB = {
    "light": (232, 190, 162),
    "fair": (224, 172, 140),
    "medium": (198, 143, 108),
    "tan": (172, 118, 84),
    "brown": (135, 88, 58),
    "dark": (92, 58, 40),
}
NAMED_RGB = {
    "black": (28, 28, 30),
    "white": (235, 235, 232),
    "grey": (128, 128, 130),
    "navy": (30, 40, 90),
    "blue": (40, 80, 170),
    "red": (170, 35, 40),
    "green": (40, 120, 60),
    "olive": (100, 105, 50),
    "yellow": (210, 180, 50),
    "orange": (220, 110, 30),
    "purple": (100, 50, 130),
    "brown": (95, 60, 35),
    "khaki": (170, 150, 110),
    "denim": (60, 80, 120),
    "teal": (30, 120, 120),
    "maroon": (110, 30, 40),
    "beige": (200, 180, 150),
    "charcoal": (55, 55, 60),
    "blonde": (200, 165, 100),
    "auburn": (120, 55, 30),
    "darkbrown": (55, 35, 25),
    "wood": (196, 142, 100),  # a light, skin-toned wood: the deliberate distractor
}


def parse_rgb(value: str | tuple, where: str, *, skin: bool = False) -> np.ndarray:
    """A colour name or ``[r, g, b]`` (0-255) -> BGR albedo in [0, 1]."""
    table = SKIN_TONES_RGB if skin else NAMED_RGB
    if isinstance(value, str):
        if value not in table:
            raise ConfigError(
                f"{where}: unknown colour {value!r}; use [r, g, b] or one of "
                f"{', '.join(sorted(table))}"
            )
        rgb = table[value]
    else:
        rgb = value
        if len(rgb) != 3 or not all(0 <= c <= 255 for c in rgb):
            raise ConfigError(f"{where} must be [r, g, b] with values 0-255, got {value!r}")
    return np.array(rgb[::-1], dtype=np.float64) / 255.0


@dataclass(frozen=True, kw_only=True)
class SceneSpec:
    name: str = setting("scene", "scenario name")
    duration_s: float = setting(
        10.0, "length of the action, seconds (after the empty-room lead-in)", min=0.5, max=3600
    )
    empty_room_s: float = setting(
        2.0,
        "seconds of empty room recorded before the people appear (the background model's "
        "learning phase); action times count from the end of it",
        min=0.0,
        max=600,
    )
    fps: float = setting(15.0, "frame rate", min=1.0, max=120)
    seed: int = setting(0, "seed of every random choice", min=0)
    description: str = setting("", "free text")


@dataclass(frozen=True, kw_only=True)
class RigSpec:
    file: str = setting("", "rig YAML relative to the scenario file; empty = generate")
    n_cameras: int = setting(4, "generated rig: cameras round the room", min=1, max=16)
    width: int = setting(640, "generated rig: image width, px", min=64, max=4096)
    height: int = setting(480, "generated rig: image height, px", min=48, max=4096)
    height_m: float = setting(2.6, "generated rig: camera height, m", min=0.5, max=10)
    hfov_deg: float = setting(78.0, "generated rig: horizontal field of view", min=20, max=150)


@dataclass(frozen=True, kw_only=True)
class RoomSpec:
    size_m: tuple[float, float, float] = setting((6.0, 5.0, 2.8), "x, y extent and height, m")
    floor: str = setting("tiles", "floor texture", choices=("tiles", "wood", "carpet"))
    wall_rgb: tuple[int, int, int] = setting((214, 210, 198), "wall paint colour")
    skin_panel: bool = setting(True, "a skin-toned cork board on a wall (distractor)")
    poster: bool = setting(True, "a colourful poster on a wall (hue distractor)")
    light_azimuth_deg: float = setting(30.0, "main light direction, azimuth")
    light_elevation_deg: float = setting(65.0, "main light elevation", min=10, max=90)


@dataclass(frozen=True, kw_only=True)
class FurnitureSpec:
    name: str = setting(doc="unique name, used by pick/place")
    kind: str = setting("table", "table or cabinet", choices=("table", "cabinet"))
    centre_m: tuple[float, float] = setting(doc="floor position of the centre, m")
    size_m: tuple[float, float, float] = setting((1.2, 0.7, 0.75), "x, y extent and height")
    yaw_deg: float = setting(0.0, "rotation about Z")
    colour: str | tuple[int, int, int] = setting("wood", "name or [r, g, b]")


@dataclass(frozen=True, kw_only=True)
class PersonSpec:
    id: str = setting("", "p1, p2, ... (default: by order)")
    height_m: float = setting(1.75, "body height", min=1.2, max=2.2)
    skin: str | tuple[int, int, int] = setting("medium", "skin tone name or [r, g, b]")
    shirt: str | tuple[int, int, int] = setting("blue", "colour name or [r, g, b]")
    trousers: str | tuple[int, int, int] = setting("denim", "colour name or [r, g, b]")
    hair: str | tuple[int, int, int] = setting("darkbrown", "colour name or [r, g, b]")
    shoes: str | tuple[int, int, int] = setting("black", "colour name or [r, g, b]")
    sleeves: str = setting("long", "long sleeves cover the forearms", choices=("long", "short"))
    position_m: tuple[float, float] = setting(doc="start floor position, m")
    facing_deg: float = setting(0.0, "start facing: 0 = +X, counter-clockwise")


@dataclass(frozen=True, kw_only=True)
class ObjectSpec:
    name: str = setting(doc="unique name")
    hue_deg: float = setting(120.0, "hue of its saturated colour", min=0, max=360)
    saturation: float = setting(0.85, "0-1", min=0.3, max=1.0)
    value: float = setting(0.85, "0-1", min=0.2, max=1.0)
    shape: str = setting("box", "box or ball", choices=("box", "ball"))
    size_m: tuple[float, float, float] = setting((0.09, 0.07, 0.11), "extent x, y, z")
    on: str = setting("", "furniture it rests on at the start")
    position_m: tuple[float, float] = setting(
        (0.0, 0.0), "position on that furniture, or floor position when `on` is empty"
    )
    held_by: str = setting("", "hand holding it at the start, e.g. p1/right_hand")


@dataclass(frozen=True, kw_only=True)
class ActionSpec:
    at_s: float = setting(doc="start time, seconds", min=0)
    person: str = setting(doc="who acts")
    do: str = setting(doc="the action", choices=ACTIONS)
    partner: str = setting("", "the other person (key `with` in the file)")
    object: str = setting("", "object for give/pick/place")
    hand: str = setting("", "left or right (default depends on the action)")
    to_hand: str = setting("", "give: receiving hand (default: the opposite side)")
    where: str = setting("", "place: furniture name")
    position_m: tuple[float, ...] = setting((), "walk_to / place target [x, y]")
    facing_deg: float | None = setting(None, "walk_to / turn: final facing")
    towards: str = setting("", "turn: face this person")
    speed_mps: float = setting(0.9, "walk_to speed", min=0.1, max=3)
    duration_s: float | None = setting(None, "override the action's default duration", min=0.2)
    gap_m: float = setting(0.25, "approach: distance the hands stop apart", min=0.12)


COMPRESSIONS = ("mp4v", "jpeg", "png")  # how a recording's frames are stored


@dataclass(frozen=True, kw_only=True)
class EffectsSpec:
    """Camera and recording imperfections (all on by default: good scores must mean something)."""

    noise_sigma: float = setting(2.5, "sensor read noise, grey levels", min=0, max=30)
    shot_noise: float = setting(0.6, "photon noise scale (sigma^2 += k * I)", min=0, max=5)
    compression: str = setting(
        "mp4v", "mp4v video, jpeg or png image folders", choices=COMPRESSIONS
    )
    jpeg_quality: int = setting(85, "for jpeg", min=10, max=100)
    gain_spread: float = setting(0.08, "per-camera gain sigma (relative)", min=0, max=0.5)
    white_balance_spread: float = setting(0.05, "per-camera channel gain sigma", min=0, max=0.3)
    vignetting: float = setting(0.25, "brightness loss at the image corners", min=0, max=0.8)
    illumination_drift: float = setting(0.06, "slow light level change amplitude", min=0, max=0.5)
    shadows: float = setting(0.45, "strength of people's soft floor shadows", min=0, max=1)
    calib_rotation_deg: float = setting(0.15, "written-rig rotation error sigma", min=0, max=5)
    calib_translation_m: float = setting(0.008, "written-rig position error sigma", min=0, max=0.5)
    calib_focal_rel: float = setting(0.004, "written-rig focal length error sigma", min=0, max=0.1)
    jitter_ms: float = setting(2.0, "timestamp jitter sigma", min=0, max=30)
    drop_rate: float = setting(0.01, "probability a frame is dropped", min=0, max=0.5)
    late_start_s: dict[str, float] = setting(
        default_factory=dict, doc="camera -> seconds it starts late"
    )
    mask_every: int = setting(5, "write ground-truth masks every N frames (0 = never)", min=0)


@dataclass(frozen=True, kw_only=True)
class Scenario:
    scene: SceneSpec = setting(default_factory=SceneSpec)
    rig: RigSpec = setting(default_factory=RigSpec)
    room: RoomSpec = setting(default_factory=RoomSpec)
    effects: EffectsSpec = setting(default_factory=EffectsSpec)
    furniture: tuple[FurnitureSpec, ...] = setting((), "furniture")
    people: tuple[PersonSpec, ...] = setting((), "people")
    objects: tuple[ObjectSpec, ...] = setting((), "small objects")
    actions: tuple[ActionSpec, ...] = setting((), "the timeline")


def load_scenario(path: Path) -> Scenario:
    """Read and validate a scenario TOML. Cross-references (people, objects, furniture named by
    actions) are checked too; every error names the file and the offending key."""
    path = Path(path)
    table = read_toml(path)
    for action in table.get("actions", []):
        if isinstance(action, dict) and "with" in action:
            action["partner"] = action.pop("with")
    scenario = from_table(Scenario, table, f"{path}: ")
    people = list(scenario.people)
    if not people:
        raise ConfigError(f"{path}: people: a scenario needs at least one [[people]] entry")
    ids = [p.id or f"p{i + 1}" for i, p in enumerate(people)]
    for i, pid in enumerate(ids):
        if not pid.startswith("p") or not pid[1:].isdigit() or pid[1:].startswith("0"):
            raise ConfigError(f"{path}: people[{i}].id must be p1, p2, ..., got {pid!r}")
    if len(set(ids)) != len(ids):
        raise ConfigError(f"{path}: people ids must be unique, got {ids}")
    furniture = {f.name for f in scenario.furniture}
    objects = {o.name for o in scenario.objects}
    hands = {f"{p}/{h}_hand" for p in ids for h in ("left", "right")}
    for i, obj in enumerate(scenario.objects):
        if obj.on and obj.on not in furniture:
            raise ConfigError(
                f"{path}: objects[{i}].on names unknown furniture {obj.on!r} "
                f"(have: {', '.join(sorted(furniture)) or 'none'})"
            )
        if obj.held_by and obj.held_by not in hands:
            raise ConfigError(
                f"{path}: objects[{i}].held_by must be a hand like "
                f"p1/right_hand, got {obj.held_by!r}"
            )
    for i, act in enumerate(scenario.actions):
        key = f"{path}: actions[{i}]"
        if act.person not in ids:
            raise ConfigError(
                f"{key}.person: unknown person {act.person!r} (have: {', '.join(ids)})"
            )
        if act.at_s >= scenario.scene.duration_s:
            raise ConfigError(
                f"{key}.at_s = {act.at_s} is after the end of the scene "
                f"({scenario.scene.duration_s} s)"
            )
        if act.do in ("handshake", "approach") and act.partner not in ids:
            raise ConfigError(
                f"{key}.with: {act.do} needs another person, got "
                f"{act.partner!r} (have: {', '.join(ids)})"
            )
        if act.do == "give" and act.partner not in ids:
            raise ConfigError(
                f"{key}.with: give needs the receiving person (the giver "
                f"itself for a hand-to-hand exchange), got {act.partner!r}"
            )
        if act.do in ("give", "pick", "place") and act.object not in objects:
            raise ConfigError(
                f"{key}.object: {act.do} needs an object, got {act.object!r} "
                f"(have: {', '.join(sorted(objects)) or 'none'})"
            )
        if act.do == "place" and not act.where and len(act.position_m) != 2:
            raise ConfigError(f"{key}: place needs `where` (furniture) or position_m [x, y]")
        if act.where and act.where not in furniture:
            raise ConfigError(f"{key}.where: unknown furniture {act.where!r}")
        if act.do == "walk_to" and len(act.position_m) != 2:
            raise ConfigError(
                f"{key}.position_m: walk_to needs [x, y], got {list(act.position_m)}"
            )
        if act.hand not in ("", "left", "right") or act.to_hand not in ("", "left", "right"):
            raise ConfigError(f"{key}.hand must be left or right")
        if act.towards and act.towards not in ids:
            raise ConfigError(f"{key}.towards: unknown person {act.towards!r}")
    return scenario


def person_ids(scenario: Scenario) -> list[str]:
    return [p.id or f"p{i + 1}" for i, p in enumerate(scenario.people)]
