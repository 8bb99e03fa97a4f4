"""Arm trackers per person: a facing HMM with arm particle filters per level (paper 001).

For every tracked person (a labelled head of the 3D tracker) the body's facing phi is
tracked by an HMM over ``n_facing`` levels, and for every level each arm's four angles by
a SIR particle filter (paper 001 section V-VI, Fig. 1). All particles of all persons, levels
and arms live in one array of shape (P, K, 2, N, 4) and are weighted together:

- p1 (eq. 10): per camera, 1 / (1 + alpha d^2), d = distance of the hand's projection to the
  nearest hand blob's point (blobs at a tracked head's projection are the head's); floored,
  so that a view in which the hand is hidden does not veto the arm;
- p2 (eq. 11): per camera, the share of points along the upper arm and forearm that project
  inside a silhouette (floored);
- the product over the cameras that see the head (paper 001 uses a stereo pair);
- p3 (not in paper 001): a Gaussian pull towards the 3D tracker's hand of that person and
  side while it is supported by candidates (normal state). Where two or more views see the
  hand the 3D tracker is the better estimate (papers' 34-44 mm against 001's and 003's
  76-254 mm); the arm model carries it on where fewer do.

The HMM's observation for level r is the mean particle weight of each arm times the
shoulder term s_r (eq. 13); s_r is a Gaussian in the distance of the two shoulders'
projections outside the silhouette (eq. 14 asks for the shoulders close to the foreground
edge; a Gaussian outside it keeps the term smooth and never zero, and it does not penalise
side views, where the shoulders project inside the body). Resampling is systematic, per
person, level and arm, every step.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from surveil.armpose.model import (
    JOINT_LIMITS,
    SIDES,
    ArmShape,
    arm_directions,
    clip_to_limits,
    ik_angles,
    shoulders_m,
)
from surveil.armpose.settings import ArmPoseConfig
from surveil.camera import Rig
from surveil.datatypes import ArmPose, CameraObservation, Limb, Phase, TargetSnapshot
from surveil.tracking import sir

NS = 1_000_000_000
HAND_LIMBS = (Limb.LEFT_HAND, Limb.RIGHT_HAND)
# floor of the pull towards a tracked hand (and of the push from the other side's): a 3D
# hand on the wrong blob cannot veto an arm
PULL_FLOOR = 0.01


@dataclass(frozen=True, slots=True)
class _View:
    """A camera that sees at least one person's head, with its hand blobs."""

    camera: str
    observation: CameraObservation
    sees: np.ndarray  # (P,) bool: the person's head is in view
    blobs: np.ndarray  # (B, 2) hand blob points, px


@dataclass(slots=True)
class _Person:
    """Filter state of one person's arms."""

    head_z_m: list[float]  # recent head heights (stature from their median)
    last_seen_ns: int
    belief: np.ndarray  # (K,) facing HMM
    angles: np.ndarray  # (K, 2, N, 4)


def facing_transition(n_levels: int, step_rad: float) -> np.ndarray:
    """(K, K) row-stochastic HMM transition over facing levels: a wrapped Gaussian in the
    angle between levels.

    >>> T = facing_transition(8, 0.3)
    >>> bool(np.allclose(T.sum(axis=1), 1)), bool(T[0, 0] > T[0, 1] > T[0, 2])
    (True, True)
    """
    phi = 2 * np.pi * np.arange(n_levels) / n_levels
    diff = np.angle(np.exp(1j * (phi[:, None] - phi[None, :])))
    T = np.exp(-0.5 * (diff / step_rad) ** 2)
    return T / T.sum(axis=1, keepdims=True)


