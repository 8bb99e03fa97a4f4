"""People as articulated 3D bodies: anthropometry, two-bone inverse kinematics, and the
ellipsoid primitives that the renderer draws.

A person is posed by a root (floor position and facing angle) and two hand-centre targets;
arms are solved by two-bone IK with a plausible elbow (down, out and slightly back), legs by
the same IK from hip to ankle with a forward knee. Segment lengths are fractions of body
height from the Drillis-Contini anthropometric table (upper arm 0.186 H, forearm 0.146 H,
hand 0.108 H, shoulder height 0.818 H, shoulder width 0.259 H, hip height 0.53 H,
knee 0.285 H).

All positions are metres in the world frame (Z up). Body frame: ``forward`` =
(cos yaw, sin yaw, 0), ``left`` = (-sin yaw, cos yaw, 0), ``up`` = Z.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from surveil.io.ground_truth import MaskClass

UP = np.array([0.0, 0.0, 1.0])


class Part(enum.IntEnum):
    """Body part codes (red channel of ground-truth masks)."""

    NONE = 0
    HEAD = 1  # the face / skin part of the head
    HAIR = 2
    NECK = 3
    TORSO = 4
    PELVIS = 5
    LEFT_UPPER_ARM = 6
    RIGHT_UPPER_ARM = 7
    LEFT_FOREARM = 8
    RIGHT_FOREARM = 9
    LEFT_HAND = 10
    RIGHT_HAND = 11
    LEFT_THIGH = 12
    RIGHT_THIGH = 13
    LEFT_SHIN = 14
    RIGHT_SHIN = 15
    LEFT_FOOT = 16
    RIGHT_FOOT = 17
    OBJECT = 20


@dataclass(frozen=True, slots=True)
class BodyShape:
    """Dimensions of one person, metres, derived from height."""

    height_m: float
    upper_arm_m: float
    forearm_m: float
    hand_length_m: float
    hand_width_m: float
    hand_thickness_m: float
    shoulder_height_m: float
    shoulder_half_width_m: float
    hip_height_m: float
    hip_half_width_m: float
    thigh_m: float
    shin_m: float
    head_radii_m: np.ndarray  # (3,) lateral, depth, vertical
    head_centre_height_m: float

    @classmethod
    def from_height(cls, height_m: float) -> BodyShape:
        s = height_m / 1.75
        hip = 0.53 * height_m
        knee = 0.285 * height_m
        ankle = 0.045 * height_m
        return cls(
            height_m=height_m,
            upper_arm_m=0.186 * height_m,
            forearm_m=0.146 * height_m,
            # an adult hand: ~18-19 cm long, 8-9 cm wide (the figures)
            hand_length_m=0.105 * height_m,
            hand_width_m=0.049 * height_m,
            hand_thickness_m=0.028 * s,
            shoulder_height_m=0.818 * height_m,
            shoulder_half_width_m=0.105 * height_m,
            hip_height_m=hip,
            hip_half_width_m=0.052 * height_m,
            thigh_m=hip - knee,
            shin_m=knee - ankle,
            head_radii_m=np.array([0.076, 0.094, 0.112]) * s,
            head_centre_height_m=height_m - 0.112 * s,
        )

    @property
    def arm_reach_m(self) -> float:
        """Shoulder to hand centre, arm straight."""
        return self.upper_arm_m + self.forearm_m + 0.5 * self.hand_length_m


def min_jerk(tau: np.ndarray | float) -> np.ndarray | float:
    """Minimum-jerk blend s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 on [0, 1] (Flash & Hogan 1985).

    >>> [round(float(min_jerk(x)), 4) for x in (0.0, 0.5, 1.0, 2.0)]
    [0.0, 0.5, 1.0, 1.0]
    """
    tau = np.clip(tau, 0.0, 1.0)
    return tau**3 * (10 - 15 * tau + 6 * tau**2)


def body_axes(yaw_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(forward, left) unit vectors of a body facing ``yaw_rad`` (0 = +X, counter-clockwise)."""
    c, s = np.cos(yaw_rad), np.sin(yaw_rad)
    return np.array([c, s, 0.0]), np.array([-s, c, 0.0])


