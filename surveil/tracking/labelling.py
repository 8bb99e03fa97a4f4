"""Labelling cues: head vs hand, person grouping, left vs right, and the angle rule.

Paper 004 leaves the labelling cues to the application (section 5.2) and gives one rule,
for two targets that separate after being combined (section 7.1). The cues used here, all
pure functions of the trackers' estimates (and, when the caller has them, the candidates'
blobs), are:

**Head vs hand** -- a log-odds score (positive = head) summed from clipped cues and smoothed
over frames by the manager:

- height above the floor (heads of standing and seated people are higher than resting
  hands): ``(z - head_z_mid) / head_z_scale``;
- the body's vertical structure: another target right above (within a horizontal radius,
  0.2-1.2 m higher) means "I am a hand hanging below a head";
- position in the silhouette, when observations are given: the mean relative v of the
  candidate's two blobs (``BlobSet.rel_v``, 0 at the top of the silhouette);
- motion: hands move fast, heads slowly.

**Person grouping** -- a new head starts a new person (numbers p1, p2, ... in order of
labelling, never reused); a hand joins the nearest head within arm's reach if that head is
clearly nearer than the second nearest and the person has fewer than two hands.

**Left vs right** -- from the person's *facing direction*, accumulated over time from three
cues: the head's walking direction (people walk forwards), the hands' forward excursions
(reaching, clapping and handshakes happen in front of the body: the offset of the two hands'
midpoint from the head, along the normal of the hand-to-hand line, beyond a dead zone), and
the direction to the nearest other person (interacting people face each other). With facing
f = (fx, fy), the person's left is (-fy, fx); of two hands, the one farther left is the left
hand; a lone hand is decided by the side it is on. Left / right is decided once (when the
facing evidence is strong enough, or after a maximum wait) and then kept.

**Angle rule (section 7.1)** -- when a combined pair separates, the vector joining the two
targets just before they combined is compared with the vector joining the two modes after
separation; the tracker that was at the tail of the first vector takes the mode at the tail of
the second if the angle between them is below 90 degrees, the other mode otherwise.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from surveil.camera import Camera, Rig
from surveil.datatypes import CameraObservation, Limb
from surveil.tracking.settings import LabellingConfig
from surveil.validate import require_shape


def below_another(positions_m: np.ndarray, cfg: LabellingConfig) -> np.ndarray:
    """(T,) bool: some other target is right above this one (horizontal distance at most
    ``below_radius_m``, ``below_dz_min_m``-``below_dz_max_m`` higher).

    >>> p = np.array([[0.0, 0, 1.7], [0.1, 0.2, 0.8], [2.0, 0, 0.8]])
    >>> below_another(p, LabellingConfig()).tolist()
    [False, True, False]
    """
    require_shape("positions_m", positions_m, (None, 3), np.floating)
    dxy = np.linalg.norm(positions_m[None, :, :2] - positions_m[:, None, :2], axis=2)
    dz = positions_m[None, :, 2] - positions_m[:, None, 2]  # [i, j]: how much j is above i
    above = (dxy <= cfg.below_radius_m) & (dz >= cfg.below_dz_min_m) & (dz <= cfg.below_dz_max_m)
    np.fill_diagonal(above, False)
    return above.any(axis=1)


def head_log_odds(
    z_m: np.ndarray,
    speed_mps: np.ndarray,
    below: np.ndarray,
    rel_v: np.ndarray,
    cfg: LabellingConfig,
) -> np.ndarray:
    """Per-frame log-odds that each target is a head rather than a hand (sum of clipped cues).

    Parameters
    ----------
    z_m : (T,) float64
        Height above the floor, metres.
    speed_mps : (T,) float64
        Smoothed speed, m/s.
    below : (T,) bool
        Another target is right above (:func:`below_another`).
    rel_v : (T,) float64
        Mean relative v of the supporting blobs in their silhouettes (0 top, 1 bottom); NaN
        where unknown (no observations).
    cfg : LabellingConfig

    Returns
    -------
    (T,) float64

    Examples
    --------
    >>> cfg = LabellingConfig()
    >>> head_log_odds(np.array([1.7, 0.8]), np.zeros(2), np.array([False, True]),
    ...               np.full(2, np.nan), cfg).tolist()
    [3.0, -6.0]
    """
    c = cfg.cue_clip
    llr = np.clip((np.asarray(z_m) - cfg.head_z_mid_m) / cfg.head_z_scale_m, -c, c)
    llr = llr - np.where(below, cfg.below_llr, 0.0)
    llr = llr - np.where(np.asarray(speed_mps) > cfg.hand_speed_mps, cfg.speed_llr, 0.0)
    rel_v = np.asarray(rel_v, dtype=np.float64)
    sil = np.clip((cfg.rel_v_mid - rel_v) / cfg.rel_v_scale, -c, c)
    return llr + np.where(np.isfinite(sil), sil, 0.0)


def body_support(
    head_m: np.ndarray,
    rig: Rig,
    observations: Mapping[str, CameraObservation],
    cfg: LabellingConfig,
) -> float | None:
    """Fraction of the cameras seeing the column under a head in which it lies inside a
    silhouette (within ``body_tolerance_px``); None when fewer than two cameras see it.

    A head stands on a body: the points at ``body_heights`` (fractions of the head's height
    above the floor) under it project into person silhouettes in every camera. A ghost head
    (two heads' lines of sight crossing between two people, a mismatched blob pair) floats
    over empty floor, which some camera sees as background.

    Parameters
    ----------
    head_m : (3,) float64 -- world frame, z up from the floor, m
    rig : Rig
    observations : Mapping[str, CameraObservation] -- this frame set's, by camera name
    cfg : LabellingConfig
    """
    head_m = np.asarray(head_m, dtype=np.float64)
    column = np.repeat(head_m[None], len(cfg.body_heights), axis=0)
    column[:, 2] = head_m[2] * np.asarray(cfg.body_heights, dtype=np.float64)
    seeing = supported = 0
    for name, obs in observations.items():
        if name not in rig.names:
            continue
        cam = rig[name]
        px, depth = cam.project(column)
        if not cam.in_image(px, depth).all():
            continue
        dist = obs.silhouettes.dist_outside_px
        h, w = dist.shape
        u = np.clip(np.round(px[:, 0] * w / cam.width).astype(int), 0, w - 1)
        v = np.clip(np.round(px[:, 1] * h / cam.height).astype(int), 0, h - 1)
        seeing += 1
        supported += int((dist[v, u] * cam.width / w <= cfg.body_tolerance_px).all())
    return supported / seeing if seeing >= 2 else None


def nearest_person(
    hand_m: np.ndarray, heads_m: np.ndarray, n_hands: np.ndarray, cfg: LabellingConfig
) -> int:
    """Index of the person (head) a hand belongs to, or -1 if none is clear.

    The nearest head must be within ``arm_reach_m`` (3-D), at least ``person_margin_m``
    nearer than the second nearest head, and its person must have fewer than two hands.

    Parameters
    ----------
    hand_m : (3,) float64
    heads_m : (P, 3) float64
    n_hands : (P,) int -- hands each person already has
    cfg : LabellingConfig

    Examples
    --------
    >>> heads = np.array([[0.0, 0, 1.7], [1.0, 0, 1.7]])
    >>> nearest_person(np.array([0.1, 0.25, 0.9]), heads, np.array([0, 0]), LabellingConfig())
    0
    """
    if len(heads_m) == 0:
        return -1
    d = np.linalg.norm(heads_m - hand_m, axis=1)
    order = np.argsort(d)
    best = int(order[0])
    if d[best] > cfg.arm_reach_m or n_hands[best] >= 2:
        return -1
    if len(d) > 1 and d[order[1]] - d[best] < cfg.person_margin_m:
        return -1
    return best


def left_axis(facing_xy: np.ndarray) -> np.ndarray:
    """(2,) unit vector to the left of a facing direction (Z up): (-fy, fx).

    >>> left_axis(np.array([1.0, 0.0])).tolist()
    [-0.0, 1.0]
    """
    f = np.asarray(facing_xy, dtype=np.float64)
    n = np.linalg.norm(f)
    f = f / n if n > 0 else np.array([1.0, 0.0])
    return np.array([-f[1], f[0]])


def lateral_offsets_m(
    hands_m: np.ndarray, head_m: np.ndarray, facing_xy: np.ndarray
) -> np.ndarray:
    """(H,) how far each hand is to the person's left of the head (negative = right), m."""
    return (np.asarray(hands_m)[:, :2] - np.asarray(head_m)[:2]) @ left_axis(facing_xy)


def across_body(
    hands_m: np.ndarray,
    challenger_m: np.ndarray,
    head_m: np.ndarray,
    facing_xy: np.ndarray,
    side_m: float,
) -> np.ndarray:
    """(H,) bool: each hand is on the other side of the person from ``challenger_m``, both
    at least ``side_m`` to their side of the head (False for all when ``side_m`` is 0).

    A hand tracker to a person's right is not their left hand, however well two views see
    it: a shirt region by the right elbow, as strong as a hand, must not take the slot of
    a left hand that holds a ball out in front (three_people).

    >>> hands = np.array([[0.0, 0.25, 0.8], [0.0, -0.2, 0.8], [0.0, 0.05, 0.8]])
    >>> across_body(hands, np.array([0.0, -0.3, 1.0]), np.zeros(3), np.array([1.0, 0]), 0.1)
    array([ True, False, False])
    """
    hands_m = np.asarray(hands_m, dtype=np.float64)
    require_shape("hands_m", hands_m, (None, 3), np.floating)
    if side_m <= 0:
        return np.zeros(len(hands_m), dtype=bool)
    lat = lateral_offsets_m(hands_m, head_m, facing_xy)
    lat_c = float(lateral_offsets_m(np.asarray(challenger_m)[None], head_m, facing_xy)[0])
    if abs(lat_c) < side_m:
        return np.zeros(len(hands_m), dtype=bool)
    return (np.sign(lat) == -np.sign(lat_c)) & (np.abs(lat) >= side_m)


def decide_left_right(
    hands_m: np.ndarray, head_m: np.ndarray, facing_xy: np.ndarray
) -> tuple[Limb, ...]:
    """Left / right for one or two hands of a person facing ``facing_xy``.

    Two hands: the one farther to the left is the left hand. One hand: the side it is on.

    Parameters
    ----------
    hands_m : (H, 3) float64, H in {1, 2}
    head_m : (3,) float64
    facing_xy : (2,) float64 -- horizontal facing direction (need not be unit)

    Returns
    -------
    tuple of Limb, one per hand

    Examples
    --------
    >>> hands = np.array([[0.0, -0.25, 0.8], [0.0, 0.25, 0.8]])
    >>> decide_left_right(hands, np.array([0.0, 0, 1.7]), np.array([1.0, 0]))
    (<Limb.RIGHT_HAND: 2>, <Limb.LEFT_HAND: 1>)
    """
    hands_m = np.asarray(hands_m, dtype=np.float64)
    require_shape("hands_m", hands_m, (None, 3), np.floating)
    lat = lateral_offsets_m(hands_m, head_m, facing_xy)
    if len(hands_m) == 1:
        return (Limb.LEFT_HAND if lat[0] >= 0 else Limb.RIGHT_HAND,)
    if len(hands_m) == 2:
        left_first = lat[0] >= lat[1]
        return (
            (Limb.LEFT_HAND, Limb.RIGHT_HAND) if left_first else (Limb.RIGHT_HAND, Limb.LEFT_HAND)
        )
    raise ValueError(f"hands_m must hold 1 or 2 hands, got {len(hands_m)}")


def facing_cues(
    head_m: np.ndarray,
    head_velocity_mps: np.ndarray,
    hands_m: np.ndarray,
    other_heads_m: np.ndarray,
    cfg: LabellingConfig,
) -> np.ndarray:
    """One frame's horizontal facing evidence (2,) for one person (added to a decaying sum).

    Cues (see the module docstring): walking direction (unit, weight 0.3 when the head moves
    faster than ``walk_speed_mps``); the two hands' forward excursion (unit normal of the
    hand-to-hand line towards their midpoint, weight growing from 0 at 5 cm to 1 at 15 cm of
    offset); the direction to the nearest other head within ``social_range_m`` (weight
    ``social_weight``).

    Parameters
    ----------
    head_m : (3,) float64
    head_velocity_mps : (3,) float64
    hands_m : (H, 3) float64 -- the person's hands (0, 1 or 2)
    other_heads_m : (P, 3) float64 -- other people's heads
    cfg : LabellingConfig

    Returns
    -------
    (2,) float64

    Examples
    --------
    >>> hands = np.array([[0.4, -0.1, 1.1], [0.4, 0.1, 1.1]])   # clapping in front (+x)
    >>> facing_cues(np.array([0.0, 0, 1.7]), np.zeros(3), hands, np.zeros((0, 3)),
    ...             LabellingConfig()).round(3).tolist()
    [1.0, 0.0]
    """
    ev = np.zeros(2)
    v = np.asarray(head_velocity_mps, dtype=np.float64)[:2]
    speed = float(np.linalg.norm(v))
    if speed > cfg.walk_speed_mps:
        ev += 0.3 * v / speed
    hands_m = np.asarray(hands_m, dtype=np.float64).reshape(-1, 3)
    if len(hands_m) == 2:
        across = hands_m[0, :2] - hands_m[1, :2]
        n_across = float(np.linalg.norm(across))
        mid = hands_m[:, :2].mean(axis=0) - head_m[:2]
        if n_across > 1e-3:
            normal = np.array([-across[1], across[0]]) / n_across
            fwd = float(mid @ normal)
        else:  # hands together: the midpoint offset itself
            n_mid = float(np.linalg.norm(mid))
            normal = mid / n_mid if n_mid > 0 else np.zeros(2)
            fwd = n_mid
        ev += np.sign(fwd) * normal * np.clip((abs(fwd) - 0.05) / 0.1, 0.0, 1.0)
    others = np.asarray(other_heads_m, dtype=np.float64).reshape(-1, 3)
    if len(others):
        d = others[:, :2] - head_m[:2]
        dist = np.linalg.norm(d, axis=1)
        k = int(np.argmin(dist))
        if 1e-6 < dist[k] <= cfg.social_range_m:
            ev += cfg.social_weight * d[k] / dist[k]
    return ev


def head_skin_share(
    head_m: np.ndarray, observation: CameraObservation, camera: Camera, radius_m: float
) -> float:
    """Share of skin pixels (``observation.skin``) in the square of half-side ``radius_m``,
    at the head's depth, around the head's projection into ``camera``: about half for a
    face seen from the front, a little neck from behind (hair), in between from the side.
    NaN where it says nothing: the head behind the camera, its square not wholly in the
    image, or its projection off every silhouette.
    """
    px, depth = camera.project(np.asarray(head_m, dtype=np.float64)[None])
    if depth[0] <= 0:
        return float("nan")
    u, v = px[0]
    r = radius_m * float(camera.K[0, 0]) / depth[0]
    h, w = observation.skin.shape
    u0, u1 = round(u - r), round(u + r) + 1
    v0, v1 = round(v - r), round(v + r) + 1
    if u0 < 0 or v0 < 0 or u1 > w or v1 > h:
        return float("nan")
    if observation.silhouettes.labels[round(v), round(u)] == 0:
        return float("nan")
    return float(observation.skin[v0:v1, u0:u1].mean())


def face_cue(
    head_m: np.ndarray, cameras_m: np.ndarray, skin_shares: np.ndarray, weight: float
) -> np.ndarray:
    """One frame's facing evidence (2,) from where the face is seen.

    Each camera's skin share around the head (:func:`head_skin_share`; NaN = none) is
    modelled as ``a + b . d`` with ``d`` the horizontal unit vector from the head to the
    camera: most skin where the face looks, least from behind (hair). ``b`` is fitted by
    least squares over the cameras (three or more; with two, the least ``b`` along the line
    between them that explains their difference) and returned times ``weight``, its length
    capped at ``weight``. The fit, not a plain sum of ``share * d``, because a person near a
    wall has most cameras on one side. A head that looks the same from everywhere (a bald
    head, skin missed in every view) gives ~0; so does a single camera.

    >>> head = np.array([0.0, 0.0, 1.7])
    >>> cams = np.array([[3.0, 0, 2.5], [-3.0, 0, 2.5], [0, 3.0, 2.5]])
    >>> face_cue(head, cams, np.array([0.5, 0.1, 0.3]), 1.0).round(3).tolist()
    [0.2, 0.0]
    """
    ok = np.isfinite(skin_shares)
    if ok.sum() < 2 or weight <= 0:
        return np.zeros(2)
    to_cam = np.asarray(cameras_m, dtype=np.float64)[ok, :2] - np.asarray(head_m)[:2]
    to_cam /= np.maximum(np.linalg.norm(to_cam, axis=1, keepdims=True), 1e-9)
    s = skin_shares[ok]
    if len(s) == 2:
        across = to_cam[0] - to_cam[1]
        b = (s[0] - s[1]) * across / max(float(across @ across), 1e-9)
    else:
        design = np.column_stack([np.ones(len(s)), to_cam])
        b = np.linalg.lstsq(design, s, rcond=None)[0][1:]
    length = float(np.linalg.norm(b))
    return weight * (b if length <= 1.0 else b / length)


def owner_rule(
    modes_m: np.ndarray, heads_m: np.ndarray, margin_m: float
) -> tuple[tuple[int, int], float] | None:
    """Which mode each of two separating hands of different people takes, by their owners.

    Each hand goes back to its own body: of the two ways to give the modes to the hands, the
    one with the smaller summed distance from each mode to its hand's head wins, if it is at
    least ``margin_m`` smaller. Where it applies, this is stronger evidence than the angle
    rule, which guesses when the hands part across the line they came along (a handshake
    whose pair follows one hand sideways gives angles near 90 degrees).

    Parameters
    ----------
    modes_m : (2, 3) float64 -- the two modes, metres
    heads_m : (2, 3) float64 -- the heads of hand A's and hand B's people
    margin_m : float -- how much better the winning assignment must be, metres

    Returns
    -------
    ((mode of A, mode of B), gain_m) or None
        ``gain_m`` is how much shorter the winning assignment is; None when it is shorter
        by less than ``margin_m``.

    Examples
    --------
    >>> heads = np.array([[0.0, 0, 1.7], [1.2, 0, 1.7]])
    >>> owner_rule(np.array([[1.0, 0, 1.0], [0.2, 0, 1.0]]), heads, 0.2)[0]
    (1, 0)
    """
    d = np.linalg.norm(
        np.asarray(modes_m, dtype=np.float64)[:, None] - np.asarray(heads_m)[None], axis=2
    )
    straight = d[0, 0] + d[1, 1]  # A takes mode 0, B mode 1
    crossed = d[1, 0] + d[0, 1]
    gain = float(abs(straight - crossed))
    if gain < margin_m:
        return None
    return ((0, 1) if straight < crossed else (1, 0)), gain


def astray(
    hand_m: np.ndarray, own_head_m: np.ndarray, other_heads_m: np.ndarray, cfg: LabellingConfig
) -> bool:
    """Whether a person's hand is out of their reach and within another person's.

    True when the hand is farther than ``arm_reach_m`` + ``person_margin_m`` from its own
    head (beyond any reach, with room for a tall person and estimation error; a hand held
    out to shake another's can be just beyond ``arm_reach_m``) and some other head is within
    ``arm_reach_m`` and at least ``person_margin_m`` nearer (3-D distances): the label went
    with the wrong target (a pair parted the wrong way round), since a hand cannot leave its
    body.

    Parameters
    ----------
    hand_m, own_head_m : (3,) float64
    other_heads_m : (P, 3) float64 -- the other people's heads
    cfg : LabellingConfig

    Examples
    --------
    >>> heads = np.array([[1.2, 0, 1.6]])
    >>> astray(np.array([1.1, 0.2, 0.8]), np.array([0.0, 0, 1.6]), heads, LabellingConfig())
    True
    >>> astray(np.array([0.6, 0.0, 1.0]), np.array([0.0, 0, 1.6]), heads, LabellingConfig())
    False
    """
    own = float(np.linalg.norm(np.asarray(hand_m) - own_head_m))
    if own <= cfg.arm_reach_m + cfg.person_margin_m or len(other_heads_m) == 0:
        return False
    other = float(np.min(np.linalg.norm(np.asarray(other_heads_m) - hand_m, axis=1)))
    return other <= cfg.arm_reach_m and other <= own - cfg.person_margin_m


def owned_elsewhere(
    holder_m: np.ndarray,
    challenger_m: np.ndarray,
    heads_m: np.ndarray,
    person: int,
    cfg: LabellingConfig,
) -> bool:
    """Whether a hand holding person ``person``'s slot looks like another person's, next to a
    challenger that looks like ``person``'s own.

    Ownership of a point x is s(x) = d(x, own head) - d(x, nearest other head) (3-D
    distances; negative: nearer its own). True when the holder is at least
    ``person_margin_m`` nearer another head (s >= margin) and the challenger's s is lower by
    at least twice that. A hand held out to another person is about midway (s near 0); a
    ghost in front of the other body is not, and a real hand, hanging or raised, has s well
    below 0.

    Parameters
    ----------
    holder_m, challenger_m : (3,) float64
    heads_m : (P, 3) float64 -- every person's head
    person : int -- index of the holder's person in ``heads_m``
    cfg : LabellingConfig

    Examples
    --------
    >>> heads = np.array([[1.7, 3.2, 1.7], [2.6, 3.2, 1.6]])
    >>> owned_elsewhere(np.array([2.39, 3.18, 0.93]), np.array([1.98, 3.42, 1.11]), heads, 0,
    ...                 LabellingConfig())
    True
    >>> owned_elsewhere(np.array([2.15, 3.2, 1.1]), np.array([1.98, 3.42, 1.11]), heads, 0,
    ...                 LabellingConfig())
    False
    """
    heads_m = np.asarray(heads_m, dtype=np.float64)
    if len(heads_m) < 2:
        return False
    others = np.delete(heads_m, person, axis=0)

    def ownership(x: np.ndarray) -> float:
        x = np.asarray(x, dtype=np.float64)
        own = float(np.linalg.norm(heads_m[person] - x))
        return own - float(np.linalg.norm(others - x, axis=1).min())

    s_holder = ownership(holder_m)
    margin = cfg.person_margin_m
    return s_holder >= margin and ownership(challenger_m) <= s_holder - 2 * margin


def angle_rule(
    before_a_to_b_m: np.ndarray, mode0_m: np.ndarray, mode1_m: np.ndarray
) -> tuple[tuple[int, int], float]:
    """Which mode each tracker of a separating pair takes (paper 004 section 7.1).

    Before joining, tracker A was at p_A and tracker B at p_B: v_before = p_B - p_A. After
    separating, the modes are m0 and m1: v_after = m1 - m0. If the angle between v_before and
    v_after is at most 90 degrees A takes m0 and B takes m1, otherwise A takes m1 and B m0.

    Parameters
    ----------
    before_a_to_b_m : (3,) float64 -- v_before, metres
    mode0_m, mode1_m : (3,) float64

    Returns
    -------
    (mode of A, mode of B) : tuple[int, int]
    angle_rad : float
        The angle between v_before and v_after, radians (pi/2 when either is zero).

    Examples
    --------
    >>> angle_rule(np.array([0.2, 0, 0]), np.array([0.1, 0, 0]), np.array([-0.1, 0, 0]))[0]
    (1, 0)
    """
    v0 = np.asarray(before_a_to_b_m, dtype=np.float64)
    v1 = np.asarray(mode1_m, dtype=np.float64) - np.asarray(mode0_m, dtype=np.float64)
    n = float(np.linalg.norm(v0) * np.linalg.norm(v1))
    angle = float(np.arccos(np.clip(v0 @ v1 / n, -1.0, 1.0))) if n > 0 else np.pi / 2
    return ((0, 1) if angle <= np.pi / 2 else (1, 0)), angle
