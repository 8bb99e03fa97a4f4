"""The arm model of paper 001: a rigid upright body turned by phi, two 4-DoF arms.

Pure functions, vectorised over any leading shape. World frame Z up, metres, radians.

Body. The body is rigid and stands upright under the tracked head (paper 001 section IV:
"a rigid human body located on the ground plane at the locations constrained by the 3D
coordinates of the head"); its one free parameter is the facing ``phi`` about the vertical
(0 = facing +X, counter-clockwise). The stature follows from the head centre's height and
the limb lengths from the stature by anthropometric ratios (Drillis and Contini's segment
lengths as fractions of the stature H: upper arm 0.186 H, forearm 0.146 H, hand 0.108 H,
shoulder joint height 0.818 H; head centre at 0.936 H; shoulder joint centres 0.21 H apart).

Arm. Four angles per arm, the degrees of freedom of paper 001's Denavit-Hartenberg chain
(its Table 1), written as rotations in the body frame (forward, left, up) instead of DH
matrices, which gives the same joint positions for the same four rotations:

- ``flexion``: the upper arm swings forward and up about the shoulders' axis (0 = hanging,
  pi/2 = pointing forward);
- ``abduction``: the upper arm swings outward about the forward axis (pi/2 = pointing
  sideways, away from the body, for either arm);
- ``twist``: the upper arm turns about its own axis (rotates the plane the elbow bends in;
  0 = the forearm bends forward, positive = towards the body's midline);
- ``elbow``: flexion of the elbow (0 = straight).

The hand point is the hand's centre, ``forearm + hand / 2`` beyond the elbow along the
forearm: the point the 3D tracker and the ground truth call the hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# anthropometric ratios (fractions of the stature)
HEAD_CENTRE_REL = 0.936
SHOULDER_HEIGHT_REL = 0.818
SHOULDER_HALF_WIDTH_REL = 0.105
UPPER_ARM_REL = 0.186
FOREARM_REL = 0.146
HAND_REL = 0.108
# the head's centre sits a little in front of the shoulder joints (m)
HEAD_AHEAD_OF_SHOULDERS_M = 0.02

N_ANGLES = 4
#: (4, 2) lower and upper joint limits, radians: flexion, abduction, twist, elbow
JOINT_LIMITS = np.deg2rad(
    np.array([[-50.0, 180.0], [-45.0, 180.0], [-135.0, 135.0], [0.0, 160.0]])
)
#: side of each arm: +1 left, -1 right (index 0 = left arm, 1 = right arm)
SIDES = np.array([1.0, -1.0])


@dataclass(frozen=True, slots=True)
class ArmShape:
    """Lengths of one person's arms, metres, from the stature."""

    stature_m: float
    upper_arm_m: float
    forearm_to_hand_m: float  # elbow to hand centre
    shoulder_drop_m: float  # head centre to shoulder joints, vertically
    shoulder_half_width_m: float

    @classmethod
    def from_head_height(cls, head_centre_z_m: float) -> ArmShape:
        """Anthropometric arm of a person standing upright with the head centre this high.

        >>> s = ArmShape.from_head_height(1.638)
        >>> round(s.stature_m, 3), round(s.upper_arm_m, 3)
        (1.75, 0.325)
        """
        h = float(head_centre_z_m) / HEAD_CENTRE_REL
        return cls(
            stature_m=h,
            upper_arm_m=UPPER_ARM_REL * h,
            forearm_to_hand_m=(FOREARM_REL + 0.5 * HAND_REL) * h,
            shoulder_drop_m=(HEAD_CENTRE_REL - SHOULDER_HEIGHT_REL) * h,
            shoulder_half_width_m=SHOULDER_HALF_WIDTH_REL * h,
        )

    @property
    def reach_m(self) -> float:
        """Shoulder to hand centre with the arm straight."""
        return self.upper_arm_m + self.forearm_to_hand_m


