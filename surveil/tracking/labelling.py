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
facing evidence is strong enough, or after a maximum wait) and revised only when the facing
says for a while that they are swapped. Where the face is seen adds a cue (:func:`face_cue`).
The angle of the facing comes from the *body axis* once that is known: the silhouettes'
widths across the shoulders in three or more views (:func:`silhouette_width_m`,
:func:`body_axis_cue`); the cues above give only its sign (:func:`facing_on_axis`).

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


def same_side(
    a_m: np.ndarray,
    b_m: np.ndarray,
    head_m: np.ndarray,
    facing_xy: np.ndarray,
    side_m: float,
) -> bool:
    """Whether two points are both at least ``side_m`` to the same side of a person's head
    (along the facing direction's left axis; False when ``side_m`` is 0).

    Two hands of one person on one side of the body, one above the other, are rarely both
    hands: the upper one is a shirt region by the elbow (three_people: the colour fringe
    where a hanging red sleeve meets the wall seen between arm and body, 25 cm above the
    hand, seen alike by every camera).

    >>> head, facing = np.array([0.0, 0.0, 1.7]), np.array([1.0, 0.0])
    >>> same_side(np.array([0.0, -0.27, 0.8]), np.array([0.0, -0.25, 1.05]), head, facing, 0.1)
    True
    >>> same_side(np.array([0.0, -0.27, 0.8]), np.array([0.0, 0.2, 1.05]), head, facing, 0.1)
    False
    """
    if side_m <= 0:
        return False
    lat = lateral_offsets_m(np.array([a_m, b_m], dtype=np.float64), head_m, facing_xy)
    return bool(np.all(np.abs(lat) >= side_m) and np.sign(lat[0]) == np.sign(lat[1]))


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