def two_bone_ik(
    root: np.ndarray, target: np.ndarray, len_a: float, len_b: float, pole: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Joint and end positions of a two-segment chain reaching for ``target``.

    The chain bends in the plane containing root, target and the ``pole`` direction, the joint
    displaced towards ``pole``. Out-of-reach targets are clamped to the reachable shell.

    Parameters
    ----------
    root, target : (3,) float, metres
    len_a, len_b : float, segment lengths (root-joint, joint-end), metres
    pole : (3,) float, preferred bend direction

    Returns
    -------
    joint_m, end_m : (3,) float64 -- ``end_m`` equals ``target`` when it is reachable.

    >>> j, e = two_bone_ik(np.zeros(3), np.array([0.0, 0, -0.5]), 0.3, 0.3,
    ...                    np.array([1.0, 0, 0]))
    >>> np.round(e, 3).tolist(), round(float(np.linalg.norm(j)), 3), bool(j[0] > 0)
    ([0.0, 0.0, -0.5], 0.3, True)
    """
    delta = target - root
    dist = float(np.linalg.norm(delta))
    lo, hi = abs(len_a - len_b) + 1e-4, len_a + len_b - 1e-4
    u = delta / dist if dist > 1e-9 else np.array([0.0, 0.0, -1.0])
    dist = min(max(dist, lo), hi)
    # law of cosines: angle at the root between the chain's first segment and root->end
    cos_a = (len_a**2 + dist**2 - len_b**2) / (2 * len_a * dist)
    sin_a = np.sqrt(max(0.0, 1 - cos_a**2))
    w = pole - np.dot(pole, u) * u
    if np.linalg.norm(w) < 1e-9:
        w = np.cross(u, [1.0, 0.0, 0.0])
    w /= np.linalg.norm(w)
    joint = root + len_a * (cos_a * u + sin_a * w)
    return joint, root + dist * u


@dataclass(frozen=True, slots=True)
class Appearance:
    """Albedo colours, BGR floats in [0, 1]."""

    skin: np.ndarray
    hair: np.ndarray
    shirt: np.ndarray
    trousers: np.ndarray
    shoes: np.ndarray
    long_sleeves: bool


@dataclass(frozen=True, slots=True)
class Ellipsoid:
    """A renderable primitive: an ellipsoid or a box.

    centre_m : (3,) world;  axes : (3, 3) columns are unit axes in the world frame;
    radii_m : (3,) half-extents along the axes;  albedo : (3,) BGR in [0, 1];
    kind: 0 ellipsoid, 1 box; mask_class, person, part: ground-truth mask codes.
    """

    centre_m: np.ndarray
    axes: np.ndarray
    radii_m: np.ndarray
    albedo: np.ndarray
    mask_class: int
    person: int
    part: int
    kind: int = 0


def segment_ellipsoid(
    a: np.ndarray,
    b: np.ndarray,
    radius_m: float,
    albedo: np.ndarray,
    mask_class: int,
    person: int,
    part: int,
    *,
    overlap: float = 1.08,
    side: np.ndarray | None = None,
    flat: float = 1.0,
) -> Ellipsoid:
    """An elongated ellipsoid spanning segment a-b (slightly longer so joints close)."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    u = axis / length if length > 1e-9 else UP
    ref = side if side is not None else (UP if abs(u[2]) < 0.9 else np.array([1.0, 0, 0]))
    v = ref - np.dot(ref, u) * u
    v /= np.linalg.norm(v)
    w = np.cross(u, v)
    return Ellipsoid(
        0.5 * (a + b),
        np.column_stack([u, v, w]),
        np.array([0.5 * length * overlap, radius_m, radius_m * flat]),
        albedo,
        mask_class,
        person,
        part,
    )


@dataclass(frozen=True, slots=True)
class Pose:
    """One person's pose at one instant (world frame, metres)."""

    root_m: np.ndarray  # (3,) floor point under the pelvis
    yaw_rad: float
    hands_m: np.ndarray  # (2, 3) left, right hand centres (after IK clamping)
    elbows_m: np.ndarray  # (2, 3)
    wrists_m: np.ndarray  # (2, 3)
    shoulders_m: np.ndarray  # (2, 3)
    head_m: np.ndarray  # (3,) head centre
    feet_m: np.ndarray  # (2, 3) ankles
    knees_m: np.ndarray  # (2, 3)
    hips_m: np.ndarray  # (2, 3)
    hand_axes: np.ndarray  # (2, 3, 3) columns: along fingers, across palm, palm normal


def solve_pose(
    shape: BodyShape,
    root_m: np.ndarray,
    yaw_rad: float,
    hand_targets_m: np.ndarray,
    *,
    gait_phase: float = 0.0,
    gait_amp: float = 0.0,
    head_offset_m: np.ndarray | None = None,
) -> Pose:
    """Pose a person: root, facing, and targets (2, 3) for the left and right hand centres.

    ``gait_phase`` (radians) and ``gait_amp`` (0 standing, 1 walking) swing the legs.
    """
    fwd, left = body_axes(yaw_rad)
    root = np.asarray(root_m, dtype=np.float64)
    head = root + UP * shape.head_centre_height_m + 0.02 * fwd
    if head_offset_m is not None:
        head = head + head_offset_m
    shoulders = np.stack(
        [
            root
            + UP * shape.shoulder_height_m
            + s * shape.shoulder_half_width_m * left
            - 0.01 * fwd
            for s in (1.0, -1.0)
        ]
    )
    hand_part = 0.5 * shape.hand_length_m
    elbows, wrists, hands, axes = [], [], [], []
    for i, side in enumerate((1.0, -1.0)):
        pole = -UP * 1.0 + side * left * 0.6 - fwd * 0.35
        elbow, hand = two_bone_ik(
            shoulders[i], hand_targets_m[i], shape.upper_arm_m, shape.forearm_m + hand_part, pole
        )
        along = hand - elbow
        along /= np.linalg.norm(along)
        wrist = hand - hand_part * along
        # palm faces the body's side axis, turned to stay perpendicular to the fingers
        normal = left - np.dot(left, along) * along
        if np.linalg.norm(normal) < 1e-6:
            normal = fwd - np.dot(fwd, along) * along
        normal /= np.linalg.norm(normal)
        elbows.append(elbow)
        wrists.append(wrist)
        hands.append(hand)
        axes.append(np.column_stack([along, np.cross(normal, along), normal]))
    hips = np.stack(
        [root + UP * shape.hip_height_m + s * shape.hip_half_width_m * left for s in (1.0, -1.0)]
    )
    feet, knees = [], []
    for i, side in enumerate((1.0, -1.0)):
        swing = gait_amp * np.sin(gait_phase + (0.0 if side > 0 else np.pi))
        lift = (
            gait_amp
            * 0.07
            * max(0.0, np.sin(gait_phase + (0.0 if side > 0 else np.pi) + np.pi / 2))
        )
        ankle = (
            root
            + side * shape.hip_half_width_m * left
            + 0.28 * swing * fwd
            + UP * (0.045 * shape.height_m + lift)
        )
        knee, ankle = two_bone_ik(hips[i], ankle, shape.thigh_m, shape.shin_m, fwd)
        feet.append(ankle)
        knees.append(knee)
    return Pose(
        root,
        yaw_rad,
        np.stack(hands),
        np.stack(elbows),
        np.stack(wrists),
        shoulders,
        head,
        np.stack(feet),
        np.stack(knees),
        hips,
        np.stack(axes),
    )


def rest_hand_targets(
    shape: BodyShape, root_m: np.ndarray, yaw_rad: float, swing: float = 0.0
) -> np.ndarray:
    """(2, 3) hand centres hanging at the sides; ``swing`` in [-1, 1] swings the arms."""
    fwd, left = body_axes(yaw_rad)
    drop = 0.96 * shape.arm_reach_m
    out = []
    for side, sgn in ((1.0, 1.0), (-1.0, -1.0)):
        shoulder = (
            root_m + UP * shape.shoulder_height_m + side * shape.shoulder_half_width_m * left
        )
        out.append(shoulder - UP * drop + side * 0.07 * left + (0.03 + 0.16 * swing * sgn) * fwd)
    return np.stack(out)


def carry_hand_target(
    shape: BodyShape, root_m: np.ndarray, yaw_rad: float, side: float
) -> np.ndarray:
    """(3,) hand centre holding an object in front of the body, forearm forward."""
    fwd, left = body_axes(yaw_rad)
    shoulder = root_m + UP * shape.shoulder_height_m + side * shape.shoulder_half_width_m * left
    return shoulder + 0.30 * fwd - 0.36 * UP * shape.height_m / 1.75 + side * 0.03 * left


def body_primitives(
    shape: BodyShape, look: Appearance, pose: Pose, person: int
) -> list[Ellipsoid]:
    """The ellipsoids of one posed person, with ground-truth mask codes."""
    fwd, left = body_axes(pose.yaw_rad)
    s = shape.height_m / 1.75
    root = pose.root_m
    SKIN, HAIR, CLOTH = int(MaskClass.SKIN), int(MaskClass.HAIR), int(MaskClass.CLOTHING)
    body_axes_m = np.column_stack([left, fwd, UP])
    prims = [
        Ellipsoid(
            pose.head_m, body_axes_m, shape.head_radii_m, look.skin, SKIN, person, Part.HEAD
        ),
        # hair: a slightly larger cap behind and above the face
        Ellipsoid(
            pose.head_m - 0.022 * s * fwd + 0.022 * s * UP,
            body_axes_m,
            shape.head_radii_m * np.array([1.07, 0.97, 0.93]),
            look.hair,
            HAIR,
            person,
            Part.HAIR,
        ),
        Ellipsoid(
            root + UP * (0.855 * shape.height_m),
            body_axes_m,
            np.array([0.052, 0.052, 0.07]) * s,
            look.skin,
            SKIN,
            person,
            Part.NECK,
        ),
        Ellipsoid(
            root + UP * (0.69 * shape.height_m),
            body_axes_m,
            np.array([0.17, 0.11, 0.24]) * s,
            look.shirt,
            CLOTH,
            person,
            Part.TORSO,
        ),
        Ellipsoid(
            root + UP * (shape.shoulder_height_m - 0.04 * s),
            body_axes_m,
            np.array([0.205, 0.10, 0.075]) * s,
            look.shirt,
            CLOTH,
            person,
            Part.TORSO,
        ),
        Ellipsoid(
            root + UP * (0.54 * shape.height_m),
            body_axes_m,
            np.array([0.165, 0.11, 0.13]) * s,
            look.trousers,
            CLOTH,
            person,
            Part.PELVIS,
        ),
    ]
    fore_colour, fore_class = (look.shirt, CLOTH) if look.long_sleeves else (look.skin, SKIN)
    for i, (ua, fa, hp, th, sh, ft) in enumerate(
        (
            (
                Part.LEFT_UPPER_ARM,
                Part.LEFT_FOREARM,
                Part.LEFT_HAND,
                Part.LEFT_THIGH,
                Part.LEFT_SHIN,
                Part.LEFT_FOOT,
            ),
            (
                Part.RIGHT_UPPER_ARM,
                Part.RIGHT_FOREARM,
                Part.RIGHT_HAND,
                Part.RIGHT_THIGH,
                Part.RIGHT_SHIN,
                Part.RIGHT_FOOT,
            ),
        )
    ):
        prims.append(
            segment_ellipsoid(
                pose.shoulders_m[i], pose.elbows_m[i], 0.052 * s, look.shirt, CLOTH, person, ua
            )
        )
        wrist_end = pose.wrists_m[i] - 0.012 * (pose.wrists_m[i] - pose.elbows_m[i])
        prims.append(
            segment_ellipsoid(
                pose.elbows_m[i],
                wrist_end,
                0.042 * s,
                fore_colour,
                fore_class,
                person,
                fa,
                overlap=1.0,
            )
        )
        ax = pose.hand_axes[i]
        prims.append(
            Ellipsoid(
                pose.hands_m[i],
                ax,
                np.array(
                    [
                        0.5 * shape.hand_length_m,
                        0.5 * shape.hand_width_m,
                        0.5 * shape.hand_thickness_m,
                    ]
                ),
                look.skin,
                SKIN,
                person,
                hp,
            )
        )
        prims.append(
            segment_ellipsoid(
                pose.hips_m[i], pose.knees_m[i], 0.075 * s, look.trousers, CLOTH, person, th
            )
        )
        prims.append(
            segment_ellipsoid(
                pose.knees_m[i], pose.feet_m[i], 0.055 * s, look.trousers, CLOTH, person, sh
            )
        )
        foot_c = pose.feet_m[i] + 0.06 * s * fwd - UP * 0.015
        prims.append(
            Ellipsoid(
                foot_c,
                body_axes_m,
                np.array([0.045, 0.13, 0.04]) * s,
                look.shoes,
                CLOTH,
                person,
                ft,
            )
        )
    return prims