def resample_blocks(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices (..., N) of systematic resampling within every block of the last axis
    (``weights`` (..., N) non-negative, each block with a positive sum).

    >>> w = np.array([[0.0, 1.0, 0.0], [0.5, 0.0, 0.5]])
    >>> resample_blocks(w, np.random.default_rng(0)).tolist()
    [[1, 1, 1], [0, 0, 2]]
    """
    lead, n = weights.shape[:-1], weights.shape[-1]
    w = weights.reshape(-1, n)
    w = w / w.sum(axis=1, keepdims=True)
    starts = np.arange(len(w)) * n
    idx = sir.block_systematic_resample(w.ravel(), starts, rng)
    return (idx - np.repeat(starts, n)).reshape(*lead, n)


class ArmTracker:
    """The arms of every tracked person, one step per frame set."""

    def __init__(self, cfg: ArmPoseConfig, rig: Rig, seed: int = 0) -> None:
        self.cfg = cfg
        self.rig = rig
        self.rng = np.random.default_rng(np.random.SeedSequence([seed, 0xA125]))
        self.levels_rad = 2 * np.pi * np.arange(cfg.n_facing) / cfg.n_facing
        self.transition = facing_transition(cfg.n_facing, np.deg2rad(cfg.facing_step_deg))
        self.steps_rad = np.deg2rad(
            [
                cfg.shoulder_step_deg,
                cfg.shoulder_step_deg,
                cfg.twist_step_deg,
                cfg.elbow_step_deg,
            ]
        )
        self.persons: dict[int, _Person] = {}

    def reset(self) -> None:
        self.persons.clear()

    # --- state ---------------------------------------------------------------------------
    def _new_person(self, head_z_m: float, t_ns: int) -> _Person:
        k, n = self.cfg.n_facing, self.cfg.particles
        lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
        # start near a resting arm (hanging, elbow a little bent) with a wide spread: people
        # enter walking; the likelihood sorts out the rest within a few frame sets
        rest = np.array([0.0, 0.1, 0.0, 0.3])
        angles = rest + self.rng.normal(0.0, 0.5, (k, 2, n, 4))
        angles = np.clip(angles, lo, hi)
        return _Person([head_z_m], t_ns, np.full(k, 1.0 / k), angles)

    def _update_people(
        self, t_ns: int, heads: Mapping[int, np.ndarray]
    ) -> list[tuple[int, _Person]]:
        for pid, head in heads.items():
            person = self.persons.get(pid)
            if person is None:
                self.persons[pid] = self._new_person(float(head[2]), t_ns)
            else:
                person.last_seen_ns = t_ns
                person.head_z_m.append(float(head[2]))
                del person.head_z_m[:-30]
        gone = [
            pid
            for pid, p in self.persons.items()
            if t_ns - p.last_seen_ns > self.cfg.retire_after_s * NS
        ]
        for pid in gone:
            del self.persons[pid]
        return [(pid, self.persons[pid]) for pid in sorted(heads)]

    # --- one step ------------------------------------------------------------------------
    def step(
        self,
        t_ns: int,
        targets: Sequence[TargetSnapshot],
        observations: Mapping[str, CameraObservation],
    ) -> tuple[ArmPose, ...]:
        """Advance every person's arm filters to ``t_ns``; their poses."""
        heads = {
            t.person: np.asarray(t.mean_m, dtype=np.float64)
            for t in targets
            if t.limb is Limb.HEAD and t.person > 0 and t.phase is not Phase.LOST
        }
        active = self._update_people(t_ns, heads)
        if not active:
            return ()
        cfg = self.cfg
        pids = [pid for pid, _ in active]
        head_m = np.stack([heads[pid] for pid in pids])  # (P, 3)
        shapes = [ArmShape.from_head_height(float(np.median(p.head_z_m))) for _, p in active]
        # the 3D tracker's hands in the normal state, in label order; which arm each belongs
        # to is decided per facing level below, not by the label
        hands = np.full((len(pids), 2, 3), np.nan)
        for t in targets:
            if t.limb in HAND_LIMBS and t.person in heads and t.phase is Phase.NORMAL:
                hands[pids.index(t.person), 0 if t.limb is Limb.LEFT_HAND else 1] = t.mean_m

        # predict the facing HMM; propose arm angles from the motion prior and from inverse
        # kinematics towards the hand hypotheses, weighted by prior / proposal
        phi = self.levels_rad  # (K,)
        n_p = len(pids)
        belief = np.stack([p.belief for _, p in active]) @ self.transition  # (P, K)
        prev = np.stack([p.angles for _, p in active])  # (P, K, 2, N, 4)
        shoulders = np.stack(
            [shoulders_m(head_m[i], phi, shapes[i]) for i in range(n_p)]
        )  # (P, K, 2, 3)
        angles = self._motion_draws(prev)
        sided = hands_by_side(hands, head_m, phi)  # (P, K, 2, 3)
        likely = belief.argmax(axis=1)
        rays = [
            self.rig[name].backproject(obs.blobs.centroids_px)
            for name, obs in observations.items()
            if len(obs.blobs)
        ]
        hypotheses = [
            self._hand_hypotheses(head_m[i], shapes[i], sided[i, likely[i]], rays)
            for i in range(n_p)
        ]
        n_ik = self._ik_draws(angles, shoulders, shapes, hypotheses)
        log_correction = self._log_prior_over_proposal(angles, prev, n_ik)

        # joints of every particle
        upper = np.array([s.upper_arm_m for s in shapes])[:, None, None, None]
        fore = np.array([s.forearm_to_hand_m for s in shapes])[:, None, None, None]
        phi_b = np.broadcast_to(phi[None, :, None, None], angles.shape[:-1])
        side_b = np.broadcast_to(SIDES[None, None, :, None], angles.shape[:-1])
        u, f = arm_directions(angles, phi_b, side_b)
        sh = shoulders[:, :, :, None, :]
        elbows = sh + upper[..., None] * u
        hand_pts = elbows + fore[..., None] * f  # (P, K, 2, N, 3)

        views = self._views(head_m, observations)
        log_w, log_s = self._log_likelihood(views, shoulders, sh, elbows, hand_pts)
        n_views = sum((v.sees.astype(np.int64) for v in views), np.zeros(n_p, np.int64))
        log_w = log_w + log_correction + self._log_side_prior(hand_pts, head_m, phi)
        if cfg.hand_sigma_m > 0:
            log_w = log_w + _log_pull_push(hand_pts, sided, cfg.hand_sigma_m)

        # weights, HMM update (eq. 12-13)
        shift = log_w.max(axis=(1, 2, 3), keepdims=True)
        w = np.exp(log_w - shift)  # (P, K, 2, N)
        mean_w = w.mean(axis=3)  # (P, K, 2)
        obs = np.log(mean_w).sum(axis=2) + log_s  # (P, K)
        post = np.log(np.maximum(belief, 1e-300)) + obs
        post = np.exp(post - post.max(axis=1, keepdims=True))
        belief = post / post.sum(axis=1, keepdims=True)

        # estimates from the most likely level, before resampling
        best = belief.argmax(axis=1)
        rows = np.arange(n_p)
        wb = w[rows, best]  # (P, 2, N)
        wb = wb / wb.sum(axis=2, keepdims=True)
        est_elbow = np.einsum("pan,panc->pac", wb, elbows[rows, best])
        est_hand = np.einsum("pan,panc->pac", wb, hand_pts[rows, best])

        idx = resample_blocks(w, self.rng)
        angles = np.take_along_axis(angles, idx[..., None], axis=3)
        out = []
        for i, (pid, person) in enumerate(active):
            person.belief = belief[i]
            person.angles = angles[i]
            out.append(
                ArmPose(
                    t_ns=t_ns,
                    person=pid,
                    facing_rad=float(phi[best[i]]),
                    facing_belief=float(belief[i, best[i]]),
                    shoulders_m=shoulders[i, best[i]].copy(),
                    elbows_m=est_elbow[i],
                    hands_m=est_hand[i],
                    n_views=int(n_views[i]),
                )
            )
        return tuple(out)

    def _motion_draws(self, prev: np.ndarray) -> np.ndarray:
        """Angles drawn from the motion prior: a random walk, and with probability
        ``jump_share`` a uniform draw within the joint limits (paper 003's share of random
        propagation, so that a lost arm can be found again)."""
        lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
        walk = clip_to_limits(prev + self.rng.normal(0.0, 1.0, prev.shape) * self.steps_rad)
        jump = self.rng.random(prev.shape[:-1]) < self.cfg.jump_share
        uniform = self.rng.uniform(lo, hi, prev.shape)
        return np.where(jump[..., None], uniform, walk)

    def _hand_hypotheses(
        self,
        head_m: np.ndarray,
        shape: ArmShape,
        tracked_hands: np.ndarray,
        rays: Sequence[tuple[np.ndarray, np.ndarray]],
    ) -> list[np.ndarray]:
        """Per arm, (H, 2, 3) segments (start, end) in which its hand may lie: the 3D
        tracker's hand of that side (a point) and, for every camera, the stretch of every
        hand blob's line of sight (``rays``: per camera its centre and the blobs' unit
        directions) within reach of the shoulders (paper 000's proposal from skin-blob hand
        candidates)."""
        centre = head_m - np.array([0.0, 0.0, shape.shoulder_drop_m])
        radius = shape.reach_m + shape.shoulder_half_width_m
        chords = [np.zeros((0, 2, 3))]
        for origin, dirs in rays:
            # |o + t d - c| = radius: the chord of each line of sight in the reach sphere
            oc = origin - centre
            b = dirs @ oc
            root = np.sqrt(np.maximum(b * b - (oc @ oc - radius * radius), 0.0))
            t0, t1 = np.maximum(-b - root, 0.05), -b + root
            ok = t1 > t0
            ends = origin + np.stack([t0[ok], t1[ok]], axis=1)[..., None] * dirs[ok, None, :]
            chords.append(ends)
        segments = np.concatenate(chords)
        out = []
        for arm in range(2):
            if np.isfinite(tracked_hands[arm]).all():
                point = np.broadcast_to(tracked_hands[arm], (1, 2, 3))
                out.append(np.concatenate([segments, point]))
            else:
                out.append(segments)
        return out

    def _ik_draws(
        self,
        angles: np.ndarray,
        shoulders: np.ndarray,
        shapes: Sequence[ArmShape],
        hypotheses: Sequence[Sequence[np.ndarray]],
    ) -> np.ndarray:
        """Replace the last ``ik_share`` of every (person, arm) block's particles, at every
        facing level, by inverse kinematics towards points drawn on its hand hypotheses.
        Returns (P, 2) the number replaced per block (0 where there is no hypothesis)."""
        cfg = self.cfg
        n_p, k, _, n, _ = angles.shape
        m = int(round(cfg.ik_share * n))
        counts = np.zeros((n_p, 2), np.int64)
        if m == 0:
            return counts
        for i in range(n_p):
            for arm in range(2):
                segs = hypotheses[i][arm]
                if not len(segs):
                    continue
                pick = segs[self.rng.integers(0, len(segs), (k, m))]  # (K, M, 2, 3)
                t = self.rng.random((k, m, 1))
                target = pick[:, :, 0] + t * (pick[:, :, 1] - pick[:, :, 0])
                target = target + self.rng.normal(0.0, cfg.ik_target_sd_m, target.shape)
                swivel = self.rng.normal(0.0, np.deg2rad(cfg.swivel_sd_deg), (k, m))
                angles[i, :, arm, n - m :] = ik_angles(
                    np.broadcast_to(shoulders[i, :, arm, None, :], (k, m, 3)),
                    target,
                    np.broadcast_to(self.levels_rad[:, None], (k, m)),
                    np.full((k, m), SIDES[arm]),
                    shapes[i],
                    swivel,
                )
                counts[i, arm] = m
        return counts

    def _log_prior_over_proposal(
        self, angles: np.ndarray, prev: np.ndarray, n_ik: np.ndarray
    ) -> np.ndarray:
        """log p(x) / q(x) per particle (P, K, 2, N): p the motion prior (a kernel density
        over the previous particles plus the uniform jumps), q the mixture actually sampled
        (motion draws and inverse-kinematics draws, the latter's density a kernel density
        over themselves with the motion's widths). Zero where a block had no IK draws, as
        its particles then come from p alone (paper 000's multiple importance sampling)."""
        cfg = self.cfg
        n = angles.shape[3]
        out = np.zeros(angles.shape[:-1])
        if not n_ik.any():
            return out
        lo, hi = JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]
        log_uniform = -np.sum(np.log(hi - lo))
        sd = np.maximum(self.steps_rad, 1e-3)
        log_norm = -np.sum(np.log(sd)) - 2 * np.log(2 * np.pi)

        def log_kde(x: np.ndarray, centres: np.ndarray) -> np.ndarray:
            z = (x[..., :, None, :] - centres[..., None, :, :]) / sd
            return _logmeanexp(-0.5 * np.sum(z * z, axis=-1), axis=-1) + log_norm

        log_p = np.logaddexp(
            np.log1p(-cfg.jump_share) + log_kde(angles, prev),
            np.log(cfg.jump_share) + log_uniform,
        )
        m = int(n_ik.max())
        beta = m / n
        log_q_ik = log_kde(angles, angles[..., n - m :, :])
        log_q = np.logaddexp(np.log1p(-beta) + log_p, np.log(beta) + log_q_ik)
        return np.where(n_ik[:, None, :, None] > 0, log_p - log_q, 0.0)

    def _log_side_prior(self, hand_pts: np.ndarray, head_m: np.ndarray, phi: np.ndarray):
        """log prior (P, K, 2, N) that keeps each hand on its own side of the body: a
        half-Gaussian in how far it reaches past the midline (without it, the two arms
        of a level are independent and either may take the other hand's blob)."""
        fwd = np.stack([np.cos(phi), np.sin(phi)], axis=-1)  # (K, 2)
        left = np.stack([-fwd[:, 1], fwd[:, 0]], axis=-1)
        rel = hand_pts[..., :2] - head_m[:, None, None, None, :2]
        lateral = np.sum(rel * left[None, :, None, None, :], axis=-1) * SIDES[:, None]
        past = np.maximum(-lateral, 0.0) / self.cfg.midline_sigma_m
        return -0.5 * past * past

    def _views(
        self, head_m: np.ndarray, observations: Mapping[str, CameraObservation]
    ) -> list[_View]:
        """The cameras that see at least one person's head (within ``max_distance_m``),
        each with its hand blobs: every blob point not at a tracked head's projection."""
        cfg = self.cfg
        out = []
        for name, obs in observations.items():
            cam = self.rig[name]
            head_px, head_depth = cam.project_many(head_m)
            h, w_img = obs.silhouettes.labels.shape
            dist_to_cam = np.linalg.norm(head_m - cam.centre_m, axis=1)
            sees = (
                (head_depth > 0.1)
                & (head_px[:, 0] >= 0)
                & (head_px[:, 0] < w_img)
                & (head_px[:, 1] >= 0)
                & (head_px[:, 1] < h)
                & (dist_to_cam <= cfg.max_distance_m)
            )
            if not sees.any():
                continue
            blobs = obs.blobs.centroids_px
            if len(blobs):
                head_r_px = cam.K[0, 0] * cfg.head_blob_m / np.maximum(head_depth, 0.1)
                near_head = (
                    np.linalg.norm(blobs[:, None, :] - head_px[None, :, :], axis=2)
                    < head_r_px[None, :]
                ) & (head_depth[None, :] > 0.1)
                blobs = blobs[~near_head.any(axis=1)]
            out.append(_View(name, obs, sees, blobs))
        return out

    def _log_likelihood(
        self,
        views: Sequence[_View],
        shoulders: np.ndarray,
        sh: np.ndarray,
        elbows: np.ndarray,
        hand_pts: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """log p1 p2 per particle (P, K, 2, N) and log s per level (P, K)."""
        cfg = self.cfg
        log_w = np.zeros(hand_pts.shape[:-1])
        log_s = np.zeros(shoulders.shape[:2])
        t = (np.arange(cfg.arm_samples) + 0.5) / cfg.arm_samples
        # points along the upper arm and the forearm: (P, K, 2, N, 2S, 3)
        along = np.concatenate(
            [
                sh[..., None, :] + t[:, None] * (elbows - sh)[..., None, :],
                elbows[..., None, :] + t[:, None] * (hand_pts - elbows)[..., None, :],
            ],
            axis=-2,
        )
        for v in views:
            cam = self.rig[v.camera]
            h, w_img = v.observation.silhouettes.labels.shape
            dist_out = v.observation.silhouettes.dist_outside_px
            sel = np.flatnonzero(v.sees)
            hand_px, hand_depth = cam.project_many(hand_pts[sel])
            if len(v.blobs):
                d2 = np.min(np.sum((hand_px[..., None, :] - v.blobs) ** 2, axis=-1), axis=-1)
                p1 = np.maximum(1.0 / (1.0 + cfg.alpha_px2 * d2), cfg.p1_floor)
            else:
                p1 = np.full(hand_px.shape[:-1], cfg.p1_floor)
            along_px, along_depth = cam.project_many(along[sel])
            inside = _lookup(dist_out, along_px) <= cfg.inside_tol_px
            valid = _in_image(along_px, along_depth, w_img, h)
            n_valid = valid.sum(axis=-1)
            share = np.where(
                n_valid > 0, (inside & valid).sum(axis=-1) / np.maximum(n_valid, 1), 1.0
            )
            p2 = np.maximum(share, cfg.p2_floor)
            log_w[sel] += np.log(p1) + np.log(p2)
            sh_px, sh_depth = cam.project_many(shoulders[sel])  # (P', K, 2, 2)
            d_out = _lookup(dist_out, sh_px)
            d_out = np.where(_in_image(sh_px, sh_depth, w_img, h), d_out, 0.0)
            log_s[sel] += -0.5 * np.sum((d_out / cfg.shoulder_sigma_px) ** 2, axis=-1)
        return log_w, log_s


def hands_by_side(tracked: np.ndarray, head_m: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(P, K, 2, 3) the tracked hands ``tracked`` (P, 2, 3, any order, NaN rows for none)
    given to the arms (left, right) at every facing level ``phi`` (K,): of two hands the one
    farther to the body's left (from the head ``head_m`` (P, 3)) goes to the left arm; a lone
    hand goes to the arm of its side. The 3D tracker's own left/right labels are not used:
    they come from its weaker facing cues, and an arm pulled to a hand of the wrong label
    would follow the mislabel.

    >>> tracked = np.array([[[1.0, -0.2, 1.0], [np.nan] * 3]])  # one hand, to the right
    >>> out = hands_by_side(tracked, np.zeros((1, 3)), np.array([0.0, np.pi]))
    >>> np.isnan(out[0, :, :, 0]).tolist()  # facing +X: the right arm's; facing -X: left's
    [[True, False], [False, True]]
    """
    left_axis = np.stack([-np.sin(phi), np.cos(phi)], axis=-1)  # (K, 2)
    lateral = np.einsum("phc,kc->pkh", tracked[..., :2] - head_m[:, None, :2], left_axis)
    has0, has1 = np.isfinite(lateral[..., 0]), np.isfinite(lateral[..., 1])  # (P, K)
    # of two hands the first is the left one when it is farther left; a lone hand by its sign
    first_left = np.where(
        has1, lateral[..., 0] >= np.nan_to_num(lateral[..., 1], nan=0.0), lateral[..., 0] >= 0
    )
    second_left = np.where(has0, ~first_left, lateral[..., 1] >= 0)
    h0, h1 = tracked[:, None, 0, :], tracked[:, None, 1, :]  # (P, 1, 3)
    nan = np.full_like(h0, np.nan)

    def pick(take0: np.ndarray, take1: np.ndarray) -> np.ndarray:
        return np.where(take0[..., None], h0, np.where(take1[..., None], h1, nan))

    left = pick(has0 & first_left, has1 & second_left)
    right = pick(has0 & ~first_left, has1 & ~second_left)
    return np.stack([left, right], axis=2)


def _log_pull_push(hand_pts: np.ndarray, sided: np.ndarray, sigma_m: float) -> np.ndarray:
    """log weight (P, K, 2, N) from the 3D tracker's hands given to the arms ``sided``
    (P, K, 2, 3; NaN where an arm has none, :func:`hands_by_side`): a pull towards the hand
    of the arm's own side and a push away from the other side's (a dip to ``PULL_FLOOR`` at
    it). Without the push both arms settle on the same blob when one hand is hard to see;
    hands that meet are combined in the 3D tracker, not normal, so the push does not keep
    them apart.

    >>> pts = np.zeros((1, 1, 2, 1, 3))
    >>> sided = np.array([[[[0.0, 0, 0], [np.nan, np.nan, np.nan]]]])
    >>> w = _log_pull_push(pts, sided, 0.1)[0, 0, :, 0]
    >>> bool(w[0] > 0 > w[1])
    True
    """

    def closeness(ref: np.ndarray) -> np.ndarray:
        d2 = np.sum((hand_pts - ref[:, :, :, None, :]) ** 2, axis=-1)
        return np.exp(-0.5 * np.nan_to_num(d2, nan=np.inf) / sigma_m**2)

    own = np.isfinite(sided[..., 0])[..., None]  # (P, K, 2, 1)
    other = own[:, :, ::-1]
    pull = np.where(own, np.log(closeness(sided) + PULL_FLOOR), 0.0)
    push = np.where(other, np.log1p(-(1 - PULL_FLOOR) * closeness(sided[:, :, ::-1])), 0.0)
    return pull + push


def _logmeanexp(x: np.ndarray, axis: int) -> np.ndarray:
    top = np.max(x, axis=axis, keepdims=True)
    return np.log(np.mean(np.exp(x - top), axis=axis)) + np.squeeze(top, axis=axis)


def _in_image(px: np.ndarray, depth: np.ndarray, width: int, height: int) -> np.ndarray:
    return (
        (depth > 0.05)
        & (px[..., 0] >= 0)
        & (px[..., 0] <= width - 1)
        & (px[..., 1] >= 0)
        & (px[..., 1] <= height - 1)
    )


def _lookup(image: np.ndarray, px: np.ndarray) -> np.ndarray:
    """Nearest-pixel values of ``image`` at ``px`` (..., 2), clipped to the frame."""
    h, w = image.shape
    u = np.clip(np.rint(px[..., 0]), 0, w - 1).astype(np.intp)
    v = np.clip(np.rint(px[..., 1]), 0, h - 1).astype(np.intp)
    return image[v, u].astype(np.float64)