# two hands nearer than this (3D) are together: their midpoint's offset from the head is
# the forward excursion; farther apart they must lie more across than one above the other
# for the normal of the line between them to say where the front is, m
HANDS_TOGETHER_M = 0.1


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
    offset; no hand cue for two hands one above the other, more than
    :data:`HANDS_TOGETHER_M` apart and less across); the direction to the nearest other
    head within ``social_range_m`` (weight ``social_weight``).

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
        apart = hands_m[0] - hands_m[1]
        n_across = float(np.linalg.norm(apart[:2]))
        mid = hands_m[:, :2].mean(axis=0) - head_m[:2]
        fwd, normal = 0.0, np.zeros(2)
        if n_across >= max(HANDS_TOGETHER_M, abs(apart[2])):
            normal = np.array([-apart[1], apart[0]]) / n_across
            fwd = float(mid @ normal)
        elif np.linalg.norm(apart) < HANDS_TOGETHER_M:  # the midpoint offset itself
            fwd = float(np.linalg.norm(mid))
            normal = mid / fwd if fwd > 0 else normal
        # else one above the other (a hand and a point by its elbow): no side to face
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
    """Share of skin pixels (``observation.skin``) among the person's (silhouette) pixels
    in the square of half-side ``radius_m``, at the head's depth, around the head's
    projection into ``camera``: about half for a face seen from the front, a little neck
    from behind (hair), in between from the side. Skin-coloured scenery beside the head (a
    cork board on the wall behind it) is not counted. NaN where it says nothing: the head
    behind the camera, its square not wholly in the image, or its projection off every
    silhouette.
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
    person = observation.silhouettes.labels[v0:v1, u0:u1] > 0
    face = observation.skin[v0:v1, u0:u1] & person
    return np.count_nonzero(face) / np.count_nonzero(person)


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


# least spread of the views' doubled viewing angles (smallest eigenvalue of their
# covariance, 0-0.5) for a full fit of the width model; below it the views are degenerate
# (measured: 0.001 with four corner cameras and a person in the middle, 0.01-0.37 elsewhere)
AXIS_SPREAD_MIN = 0.005

# a side of a silhouette's run that comes this near another person's body axis measures
# that body too, m (the other head's tracking error, a neck; benchmarks/facing_bench.py on
# three_people: any value 0-0.15 gives the same, 0.25 loses half-widths that were right)
OTHER_BODY_CORE_M = 0.1

# rows below the head centre where the shoulders and upper chest are, for people of
# 1.5-1.9 m standing or seated: a body is widest across them and shallowest front to back
BODY_AXIS_DROPS_M = (0.22, 0.28, 0.34)


def silhouette_width_m(
    labels: np.ndarray,
    camera: Camera,
    points_m: np.ndarray,
    max_width_m: float,
    others_m: np.ndarray | None = None,
) -> float:
    """How wide the silhouette under ``points_m`` is in ``camera``, metres: the median over
    the points of the run of the point's silhouette along its image row, scaled by the
    point's depth. Where one side of the run comes within :data:`OTHER_BODY_CORE_M` of
    another person's body axis (two silhouettes merged, or one person in front of the
    other), the width is twice the other side's half, from the point to its edge. NaN
    unless two or more points give a width: a point behind the camera, off the image or off
    every silhouette gives none, and so does a run that reaches the image border (the body
    is cut), is wider than ``max_width_m`` or comes near other bodies on both sides.

    Parameters
    ----------
    labels : (H, W) int -- silhouette labels (``Silhouettes.labels``; 0 = background)
    camera : Camera
    points_m : (R, 3) float64 -- points on the body's vertical axis (:data:`BODY_AXIS_DROPS_M`
        below the head), world metres
    max_width_m : float
    others_m : (Q, 3) float64, optional -- one point on each other person's body axis

    Examples
    --------
    >>> cam = Camera("c", 640, 480, [[500, 0, 320], [0, 500, 240], [0, 0, 1]],
    ...              np.zeros(5), np.eye(3), np.zeros(3))
    >>> labels = np.zeros((480, 640), np.int32)
    >>> labels[200:300, 270:370] = 1                       # 100 px wide at 2 m: 0.4 m
    >>> pts = np.array([[0.0, 0.0, 2.0], [0.0, 0.1, 2.0]])
    >>> round(silhouette_width_m(labels, cam, pts, 0.8), 3)
    0.4
    >>> labels[200:300, 370:420] = 1                       # another person merged on the right
    >>> other = np.array([[0.3, 0.0, 2.0]])
    >>> round(silhouette_width_m(labels, cam, pts, 0.8, others_m=other), 3)  # 2 x 50.5 px
    0.404
    """
    points_m = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    others_m = np.zeros((0, 3)) if others_m is None else np.asarray(others_m, np.float64)
    px, depth = camera.project(np.vstack([points_m, others_m.reshape(-1, 3)]))
    fx = float(camera.K[0, 0])
    h, w = labels.shape
    n = len(points_m)
    near = [  # (first, last) image column of each other body's core
        (u - OTHER_BODY_CORE_M * fx / z, u + OTHER_BODY_CORE_M * fx / z)
        for (u, _), z in zip(px[n:].tolist(), depth[n:].tolist(), strict=True)
        if z > 0
    ]
    widths = []
    for (u, v), z in zip(px[:n].tolist(), depth[:n].tolist(), strict=True):
        col, row = round(u), round(v)
        if z <= 0 or not (0 <= col < w and 0 <= row < h) or labels[row, col] == 0:
            continue
        other = labels[row] != labels[row, col]
        before = np.flatnonzero(other[:col])
        after = np.flatnonzero(other[col:])
        if not len(before) or not len(after):
            continue
        first, last = int(before[-1]) + 1, int(after[0]) + col - 1
        # a side that reaches another body measures that body: the other side, doubled
        left_free = not any(a <= col and b >= first for a, b in near)
        right_free = not any(a <= last and b >= col for a, b in near)
        if left_free and right_free:
            width_px = last - first + 1
        elif left_free or right_free:
            width_px = 2 * (col - first + 0.5 if left_free else last - col + 0.5)
        else:
            continue
        width = width_px * z / fx
        if width <= max_width_m:
            widths.append(width)
    if len(widths) < 2:
        return float("nan")
    widths.sort()
    mid = len(widths) // 2
    return widths[mid] if len(widths) % 2 else 0.5 * (widths[mid - 1] + widths[mid])


def body_axis_cue(
    head_m: np.ndarray, cameras_m: np.ndarray, widths_m: np.ndarray, contrast: float
) -> np.ndarray:
    """One frame's evidence (2,) on the body's front-back axis, as a doubled angle
    ``(cos 2 phi, sin 2 phi)`` times a confidence in [0, 1]: an axis has no sign.

    A body is wider across the shoulders than front to back. Seen along a horizontal
    direction at angle ``beta``, an ellipse of half-axes ``a`` (across) and ``b`` (front to
    back) whose front faces ``phi`` is ``2 sqrt(a^2 cos^2 + b^2 sin^2)`` wide in
    ``beta - phi``; squared, that is ``c0 + c1 cos 2 beta + c2 sin 2 beta`` with
    ``(c1, c2)`` pointing at ``2 phi`` (widest seen from the front or the back). The three
    coefficients are fitted by least squares to the silhouette widths of three or more
    cameras (:func:`silhouette_width_m`; NaN = none); where the views' doubled angles are
    degenerate (:data:`AXIS_SPREAD_MIN`), ``c0`` is the mean squared width and only
    ``(c1, c2)`` are fitted. The confidence is the fitted contrast ``|(c1, c2)| / c0`` over
    ``contrast``, capped at 1: a round body (or widths that disagree) says little. Zeros
    with fewer than three widths.

    >>> head = np.array([0.0, 0.0, 1.7])
    >>> cams = np.array([[3.0, 0, 2.5], [0, 3.0, 2.5], [-3.0, 0, 2.5], [0, -3.0, 2.5]])
    >>> ev = body_axis_cue(head, cams, np.array([0.5, 0.25, 0.5, 0.25]), 0.3)
    >>> (ev.round(3) + 0.0).tolist()                       # facing +-X: 2 phi = 0
    [1.0, 0.0]
    """
    ok = np.isfinite(widths_m)
    if ok.sum() < 3 or contrast <= 0:
        return np.zeros(2)
    seen = np.asarray(head_m, dtype=np.float64)[:2] - np.asarray(cameras_m)[ok, :2]
    beta = np.arctan2(seen[:, 1], seen[:, 0])
    doubled = np.column_stack([np.cos(2 * beta), np.sin(2 * beta)])
    squared = np.asarray(widths_m, dtype=np.float64)[ok] ** 2
    spread = doubled - doubled.mean(axis=0)
    if np.linalg.eigvalsh(spread.T @ spread / len(beta))[0] >= AXIS_SPREAD_MIN:
        design = np.column_stack([np.ones(len(beta)), doubled])
        c0, c1, c2 = np.linalg.lstsq(design, squared, rcond=None)[0]
    else:
        # the views' doubled angles lie on one line (cameras in the corners of a room and
        # the person in the middle: two pairs of opposite views); c0 and the swing along
        # that line cannot be told apart, so c0 is the mean squared width, which opposite
        # doubled angles leave unbiased
        c0 = float(squared.mean())
        c1, c2 = np.linalg.lstsq(doubled, squared - c0, rcond=None)[0]
    amplitude = float(np.hypot(c1, c2))
    if c0 <= 0 or amplitude == 0:
        return np.zeros(2)
    return min(1.0, amplitude / c0 / contrast) * np.array([c1, c2]) / amplitude


def facing_on_axis(facing_xy: np.ndarray, axis_ev: np.ndarray, axis_min: float) -> np.ndarray:
    """The facing direction (2,) with the body axis's angle and the facing evidence's sign
    and length.

    The facing evidence (:func:`facing_cues`, :func:`face_cue`) tells front from back but
    its angle strays tens of degrees; the silhouettes' body axis (:func:`body_axis_cue`,
    accumulated as ``axis_ev``) is within a few degrees but has no sign. Where the axis
    evidence reaches ``axis_min`` and the facing evidence is not square to it, the facing
    is the axis direction on the evidence's side, as long as the evidence; otherwise the
    evidence itself.

    >>> facing_on_axis(np.array([0.6, 0.8]), np.array([2.0, 0.0]), 1.0).tolist()
    [1.0, 0.0]
    >>> (facing_on_axis(np.array([-0.6, 0.8]), np.array([2.0, 0.0]), 1.0) + 0.0).tolist()
    [-1.0, 0.0]
    """
    facing_xy = np.asarray(facing_xy, dtype=np.float64)
    strength = float(np.linalg.norm(axis_ev))
    if strength < max(axis_min, 1e-12):
        return facing_xy
    half = 0.5 * np.arctan2(axis_ev[1], axis_ev[0])
    axis = np.array([np.cos(half), np.sin(half)])
    along = float(facing_xy @ axis)
    length = float(np.linalg.norm(facing_xy))
    if abs(along) <= 1e-9 * length:
        return facing_xy
    return np.sign(along) * length * axis


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