def body_axes(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(..., 3) forward and left unit vectors of bodies facing ``phi`` (...,)."""
    c, s = np.cos(phi), np.sin(phi)
    z = np.zeros_like(c)
    return np.stack([c, s, z], axis=-1), np.stack([-s, c, z], axis=-1)


def shoulders_m(head_m: np.ndarray, phi: np.ndarray, shape: ArmShape) -> np.ndarray:
    """(..., 2, 3) left and right shoulder joints of a body under ``head_m`` (3,) facing
    ``phi`` (...,).

    >>> shape = ArmShape.from_head_height(1.638)
    >>> shoulders_m(np.array([0.0, 0, 1.638]), np.array(0.0), shape).round(3).tolist()
    [[-0.02, 0.184, 1.431], [-0.02, -0.184, 1.431]]
    """
    fwd, left = body_axes(np.asarray(phi, dtype=np.float64))
    centre = np.asarray(head_m, dtype=np.float64) - HEAD_AHEAD_OF_SHOULDERS_M * fwd
    centre = centre + np.array([0.0, 0.0, -shape.shoulder_drop_m])
    lateral = shape.shoulder_half_width_m * left[..., None, :] * SIDES[:, None]
    return centre[..., None, :] + lateral


def arm_directions(
    angles: np.ndarray, phi: np.ndarray, side: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions (..., 3) of the upper arm and the forearm, world frame.

    angles : (..., 4) flexion, abduction, twist, elbow (radians)
    phi : (...,) body facing;  side : (...,) +1 left arm, -1 right arm
    """
    flex, abd, twist, elbow = np.moveaxis(np.asarray(angles, dtype=np.float64), -1, 0)
    side = np.asarray(side, dtype=np.float64)
    sf, cf = np.sin(flex), np.cos(flex)
    sa, ca = np.sin(abd), np.cos(abd)
    # body frame (forward, left, up): the hanging arm (0, 0, -1) turned outward about the
    # forward axis by side * abduction, then forward about the shoulders' axis by flexion
    u = np.stack([ca * sf, side * sa, -ca * cf], axis=-1)
    # "forward" carried by the same two rotations (orthogonal to u): the elbow's bending
    # direction at twist 0, then turned about u by the twist (Rodrigues, n0 _|_ u)
    n0 = np.stack([cf, np.zeros_like(cf), sf], axis=-1)
    # (times side, so that a positive twist turns either forearm towards the body's midline)
    n = np.cos(twist)[..., None] * n0 + (side * np.sin(twist))[..., None] * np.cross(u, n0)
    f = np.cos(elbow)[..., None] * u + np.sin(elbow)[..., None] * n
    fwd, left = body_axes(np.asarray(phi, dtype=np.float64))
    up = np.array([0.0, 0.0, 1.0])

    def world(v: np.ndarray) -> np.ndarray:
        return v[..., 0:1] * fwd + v[..., 1:2] * left + v[..., 2:3] * up

    return world(u), world(f)


def arm_joints_m(
    shoulder_m: np.ndarray,
    angles: np.ndarray,
    phi: np.ndarray,
    side: np.ndarray,
    shape: ArmShape,
) -> tuple[np.ndarray, np.ndarray]:
    """Elbow and hand centre (..., 3) of arms at ``shoulder_m`` (..., 3) with ``angles``
    (..., 4) on bodies facing ``phi`` (...,); ``side`` (...,) +1 left, -1 right.

    >>> z = np.zeros(4)
    >>> shape = ArmShape.from_head_height(1.638)
    >>> e, h = arm_joints_m(np.zeros(3), z, np.array(0.0), np.array(1.0), shape)
    >>> e.round(3).tolist(), h.round(3).tolist()  # hanging straight down
    ([0.0, 0.0, -0.325], [0.0, 0.0, -0.675])
    """
    u, f = arm_directions(angles, phi, side)
    elbow = shoulder_m + shape.upper_arm_m * u
    return elbow, elbow + shape.forearm_to_hand_m * f


def clip_to_limits(angles: np.ndarray) -> np.ndarray:
    """Reflect (..., 4) angles back inside :data:`JOINT_LIMITS` (a random walk that steps
    over a limit bounces off it instead of piling up on it)."""
    lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
    a = np.where(angles < lo, 2 * lo - angles, angles)
    a = np.where(a > hi, 2 * hi - a, a)
    return np.clip(a, lo, hi)


def ik_angles(
    shoulder_m: np.ndarray,
    hand_m: np.ndarray,
    phi: np.ndarray,
    side: np.ndarray,
    shape: ArmShape,
    swivel_rad: np.ndarray,
) -> np.ndarray:
    """Angles (..., 4) of arms whose hand centre reaches ``hand_m`` (..., 3) from
    ``shoulder_m`` (..., 3): inverse kinematics, the inverse of :func:`arm_joints_m`.

    The elbow lies on a circle about the shoulder-hand axis; ``swivel_rad`` (...,) turns it
    away from its natural place (down, out and back, where a relaxed elbow hangs). Targets
    out of reach are pulled in to the arm's reach (and pushed out of the shoulder), and the
    angles clipped to the joint limits.

    >>> shape = ArmShape.from_head_height(1.6)
    >>> a = np.deg2rad([40.0, 20.0, 10.0, 60.0])
    >>> _, hand = arm_joints_m(np.zeros(3), a, np.float64(0.3), np.float64(1.0), shape)
    >>> b = ik_angles(np.zeros(3), hand, np.float64(0.3), np.float64(1.0), shape, np.float64(0))
    >>> _, again = arm_joints_m(np.zeros(3), b, np.float64(0.3), np.float64(1.0), shape)
    >>> bool(np.allclose(again, hand))
    True
    """
    l1, l2 = shape.upper_arm_m, shape.forearm_to_hand_m
    side = np.asarray(side, dtype=np.float64)
    fwd, left = body_axes(np.asarray(phi, dtype=np.float64))
    up = np.array([0.0, 0.0, 1.0])
    d = np.asarray(hand_m, dtype=np.float64) - shoulder_m
    dist = np.linalg.norm(d, axis=-1, keepdims=True)
    axis = d / np.maximum(dist, 1e-9)
    dist = np.clip(dist, abs(l1 - l2) + 1e-3, (l1 + l2) * 0.999)
    along = (l1 * l1 - l2 * l2 + dist * dist) / (2 * dist)
    radius = np.sqrt(np.maximum(l1 * l1 - along * along, 0.0))
    pole = -up + 0.6 * side[..., None] * left - 0.35 * fwd
    e1 = pole - np.sum(pole * axis, axis=-1, keepdims=True) * axis
    e1_norm = np.linalg.norm(e1, axis=-1, keepdims=True)
    # a target straight down the pole: any perpendicular will do
    e1 = np.where(e1_norm > 1e-6, e1 / np.maximum(e1_norm, 1e-9), np.cross(axis, fwd))
    e2 = np.cross(axis, e1)
    sw = np.asarray(swivel_rad, dtype=np.float64)[..., None]
    elbow = shoulder_m + along * axis + radius * (np.cos(sw) * e1 + np.sin(sw) * e2)
    hand = shoulder_m + dist * axis
    u = (elbow - shoulder_m) / l1
    f = (hand - elbow) / l2

    def body(v: np.ndarray) -> np.ndarray:
        return np.stack([np.sum(v * fwd, axis=-1), np.sum(v * left, axis=-1), v[..., 2]], axis=-1)

    ub, fb = body(u), body(f)
    abd = np.arcsin(np.clip(side * ub[..., 1], -1.0, 1.0))
    flex = np.arctan2(ub[..., 0], -ub[..., 2])
    # the same upper arm is also (flex + pi, pi - abd): take it where flex is out of range
    flip = flex < JOINT_LIMITS[0, 0]
    flex = np.where(flip, flex + np.pi, flex)
    abd = np.where(flip, np.pi - abd, abd)
    n0 = np.stack([np.cos(flex), np.zeros_like(flex), np.sin(flex)], axis=-1)
    m0 = np.cross(ub, n0)
    cos_e = np.sum(fb * ub, axis=-1)
    perp = fb - cos_e[..., None] * ub
    elbow_angle = np.arctan2(np.linalg.norm(perp, axis=-1), cos_e)
    twist = np.arctan2(side * np.sum(perp * m0, axis=-1), np.sum(perp * n0, axis=-1))
    return clip_to_limits(np.stack([flex, abd, twist, elbow_angle], axis=-1))
