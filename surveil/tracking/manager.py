"""The multi-target 3-D tracker: parallel SIR filters + the Fig. 1 state machine (paper 004 §5).

:class:`MultiTargetTracker` owns the particles of every tracker in one array (tracker k's
particles are the contiguous block ``k*N:(k+1)*N``), the trackers' phases and labels, and the
people. One :meth:`MultiTargetTracker.step` per frame set:

1. predict every active particle by the constant-velocity model (hand or head noise);
2. weight all particles of all targets by eq. 17 in one array operation; estimate (posterior
   mean / covariance) and resample every block (a combined pair pools its two blocks, splits
   the pool into two modes by weighted 2-means and resamples each mode into one block);
3. measure the lifecycle evidence: likelihood level (lost), distances (combine), mode
   distances (separate), candidates near lost targets (re-acquire);
4. labelling cues (head / hand, person, left / right) for unlabelled trackers;
5. the pure :func:`surveil.tracking.lifecycle.next_phase` for every tracker; apply the
   changes (angle rule on separation, re-initialisation on re-acquisition, removal on
   retirement) and record them as :class:`surveil.datatypes.Transition`;
6. start trackers at strong candidates that no live tracker explains and that persisted.

Randomness: one ``np.random.Generator`` seeded from ``seed`` serves the whole particle array
(the particles are sampled in one batch, not per target); the same seed and inputs give the
same output. Same for ``reset()``.
"""

from __future__ import annotations

import itertools
import logging
from collections import deque
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from surveil.camera import Rig
from surveil.datatypes import (
    CameraObservation,
    CandidateSet,
    Limb,
    Phase,
    TargetSnapshot,
    TrackFrame,
    Transition,
    make_label,
)
from surveil.tracking import labelling as lab
from surveil.tracking import sir
from surveil.tracking.head_centre import CROWN_TO_CENTRE_M, head_rises_m
from surveil.tracking.lifecycle import Evidence, next_phase
from surveil.tracking.settings import TrackingConfig

log = logging.getLogger(__name__)

ACTIVE = (Phase.UNLABELLED, Phase.NORMAL, Phase.COMBINED)
HISTORY_FRAMES = 30  # estimates kept per tracker (for the angle rule's "before" vector)
# how long unexplained candidates are remembered (the parting test looks back to a pair's
# joining; pairs held longer than this are not checked against ghosts seen as they joined)
UNEXPLAINED_LOG_S = 10.0
# the hand left behind by an out-of-reach pair (_seed_of_left_hand): a seed seen in one frame
# set only counts as this much farther from where the pair joined (a one-frame ghost beside
# the hand's own seed, seen twice), m
SEEN_ONCE_PENALTY_M = 0.1

# a lost hand moving towards a seed on a head at least this fast when it was lost (a hand
# raised to the face: 0.56 m/s on the held-out negative takes) may still be re-acquired on it
# (``reacquire_above_head_m``), m/s
TOWARDS_HEAD_MPS = 0.2


# per-frame decay of the facing evidence of the last few frames (about 5), against which
# the accumulated evidence (``facing_decay``, about 30 frames) is checked: after a person
# turns round, the accumulated sum points backwards for a second or more
RECENT_FACING_DECAY = 0.8


# (3, 3) offsets from a head down to the rows whose silhouette widths tell the body axis
_AXIS_DROPS_M = np.outer(lab.BODY_AXIS_DROPS_M, (0.0, 0.0, 1.0))


def _persisted(since_ns: int | None, t_ns: int, need_s: float) -> tuple[int, bool]:
    """For a condition that holds at ``t_ns``: when it began (``since_ns``, or ``t_ns`` if it
    begins now) and whether it has held for ``need_s`` seconds. The caller stores the first
    and resets it to None when the condition fails.

    >>> _persisted(None, 5_000_000_000, 1.0)
    (5000000000, False)
    >>> _persisted(4_000_000_000, 5_000_000_000, 1.0)
    (4000000000, True)
    """
    since = t_ns if since_ns is None else since_ns
    return since, (t_ns - since) * 1e-9 >= need_s


def _common_history(a: _Track, b: _Track) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(t_ns, a's estimate, b's estimate) at every time both trackers' histories hold,
    oldest first."""
    hist_b = dict(b.history)
    return [(t, m, hist_b[t]) for t, m in a.history if t in hist_b]


def _window_ends(samples: list[tuple], window_s: float) -> tuple[tuple, tuple] | None:
    """Of time-ordered samples (time in ns first), the first one within ``window_s`` of the
    last, and the last; None when there are none or they are not apart in time.

    >>> _window_ends([(0, "a"), (1_000_000_000, "b"), (2_000_000_000, "c")], 1.5)
    ((1000000000, 'b'), (2000000000, 'c'))
    >>> _window_ends([(0, "a")], 1.5) is None
    True
    """
    if not samples:
        return None
    last = samples[-1]
    start = last[0] - window_s * 1e9
    first = next(s for s in samples if s[0] >= start)
    return (first, last) if last[0] > first[0] else None


@dataclass(slots=True, eq=False)
class _Track:
    """Mutable bookkeeping of one tracker (its particles live in the manager's array)."""

    id: int
    phase: Phase
    born_ns: int
    mean_m: np.ndarray
    cov_m2: np.ndarray
    vel_mps: np.ndarray
    last_good_m: np.ndarray
    last_good_ns: int = 0
    last_good_vel_mps: np.ndarray = field(default_factory=lambda: np.zeros(3))
    # its last supported time before its latest miss began (a tracker that slid onto another
    # target's candidate is supported again, and its last_good_* follow the slide)
    miss_from_ns: int = 0
    person: int = 0
    limb: Limb = Limb.UNKNOWN
    is_hand: bool | None = None  # typed as hand (True) / head (False); None = not yet
    attached_ns: int | None = None  # when a hand joined its person
    astray_ns: int | None = None  # since when it is out of its person's reach (and in another's)
    misses: int = 0
    since_miss: int = 1 << 30  # frame sets since the last unsupported one
    level: float = 0.0
    lost_since_ns: int | None = None
    # its person's head (estimate) when it was last supported before it was lost
    lost_head_m: np.ndarray | None = None
    ever_labelled: bool = False
    # it lost a hand slot in a contest and has not been labelled since: judged a ghost
    demoted: bool = False
    type_llr: float = 0.0
    typed_frames: int = 0
    speed_ema_mps: float = 0.0
    support_ema: float = 0.0  # smoothed likelihood level (a ghost's is lower: fewer views)
    rescued_frames: int = 0  # consecutive frame sets its nearest candidate was a rescued one
    # frame sets since its nearest candidate was one of its own (kept, not rescued)
    since_own_support: int = 1 << 30
    contest_ns: int | None = None  # since when it out-supports a hand holding a slot
    third_hand_ns: int | None = None  # since when it is a third hand beside an own-hands pair
    home_hand_ns: int | None = None  # since when it is an owner's hand gone home from a pair
    split_fixed: int | None = None  # the mode (of split_m) it takes when its pair separates
    partner: int | None = None
    joined_ns: int | None = None  # when it entered its current combined state
    joined_m: np.ndarray | None = None  # its estimate then
    joined_others: dict[int, np.ndarray] | None = None  # other labelled targets' estimates then
    # where such targets' trackers had drifted to, since, before they were put back
    ghosts_m: list[np.ndarray] = field(default_factory=list)
    joined_apart: bool = False  # it combined while combine_distance_m or more from its partner
    # the partner of its latest pair that parted as never met, when, and where it restarted
    never_met: tuple[int, int, np.ndarray] | None = None
    unjoin_frames: int = 0  # consecutive frame sets whose modes say the pair never met
    body_fails: int = 0  # frame sets in which it failed the body check (a head candidate)
    before_vec_m: np.ndarray | None = None
    apart_frames: int = 0
    split_m: np.ndarray | None = None  # (2, 3) the two modes of a combined pair this frame
    split_first_m: float = 0.0  # distance between the modes when they first appeared
    split_gain_m: float = 0.0  # how much farther apart they are now
    split_vel_mps: np.ndarray | None = None  # (2, 3) their velocities
    out_of_reach_frames: int = 0  # consecutive frame sets a pair was beyond an owner's reach
    # a head's centre above its skin point, smoothed (head_centre); None = not measured yet
    head_rise_m: float | None = None
    history: deque = field(default_factory=lambda: deque(maxlen=HISTORY_FRAMES))

    @property
    def label(self) -> str:
        return make_label(self.person, self.limb, self.id)

    @property
    def labelled(self) -> bool:
        return self.person > 0 and self.limb is not Limb.UNKNOWN

    @property
    def stray(self) -> bool:
        """It never joined a person, or lost its slot in a contest since it last did: near a
        person's target it is a duplicate or a ghost."""
        return (not self.ever_labelled or self.demoted) and self.person == 0

    def take_label_off(self) -> None:
        """Back to no person and no limb (the caller frees its person's slot)."""
        self.person, self.limb, self.attached_ns, self.astray_ns = 0, Limb.UNKNOWN, None, None


@dataclass(slots=True, eq=False)
class _Person:
    number: int
    head_id: int | None
    born_ns: int
    facing_ev: np.ndarray = field(default_factory=lambda: np.zeros(2))
    axis_ev: np.ndarray = field(default_factory=lambda: np.zeros(2))  # doubled angle
    recent_ev: np.ndarray = field(default_factory=lambda: np.zeros(2))  # the last few frames'
    hand_ids: list[int] = field(default_factory=list)
    # how long the facing has said its sides are swapped, net of the time it has not
    contradicted_s: float = 0.0
    revised_ns: int | None = None  # when contradicted_s was last updated


@dataclass(slots=True)
class _Pending:
    position_m: np.ndarray
    count: int
    velocity_mps: np.ndarray
    first_ns: int  # when its run of consecutive frame sets began
    # combined tracker id -> the seed's distance from it when first seen together
    pair_first_m: dict[int, float] = field(default_factory=dict)
    # consecutive frame sets seen at all, strong or weak (a weak seed, prior below
    # init_prior_min, has count 0: it may only re-acquire a lost target)
    seen: int = 0
    head_only: bool = False  # its candidate is evidence of a head only (a crown head)
    # frame sets seen in a run that may skip single frame sets (``reacquire_bridge``; 0: the
    # seed bridged no gap, its run is ``seen``). Only a lost target's re-acquisition reads it
    bridged_seen: int = 0


class MultiTargetTracker:
    """Track heads and hands in 3-D from candidate points (paper 004 sections 4-5, 7.1).

    Parameters
    ----------
    cfg : TrackingConfig
    rig : Rig
        The cameras, in the order ``CandidateSet.cam_pairs`` indexes.
    seed : int
        Seed of the particle random generator.

    Examples
    --------
    >>> from surveil.camera import Rig, look_at
    >>> cam = look_at("c0", np.array([0.0, 0, 2]), np.array([1.0, 0, 1]),
    ...               width=640, height=480, hfov_deg=60)
    >>> trk = MultiTargetTracker(TrackingConfig(), Rig((cam,)), seed=0)
    >>> cands = CandidateSet(np.array([[1.0, 0.0, 1.0]]), np.array([0.9]))
    >>> [len(trk.step(i * 66_666_667, cands).targets) for i in range(4)]
    [0, 0, 1, 1]
    """

    def __init__(self, cfg: TrackingConfig, rig: Rig, *, seed: int) -> None:
        if not isinstance(cfg, TrackingConfig):
            raise TypeError(f"cfg must be a TrackingConfig, got {type(cfg).__name__}")
        if not isinstance(rig, Rig):
            raise TypeError(f"rig must be a Rig, got {type(rig).__name__}")
        self.cfg = cfg
        self.rig = rig
        self.seed = int(seed)
        self.reset()

    def reset(self) -> None:
        """Forget every tracker, person and pending candidate; re-seed the generator."""
        self._rng = np.random.default_rng(self.seed)
        self._tracks: dict[int, _Track] = {}
        self._states = np.zeros((0, sir.STATE_DIM))
        self._persons: dict[int, _Person] = {}
        self._pending: list[_Pending] = []
        self._unseen: list[_Pending] = []  # last frame set's seeds not continued in this one
        self._next_id = 1
        self._next_person = 1
        self._last_t_ns: int | None = None
        self._shares: dict[int, np.ndarray] = {}  # tracker id -> exclusion share per candidate
        self._head_only = np.zeros(0, dtype=bool)  # this step's candidates no hand may take
        self._pts = np.zeros((0, 3))  # this step's candidates ...
        self._views = np.zeros(0, dtype=np.int64)  # ... and how many cameras support each
        # (t_ns, (k, 3) unexplained candidates) of the last UNEXPLAINED_LOG_S seconds
        self._unexplained_log: deque[tuple[int, np.ndarray]] = deque()

    # ------------------------------------------------------------------ public step

    def step(
        self,
        t_ns: int,
        candidates: CandidateSet,
        observations: Mapping[str, CameraObservation] | None = None,
    ) -> TrackFrame:
        """Advance every tracker to time ``t_ns`` with this frame set's candidates.

        Parameters
        ----------
        t_ns : int
            Time of the frame set, ns on the recording clock (non-decreasing between calls;
            frames may be skipped: the time step comes from the difference).
        candidates : CandidateSet
            The 3-D candidates (points in metres, priors). ``cam_pairs`` / ``blob_pairs``
            are optional.
        observations : Mapping[str, CameraObservation] | None
            Per-camera blobs, used only as labelling cues (blob ``rel_v``) when the
            candidates carry ``cam_pairs`` and ``blob_pairs``.

        Returns
        -------
        TrackFrame
            Live trackers (every phase but uninitialised) in id order, the phase changes of
            this step, and the particles of the active trackers with their owners' ids.

        Raises
        ------
        TypeError
            ``candidates`` is not a CandidateSet.
        ValueError
            ``t_ns`` is earlier than the previous step's.
        """
        if not isinstance(candidates, CandidateSet):
            raise TypeError(f"candidates must be a CandidateSet, got {type(candidates).__name__}")
        t_ns = int(t_ns)
        if self._last_t_ns is not None and t_ns < self._last_t_ns:
            raise ValueError(
                f"t_ns must not decrease between steps: got {t_ns} after {self._last_t_ns}"
            )
        dt_s = self._step_s(t_ns)
        self._last_t_ns = t_ns
        pts = np.asarray(candidates.points_m, dtype=np.float64)
        prior = np.asarray(candidates.prior, dtype=np.float64)
        typed = self.cfg.filter.heads_only_for_heads and candidates.head_only is not None
        self._head_only = (
            np.asarray(candidates.head_only, dtype=bool) if typed else np.zeros(len(pts), bool)
        )
        self._views = (
            np.full(len(pts), 2, np.int64)
            if candidates.views is None
            else np.asarray(candidates.views, dtype=np.int64)
        )
        self._pts = pts
        self._filter(pts, prior, dt_s)
        self._count_rescued(pts, candidates.rescued)
        pairs, drifted = self._combine_pairs()
        self._unlabel_astray_joiners(pairs)
        self._measure_separation(pts, prior, dt_s, t_ns)
        seeds = self._update_seeds(pts, prior, dt_s, t_ns)
        reacquired = self._reacquire(seeds, t_ns)
        used = set(reacquired.values())  # seeds taken: no tracker starts on them
        reacquired = self._restart_unsupported(reacquired, seeds)
        strong = [sd for sd in seeds if sd.count > 0 and not sd.head_only]
        merged = self._merge_lost(t_ns, reacquired, pairs, strong)
        weak = {i for i, sd in enumerate(seeds) if sd.count == 0}  # they only re-acquire
        heads_only = {i for i, sd in enumerate(seeds) if sd.head_only}  # no hand's
        used |= self._return_drifted(seeds, used | weak)
        used |= self._split_on_seeds(seeds, used | weak)
        used |= self._split_out_of_reach(seeds, used | weak | heads_only)
        used |= self._return_slid_hands(seeds, used | weak | heads_only)
        self._split_on_third_hand(t_ns)
        self._split_on_home_hand(t_ns)
        rel_v = self._candidate_rel_v(candidates, observations)
        self._label(pts, rel_v, t_ns, observations or {}, set(reacquired) | set(merged))
        self._measure_head_rise(observations or {}, dt_s)
        transitions = self._advance_phases(t_ns, pairs, drifted, reacquired, merged)
        transitions += self._initialise(seeds, used, t_ns)
        return self._frame(t_ns, transitions)

    def _count_rescued(self, pts: np.ndarray, rescued: np.ndarray | None) -> None:
        """Update every active tracker's ``rescued_frames`` (one more if the candidate
        nearest its estimate, within ``explained_radius_m``, was kept only because a target
        was expected there, ``CandidateSet.rescued``, else back to 0) and
        ``since_own_support`` (0 if that candidate was kept on its own, else one more)."""
        act = [tr for tr in self._tracks.values() if tr.phase in ACTIVE]
        if not act:
            return
        if not len(pts):
            for tr in act:
                tr.rescued_frames = 0
                tr.since_own_support += 1
            return
        d = np.linalg.norm(np.array([tr.mean_m for tr in act])[:, None] - pts[None], axis=2)
        nearest = d.argmin(axis=1)
        near = d[np.arange(len(act)), nearest] <= self.cfg.lifecycle.explained_radius_m
        for tr, k, ok in zip(act, nearest, near, strict=True):
            was_rescued = bool(ok and rescued is not None and rescued[k])
            tr.rescued_frames = tr.rescued_frames + 1 if was_rescued else 0
            tr.since_own_support = 0 if ok and not was_rescued else tr.since_own_support + 1

    def _step_s(self, t_ns: int) -> float:
        """Time step from the previous frame set to ``t_ns``, at most ``max_dt_s`` (0 first)."""
        dt_s = 0.0 if self._last_t_ns is None else (t_ns - self._last_t_ns) * 1e-9
        return min(dt_s, self.cfg.filter.max_dt_s)

    # ------------------------------------------------------------------ 1-2: SIR filters

    @staticmethod
    def _hand_like(tr: _Track) -> bool:
        """Typed or labelled as a hand: no head-only candidate (a crown head) is its."""
        return tr.is_hand is True or tr.limb.is_hand

    def _lost_claimants(self) -> list[_Track]:
        """Labelled targets lost at most ``lost_claim_s`` ago: they still claim candidates."""
        window = self.cfg.filter.lost_claim_s
        if window <= 0 or self._last_t_ns is None:
            return []
        since = self._last_t_ns - int(window * 1e9)
        return [
            tr
            for tr in self._tracks.values()
            if tr.phase is Phase.LOST
            and tr.labelled
            and tr.lost_since_ns is not None
            and tr.lost_since_ns >= since
        ]

    def _block_rows(self, blocks: np.ndarray) -> np.ndarray:
        n = self.cfg.filter.n_particles
        return (np.asarray(blocks)[:, None] * n + np.arange(n)).ravel()

    def _filter(self, pts: np.ndarray, prior: np.ndarray, dt_s: float) -> None:
        fcfg = self.cfg.filter
        n = fcfg.n_particles
        tracks = list(self._tracks.values())
        act = np.array([tr.phase in ACTIVE for tr in tracks], dtype=bool)
        self._shares = {}
        if not act.any():
            return
        blocks = np.flatnonzero(act)
        act_tracks = [tracks[b] for b in blocks]
        rows = self._block_rows(blocks)
        is_head = np.repeat([tr.is_hand is False for tr in act_tracks], n)
        # hands (and untyped targets): a mixture of smooth constant-velocity motion and
        # stop-and-go (a fresh velocity), because hands start and stop abruptly
        reset = ~is_head & (self._rng.random(len(rows)) < fcfg.reset_fraction)
        accel = np.where(is_head, fcfg.accel_std_head_mps2, fcfg.accel_std_hand_mps2)
        st = sir.predict_constant_velocity(
            self._states[rows],
            accel,
            dt_s,
            self._rng,
            jitter_m=fcfg.position_jitter_m,
            max_speed_mps=fcfg.max_speed_mps,
        )
        if reset.any():
            st[reset] = sir.predict_velocity_reset(
                self._states[rows[reset]],
                fcfg.reset_speed_std_mps,
                dt_s,
                self._rng,
                jitter_m=fcfg.position_jitter_m,
            )
        starts = np.arange(len(blocks)) * n
        weights = prior
        shares = np.ones((len(blocks), len(pts)))
        # labelled targets lost a moment ago still claim their candidates (lost_claim_s)
        lost = self._lost_claimants() if fcfg.exclusion else []
        claimants = act_tracks + lost
        allowed = None
        if self._head_only.any():
            hands = np.array([self._hand_like(tr) for tr in claimants])
            allowed = ~(hands[:, None] & self._head_only[None, :])
        if fcfg.exclusion and len(pts) and len(claimants) > 1:
            pred = st[:, :3].reshape(len(blocks), n, 3)
            means = np.vstack([pred.mean(axis=1), *[self._lost_prior_m(tr) for tr in lost]])
            spreads = np.concatenate(
                [pred.var(axis=1).mean(axis=1), np.full(len(lost), fcfg.lost_claim_std_m**2)]
            )
            shares = sir.claim_shares(means, spreads, pts, fcfg.sigma_m, allowed)[: len(blocks)]
            weights = np.repeat(shares * prior[None, :], n, axis=0)
        elif allowed is not None:
            shares = allowed.astype(np.float64)
            weights = np.repeat(shares * prior[None, :], n, axis=0)
        self._shares = {tr.id: shares[i] for i, tr in enumerate(act_tracks)}
        # eq. 17 for all particles of all targets at once; w_k ∝ p(z|x) (eq. 12, SIR)
        log_lik, support = sir.candidate_log_likelihood(
            st[:, :3], pts, weights, fcfg.sigma_m, fcfg.clutter_level
        )
        # likelihood level: the support of the best particle (the ML point, section 5.2)
        level = np.maximum.reduceat(support, starts)
        log_w, _ = sir.block_normalise(log_lik, starts)
        mean, cov = sir.block_mean_cov(st, log_w, starts)
        keep = sir.block_systematic_resample(np.exp(log_w), starts, self._rng)
        new = st[keep]
        local = {tr.id: i for i, tr in enumerate(act_tracks)}
        done: set[int] = set()
        for i, tr in enumerate(act_tracks):
            if tr.phase is not Phase.COMBINED or tr.id in done or tr.partner not in local:
                continue
            j = local[tr.partner]
            done.update((tr.id, tr.partner))
            self._pooled_update(i, j, log_lik, support, st, new, mean, cov, level)
        self._states[rows] = new
        for i, tr in enumerate(act_tracks):
            tr.mean_m = mean[i, :3].copy()
            tr.vel_mps = mean[i, 3:].copy()
            tr.cov_m2 = cov[i, :3, :3].copy()
            tr.level = float(level[i])
            if tr.level < self.cfg.lifecycle.lost_level:
                if tr.misses == 0:
                    tr.miss_from_ns = tr.last_good_ns
                tr.misses += 1
                tr.since_miss = 0
            else:
                tr.misses = 0
                tr.since_miss += 1
                tr.last_good_m = tr.mean_m.copy()
                tr.last_good_ns = self._last_t_ns
                tr.last_good_vel_mps = tr.vel_mps.copy()
            tr.history.append((self._last_t_ns, tr.mean_m.copy()))
            a = self.cfg.labelling.evidence_alpha
            tr.speed_ema_mps = (1 - a) * tr.speed_ema_mps + a * float(np.linalg.norm(tr.vel_mps))
            b = self.cfg.labelling.contest_alpha if len(tr.history) > 1 else 1.0
            tr.support_ema = (1 - b) * tr.support_ema + b * tr.level

    def _pooled_update(
        self,
        i: int,
        j: int,
        log_lik: np.ndarray,
        support: np.ndarray,
        st: np.ndarray,
        new: np.ndarray,
        mean: np.ndarray,
        cov: np.ndarray,
        level: np.ndarray,
    ) -> None:
        """One filter for a combined pair (section 5.2): pool both blocks' particles and
        weights, and resample each block from the pooled posterior. Both trackers then carry
        the pair's estimate; its modes, when the targets part, are found among the candidates
        (:meth:`_measure_separation`), not by splitting this cloud: while the targets are
        together the cloud has one mode, and a split of it drifts apart on the particles'
        old, opposite velocities instead of following the candidates."""
        n = self.cfg.filter.n_particles
        pool = np.concatenate([np.arange(i * n, (i + 1) * n), np.arange(j * n, (j + 1) * n)])
        lw, _ = sir.block_normalise(log_lik[pool], np.zeros(1, dtype=np.intp))
        w = np.exp(lw)
        m6, c6 = sir.block_mean_cov(st[pool], lw, np.zeros(1, dtype=np.intp))
        for blk in (i, j):
            new[blk * n : (blk + 1) * n] = st[pool[sir.systematic_resample(w, self._rng, n)]]
            mean[blk], cov[blk] = m6[0], c6[0]
        level[i] = level[j] = float(support[pool].max())

    # ------------------------------------------------------------------ 3: evidence

    def _combine_pairs(self) -> tuple[dict[int, int], set[int]]:
        """Pairs of unlabelled/normal trackers whose estimates are closer than the combine
        distance; closest first, each tracker in at most one pair (at most two targets join
        at once, paper 004 section 5). A tracker of a close pair that was unsupported in its
        last ``drift_window_frames`` frame sets has drifted instead (returned apart), and so
        has a stray (:attr:`_Track.stray`) that meets a person's tracker or a combined pair."""
        lc = self.cfg.lifecycle
        cand = [tr for tr in self._tracks.values() if tr.phase in (Phase.UNLABELLED, Phase.NORMAL)]
        drifted = self._strays_in_pairs(cand)
        if len(cand) < 2:
            return {}, drifted
        pos = np.array([tr.mean_m for tr in cand])
        d = np.linalg.norm(pos[:, None] - pos[None], axis=2)
        iu, ju = np.triu_indices(len(cand), 1)
        hand = np.array([bool(tr.is_hand) and tr.person > 0 for tr in cand])
        missing = np.array([tr.misses > 0 for tr in cand])
        hands = hand[iu] & hand[ju]
        # two hands of people meeting often leave one candidate (their blobs merge), which
        # the nearer tracker takes: the other loses its support beside it; they have met if
        # it was approaching the other before its miss (one that lost its candidate beside a
        # still hand and slides onto it has not)
        close = d[iu, ju] < lc.combine_distance_m
        maybe = hands & (missing[iu] | missing[ju]) & (d[iu, ju] < lc.hand_merge_distance_m)
        for k in np.flatnonzero(maybe & ~close):
            a, b = cand[iu[k]], cand[ju[k]]
            close[k] = any(self._met(x, y) for x, y in ((a, b), (b, a)) if x.misses > 0)
        pairs: dict[int, int] = {}
        for k in np.flatnonzero(close)[np.argsort(d[iu, ju][close], kind="stable")]:
            a, b = cand[iu[k]], cand[ju[k]]
            if a.id in pairs or b.id in pairs or a.id in drifted or b.id in drifted:
                continue
            bad = [tr for tr in (a, b) if tr.since_miss < lc.drift_window_frames]
            # a hand raised to its own face merges with the head's blob in the same way
            meets = hands[k] or self._head_and_own_hand(a, b) is not None
            met = meets and any(self._met(x, y) for x, y in ((a, b), (b, a)) if x in bad)
            stray = [tr for tr in (a, b) if tr.stray]
            if len(stray) == 1 and (a if stray[0] is b else b).person > 0:
                # a tracker that never joined a person meets one that did: it is a duplicate
                # of that target or a ghost beside it (mismatched blob pair), not a second
                # target -- combining would hand the person's label to an empty pair
                drifted.add(stray[0].id)
            elif bad and not met:  # the one that missed most recently slid onto the other
                drifted.add(min(bad, key=lambda tr: (tr.since_miss, -tr.id)).id)
            else:
                pairs[a.id], pairs[b.id] = b.id, a.id
        return pairs, drifted

    def _strays_in_pairs(self, cand: list[_Track]) -> set[int]:
        """Strays among ``cand`` within the combine distance of a combined pair: duplicates
        of its targets. Left inside the pair, a stray claims the candidate of the target
        that leaves, and the pair never finds its second mode."""
        joined = [tr.mean_m for tr in self._tracks.values() if tr.phase is Phase.COMBINED]
        strays = [tr for tr in cand if tr.stray]
        if not joined or not strays:
            return set()
        pos = np.array([tr.mean_m for tr in strays])
        near = np.linalg.norm(pos[:, None] - np.array(joined)[None], axis=2).min(axis=1)
        gate = self.cfg.lifecycle.combine_distance_m
        out = {tr.id for tr, d in zip(strays, near, strict=True) if d < gate}
        for tid in sorted(out):
            log.debug("t%d is a duplicate inside a combined pair", tid)
        return out

    def _came(self, a: _Track, b: _Track) -> bool:
        """Whether a was approaching b at ``merge_closing_mps`` or faster before its latest
        miss began (:meth:`_approach_mps`)."""
        return self._approach_mps(a, b) >= self.cfg.lifecycle.merge_closing_mps

    def _met(self, missing: _Track, other: _Track) -> bool:
        """Whether a tracker that lost its support beside another met it: it was approaching
        the other before its miss began (:meth:`_came`), or (``met_by_other``) the other,
        still supported, is coming to where it was last seen (:meth:`_comes_to`)."""
        return self._came(missing, other) or (
            self.cfg.lifecycle.met_by_other
            and other.misses == 0
            and self._comes_to(other, missing.last_good_m)
        )

    def _comes_to(self, a: _Track, point_m: np.ndarray) -> bool:
        """Whether a came closer to ``point_m`` at ``merge_closing_mps`` or faster over the
        last ``approach_window_s`` (from its estimate history): a supported hand reaching
        for where the other was last seen (the other, going behind it, was hidden before
        it moved)."""
        lc = self.cfg.lifecycle
        ends = _window_ends(list(a.history), lc.approach_window_s)
        if ends is None:
            return False
        (t0, m0), (t1, m1) = ends
        gain = np.linalg.norm(m0 - point_m) - np.linalg.norm(m1 - point_m)
        return float(gain) / ((t1 - t0) * 1e-9) >= lc.merge_closing_mps

    def _approach_mps(self, a: _Track, b: _Track) -> float:
        """How fast a and b came closer in the last ``approach_window_s`` before a's latest
        miss began, m/s: from the two trackers' estimate histories, not their velocity
        estimates, whose noise alone exceeds ``merge_closing_mps`` now and then for two
        still hands. -inf when the histories do not cover the window."""
        common = [c for c in _common_history(a, b) if c[0] <= a.miss_from_ns]
        ends = _window_ends(common, self.cfg.lifecycle.approach_window_s)
        if ends is None:
            return -np.inf
        (t0, a0, b0), (t1, a1, b1) = ends
        return float(np.linalg.norm(b0 - a0) - np.linalg.norm(b1 - a1)) / ((t1 - t0) * 1e-9)

    def _combined_pairs(self) -> list[tuple[_Track, _Track]]:
        """Every combined pair once, as (tracker, its partner), by the first one's id."""
        out: list[tuple[_Track, _Track]] = []
        done: set[int] = set()
        for tr in self._tracks.values():
            if tr.phase is not Phase.COMBINED or tr.partner not in self._tracks or tr.id in done:
                continue
            out.append((tr, self._tracks[tr.partner]))
            done.update((tr.id, tr.partner))
        return out

    def _measure_separation(
        self, pts: np.ndarray, prior: np.ndarray, dt_s: float, t_ns: int
    ) -> None:
        """The modes of each combined pair's posterior, from the candidates it claims.

        Under eq. 17 the posterior's modes sit on candidates. A pair has two modes when,
        among the candidates within ``separate_gate_m`` of its estimate that it claims (an
        exclusion share of at least a half; ``separate_min_prior`` or more), the strongest
        and the strongest of those at least ``separate_distance_m`` from it exist; both
        trackers record them (``split_m``) and their velocities from the previous frame's
        modes, count the consecutive frames (``apart_frames``) and how much farther apart the
        modes moved since they appeared (``split_gain_m``): parting targets move apart, while
        a stray candidate beside joined hands (a bare forearm, a mismatched blob pair) stays
        where it appeared. Frames whose modes say the pair never met (:meth:`_never_met`)
        are counted too (``unjoin_frames``)."""
        lc = self.cfg.lifecycle
        for tr, other in self._combined_pairs():
            split = None
            if len(pts):
                share = self._shares.get(tr.id, 1.0) + self._shares.get(other.id, 1.0)
                ok = (
                    (share >= 0.5)
                    & (prior >= lc.separate_min_prior)
                    & (np.linalg.norm(pts - tr.mean_m, axis=1) < lc.separate_gate_m)
                )
                idx = np.flatnonzero(ok)
                idx = idx[np.argsort(-prior[idx], kind="stable")]
                if len(idx) >= 2:
                    far = np.linalg.norm(pts[idx[1:]] - pts[idx[0]], axis=1)
                    far = np.flatnonzero(far >= lc.separate_distance_m)
                    if len(far):
                        split = pts[[idx[0], idx[1 + far[0]]]]
            vel = np.zeros((2, 3))
            continued = False
            if split is not None and tr.split_m is not None and dt_s > 0:
                prev = tr.split_m
                if np.linalg.norm(split - prev) > np.linalg.norm(split - prev[::-1]):
                    prev = prev[::-1]
                step = np.linalg.norm(split - prev, axis=1)
                continued = bool((step <= lc.mode_gate_m).all())
                vel = (split - prev) / dt_s if continued else vel
            apart = 0 if split is None else (tr.apart_frames + 1 if continued else 1)
            dist = 0.0 if split is None else float(np.linalg.norm(split[1] - split[0]))
            first = dist if apart <= 1 else tr.split_first_m
            never = (
                split is not None
                and dist - first < lc.separate_gain_m
                and self._never_met(tr, other, split, t_ns, tr.unjoin_frames == 0)
            )
            unjoin = tr.unjoin_frames + 1 if never else 0
            for t in (tr, other):
                t.unjoin_frames = unjoin
                t.apart_frames = apart
                t.split_m = split
                t.split_vel_mps = vel
                t.split_first_m = first
                t.split_gain_m = dist - first

    def _far_apart(self, tr: _Track) -> bool:
        """Whether a combined pair's two modes have been there for ``separate_far_frames``
        frame sets, are ``separate_far_m`` or more apart and have not closed in by
        ``separate_gain_m`` since they appeared (a stray closing in on the pair is not a
        target that left it)."""
        lc = self.cfg.lifecycle
        return (
            lc.separate_far_m > 0
            and tr.apart_frames >= lc.separate_far_frames
            and tr.split_m is not None
            and tr.split_gain_m > -lc.separate_gain_m
            and float(np.linalg.norm(tr.split_m[1] - tr.split_m[0])) >= lc.separate_far_m
        )

    def _never_met(
        self, a: _Track, b: _Track, modes: np.ndarray, t_ns: int, starting: bool
    ) -> bool:
        """Whether a combined pair's two modes (``modes``, (2, 3)) say its targets never met:
        it combined while its trackers were ``combine_distance_m`` or more apart (one had
        lost its candidate beside the other: :meth:`_combine_pairs`), and each mode lies
        within ``unjoin_gate_m`` of where one of the two trackers was at the join; a run of
        such frames (``starting``: this would be its first) must begin at most
        ``unjoin_within_s`` after the join. Two hands held out near each other (the
        negative scene: 27 cm apart for a second) lose a candidate now and then when their
        blobs touch in one view; their candidates come back at once where the hands stayed.
        Hands that met are together for a while, and leave the meeting point when they
        part."""
        lc = self.cfg.lifecycle
        if (
            lc.unjoin_gate_m <= 0
            or not a.joined_apart
            or a.joined_ns is None
            or a.joined_m is None
            or b.joined_m is None
            or (starting and (t_ns - a.joined_ns) * 1e-9 > lc.unjoin_within_s)
        ):
            return False
        return self._modes_by_place(a, b, modes)[1] <= lc.unjoin_gate_m

    @staticmethod
    def _modes_by_place(a: _Track, b: _Track, modes: np.ndarray) -> tuple[tuple[int, int], float]:
        """The modes of a and b, by where the two were at their join (``joined_m``): the
        assignment whose farther mode is nearer its tracker's place, and that distance, m."""
        pre = np.array([a.joined_m, b.joined_m])
        straight = float(np.linalg.norm(modes - pre, axis=1).max())
        crossed = float(np.linalg.norm(modes[::-1] - pre, axis=1).max())
        return ((0, 1), straight) if straight <= crossed else ((1, 0), crossed)

    def _unexplained(self, pts: np.ndarray, prior: np.ndarray, min_prior: float) -> np.ndarray:
        """Indices of candidates with prior >= min_prior farther than explained_radius_m
        from every active tracker's estimate and every mode of a combined pair (the parting
        targets' own candidates, which they take when they separate)."""
        ok = prior >= min_prior
        act = [tr.mean_m for tr in self._tracks.values() if tr.phase in ACTIVE]
        act += [m for tr in self._tracks.values() if tr.split_m is not None for m in tr.split_m]
        if act and len(pts):
            d = np.linalg.norm(pts[:, None] - np.array(act)[None], axis=2)
            ok &= d.min(axis=1) > self.cfg.lifecycle.explained_radius_m
        return np.flatnonzero(ok)

    def _update_seeds(
        self, pts: np.ndarray, prior: np.ndarray, dt_s: float, t_ns: int
    ) -> list[_Pending]:
        """Strong candidates no active tracker explains, continued from the previous frame
        set's (within ``init_gate_m``): the seeds of new and re-acquired trackers.

        Non-maximum suppression (strongest first, ``explained_radius_m``) keeps one seed per
        target. Returns this frame set's seeds; those with ``count >= init_confirm_frames``
        persisted long enough to be trusted (one-frame ghosts never are). The unexplained
        candidates are also logged for :meth:`_there_as_pair_joined`."""
        lc = self.cfg.lifecycle
        floor = min(lc.init_prior_min, lc.reacquire_prior_min)
        free = self._unexplained(pts, prior, floor)
        self._log_unexplained(pts[free[prior[free] >= lc.init_prior_min]], t_ns)
        kept: list[int] = []
        for k in sorted(free.tolist(), key=lambda k: (-prior[k], k)):
            if all(np.linalg.norm(pts[k] - pts[j]) > lc.explained_radius_m for j in kept):
                kept.append(k)
        combined = [tr for tr in self._tracks.values() if tr.phase is Phase.COMBINED]
        seeds: list[_Pending] = []
        taken_prev: set[int] = set()
        bridge_from = self._unseen if lc.reacquire_bridge else []
        for k in kept:
            strong = prior[k] >= lc.init_prior_min
            best, best_key = -1, (True, lc.init_gate_m)
            for i, pend in enumerate(self._pending):
                d = float(np.linalg.norm(pts[k] - pend.position_m))
                # a strong seed continues a strong one first: weak ones must not break runs
                key = (strong and pend.count == 0, d)
                if i not in taken_prev and d <= lc.init_gate_m and key <= best_key:
                    best, best_key = i, key
            prev = self._pending[best] if best >= 0 else None
            bridged = 0
            if prev is None:
                bridged = self._bridged_seen(pts[k], bridge_from)
            elif prev.bridged_seen:
                bridged = prev.bridged_seen + 1
            seen = 1 if prev is None else prev.seen + 1
            if prev is not None and (prev.count > 0 or not strong):
                taken_prev.add(best)
                vel = (pts[k] - prev.position_m) / dt_s if dt_s > 0 else np.zeros(3)
                seed = _Pending(
                    pts[k].copy(),
                    prev.count + 1 if strong else 0,
                    vel,
                    prev.first_ns,
                    dict(prev.pair_first_m),
                    seen,
                    bool(self._head_only[k]),
                    bridged,
                )
            else:
                if prev is not None:
                    taken_prev.add(best)
                seed = _Pending(
                    pts[k].copy(),
                    int(strong),
                    np.zeros(3),
                    t_ns,
                    seen=seen,
                    head_only=bool(self._head_only[k]),
                    bridged_seen=bridged,
                )
            for tr in combined:
                seed.pair_first_m.setdefault(tr.id, float(np.linalg.norm(pts[k] - tr.mean_m)))
            seeds.append(seed)
        if lc.reacquire_bridge:
            self._unseen = [p for i, p in enumerate(self._pending) if i not in taken_prev]
        self._pending = seeds
        return seeds

    def _bridged_seen(self, point_m: np.ndarray, unseen: list[_Pending]) -> int:
        """The run a candidate at ``point_m`` continues across one frame set without it
        (``reacquire_bridge``): 1 + the frame sets seen of the nearest seed of the frame set
        before last that was not continued last time, within ``init_gate_m``; 0 if none."""
        if not unseen:
            return 0
        d = np.linalg.norm(np.array([p.position_m for p in unseen]) - point_m, axis=1)
        i = int(d.argmin())
        if d[i] > self.cfg.lifecycle.init_gate_m:
            return 0
        return 1 + max(unseen[i].seen, unseen[i].bridged_seen)

    def _log_unexplained(self, pts: np.ndarray, t_ns: int) -> None:
        """Remember this frame set's unexplained candidates (``pts``, owned by the log from
        now on) and forget those older than ``UNEXPLAINED_LOG_S``."""
        log_ = self._unexplained_log
        log_.append((t_ns, pts))
        while log_ and (t_ns - log_[0][0]) * 1e-9 > UNEXPLAINED_LOG_S:
            log_.popleft()

    def _there_as_pair_joined(self, pair: _Track, seed_m: np.ndarray, first_ns: int) -> bool:
        """True if a seed at ``seed_m`` (or a tracker there since ``first_ns``) was there as
        the combined pair ``pair`` joined (:meth:`_there_as_joined`), judged from either of
        its two trackers. Each keeps where it was as they joined (0.25 m apart in the case
        below: hands whose blobs merged), so the time a target needs to reach the seed
        differs between them; judged from one alone, the pair's fate would depend on which
        of its trackers asks first. Demo take 101 with the bare-forearm option, seed 0, 4.33
        s: a ghost 0.59 m from the pair, seen there 0.13 s before the hands joined, lay just
        outside the nearer tracker's window and inside the farther one's; the pair parted
        onto it while the hands still held the ball, and the exchange read as a place
        (docs/benchmarks.md, session 98)."""
        partner = self._tracks.get(pair.partner) if pair.partner is not None else None
        members = [pair] if partner is None or partner.partner != pair.id else [pair, partner]
        return any(self._there_as_joined(t, seed_m, first_ns) for t in members)

    def _there_as_joined(self, tr: _Track, seed_m: np.ndarray, first_ns: int) -> bool:
        """:meth:`_there_as_pair_joined` from one tracker ``tr`` of the pair: True if a seed
        at ``seed_m`` (or a tracker there since ``first_ns``) was there before, as the pair
        joined, and has since vanished and come back: an unexplained candidate within
        ``init_gate_m`` of it, before its present run of frame sets (which began at
        ``first_ns``), so close in time to the joining that neither of the pair's targets
        could have been there (at ``leave_speed_mps`` a hand needs (distance - gate) / speed
        to get from where ``tr`` was as the pair joined to the seed). Such a seed is not a
        target leaving the pair but something that stood beside it (a ghost from
        skin-coloured clothes beside shaking hands). A seed whose present run began that
        early is not judged: its own steady evidence says the joining was not of two targets
        (a tracker that slid onto the other's hand while its own went home). Also true if
        another labelled target (normal) stood there when the pair joined
        (:meth:`_stood_there`): that target's tracker has drifted off it since
        (:meth:`_return_drifted`). (Not an unlabelled tracker: one left over where a hand
        rested before it reached out marks that hand's home, where it comes back.)"""
        lc = self.cfg.lifecycle
        if tr.joined_ns is None or tr.joined_m is None:
            return False
        travel_s = max(float(np.linalg.norm(seed_m - tr.joined_m)) - lc.init_gate_m, 0.0)
        travel_ns = travel_s / lc.leave_speed_mps * 1e9
        start_ns = tr.joined_ns - travel_ns
        stop_ns = min(tr.joined_ns + travel_ns, first_ns)
        for t_ns, pts in self._unexplained_log:  # oldest first
            if t_ns >= stop_ns:
                break
            if t_ns > start_ns and (np.linalg.norm(pts - seed_m, axis=1) <= lc.init_gate_m).any():
                return True
        if any(np.linalg.norm(g - seed_m) <= lc.init_gate_m for g in tr.ghosts_m):
            return True
        return self._stood_there(tr, seed_m) is not None

    def _stood_there(self, pair: _Track, seed_m: np.ndarray) -> int | None:
        """The id of the labelled target whose estimate was nearest ``seed_m``, within
        ``init_gate_m``, when the combined pair ``pair`` joined (``joined_others``); None if
        there was none."""
        if not pair.joined_others:
            return None
        ids = list(pair.joined_others)
        d = np.linalg.norm(np.array(list(pair.joined_others.values())) - seed_m, axis=1)
        k = int(np.argmin(d))
        return ids[k] if d[k] <= self.cfg.lifecycle.init_gate_m else None

    def _return_drifted(self, seeds: list[_Pending], used: set[int]) -> set[int]:
        """Put labelled targets' trackers that drifted off them back on their seeds; returns
        the seeds used.

        A confirmed seed where a labelled target (normal) stood as a combined pair joined
        (:meth:`_stood_there`) is that target, not one leaving the pair
        (:meth:`_there_as_pair_joined`). The target's tracker, no longer explaining it, has
        moved off it, onto a ghost beside it (bundled handshake, seed 3: p2's resting left
        hand lost its candidate for a frame set and its tracker slid 33 cm up onto a blob
        pair on p2's shirt). Started there, a new tracker would take the target from it
        (an identity switch); instead the target's own tracker is drawn again around the
        seed. The place it leaves is a ghost that stood beside the pair while both its
        targets were in it: the pair remembers it (``ghosts_m``), and a seed there does not
        part it either."""
        lc = self.cfg.lifecycle
        out: set[int] = set()
        for pair, other in self._combined_pairs():
            for i, sd in enumerate(seeds):
                if i in used or i in out or sd.count < lc.init_confirm_frames:
                    continue
                tid = self._stood_there(pair, sd.position_m)
                back = self._tracks.get(tid) if tid is not None else None
                if back is None or back.phase is not Phase.NORMAL or not back.labelled:
                    continue
                if sd.head_only and self._hand_like(back):
                    continue
                for t in (pair, other):
                    t.ghosts_m.append(back.mean_m.copy())
                self._reinit(back, sd.position_m, sd.velocity_mps)
                out.add(i)
                log.debug("t%d back on its target at %s", back.id, sd.position_m.round(2))
        return out

    def _return_slid_hands(self, seeds: list[_Pending], used: set[int]) -> set[int]:
        """Put labelled hands' trackers that slid up their arm back on the hand; returns the
        seeds used.

        A bare forearm, or a shirt patch beside a hand, gives a candidate 15-30 cm from the
        hand towards the body. When the hand's own candidate is missing for a few frame sets
        the tracker slides onto that one, and when the hand's candidate comes back it becomes
        a seed: started there, a new tracker would take the hand from the labelled one (an
        identity switch; negative scene, bare-forearm option on: in all six seeds). So a
        confirmed seed goes back to a person's hand (normal) when

        - it is within ``slid_hand_gate_m`` of the hand's estimate and farther from the
          person's head, by ``slid_hand_gain_m``: farther out along the arm;
        - relative to the head, the tracker stood there (``slid_hand_stood_m``) within the
          last ``slid_hand_within_s``: the hand is where it was, the tracker moved (relative
          to the head, because the person may walk meanwhile);
        - the head is tracked, the seed within its ``arm_reach_m`` and not nearer another
          tracked head by ``person_margin_m``, and the person's other hand tracked (normal
          or combined) and farther from the seed: it is not the other hand, nor someone
          else's.

        The hand's tracker is drawn again around the seed."""
        lc, lcfg = self.cfg.lifecycle, self.cfg.labelling
        out: set[int] = set()
        if lc.slid_hand_gate_m <= 0 or self._last_t_ns is None:
            return out
        hands = [
            tr
            for tr in self._tracks.values()
            if tr.phase is Phase.NORMAL and tr.labelled and tr.limb.is_hand
        ]
        heads = {p: h for p in self._persons if (h := self._active_head(p)) is not None}
        since_ns = self._last_t_ns - int(lc.slid_hand_within_s * 1e9)
        for i, sd in enumerate(seeds):
            if i in used or sd.count < lc.init_confirm_frames:
                continue
            best, best_d = None, lc.slid_hand_gate_m  # the nearest such hand
            for tr in hands:
                head = heads.get(tr.person)
                d = float(np.linalg.norm(sd.position_m - tr.mean_m))
                if head is None or d > best_d:
                    continue
                out_m = float(np.linalg.norm(sd.position_m - head.mean_m))
                tr_out_m = float(np.linalg.norm(tr.mean_m - head.mean_m))
                if out_m < tr_out_m + lc.slid_hand_gain_m or out_m > lcfg.arm_reach_m:
                    continue
                if any(
                    np.linalg.norm(sd.position_m - h.mean_m) + lcfg.person_margin_m <= out_m
                    for p, h in heads.items()
                    if p != tr.person
                ):
                    continue
                if not self._other_hand_farther(tr, sd.position_m, d):
                    continue
                if self._stood_on_body(tr, head, sd.position_m, since_ns):
                    best, best_d = tr, d
            if best is not None:
                self._reinit(best, sd.position_m, sd.velocity_mps)
                hands.remove(best)
                out.add(i)
                log.debug("t%d slid back to its hand at %s", best.id, sd.position_m.round(2))
        return out

    @staticmethod
    def _history_at(tr: _Track, t_ns: int) -> np.ndarray | None:
        """A copy of ``tr``'s estimate at ``t_ns``: the latest one at or before it that its
        history holds, or None if the history starts later."""
        for t, m in reversed(tr.history):
            if t <= t_ns:
                return m.copy()
        return None

    def _before_miss_m(self, tr: _Track) -> np.ndarray:
        """Where ``tr`` stood when it was last supported before its latest miss began (a
        tracker that slid onto something is supported again there)."""
        m = self._history_at(tr, tr.miss_from_ns)
        return tr.last_good_m.copy() if m is None else m

    def _other_hand_farther(self, tr: _Track, point_m: np.ndarray, d_m: float) -> bool:
        """Whether the other hand of ``tr``'s person is tracked (normal or combined) and
        farther than ``d_m`` from ``point_m``."""
        person = self._persons.get(tr.person)
        others = [
            o
            for tid in (person.hand_ids if person is not None else [])
            if tid != tr.id and (o := self._tracks.get(tid)) is not None
        ]
        return bool(others) and all(
            o.phase in (Phase.NORMAL, Phase.COMBINED)
            and float(np.linalg.norm(o.mean_m - point_m)) > d_m
            for o in others
        )

    def _stood_on_body(self, tr: _Track, head: _Track, point_m: np.ndarray, since_ns: int) -> bool:
        """Whether, relative to its person's head, ``tr`` stood within ``slid_hand_stood_m``
        of where ``point_m`` is relative to the head now, at a time since ``since_ns``."""
        head_at = dict(head.history)
        rel = point_m - head.mean_m
        reach = self.cfg.lifecycle.slid_hand_stood_m
        return any(
            t >= since_ns and t in head_at and float(np.linalg.norm(m - head_at[t] - rel)) <= reach
            for t, m in tr.history
        )

    def _split_on_seeds(self, seeds: list[_Pending], used: set[int]) -> set[int]:
        """Part combined pairs on confirmed seeds near them; returns the seeds used.

        A target leaving a combined pair is the pair's second mode; when it left faster than
        the mode measurement follows (a frame without its candidate, a jump beyond
        ``separate_gate_m``), its candidate turns into a seed. Started as a new tracker it
        would take that candidate from the pair, which then never separates and keeps both
        labels on the target that stayed. So a confirmed seed within ``pair_seed_gate_m`` of a
        combined pair (and at least ``separate_distance_m`` from it) becomes the pair's second
        mode (the pair's estimate the first), and the pair separates by the angle rule. The
        gate applies to the distance when the seed and the pair were first seen together
        (``_Pending.pair_first_m``): a hand parting at 2.5 m/s is 70 cm away by the time its
        seed is confirmed, and after a handshake the pair follows the other hand away in the
        opposite direction (demo: 54 cm when the seed appeared, 75 cm from where the pair
        then was two frame sets later). A seed that was already there as the pair joined
        (:meth:`_there_as_pair_joined`) is not one of its targets. A pair of a person's head
        and own hand (a hand raised to the face) parts on a seed anywhere within
        ``arm_reach_m`` of it, and the head takes the higher mode: the hand can drop from the
        face to the hip, 75 cm, faster than the gate follows (negative scene with the
        bare-forearm option, p2 at 9 s)."""
        lc = self.cfg.lifecycle
        out: set[int] = set()
        parted: set[int] = set()
        retired: set[int] = set()  # young trackers a pair parted onto (:meth:`_young_hands`)
        # strong seeds, confirmed or not: an unconfirmed one only ever parts a pair together
        # with a confirmed one (:meth:`_both_leaving`)
        free = [i for i, sd in enumerate(seeds) if i not in used and sd.count > 0]
        for tr in self._tracks.values():
            if tr.phase is not Phase.COMBINED or tr.partner not in self._tracks or not free:
                continue
            if tr.id in parted or tr.apart_frames >= lc.separate_frames:
                continue
            other = self._tracks[tr.partner]
            if self._hand_like(tr) and self._hand_like(other):
                free_here = [i for i in free if not seeds[i].head_only]
            else:
                free_here = free
            if not free_here:
                continue
            d = np.array([np.linalg.norm(seeds[i].position_m - tr.mean_m) for i in free_here])
            d0 = np.array([seeds[i].pair_first_m.get(tr.id, np.inf) for i in free_here])
            heads = self._owner_heads(tr, other)
            head_first = self._head_and_own_hand(tr, other)
            if head_first is None:
                fit = np.array(
                    [self._parting_fit(heads, tr.mean_m, seeds[i].position_m) for i in free_here]
                )
            else:  # a person's hand is never beyond arm's reach of their head
                fit = np.where(d <= self.cfg.labelling.arm_reach_m, 2, 0)
            ok = (
                (d >= lc.separate_distance_m)
                & (fit > 0)
                & ((d0 <= lc.pair_seed_gate_m) | (fit > 1))
            )
            for j in np.flatnonzero(ok):
                seed = seeds[free_here[j]]
                ok[j] = not self._there_as_pair_joined(tr, seed.position_m, seed.first_ns)
            confirmed = np.array([seeds[i].count >= lc.init_confirm_frames for i in free_here])
            if not (ok & confirmed).any():
                continue
            both = None
            leaving = [free_here[j] for j in np.flatnonzero(ok)]
            young: list[_Track] = []  # trackers that may be a hand that left (confirmed)
            if head_first is None:
                young = [c for c in self._young_hands(tr) if c.id not in retired]
                options = [seeds[i] for i in leaving] + [
                    _Pending(c.mean_m, lc.init_confirm_frames, c.vel_mps, c.born_ns) for c in young
                ]
                both = self._both_leaving(tr, heads, options)
            if both is not None and self._held(tr):
                log.debug("t%d / t%d are held where they met: not both leaving", tr.id, other.id)
                both = None
            fixed: tuple[int | None, int | None] = (None, None)
            if both is not None:
                picked = [leaving[k] for k in both if k < len(leaving)]
                for k in both:
                    if k >= len(leaving):  # a tracker is the hand: the pair's takes its place
                        c = young[k - len(leaving)]
                        log.debug("t%d / t%d part on t%d", tr.id, other.id, c.id)
                        retired.add(c.id)
                modes = np.array([options[k].position_m for k in both])
                vels = np.array([options[k].velocity_mps for k in both])
            else:
                picked = [free_here[int(np.argmin(np.where(ok & confirmed, d0, np.inf)))]]
                seed = seeds[picked[0]]
                modes = np.array([tr.mean_m, seed.position_m])
                vels = np.array([tr.vel_mps, seed.velocity_mps])
                if head_first is not None:  # the head takes the higher mode
                    high = int(modes[1, 2] > modes[0, 2])
                    fixed = (high, 1 - high) if head_first else (1 - high, high)
            free = [i for i in free if i not in picked]
            self._part((tr, other), modes, vels, fixed)
            out.update(picked)
            parted.update((tr.id, other.id))
            log.debug("t%d / t%d part on new candidates at %s", tr.id, other.id, modes)
        for tid in retired:
            self._remove(tid)
        return out

    def _young_hands(self, pair: _Track) -> list[_Track]:
        """Trackers that may be a hand that left the combined pair ``pair``: started after
        it joined, not typed a head, in no person's slots, on a candidate (one within
        ``explained_radius_m``: a tracker started on a ghost slides off once the ghost goes,
        three_people take 101 at 5.8 s), ``separate_distance_m`` or more from the pair and
        not there as it joined (:meth:`_there_as_pair_joined`).

        A hand that left the pair appears as a new candidate, and its seed can grow into a
        tracker (typed a hand only a few frame sets later) before the pair parts: handshake,
        seeds 4 and 5 at 10.07 s, a tracker started on p1's hand going home one frame set
        before the pair, held between the two people by a ghost, parted onto p2's hand and
        a ghost by p1's chest. :meth:`_both_leaving` weighs these trackers like seeds."""
        if pair.joined_ns is None or not len(self._pts):
            return []
        lc = self.cfg.lifecycle
        return [
            c
            for c in self._tracks.values()
            if c.phase is Phase.UNLABELLED
            and c.person == 0
            and c.is_hand is not False
            and not c.demoted
            and c.born_ns > pair.joined_ns
            and np.linalg.norm(c.mean_m - pair.mean_m) >= lc.separate_distance_m
            and self._on_a_candidate(c, lc.explained_radius_m)
            and not self._there_as_pair_joined(pair, c.mean_m, c.born_ns)
        ]

    def _head_and_own_hand(self, a: _Track, b: _Track) -> bool | None:
        """True when ``a`` is a person's head and ``b`` one of that person's hands, False
        the other way round, None for any other pair."""
        if a.person == 0 or a.person != b.person or {a.is_hand, b.is_hand} != {True, False}:
            return None
        return b.is_hand is True

    def _held(self, pair: _Track) -> bool:
        """Whether a candidate within ``explained_radius_m`` of a combined pair's estimate
        is supported by ``held_views`` cameras or more: one of its targets is still there.

        three_people, seeds 0 and 1 at 4.73 s: the two hands of a handshake stayed together
        on a candidate four views support while a ghost and another point 0.5 m away, on
        opposite sides, became seeds; parted onto both, the pair left the hands to a new
        tracker (two identity switches). Candidates without a view count count as two
        views."""
        lc = self.cfg.lifecycle
        if lc.held_views <= 0 or not len(self._pts):
            return False
        near = np.linalg.norm(self._pts - pair.mean_m, axis=1) <= lc.explained_radius_m
        return bool((self._views[near] >= lc.held_views).any())

    def _both_leaving(
        self, pair: _Track, heads: np.ndarray | None, seeds: list[_Pending]
    ) -> tuple[int, int] | None:
        """Two of ``seeds`` (those a combined pair may part on) that are both of its targets,
        leaving at once, or None. At least one of the two must be confirmed.

        Two hands that part fast can both outrun the pair: it stays where they met, held
        there by a ghost where their lines of sight cross (handshake, seeds 0, 2 and 5 at
        10.1 s), and both hands' candidates become seeds in the same frame set. Parted onto
        one of them, the pair's estimate (the ghost) would be the other mode and the second
        hand would get a new tracker. Two seeds on opposite sides of the pair (their
        directions from it more than 90 degrees apart) whose owners can reach them (the
        owner rule, :func:`lab.owner_rule`, for two people's hands) are taken as both
        targets: the nearest such two. Trackers started since the pair joined that may be a
        hand that left it (:meth:`_young_hands`) come as confirmed seeds where they are."""
        if len(seeds) < 2:
            return None
        reach = self.cfg.labelling.arm_reach_m + self.cfg.labelling.person_margin_m
        pts = np.array([sd.position_m for sd in seeds])
        away = pts - pair.mean_m
        best, best_d = None, np.inf
        confirmed = [sd.count >= self.cfg.lifecycle.init_confirm_frames for sd in seeds]
        for a, b in itertools.combinations(range(len(seeds)), 2):
            if float(away[a] @ away[b]) >= 0 or not (confirmed[a] or confirmed[b]):
                continue
            if heads is not None:
                owners = lab.owner_rule(pts[[a, b]], heads, 0.0)
                assert owners is not None  # a zero margin always decides
                to_head = np.linalg.norm(pts[[a, b]][list(owners[0])] - heads, axis=1)
                if (to_head > reach).any():
                    continue
            d = float(np.linalg.norm(away[a]) + np.linalg.norm(away[b]))
            if d < best_d:
                best, best_d = (a, b), d
        return best

    def _part(
        self,
        pair: tuple[_Track, _Track],
        modes_m: np.ndarray,
        vel_mps: np.ndarray,
        fixed: tuple[int | None, int | None] = (None, None),
        *,
        never_met: bool = False,
    ) -> None:
        """Make a combined pair separate in this frame set onto ``modes_m`` ((2, 3), with
        velocities ``vel_mps``): ``fixed`` gives each tracker its mode (None: the owner or
        angle rule decides, :meth:`_separate`); ``never_met`` makes it a pair that never met
        (the activity stage drops its episode)."""
        lc = self.cfg.lifecycle
        for t, mode in zip(pair, fixed, strict=True):
            t.split_m, t.split_vel_mps = modes_m, vel_mps
            t.apart_frames = lc.separate_frames
            t.split_gain_m = np.inf
            t.split_fixed = mode
            if never_met:
                t.unjoin_frames = lc.separate_frames

    def _split_out_of_reach(self, seeds: list[_Pending], used: set[int]) -> set[int]:
        """Part combined pairs of two people's hands that one owner cannot reach; returns the
        seeds used.

        A pair that joined two people's hands and then followed one of them home, while the
        other went unseen (three_people: after an exchange, the taker's hand in one view
        only), has no second mode to separate on, and keeps both labels on the hand it
        follows. Once its estimate has been farther than ``arm_reach_m`` +
        ``person_margin_m`` from one owner's head for ``out_of_reach_frames`` frame sets,
        that owner's hand is not in it: the pair separates, the other keeps the estimate,
        and the hand left behind goes to the seed (unconfirmed too) nearest where the pair
        joined that is within ``arm_reach_m`` of its owner's head, ``separate_distance_m``
        or more from the pair (handshake: the hand was seen going home but its candidates
        came and went, so no mode or seed lasted), else where the pair joined (its last
        known place, at rest). The owner rule (:meth:`_separate`) gives each its mode."""
        lc, lcfg = self.cfg.lifecycle, self.cfg.labelling
        out: set[int] = set()
        if lc.out_of_reach_frames <= 0:
            return out
        for tr, other in self._combined_pairs():
            heads = self._owner_heads(tr, other)
            if heads is None or tr.joined_m is None or tr.apart_frames >= lc.separate_frames:
                tr.out_of_reach_frames = other.out_of_reach_frames = 0
                continue
            reach = np.linalg.norm(heads - tr.mean_m, axis=1)
            beyond = reach > lcfg.arm_reach_m + lcfg.person_margin_m
            count = tr.out_of_reach_frames + 1 if beyond.any() else 0
            tr.out_of_reach_frames = other.out_of_reach_frames = count
            if count < lc.out_of_reach_frames:
                continue
            left_m, left_vel = tr.joined_m, np.zeros(3)
            if beyond.sum() == 1:  # that owner's hand was left behind
                k = self._seed_of_left_hand(
                    seeds, used | out, heads[beyond][0], tr.mean_m, tr.joined_m
                )
                if k is not None:
                    left_m, left_vel = seeds[k].position_m, seeds[k].velocity_mps
                    out.add(k)
            # the owner who cannot reach the pair's estimate has the hand left behind
            fixed = ((1, 0) if beyond[0] else (0, 1)) if beyond.sum() == 1 else (None, None)
            self._part(
                (tr, other),
                np.array([tr.mean_m, left_m]),
                np.array([tr.vel_mps, left_vel]),
                fixed,
            )
            tr.out_of_reach_frames = other.out_of_reach_frames = 0
            log.debug(
                "t%d / t%d part: %.2f m from a head, out of reach; the other hand at %s",
                tr.id,
                other.id,
                reach.max(),
                left_m,
            )
        return out

    def _split_on_third_hand(self, t_ns: int) -> None:
        """Part a combined pair of one person's two hands onto a third hand of that person.

        A ghost beside a hand (two views' lines of sight of different limbs crossing near the
        body) can take a hand slot before the real hand's tracker is confirmed; when the
        ghost's candidate goes, its tracker slides onto the neighbouring hand and the two
        combine. The real hand is then followed by an unlabelled tracker that no slot is
        free for, and the pair never finds a second mode, since that tracker claims the
        hand's candidates (handshake, scene seed 102: p2's two labels sat on his left hand
        from his first second in view, and both handshakes went to "one tracker"). So an
        unlabelled hand tracker that is clearly the pair's person's
        (:func:`lab.nearest_person`), tracked since before the pair joined, out of every
        other person's reach, at least ``separate_distance_m`` from the pair and at most
        ``contest_margin`` less supported than it (``support_ema``; a ghost beside clasped
        hands is seen by fewer views) for ``own_pair_third_hand_s`` becomes the
        pair's second mode: the pair separates as one that never met (the activity stage
        drops its episode), each tracker to the mode on its side of the body, and the
        unlabelled tracker, now a duplicate, is retired."""
        wait_s = self.cfg.lifecycle.own_pair_third_hand_s
        own = {
            a.person: (a, b)
            for a, b in self._combined_pairs()
            if a.is_hand and b.is_hand and a.person == b.person > 0
        }
        persons, heads = self._live_heads()
        waiting: set[int] = set()
        for c, k in self._free_hands(persons, heads) if wait_s > 0 and own else []:
            pair = own.get(persons[k].number) if k >= 0 else None
            if pair is None or not self._third_hand(c, *pair, np.delete(heads, k, axis=0)):
                continue
            waiting.add(c.id)
            c.third_hand_ns, due = _persisted(c.third_hand_ns, t_ns, wait_s)
            if not due:
                continue
            a, b = pair
            split = np.array([a.mean_m, c.mean_m])
            sides = self._mode_sides(a, b, split) or (None, None)
            self._part((a, b), split, np.array([a.vel_mps, c.vel_mps]), sides, never_met=True)
            log.debug("t%d / t%d part on t%d, a third hand of p%d", a.id, b.id, c.id, a.person)
            del own[a.person]
            self._remove(c.id)
        for tr in self._tracks.values():
            if tr.id not in waiting:
                tr.third_hand_ns = None

    def _free_hands(self, persons: list[_Person], heads: np.ndarray) -> list[tuple[_Track, int]]:
        """Unlabelled hand trackers that have not lost a slot contest, each with the index in
        ``persons`` of the person it clearly belongs to (:func:`lab.nearest_person`; -1
        none)."""
        lcfg = self.cfg.labelling
        free = [
            c
            for c in self._tracks.values()
            if c.is_hand and c.person == 0 and c.phase is Phase.UNLABELLED and not c.demoted
        ]
        none = np.zeros(len(persons), int)
        return [(c, lab.nearest_person(c.mean_m, heads, none, lcfg)) for c in free]

    def _third_hand(self, c: _Track, a: _Track, b: _Track, other_heads: np.ndarray) -> bool:
        """Whether ``c`` stands apart from the combined pair ``a``/``b``, is about as well
        supported, is out of every other person's reach (``other_heads``; a hand held
        out to the pair's person, in a handshake, is not a third hand of theirs), and was
        tracked already when the pair joined: then the pair's two trackers and ``c``
        followed three targets, and one of the pair's was no hand. A tracker started after
        the join may be a hand leaving the pair (:meth:`_split_on_seeds` parts it) or a
        ghost beside it (three_people, take 102: one 44 cm from p1's head while his hands
        were together at a handshake) (:meth:`_split_on_third_hand`)."""
        lcfg = self.cfg.labelling
        reach = np.linalg.norm(other_heads - c.mean_m, axis=1).min(initial=np.inf)
        return bool(
            a.joined_ns is not None
            and c.born_ns <= a.joined_ns
            and np.linalg.norm(c.mean_m - a.mean_m) >= self.cfg.lifecycle.separate_distance_m
            and c.support_ema >= max(a.support_ema, b.support_ema) - lcfg.contest_margin
            and reach > lcfg.arm_reach_m
        )

    def _split_on_home_hand(self, t_ns: int) -> None:
        """Part a combined pair of two people's hands onto one owner's hand that went home.

        After a handover the giver's hand can leave faster than the pair's modes follow
        and be seen again only at the giver's side, beyond ``pair_seed_gate_m``, where its
        seed starts a new tracker (held-out exchange take 101, seed 0: 0.6-0.7 m from the
        pair, which followed the taker's hand; the pair later parted onto a ghost and the
        giver's label read the ball). An unlabelled hand tracker started after the join
        that is clearly owner P's (:func:`lab.nearest_person`), while P's other hand is
        tracked elsewhere (normal, ``separate_distance_m`` or more from it), is P's hand
        from the pair or a ghost. Farther than ``arm_reach_m`` + ``person_margin_m`` from
        every other person's head (a ghost on P's chest beside clasped hands is about 1 m
        from the other owner's; a hand hanging at P's side 1.2 m), ``separate_distance_m``
        or more from the pair and at most ``contest_margin`` less supported than it for
        ``home_hand_s``, it is the hand: the pair separates, P's tracker on it and the
        other owner's on the pair's estimate, and it is retired as a duplicate. Not if it
        has been anywhere an unexplained candidate stood as the pair joined
        (:meth:`_there_as_pair_joined`): a ghost on P's chest can be just over that distance
        from the other head (bundled handshake, seed 0: 1.13 m)."""
        wait_s = self.cfg.lifecycle.home_hand_s
        members: dict[int, tuple[_Track, _Track]] = {}  # owner -> (its hand, the other)
        for a, b in self._combined_pairs():
            if a.is_hand and b.is_hand and a.person != b.person and 0 not in (a.person, b.person):
                members[a.person], members[b.person] = (a, b), (b, a)
        persons, heads = self._live_heads()
        waiting: set[int] = set()
        for c, k in self._free_hands(persons, heads) if wait_s > 0 and members else []:
            entry = members.get(persons[k].number) if k >= 0 else None
            if entry is None or not self._home_hand(
                c, *entry, persons[k], np.delete(heads, k, axis=0)
            ):
                continue
            waiting.add(c.id)
            c.home_hand_ns, due = _persisted(c.home_hand_ns, t_ns, wait_s)
            if not due:
                continue
            mine, other = entry
            self._part(
                (other, mine),
                np.array([other.mean_m, c.mean_m]),
                np.array([other.vel_mps, c.vel_mps]),
                (0, 1),
            )
            log.debug(
                "t%d / t%d part on t%d, p%d's hand gone home", mine.id, other.id, c.id, mine.person
            )
            for p in (mine.person, other.person):
                members.pop(p, None)
            self._remove(c.id)
        for tr in self._tracks.values():
            if tr.id not in waiting:
                tr.home_hand_ns = None

    def _home_hand(
        self, c: _Track, mine: _Track, other: _Track, p: _Person, other_heads: np.ndarray
    ) -> bool:
        """Whether ``c`` is owner ``p``'s hand gone home from the pair ``mine``/``other``
        (:meth:`_split_on_home_hand`)."""
        lc, lcfg = self.cfg.lifecycle, self.cfg.labelling
        rest = [self._tracks.get(h) for h in p.hand_ids if h != mine.id]
        reach = np.linalg.norm(other_heads - c.mean_m, axis=1).min(initial=np.inf)
        return bool(
            mine.joined_ns is not None
            and c.born_ns > mine.joined_ns
            and len(rest) == 1
            and rest[0] is not None
            and rest[0].phase is Phase.NORMAL
            and np.linalg.norm(rest[0].mean_m - c.mean_m) >= lc.separate_distance_m
            and np.linalg.norm(c.mean_m - mine.mean_m) >= lc.separate_distance_m
            and c.support_ema >= max(mine.support_ema, other.support_ema) - lcfg.contest_margin
            and reach > lcfg.arm_reach_m + lcfg.person_margin_m
            and not any(
                self._there_as_pair_joined(mine, m, c.born_ns)
                for m in [c.mean_m, *(m for _, m in c.history)]
            )
        )

    def _seed_of_left_hand(
        self,
        seeds: list[_Pending],
        used: set[int],
        head_m: np.ndarray,
        pair_m: np.ndarray,
        joined_m: np.ndarray,
    ) -> int | None:
        """Index of the seed not in ``used`` nearest ``joined_m`` (where the pair joined) that
        is within ``arm_reach_m`` of ``head_m`` and ``separate_distance_m`` or more from the
        pair's estimate ``pair_m``; None if there is none (:meth:`_split_out_of_reach`).
        A seed seen in one frame set only counts as ``SEEN_ONCE_PENALTY_M`` farther: in
        three_people at 9.93 s (five of seeds 0-5), the hand left behind had a seed seen twice
        29 cm from where the pair joined, and a ghost seen once 27 cm from it took its place.
        (Preferring any seed seen twice, however far, gave seed 5 a ghost 36 cm from the hand.)"""
        free = [k for k in range(len(seeds)) if k not in used]
        if not free:
            return None
        at = np.array([seeds[k].position_m for k in free])
        ok = (np.linalg.norm(at - head_m, axis=1) <= self.cfg.labelling.arm_reach_m) & (
            np.linalg.norm(at - pair_m, axis=1) >= self.cfg.lifecycle.separate_distance_m
        )
        if not ok.any():
            return None
        d = np.where(ok, np.linalg.norm(at - joined_m, axis=1), np.inf)
        once = np.array([seeds[k].seen < 2 for k in free])
        d[once] += SEEN_ONCE_PENALTY_M
        return free[int(np.argmin(d))]

    def _owner_heads(self, a: _Track, b: _Track) -> np.ndarray | None:
        """(2, 3) the heads of a's and b's people when a and b are hands of two different
        people with known heads; None otherwise (a clap, an unattached hand)."""
        if not (a.is_hand and b.is_hand) or a.person == b.person or 0 in (a.person, b.person):
            return None
        heads = [self._head_m(a.person), self._head_m(b.person)]
        if heads[0] is None or heads[1] is None:
            return None
        return np.array(heads)

    def _head_track(self, person: int) -> _Track | None:
        """The tracker of a person's head (None: no such person or head)."""
        p = self._persons.get(person)
        return self._tracks.get(p.head_id) if p is not None and p.head_id is not None else None

    def _active_head(self, person: int) -> _Track | None:
        """The tracker of a person's head if it is tracked now (not lost), else None."""
        head = self._head_track(person)
        return head if head is not None and head.phase in ACTIVE else None

    def _head_m(self, person: int) -> np.ndarray | None:
        """Where a person's head is: its tracker's estimate, or its last good one while lost."""
        head = self._head_track(person)
        if head is None:
            return None
        return head.mean_m if head.phase in ACTIVE else head.last_good_m

    def _parting_fit(
        self, heads: np.ndarray | None, pair_m: np.ndarray, seed_m: np.ndarray
    ) -> int:
        """How well a seed fits as the hand leaving a combined pair at ``pair_m``: 0 not at
        all, 1 possibly, 2 surely. ``heads``: the owners' heads (:meth:`_owner_heads`).

        Pairs of one person's hands (or of hands whose people are unknown, ``heads`` None)
        give 1. For two people's hands, the pair's estimate and the seed are given to the
        hands by their owners (:func:`lab.owner_rule`): 0 if either is then farther from its
        owner's head than any hand can be (``arm_reach_m`` + ``person_margin_m``: a seed out
        of reach is a ghost, a mismatched blob pair beside the pair), 2 if the pair's
        estimate is out of the seed's owner's reach (``arm_reach_m``; the pair followed the
        other hand home), 1 otherwise."""
        if heads is None:
            return 0 if self._beyond_every_reach(pair_m, seed_m) else 1
        modes = np.array([pair_m, seed_m])
        decided = lab.owner_rule(modes, heads, 0.0)
        assert decided is not None  # a zero margin always decides
        owners_modes = list(decided[0])  # the mode of head 0, of head 1
        lcfg = self.cfg.labelling
        reach = np.linalg.norm(modes[owners_modes] - heads, axis=1)
        if (reach > lcfg.arm_reach_m + lcfg.person_margin_m).any():
            return 0
        seed_owner = owners_modes.index(1)
        return 2 if np.linalg.norm(pair_m - heads[seed_owner]) > lcfg.arm_reach_m else 1

    def _beyond_every_reach(self, pair_m: np.ndarray, seed_m: np.ndarray) -> bool:
        """Whether a seed cannot be a hand leaving a pair at ``pair_m`` whose people are not
        told apart (``seed_within_reach``): the pair is within ``arm_reach_m`` of a tracked
        head, so its hands are a tracked person's, and the seed is farther than any hand
        reaches from every tracked head. A pair far from every head may be the hands of
        someone whose head is not tracked, and parts as before."""
        if not self.cfg.lifecycle.seed_within_reach:
            return False
        _, heads = self._live_heads()
        if not len(heads):
            return False
        lcfg = self.cfg.labelling
        if np.linalg.norm(heads - pair_m, axis=1).min() > lcfg.arm_reach_m:
            return False
        return bool(
            np.linalg.norm(heads - seed_m, axis=1).min() > lcfg.arm_reach_m + lcfg.person_margin_m
        )

    def _reacquire(self, seeds: list[_Pending], t_ns: int) -> dict[int, int]:
        """Lost tracker id -> index of the seed that re-acquires it.

        A lost tracker "behaves like an uninitialised one" but with its last known position
        as a prior (section 5.2): it may take a confirmed seed within a gate around that
        position (``reacquire_gate_m``, growing by ``reacquire_speed_mps`` per second lost,
        at most ``reacquire_max_m``), or any seed, confirmed or not, within
        ``reacquire_near_m`` of it. A person's hand's gate grows by
        ``reacquire_hand_speed_mps`` per second since the hand was last supported: a hand
        swung faster than its tracker can follow is lost a few frame sets later and far from
        where it was last supported. Lost trackers and seeds are matched jointly by least
        total distance (Hungarian), so two targets lost together are not swapped greedily.

        **Unsupported hands** (``reacquire_unsupported``): a person's labelled hand (normal)
        whose tracker was unsupported in one of its last ``drift_window_frames`` frame sets
        takes part as if it were lost, from where it was last supported before that miss
        began (:meth:`_before_miss_m`, the gate growing from then), but only for a confirmed
        seed within ``arm_reach_m`` of its own tracked head. A hand drawn back unseen, or
        swung faster than its tracker follows, shows again where its tracker is not; its
        tracker, coasting or slid onto something beside it, is lost ``lost_frames`` later or
        as drifted. A seed confirmed on the hand before that started a new tracker there (an
        identity switch; handshake, p2's right hand at 10.07 s in four seeds of six, with
        ``tops_from_heads`` on), or re-acquired the person's other hand, already lost (demo,
        p2's left hand at 10.0 s: the right hand's tracker took it). The caller restarts
        these trackers on their seeds (:meth:`_restart_unsupported`)."""
        lc = self.cfg.lifecycle
        lost = [tr for tr in self._tracks.values() if tr.phase is Phase.LOST]
        unsupported, their_heads = [], []
        if lc.reacquire_unsupported:
            for tr in self._tracks.values():
                if not (
                    tr.phase is Phase.NORMAL
                    and tr.labelled
                    and tr.limb.is_hand
                    and tr.since_miss < lc.drift_window_frames
                    and (lc.reacquire_supported or tr.misses > 0)
                    and not (
                        tr.misses == 0 and self._on_a_candidate(tr, lc.reacquire_supported_near_m)
                    )
                ):
                    continue
                head = self._active_head(tr.person)
                if head is not None:
                    unsupported.append(tr)
                    their_heads.append(head.mean_m)
        rows_tr = lost + unsupported
        if not rows_tr or not seeds:
            return {}
        last = np.array(
            [self._lost_prior_m(tr) for tr in lost]
            + [self._before_miss_m(tr) for tr in unsupported]
        )
        sp = np.array([sd.position_m for sd in seeds])
        seen = np.array([sd.seen >= lc.init_confirm_frames for sd in seeds])
        confirmed = np.repeat(seen[None], len(rows_tr), axis=0)
        # a run that bridged single gaps counts for the lost rows only (reacquire_bridge)
        confirmed[: len(lost)] |= np.array(
            [sd.bridged_seen >= lc.init_confirm_frames for sd in seeds]
        )
        d = np.linalg.norm(last[:, None] - sp[None], axis=2)
        hands = np.array([tr.limb.is_hand and tr.person > 0 for tr in rows_tr])
        since = [
            tr.last_good_ns if hand else (tr.lost_since_ns or t_ns)
            for tr, hand in zip(lost, hands[: len(lost)], strict=True)
        ] + [tr.miss_from_ns for tr in unsupported]
        gate = self._reacquire_gate_m((t_ns - np.array(since)) * 1e-9, hands)
        ok = (d <= gate[:, None]) & (confirmed | (d <= lc.reacquire_near_m))
        if unsupported:
            strong = np.array([sd.count >= lc.init_confirm_frames for sd in seeds])
            to_head = np.linalg.norm(sp[None] - np.array(their_heads)[:, None], axis=2)
            ok[len(lost) :] &= strong[None] & (to_head <= self.cfg.labelling.arm_reach_m)
        crown = np.array([sd.head_only for sd in seeds])
        if crown.any():  # a crown head re-acquires no hand
            ok &= ~(np.array([self._hand_like(tr) for tr in rows_tr])[:, None] & crown[None])
        if lc.reacquire_own_body:
            ok &= ~self._claimed_by_others(rows_tr, sp)
        if lc.reacquire_above_head_m > 0:
            hand = np.array([self._hand_like(tr) for tr in rows_tr])
            to_seed = sp[None] - last[:, None]
            vel = np.array([tr.vel_mps for tr in rows_tr])
            towards = np.einsum("rsk,rk->rs", to_seed, vel) / np.maximum(d, 1e-9)
            ok &= ~(
                hand[:, None]
                & self._on_a_head(sp, lc.reacquire_above_head_m)[None]
                & (d > lc.reacquire_gate_m)  # lost elsewhere, not at the face ...
                & (towards < TOWARDS_HEAD_MPS)  # ... and not on its way to it
            )
        cost = np.where(ok, d, 1e6)
        rows, cols = linear_sum_assignment(cost)
        return {rows_tr[r].id: int(c) for r, c in zip(rows, cols, strict=True) if cost[r, c] < 1e6}

    def _on_a_candidate(self, tr: _Track, radius_m: float) -> bool:
        """A candidate of this frame set lies within ``radius_m`` of the tracker's estimate."""
        if radius_m <= 0 or not len(self._pts):
            return False
        return bool(np.linalg.norm(self._pts - tr.mean_m, axis=1).min() <= radius_m)

    def _on_a_head(self, points_m: np.ndarray, radius_m: float) -> np.ndarray:
        """(S,) bool: each point is within ``radius_m`` of an active head tracker's estimate
        and higher than it (``reacquire_above_head_m``)."""
        act = [tr for tr in self._tracks.values() if tr.phase in ACTIVE]
        h = np.array([tr.mean_m for tr in act if tr.is_hand is False]).reshape(-1, 3)
        if not len(h):
            return np.zeros(len(points_m), bool)
        near = np.linalg.norm(points_m[:, None] - h[None], axis=2) <= radius_m
        above = points_m[:, None, 2] > h[None, :, 2]
        return (near & above).any(axis=1)

    def _restart_unsupported(
        self, reacquired: dict[int, int], seeds: list[_Pending]
    ) -> dict[int, int]:
        """Draw the unsupported hands that :meth:`_reacquire` matched (the trackers in
        ``reacquired`` that are not lost) again around their seeds; returns the lost ones'
        matches."""
        out = {}
        for tid, i in reacquired.items():
            tr = self._tracks[tid]
            if tr.phase is Phase.LOST:
                out[tid] = i
                continue
            self._reinit(tr, seeds[i].position_m, seeds[i].velocity_mps)
            tr.misses = 0
            log.debug("t%d re-acquired while unsupported at %s", tid, seeds[i].position_m.round(2))
        return out

    def _claimed_by_others(self, lost: list[_Track], points_m: np.ndarray) -> np.ndarray:
        """(L, S) bool: seed s lies where another person's tracked head claims a hand, for
        each lost hand whose own head is tracked (``reacquire_own_body``): that head is nearer
        to it than the hand's own by at least ``labelling.person_margin_m``, the margin by
        which labelling gives a hand to a person. False for other lost targets."""
        out = np.zeros((len(lost), len(points_m)), bool)
        heads = {
            person: head.mean_m
            for person in self._persons
            if (head := self._active_head(person)) is not None
        }
        margin = self.cfg.labelling.person_margin_m
        for i, tr in enumerate(lost):
            own = heads.get(tr.person) if tr.limb.is_hand else None
            others = [m for person, m in heads.items() if person != tr.person]
            if own is None or not others:
                continue
            to_own = np.linalg.norm(points_m - own, axis=1)
            to_other = np.linalg.norm(points_m[:, None] - np.array(others)[None], axis=2)
            out[i] = to_other.min(axis=1) + margin <= to_own
        return out

    def _lost_prior_m(self, tr: _Track) -> np.ndarray:
        """Where a lost target is looked for: its last supported position, moved horizontally
        with its person's head since then for a hand (``reacquire_with_body``) whose head is
        tracked; a hand cannot stay behind a body that walks off."""
        head = self._with_body(tr)
        if head is None or tr.lost_head_m is None:
            return tr.last_good_m
        shift = head.mean_m - tr.lost_head_m
        shift[2] = 0.0
        return tr.last_good_m + shift

    def _with_body(self, tr: _Track) -> _Track | None:
        """The tracked head of a hand's person (``reacquire_with_body``), else None. Such a
        hand, while lost, is hidden rather than gone: it is looked for around its body and
        not retired (its slot goes to a new tracker after ``yield_lost_s``)."""
        if not (self.cfg.lifecycle.reacquire_with_body and tr.limb.is_hand and tr.person > 0):
            return None
        return self._active_head(tr.person)

    def _head_when(self, person: int, t_ns: int) -> np.ndarray | None:
        """A person's head estimate at ``t_ns`` (the latest one at or before it that the head
        tracker's history holds; its current one if the history starts later), or None."""
        head = self._head_track(person)
        if head is None:
            return None
        m = self._history_at(head, t_ns)
        return head.mean_m.copy() if m is None else m

    def _reacquire_gate_m(
        self, unseen_s: float | np.ndarray, hand: bool | np.ndarray = False
    ) -> float | np.ndarray:
        """How far from its last position a lost target may be re-acquired after ``unseen_s``:
        ``reacquire_gate_m`` growing by ``reacquire_speed_mps`` (``reacquire_hand_speed_mps``
        where ``hand``), at most ``reacquire_max_m``."""
        lc = self.cfg.lifecycle
        speed = np.where(hand, lc.reacquire_hand_speed_mps, lc.reacquire_speed_mps)
        return np.minimum(lc.reacquire_gate_m + speed * unseen_s, lc.reacquire_max_m)

    def _merge_lost(
        self,
        t_ns: int,
        reacquired: dict[int, int],
        pairs: dict[int, int],
        seeds: list[_Pending],
    ) -> dict[int, int]:
        """Lost hand id -> id of the hand it is re-acquired onto (it met that hand unseen).

        Two hands that meet fast often lose one candidate a few frame sets before contact:
        their blobs merge in some views, and the hand whose candidate vanished is lost while
        the other tracker takes the merged candidate. The targets have come together, which
        is the combined state's premise (section 5.2), so the lost hand (a hand of a person,
        lost at most ``merge_lost_s``) is re-acquired onto a live hand of a person that is
        near its coasted position (last supported position + velocity there x at most
        ``merge_coast_s``): within ``merge_lost_distance_m``, growing by
        ``reacquire_speed_mps`` per second coasted (the velocity estimate lags a hand that
        accelerates). The two then combine in the next frame set and part like any combined
        pair. The live hand must also be within ``merge_reach_m`` of the lost hand's last
        supported position (a hand lost at 2 m/s would coast 60 cm in 0.3 s; hands lost
        0.2-0.4 s before they meet were at most 50 cm from the meeting point on the bundled
        scenes), and the lost hand must have been approaching it at ``merge_closing_mps``
        or faster (relative velocity along the line joining them): hands about to meet
        close at 1-2 m/s, while a hand lost beside a resting one (pick_place: its left hand
        at the table) is not moving towards it. Nearest first, one lost hand per live hand.
        A lost hand with a new candidate (a seed, confirmed or not) within its
        re-acquisition gate is not merged: its target is still seen on its own, and a
        tracker that drifted off its hand onto the other must not make the two "meet"."""
        lc = self.cfg.lifecycle
        if lc.merge_lost_s <= 0:
            return {}
        lost = [
            tr
            for tr in self._tracks.values()
            if tr.phase is Phase.LOST
            and tr.id not in reacquired
            and tr.is_hand
            and tr.person > 0
            and tr.lost_since_ns is not None
            and (t_ns - tr.lost_since_ns) * 1e-9 <= lc.merge_lost_s
        ]
        live = [
            tr
            for tr in self._tracks.values()
            if tr.phase in (Phase.UNLABELLED, Phase.NORMAL)
            and tr.is_hand
            and tr.person > 0
            and tr.id not in pairs
        ]
        if seeds and lost:
            sp = np.array([sd.position_m for sd in seeds])
            lost = [
                tr
                for tr in lost
                if np.linalg.norm(sp - tr.last_good_m, axis=1).min()
                > self._reacquire_gate_m((t_ns - tr.last_good_ns) * 1e-9, True)
            ]
        if not lost or not live:
            return {}
        last = np.array([tr.last_good_m for tr in lost])
        live_m = np.array([tr.mean_m for tr in live])
        coast_s = np.minimum([(t_ns - tr.last_good_ns) * 1e-9 for tr in lost], lc.merge_coast_s)
        coasted = last + coast_s[:, None] * np.array([tr.last_good_vel_mps for tr in lost])
        d = np.linalg.norm(coasted[:, None] - live_m[None], axis=2)
        gate = lc.merge_lost_distance_m + lc.reacquire_speed_mps * coast_s
        reach = np.linalg.norm(live_m[None] - last[:, None], axis=2)
        ok = (d < gate[:, None]) & (reach <= lc.merge_reach_m)
        for i, j in zip(*np.nonzero(ok), strict=True):
            closing = self._approach_mps(lost[i], live[j])
            ok[i, j] &= closing >= lc.merge_closing_mps
            log.debug(
                "merge t%d->t%d: reach %.2f m, closing %.2f m/s",
                lost[i].id,
                live[j].id,
                reach[i, j],
                closing,
            )
        d = np.where(ok, d, np.inf)
        out: dict[int, int] = {}
        taken: set[int] = set()
        for flat in np.argsort(d, axis=None, kind="stable"):
            i, j = divmod(int(flat), len(live))
            if not np.isfinite(d[i, j]):
                break
            if lost[i].id in out or live[j].id in taken:
                continue
            out[lost[i].id] = live[j].id
            taken.add(live[j].id)
            log.debug("t%d re-acquired onto t%d (hands met)", lost[i].id, live[j].id)
        return out

    # ------------------------------------------------------------------ 4: labelling

    def _candidate_rel_v(
        self, candidates: CandidateSet, observations: Mapping[str, CameraObservation] | None
    ) -> np.ndarray:
        """(K,) mean rel_v of each candidate's two blobs; NaN where unknown."""
        k = len(candidates.points_m)
        out = np.full(k, np.nan)
        if not observations or candidates.cam_pairs is None or candidates.blob_pairs is None:
            return out
        total = np.zeros(k)
        count = np.zeros(k)
        for m, cam in enumerate(self.rig.cameras):
            obs = observations.get(cam.name)
            if obs is None or len(obs.blobs) == 0:
                continue
            rel = np.asarray(obs.blobs.rel_v, dtype=np.float64)
            for col in (0, 1):
                sel = (candidates.cam_pairs[:, col] == m) & (
                    candidates.blob_pairs[:, col] < len(rel)
                )
                sel &= candidates.blob_pairs[:, col] >= 0
                vals = rel[candidates.blob_pairs[sel, col]]
                good = np.isfinite(vals)
                idx = np.flatnonzero(sel)[good]
                total[idx] += vals[good]
                count[idx] += 1
        has = count > 0
        out[has] = total[has] / count[has]
        return out

    def _label(
        self,
        pts: np.ndarray,
        cand_rel_v: np.ndarray,
        t_ns: int,
        observations: Mapping[str, CameraObservation],
        returning: set[int],
    ) -> None:
        """``returning``: lost trackers re-acquired in this frame set (they keep their slots)."""
        lcfg = self.cfg.labelling
        act = [tr for tr in self._tracks.values() if tr.phase in ACTIVE]
        if not act:
            return
        pos = np.array([tr.mean_m for tr in act])
        # per-frame type evidence for the untyped (unlabelled, not combined) trackers
        untyped = [
            i for i, tr in enumerate(act) if tr.is_hand is None and tr.phase is Phase.UNLABELLED
        ]
        if untyped:
            below = lab.below_another(pos, lcfg)
            rel_v = np.full(len(act), np.nan)
            on_crown = np.zeros(len(act), dtype=bool)
            if len(pts):
                d = np.linalg.norm(pos[:, None] - pts[None], axis=2)
                near = d.argmin(axis=1)
                ok = d[np.arange(len(act)), near] <= 2 * self.cfg.filter.sigma_m
                rel_v[ok] = cand_rel_v[near[ok]]
                # typed a hand, a tracker held by a crown head would lose its support
                on_crown[ok] = self._head_only[near[ok]]
            speed = np.array([tr.speed_ema_mps for tr in act])
            llr = lab.head_log_odds(pos[:, 2], speed, below, rel_v, lcfg)
            for i in untyped:
                tr = act[i]
                tr.type_llr = (1 - lcfg.evidence_alpha) * tr.type_llr + lcfg.evidence_alpha * llr[
                    i
                ]
                tr.typed_frames += 1
                if tr.typed_frames < lcfg.min_frames:
                    continue
                if (
                    tr.type_llr >= lcfg.decide_llr
                    and not self._near_head(tr)
                    and self._has_body(tr, observations)
                ):
                    tr.is_hand = False
                    self._new_person(tr, t_ns)
                elif tr.type_llr <= -lcfg.decide_llr and not on_crown[i]:
                    tr.is_hand = True
        self._detach_astray(t_ns)
        self._attach_hands(t_ns, returning)
        self._contest_slots(t_ns)
        self._update_facing(observations)
        self._decide_sides(t_ns)
        self._revise_sides(t_ns)

    def _has_body(self, tr: _Track, observations: Mapping[str, CameraObservation]) -> bool:
        """Whether silhouettes show a body under a would-be head (:func:`lab.body_support`;
        True without observations or when too few cameras see it). A tracker that fails
        ``body_fail_frames`` times never becomes a head: a ghost between two people is covered
        by one of them in some frames, a real head's column is deep inside the silhouettes in
        every view but for a glitch."""
        lcfg = self.cfg.labelling
        need = lcfg.body_support_min
        if tr.body_fails >= lcfg.body_fail_frames:
            return False
        if need <= 0 or not observations:
            return True
        support = lab.body_support(tr.mean_m, self.rig, observations, lcfg)
        if support is not None and support < need:
            log.debug("t%d looks like a head but has no body under it (%.2f)", tr.id, support)
            tr.body_fails += 1
            return False
        return True

    def _near_head(self, tr: _Track) -> bool:
        for p in self._persons.values():
            head = self._head_track(p.number)
            if head is None or head is tr:
                continue
            dxy = np.linalg.norm(head.last_good_m[:2] - tr.mean_m[:2])
            if dxy < self.cfg.labelling.duplicate_head_m:
                return True
        return False

    def _new_person(self, head: _Track, t_ns: int) -> None:
        number = self._next_person
        self._next_person += 1
        self._persons[number] = _Person(number=number, head_id=head.id, born_ns=t_ns)
        head.person = number
        head.limb = Limb.HEAD
        log.debug("t%d is the head of new person p%d", head.id, number)

    def _live_heads(self) -> tuple[list[_Person], np.ndarray]:
        persons, heads = [], []
        for p in self._persons.values():
            head_m = self._head_m(p.number)
            if head_m is not None:
                persons.append(p)
                heads.append(head_m)
        return persons, np.array(heads).reshape(-1, 3)

    def _hands_with_reach(self) -> Iterator[tuple[_Person, _Track, bool]]:
        """Every live person's hand trackers, each with whether it is out of that person's
        reach and within another's (:func:`lab.astray`). Safe to take labels off while
        iterating."""
        persons, heads = self._live_heads()
        for i, p in enumerate(persons):
            others = np.delete(heads, i, axis=0)
            for hid in list(p.hand_ids):
                h = self._tracks.get(hid)
                if h is not None:
                    yield p, h, lab.astray(h.mean_m, heads[i], others, self.cfg.labelling)

    @staticmethod
    def _unlabel_hand(p: _Person, h: _Track, why: str) -> None:
        log.debug("t%d (%s) %s p%d's reach: label taken off", h.id, h.label, why, p.number)
        p.hand_ids.remove(h.id)
        h.take_label_off()

    def _detach_astray(self, t_ns: int) -> None:
        """Take the label off a hand that stayed out of its person's reach and within
        another's for ``reach_revise_s`` (:func:`lab.astray`): it tracks someone else's hand,
        since a pair parted the wrong way round or the tracker slid across. It goes back to
        unlabelled and is attached anew, and its person's slot is free for the real hand."""
        revise_s = self.cfg.labelling.reach_revise_s
        if revise_s <= 0:
            return
        for p, h, astray in self._hands_with_reach():
            if h.phase is not Phase.NORMAL or not astray:
                h.astray_ns = None
                continue
            h.astray_ns, due = _persisted(h.astray_ns, t_ns, revise_s)
            if due:
                self._unlabel_hand(p, h, "is out of")

    def _unlabel_astray_joiners(self, pairs: dict[int, int]) -> None:
        """Take the label off a person's hand that is about to combine while out of its
        person's reach and within another's (:func:`lab.astray`, ``astray_at_join``) now,
        not after ``reach_revise_s``: the activity stage reads who met from the labels at
        the join. A tracker that slid onto another person's hand and followed it home is
        beyond its own head's reach when a second tracker finds that hand (negative scene
        with the bare-forearm option, seed 2, 12.33 s: 1.25 m from its head), and the join
        would be a handshake between one person's two trackers."""
        if not (pairs and self.cfg.labelling.astray_at_join):
            return
        for p, h, astray in self._hands_with_reach():
            if astray and h.id in pairs:
                self._unlabel_hand(p, h, "joins out of")

    def _attach_hands(self, t_ns: int, returning: set[int]) -> None:
        persons, heads = self._live_heads()
        if not persons:
            return
        for tr in list(self._tracks.values()):
            if not (tr.is_hand and tr.person == 0 and tr.phase is Phase.UNLABELLED):
                continue
            n_hands = np.array([len(p.hand_ids) for p in persons])
            k = lab.nearest_person(tr.mean_m, heads, n_hands, self.cfg.labelling)
            if k < 0:
                k = self._yield_lost_slot(tr, persons, heads, t_ns, returning)
            if k >= 0:
                persons[k].hand_ids.append(tr.id)
                tr.person = persons[k].number
                tr.attached_ns = t_ns

    def _contest_slots(self, t_ns: int) -> None:
        """Give a hand slot to an unlabelled hand tracker that has out-supported the slot's
        holder for ``contest_s``: its smoothed likelihood level (``support_ema``) exceeds the
        holder's by ``contest_margin`` or more. The holder is the nearest of the person's
        normal hands that the challenger out-supports; it loses its label and the challenger
        takes it (same person, same side). A ghost -- two views' lines of sight of different
        limbs that cross near the body -- is supported by one camera pair, a real hand by
        most pairs, whose candidates merge into a stronger one (pick_place: a ghost at hip
        height held the right hand's label at level ~0.6 while the real right hand, at ~0.9,
        stayed unlabelled through the pick).

        With ``contest_by_owner``, a holder also loses its slot to a challenger that is
        clearly its person's when the holder lies nearer another person's head
        (:func:`lab.owned_elsewhere`): a ghost in front of another body, from lines of sight
        of two of that person's limbs, is seen by as many cameras as a real hand and as
        strong (three_people: "p1/left_hand" on a ghost 0.94 m from p1's head and 0.63 m
        from p2's, while p1's real left hand, 0.59 m from p1's head, stayed unlabelled, so
        its exchange read as a handshake)."""
        lcfg = self.cfg.labelling
        if lcfg.contest_s <= 0:
            return
        persons, heads = self._live_heads()
        if not persons:
            return
        for c in list(self._tracks.values()):
            if not (c.is_hand and c.person == 0 and c.phase is Phase.UNLABELLED):
                c.contest_ns = None
                continue
            k = lab.nearest_person(c.mean_m, heads, np.zeros(len(persons), int), lcfg)
            p = persons[k] if k >= 0 else None
            by_owner = {
                h
                for h in (p.hand_ids if p is not None else [])
                if lcfg.contest_by_owner
                and self._tracks[h].phase is Phase.NORMAL
                and lab.owned_elsewhere(self._tracks[h].mean_m, c.mean_m, heads, k, lcfg)
                and not self._beside_other_hand(p, k, heads, c, h)
            }
            across = self._across_body(p, k, heads, c) if p is not None else set()
            stacked = self._stacked_above(p, k, heads, c) if p is not None else set()
            by_owner |= stacked
            held = [
                self._tracks[h]
                for h in (p.hand_ids if p is not None else [])
                if self._tracks[h].phase is Phase.NORMAL
                and (
                    (
                        c.support_ema - self._tracks[h].support_ema >= lcfg.contest_margin
                        and h not in across
                    )
                    or h in by_owner
                )
            ]
            if p is None or len(p.hand_ids) < 2 or not held:
                c.contest_ns = None
                continue
            c.contest_ns, due = _persisted(c.contest_ns, t_ns, lcfg.contest_s)
            if not due:
                continue
            h = min(
                held,
                key=lambda h: (h.id not in stacked, float(np.linalg.norm(h.mean_m - c.mean_m))),
            )
            log.debug(
                "t%d (support %.2f) takes %s from t%d (support %.2f)",
                c.id,
                c.support_ema,
                h.label,
                h.id,
                h.support_ema,
            )
            p.hand_ids[p.hand_ids.index(h.id)] = c.id
            c.person, c.limb, c.attached_ns, c.contest_ns = p.number, h.limb, t_ns, None
            h.take_label_off()
            h.demoted = lcfg.contest_demotes
            if lcfg.redecide_sides and h.id in by_owner:
                self._redecide_sides(p, k, heads)

    def _across_body(self, p: _Person, k: int, heads: np.ndarray, c: _Track) -> set[int]:
        """Ids of ``p``'s hands on the other side of the body from the challenger ``c``
        (:func:`lab.across_body`); none until ``p``'s facing evidence reaches facing_min."""
        lcfg = self.cfg.labelling
        if not self._sides_testable(p):
            return set()
        ids = [h for h in p.hand_ids if h in self._tracks]
        if not ids:
            return set()
        hands = np.array([self._tracks[h].mean_m for h in ids])
        other = lab.across_body(
            hands, c.mean_m, heads[k], self._facing(p, heads[k]), lcfg.contest_side_m
        )
        return {h for h, o in zip(ids, other, strict=True) if o}

    def _sides_testable(self, p: _Person) -> bool:
        """Whether the contest's side tests apply to ``p``: ``contest_side_m`` is on and
        ``p``'s facing evidence has reached facing_min."""
        lcfg = self.cfg.labelling
        return bool(lcfg.contest_side_m > 0 and np.linalg.norm(p.facing_ev) >= lcfg.facing_min)

    def _beside_other_hand(
        self, p: _Person, k: int, heads: np.ndarray, c: _Track, holder: int
    ) -> bool:
        """Whether the challenger ``c`` is on the same side of ``p``'s body as ``p``'s hand
        other than ``holder`` (:func:`lab.same_side`, ``contest_side_m``; False until ``p``'s
        facing evidence reaches facing_min). A slot taken by ownership is sided afresh
        (``redecide_sides``), so it is the remaining hand, not the slot's old side, that
        says where the person's other hand can be."""
        lcfg = self.cfg.labelling
        if not self._sides_testable(p):
            return False
        facing = self._facing(p, heads[k])
        others = [h for h in p.hand_ids if h != holder and h in self._tracks]
        return any(
            lab.same_side(self._tracks[h].mean_m, c.mean_m, heads[k], facing, lcfg.contest_side_m)
            for h in others
        )

    def _stacked_above(self, p: _Person, k: int, heads: np.ndarray, c: _Track) -> set[int]:
        """The upper of ``p``'s two normal hands when both are on one side of the body
        (:func:`lab.same_side`) and the challenger ``c`` is at least ``contest_side_m`` to
        the other side: a shirt region by the elbow above the hand hanging there holds the
        slot of the hand on the other side (three_people). Empty until ``p``'s facing
        evidence reaches facing_min."""
        lcfg = self.cfg.labelling
        if not self._sides_testable(p):
            return set()
        hands = [
            self._tracks[h]
            for h in p.hand_ids
            if h in self._tracks and self._tracks[h].phase is Phase.NORMAL
        ]
        if len(hands) != 2:
            return set()
        a, b = hands
        side, facing = lcfg.contest_side_m, self._facing(p, heads[k])
        if not lab.same_side(a.mean_m, b.mean_m, heads[k], facing, side):
            return set()
        if not lab.across_body(a.mean_m[None], c.mean_m, heads[k], facing, side)[0]:
            return set()
        return {max(hands, key=lambda h: float(h.mean_m[2])).id}

    def _redecide_sides(self, p: _Person, k: int, heads: np.ndarray) -> None:
        """Decide ``p``'s left and right hands afresh from its facing direction, when it has
        two hands and both are sided (``k`` indexes ``heads``, the live heads)."""
        hands = [self._tracks[h] for h in p.hand_ids if h in self._tracks]
        if len(hands) != 2 or any(h.limb is Limb.UNKNOWN for h in hands):
            return
        sides = lab.decide_left_right(
            np.array([h.mean_m for h in hands]), heads[k], self._facing(p, heads[k])
        )
        if sides != tuple(h.limb for h in hands):
            log.debug("p%d: sides decided afresh after an ownership contest", p.number)
        for h, limb in zip(hands, sides, strict=True):
            h.limb = limb

    def _yield_lost_slot(
        self,
        tr: _Track,
        persons: list[_Person],
        heads: np.ndarray,
        t_ns: int,
        returning: set[int],
    ) -> int:
        """Index (in ``persons``) of the person whose hand, lost for ``yield_lost_s`` or
        longer, gives its slot to the unlabelled hand ``tr`` (-1: none): ``tr`` would join
        that person (:func:`lab.nearest_person`) but for the lost hand. The lost tracker is
        retired: its target is the one ``tr`` now tracks (a person has two hands), and it
        could re-acquire only within its gate around its last position, which its person
        has walked away from (pick_place: both hands lost at the table, the person carrying
        the box to the cabinet with their hands tracked by new, unlabelled trackers). A lost
        hand re-acquired in this frame set (``returning``) keeps its slot, and so does one
        across the body from ``tr`` (:meth:`_across_body`): a left hand lost while it
        reached out is not replaced by a tracker on the person's right."""
        wait_s = self.cfg.labelling.yield_lost_s
        if wait_s <= 0:
            return -1

        def stale(hid: int) -> bool:
            h = self._tracks.get(hid)
            return (
                h is not None
                and hid not in returning
                and h.phase is Phase.LOST
                and h.lost_since_ns is not None
                and (t_ns - h.lost_since_ns) * 1e-9 >= wait_s
            )

        held = np.array([sum(not stale(h) for h in p.hand_ids) for p in persons])
        k = lab.nearest_person(tr.mean_m, heads, held, self.cfg.labelling)
        if k < 0:
            return -1
        p = persons[k]
        across = self._across_body(p, k, heads, tr)
        lost = sorted(
            (h for h in p.hand_ids if stale(h) and h not in across),
            key=lambda h: self._tracks[h].lost_since_ns,
        )
        while len(p.hand_ids) >= 2 and lost:
            gone = lost.pop(0)
            log.debug("t%d (%s) lost: its slot goes to t%d", gone, self._tracks[gone].label, tr.id)
            self._remove(gone)
        return k if len(p.hand_ids) < 2 else -1

    def _measure_head_rise(
        self, observations: Mapping[str, CameraObservation], dt_s: float
    ) -> None:
        """Each seen head's rise above its skin point, measured from the silhouettes' crowns
        (:func:`head_rises_m`) and smoothed with time constant ``head_rise_tau_s``; a head no
        view tells about keeps its last rise (first: ``head_centre_rise_m``)."""
        cfg = self.cfg
        if cfg.head_top_to_centre_m <= 0 or not observations:
            return
        views = [
            (self.rig[name], obs.silhouettes.labels)
            for name, obs in observations.items()
            if name in self.rig
        ]
        heads = [
            tr
            for tr in self._tracks.values()
            if tr.limb is Limb.HEAD and tr.phase in (Phase.NORMAL, Phase.UNLABELLED)
        ]
        if not heads:
            return
        rises = head_rises_m(
            np.array([tr.mean_m for tr in heads]),
            views,
            cfg.head_top_to_centre_m,
            cfg.head_rise_max_m,
        )
        alpha = 1.0 if cfg.head_rise_tau_s <= 0 else 1.0 - np.exp(-dt_s / cfg.head_rise_tau_s)
        for tr, rise in zip(heads, rises.tolist(), strict=True):
            if np.isfinite(rise):
                last = cfg.head_centre_rise_m if tr.head_rise_m is None else tr.head_rise_m
                tr.head_rise_m = last + alpha * (rise - last)

    def _update_facing(self, observations: Mapping[str, CameraObservation]) -> None:
        lcfg = self.cfg.labelling
        persons, heads = self._live_heads()
        views = [(self.rig[name], obs) for name, obs in observations.items()]
        view_cams = np.array([cam.centre_m for cam, _ in views]).reshape(-1, 3)
        for i, p in enumerate(persons):
            head = self._tracks[p.head_id]
            if head.phase not in ACTIVE:
                continue
            hands = np.array(
                [
                    self._tracks[h].mean_m
                    for h in p.hand_ids
                    if h in self._tracks and self._tracks[h].phase in ACTIVE
                ]
            ).reshape(-1, 3)
            others = np.delete(heads, i, axis=0)
            ev = lab.facing_cues(head.mean_m, head.vel_mps, hands, others, lcfg)
            seen = bool(views) and head.phase is not Phase.LOST
            if seen and lcfg.face_weight > 0:
                shares = np.array(
                    [
                        lab.head_skin_share(head.mean_m, obs, cam, lcfg.face_radius_m)
                        for cam, obs in views
                    ]
                )
                ev = ev + lab.face_cue(head.mean_m, view_cams, shares, lcfg.face_weight)
            p.facing_ev = lcfg.facing_decay * p.facing_ev + ev
            p.recent_ev = RECENT_FACING_DECAY * p.recent_ev + ev
            p.axis_ev *= lcfg.axis_decay
            if seen and lcfg.axis_weight > 0:
                widths = np.array(
                    [
                        lab.silhouette_width_m(
                            obs.silhouettes.labels,
                            cam,
                            head.mean_m - _AXIS_DROPS_M,
                            lcfg.axis_max_width_m,
                            others - _AXIS_DROPS_M[1],
                        )
                        for cam, obs in views
                    ]
                )
                p.axis_ev += lcfg.axis_weight * lab.body_axis_cue(
                    head.mean_m, view_cams, widths, lcfg.axis_contrast
                )

    def _facing(self, p: _Person, head_m: np.ndarray) -> np.ndarray:
        """``p``'s facing direction (2,): the evidence, on the body axis once that is known
        (:func:`lab.facing_on_axis`)."""
        guess = p.facing_ev
        if not np.linalg.norm(guess) > 0:
            # no evidence at all: guess the direction towards the middle of the cameras
            centre = np.mean([c.centre_m for c in self.rig.cameras], axis=0)
            guess = centre[:2] - head_m[:2]
            if not np.linalg.norm(guess) > 0:
                guess = np.array([1.0, 0.0])
        return lab.facing_on_axis(guess, p.axis_ev, self.cfg.labelling.axis_min)

    def _decide_sides(self, t_ns: int) -> None:
        lcfg = self.cfg.labelling
        for p in self._persons.values():
            head = self._head_track(p.number)
            hands = [self._tracks[h] for h in p.hand_ids if h in self._tracks]
            undecided = [h for h in hands if h.limb is Limb.UNKNOWN]
            if not undecided or head is None:
                continue
            decided = [h.limb for h in hands if h.limb is not Limb.UNKNOWN]
            if decided:
                other = Limb.RIGHT_HAND if decided[0] is Limb.LEFT_HAND else Limb.LEFT_HAND
                undecided[0].limb = other
                continue
            head_m = self._head_m(p.number)
            waited = max((t_ns - (h.attached_ns or t_ns)) * 1e-9 for h in undecided)
            ready = np.linalg.norm(p.facing_ev) >= lcfg.facing_min
            if not ready and waited < lcfg.lr_max_wait_s:
                continue
            facing = self._facing(p, head_m)
            hand_m = np.array([h.mean_m for h in undecided])
            if len(undecided) == 1:
                lat = lab.lateral_offsets_m(hand_m, head_m, facing)[0]
                if abs(lat) < lcfg.lr_margin_m and waited < lcfg.lr_max_wait_s:
                    continue
            for h, limb in zip(
                undecided, lab.decide_left_right(hand_m, head_m, facing), strict=True
            ):
                h.limb = limb

    def _revise_sides(self, t_ns: int) -> None:
        """Swap a person's left and right hands when strong facing evidence has said so for
        ``lr_revise_s`` (net: a frame that does not say so takes a frame off, so one noisy
        frame near the margin does not start the count again): a decision taken early on a
        guess (a lone person standing still) is overturned once the person reaches or claps
        in front of the body. With both hands tracked (normal), the one labelled left must
        be clearly right of the other (``lr_revise_margin_m``), so crossed hands for a
        moment do not count; with one hand tracked and the other lost, the tracked one must
        be clearly on the other label's side of the head (``lr_revise_lone_m``): the hand
        on the left labelled right while the left slot's tracker is lost where the hands
        parted. Frames in which the last few frames' cues point to the other side than the
        accumulated evidence (a turn) do not count."""
        lcfg = self.cfg.labelling
        if lcfg.lr_revise_evidence <= 0:
            return
        for p in self._persons.values():
            elapsed_s = 0.0 if p.revised_ns is None else (t_ns - p.revised_ns) * 1e-9
            p.revised_ns = t_ns
            if self._sides_contradicted(p):
                p.contradicted_s += elapsed_s
            else:
                p.contradicted_s = max(0.0, p.contradicted_s - elapsed_s)
            if p.contradicted_s < lcfg.lr_revise_s:
                continue
            p.contradicted_s = 0.0
            hands = [self._tracks[h] for h in p.hand_ids if h in self._tracks]
            for h in hands:
                h.limb = Limb.RIGHT_HAND if h.limb is Limb.LEFT_HAND else Limb.LEFT_HAND
            log.debug(
                "p%d: left / right swapped (%s)", p.number, ", ".join(f"t{h.id}" for h in hands)
            )

    def _sides_contradicted(self, p: _Person) -> bool:
        """Whether ``p``'s facing says now that its hands' sides are swapped (the cases of
        :meth:`_revise_sides`)."""
        lcfg = self.cfg.labelling
        head = self._head_track(p.number)
        hands = [self._tracks[h] for h in p.hand_ids if h in self._tracks]
        normal = [h for h in hands if h.phase is Phase.NORMAL]
        if (
            head is None
            or head.phase not in ACTIVE
            or not normal
            or any(h.phase not in (Phase.NORMAL, Phase.LOST) for h in hands)
            or any(h.limb is Limb.UNKNOWN for h in hands)
            or np.linalg.norm(p.facing_ev) < lcfg.lr_revise_evidence
        ):
            return False
        facing = self._facing(p, head.mean_m)
        if p.recent_ev @ facing < 0:
            return False  # turning: the last frames' cues already point the other way
        lat = lab.lateral_offsets_m(np.array([h.mean_m for h in normal]), head.mean_m, facing)
        side = np.array([1.0 if h.limb is Limb.LEFT_HAND else -1.0 for h in normal])
        if len(normal) == 2:  # the one labelled left is clearly right of the other
            return bool(side @ lat <= -lcfg.lr_revise_margin_m)
        return bool(lcfg.lr_revise_lone_m > 0 and side[0] * lat[0] <= -lcfg.lr_revise_lone_m)

    # ------------------------------------------------------------------ 5: state machine

    def _advance_phases(
        self,
        t_ns: int,
        pairs: dict[int, int],
        drifted: set[int],
        reacquired: dict[int, int],
        merged: dict[int, int],
    ) -> list[Transition]:
        lc = self.cfg.lifecycle
        plan: dict[int, Phase] = {}
        for tr in self._tracks.values():
            ev = Evidence(
                misses=tr.misses,
                drifted=tr.id in drifted,
                partner_id=pairs.get(tr.id),
                separated=(
                    tr.apart_frames >= lc.separate_frames
                    and (tr.split_gain_m >= lc.separate_gain_m or self._far_apart(tr))
                )
                or tr.unjoin_frames >= lc.separate_frames,
                labelled=tr.labelled,
                reacquired=tr.id in reacquired or tr.id in merged,
                lost_for_s=(t_ns - tr.lost_since_ns) * 1e-9
                if tr.lost_since_ns is not None and self._with_body(tr) is None
                else 0.0,
                ever_labelled=tr.ever_labelled,
                label_revoked=tr.phase is Phase.NORMAL and not tr.labelled,
            )
            # both of a pair combine: pairs are symmetric, and a pairing beats a loss
            new = next_phase(tr.phase, ev, lc)
            unclaimed_s = (t_ns - tr.born_ns) * 1e-9
            if (
                new is Phase.UNLABELLED
                and tr.phase is Phase.UNLABELLED
                and not tr.ever_labelled
                and tr.person == 0  # a hand attached to a person, waiting for its side
                and lc.retire_unclaimed_s > 0
                and unclaimed_s > lc.retire_unclaimed_s
            ):
                new = Phase.UNINITIALISED
            plan[tr.id] = new
        # a combined pair leaves together (lost or separated)
        for tid, new in list(plan.items()):
            tr = self._tracks[tid]
            if tr.phase is Phase.COMBINED and tr.partner in plan:
                if new is not Phase.COMBINED or plan[tr.partner] is not Phase.COMBINED:
                    pnew = plan[tr.partner]
                    plan[tid] = plan[tr.partner] = (
                        Phase.LOST if Phase.LOST in (new, pnew) else Phase.UNLABELLED
                    )
        out: list[Transition] = []
        before = {tid: (tr.label, tr.mean_m.copy()) for tid, tr in self._tracks.items()}
        separated_done: set[int] = set()
        for tid, new in plan.items():
            tr = self._tracks[tid]
            old = tr.phase
            if new is old:
                continue
            partner_id: int | None = None
            met = True
            if new is Phase.COMBINED:
                partner_id = pairs[tid]
                tr.partner = partner_id
                tr.joined_ns, tr.joined_m = t_ns, tr.mean_m.copy()
                tr.joined_others = {
                    o.id: o.mean_m.copy()
                    for o in self._tracks.values()
                    if o.phase is Phase.NORMAL and o.labelled and o.id not in (tid, partner_id)
                }
                tr.out_of_reach_frames = 0
                gap = float(np.linalg.norm(tr.mean_m - self._tracks[partner_id].mean_m))
                tr.joined_apart = gap >= lc.combine_distance_m
                rejoin = self._rejoin_place(tr, partner_id, t_ns)
                if rejoin is not None:
                    tr.joined_apart, tr.joined_m = True, rejoin
                tr.unjoin_frames = 0
                tr.before_vec_m = self._before_vector(tr, self._tracks[partner_id])
                tr.apart_frames = 0
            elif old is Phase.COMBINED:
                partner_id = tr.partner
                met = tr.unjoin_frames < lc.separate_frames
                if new is Phase.UNLABELLED and tid not in separated_done:
                    self._separate(tr, self._tracks[partner_id], t_ns, met)
                    separated_done.update((tid, partner_id))
                tr.partner = None
                tr.joined_ns = tr.joined_m = tr.joined_others = None
                tr.ghosts_m = []
                tr.joined_apart, tr.unjoin_frames = False, 0
                tr.out_of_reach_frames = 0
                tr.before_vec_m = None
                tr.apart_frames = 0
                tr.split_m = tr.split_vel_mps = None
                tr.split_fixed = None
            if new is Phase.LOST:
                tr.lost_since_ns = t_ns
                tr.mean_m = tr.last_good_m.copy()
                tr.lost_head_m = self._head_when(tr.person, tr.last_good_ns)
                tr.misses = 0
            elif old is Phase.LOST and new is Phase.UNLABELLED:
                if tid in merged:
                    onto = self._tracks[merged[tid]]
                    self._reinit(tr, onto.mean_m, onto.vel_mps)
                else:
                    self._reinit(tr, self._pending[reacquired[tid]].position_m, np.zeros(3))
                tr.lost_since_ns = None
                tr.misses = 0
                tr.since_miss = 1 << 30
            if new is Phase.NORMAL:
                tr.ever_labelled, tr.demoted = True, False
            label, pos = before[tid]
            out.append(
                Transition(
                    t_ns=t_ns,
                    target_id=tid,
                    old=old,
                    new=new,
                    label=label,
                    position_m=tr.mean_m,
                    partner_id=partner_id,
                    partner_label=before[partner_id][0] if partner_id in before else None,
                    met=met,
                )
            )
            tr.phase = new
        for tid, new in plan.items():
            if new is Phase.UNINITIALISED:
                self._remove(tid)
        return out

    def _before_vector(self, a: _Track, b: _Track) -> np.ndarray:
        """p_b - p_a "before they joined" (section 7.1): at the latest common time in the two
        trackers' histories when they were at least ``separate_distance_m`` apart (their
        estimates just before combining are too close for a reliable direction); the oldest
        common time if they never were."""
        common = _common_history(a, b)
        if not common:
            return b.mean_m - a.mean_m
        for _, pa, pb in reversed(common):
            if np.linalg.norm(pb - pa) >= self.cfg.lifecycle.separate_distance_m:
                return pb - pa
        return common[0][2] - common[0][1]

    def _separate(self, a: _Track, b: _Track, t_ns: int, met: bool = True) -> None:
        """Give a and b each a mode of the separating pair and restart them there: two people's
        hands by their owners when that is clear (:func:`lab.owner_rule`, ``owner_margin_m``),
        one person's left and right hands by its sides where its facing tells them apart
        (:meth:`_mode_sides`, ``own_hands_by_sides``; the angle rule's "before" vector can be
        stale), otherwise by the angle rule (section 7.1); a pair that never met
        (:meth:`_never_met`) by where each tracker was at the join."""
        modes, vel = a.split_m, a.split_vel_mps
        if modes is None or vel is None:
            return
        log.debug(
            "t%d / t%d modes %s, %.2f m apart, gained %.2f m in %d frame sets",
            a.id,
            b.id,
            modes.round(3).tolist(),
            float(np.linalg.norm(modes[1] - modes[0])),
            a.split_gain_m,
            a.apart_frames,
        )
        heads = self._owner_heads(a, b)
        margin = self.cfg.labelling.owner_margin_m
        by_owner = (
            lab.owner_rule(modes, heads, margin)
            if met and heads is not None and margin > 0
            else None
        )
        if a.split_fixed is not None and b.split_fixed is not None:
            mode_a, mode_b = a.split_fixed, b.split_fixed
            log.debug("t%d / t%d separate as their parting decided", a.id, b.id)
        elif not met:
            (mode_a, mode_b), _ = self._modes_by_place(a, b, modes)
            log.debug("t%d / t%d never met: apart where they were at the join", a.id, b.id)
        elif by_owner is not None:
            (mode_a, mode_b), gain = by_owner
            log.debug("t%d / t%d separate by their owners (%.2f m shorter)", a.id, b.id, gain)
        elif self.cfg.labelling.own_hands_by_sides and (by_sides := self._mode_sides(a, b, modes)):
            mode_a, mode_b = by_sides
            log.debug("t%d / t%d separate by their person's sides", a.id, b.id)
        else:
            (mode_a, mode_b), angle = lab.angle_rule(a.before_vec_m, modes[0], modes[1])
            log.debug("t%d / t%d separate, angle %.0f deg", a.id, b.id, np.degrees(angle))
        self._reinit(a, modes[mode_a], vel[mode_a])
        self._reinit(b, modes[mode_b], vel[mode_b])
        if not met:
            a.never_met = (b.id, t_ns, modes[mode_a].copy())
            b.never_met = (a.id, t_ns, modes[mode_b].copy())

    def _rejoin_place(self, tr: _Track, partner_id: int, t_ns: int) -> np.ndarray | None:
        """Where ``tr`` parted from ``partner_id`` as never met, if it combines with it again
        within ``rejoin_never_met_s`` of that; else None. Two hands held 25 cm apart (the
        negative scene's near miss) part as never met, and their trackers can drift together
        again on the next merged candidate, this time closer than ``combine_distance_m``:
        without this the second join counts as a meeting (seed 1 of the bare-forearm
        option: a false handshake)."""
        window_s = self.cfg.lifecycle.rejoin_never_met_s
        if window_s <= 0 or tr.never_met is None:
            return None
        partner, parted_ns, place_m = tr.never_met
        if partner != partner_id or (t_ns - parted_ns) * 1e-9 > window_s:
            return None
        return place_m.copy()

    def _mode_sides(self, a: _Track, b: _Track, modes: np.ndarray) -> tuple[int, int] | None:
        """The modes of a person's left and right hands ``a`` and ``b``: the one farther to the
        person's left (:func:`lab.decide_left_right`) for the left hand; None unless the two
        are that person's two sided hands and its head is known."""
        head = self._head_m(a.person)
        sided = {a.limb, b.limb} == {Limb.LEFT_HAND, Limb.RIGHT_HAND}
        if head is None or a.person != b.person or not sided:
            return None
        p = self._persons[a.person]
        limbs = lab.decide_left_right(modes, head, self._facing(p, head))
        if limbs[0] == limbs[1]:
            return None
        return (0, 1) if limbs[0] == a.limb else (1, 0)

    def _reinit(self, tr: _Track, position_m: np.ndarray, velocity_mps: np.ndarray) -> None:
        """Draw the tracker's particles around a position (new or re-acquired target)."""
        fcfg = self.cfg.filter
        n = fcfg.n_particles
        idx = list(self._tracks).index(tr.id)
        block = np.empty((n, sir.STATE_DIM))
        block[:, :3] = position_m + self._rng.standard_normal((n, 3)) * fcfg.init_spread_m
        block[:, 3:] = velocity_mps + self._rng.standard_normal((n, 3)) * fcfg.init_speed_std_mps
        self._states[idx * n : (idx + 1) * n] = block
        tr.mean_m = np.array(position_m, dtype=np.float64)
        tr.last_good_m = tr.mean_m.copy()
        tr.vel_mps = np.array(velocity_mps, dtype=np.float64)
        tr.last_good_ns = self._last_t_ns or 0
        tr.last_good_vel_mps = tr.vel_mps.copy()
        tr.cov_m2 = np.eye(3) * fcfg.init_spread_m**2

    def _remove(self, tid: int) -> None:
        n = self.cfg.filter.n_particles
        idx = list(self._tracks).index(tid)
        self._states = np.delete(self._states, np.s_[idx * n : (idx + 1) * n], axis=0)
        tr = self._tracks.pop(tid)
        p = self._persons.get(tr.person)
        if p is not None:
            if p.head_id == tid:
                p.head_id = None
            if tid in p.hand_ids:
                p.hand_ids.remove(tid)
        log.debug("t%d (%s) retired", tid, tr.label)

    # ------------------------------------------------------------------ 6: initialisation

    def _initialise(self, seeds: list[_Pending], used: set[int], t_ns: int) -> list[Transition]:
        """Start trackers at the confirmed seeds no lost tracker re-acquired (Fig. 1:
        uninitialised -> unlabelled), while fewer than ``max_trackers`` are live."""
        lc = self.cfg.lifecycle
        out: list[Transition] = []
        keep: list[_Pending] = []
        for i, seed in enumerate(seeds):
            if i in used:
                continue
            ev = Evidence(confirmed=seed.count >= lc.init_confirm_frames)
            if (
                next_phase(Phase.UNINITIALISED, ev, lc) is Phase.UNLABELLED
                and len(self._tracks) < lc.max_trackers
            ):
                out.append(self._spawn(seed, t_ns))
            else:
                keep.append(seed)
        self._pending = keep
        return out

    def _spawn(self, pend: _Pending, t_ns: int) -> Transition:
        tid = self._next_id
        self._next_id += 1
        n = self.cfg.filter.n_particles
        tr = _Track(
            id=tid,
            phase=Phase.UNLABELLED,
            born_ns=t_ns,
            mean_m=pend.position_m.copy(),
            cov_m2=np.zeros((3, 3)),
            vel_mps=np.zeros(3),
            last_good_m=pend.position_m.copy(),
        )
        self._tracks[tid] = tr
        self._states = np.concatenate([self._states, np.zeros((n, sir.STATE_DIM))])
        speed = np.linalg.norm(pend.velocity_mps)
        vel = pend.velocity_mps * min(1.0, self.cfg.filter.max_speed_mps / speed) if speed else 0
        self._reinit(tr, pend.position_m, np.zeros(3) + vel)
        log.debug("t%d started at %s", tid, np.round(pend.position_m, 3))
        return Transition(
            t_ns=t_ns,
            target_id=tid,
            old=Phase.UNINITIALISED,
            new=Phase.UNLABELLED,
            label=tr.label,
            position_m=tr.mean_m,
        )

    # ------------------------------------------------------------------ output

    def _frame(self, t_ns: int, transitions: list[Transition]) -> TrackFrame:
        n = self.cfg.filter.n_particles
        targets = []
        blocks, owners = [], []
        for idx, (tid, tr) in enumerate(self._tracks.items()):
            targets.append(self._snapshot(tid, tr, 0.0))
            if tr.phase in ACTIVE:
                blocks.append(idx)
                owners.append(tid)
        rows = self._block_rows(np.array(blocks, dtype=np.intp))
        particles = self._states[rows, :3].astype(np.float32)
        owner = np.repeat(np.array(owners, dtype=np.int32), n)
        particles.flags.writeable = False
        owner.flags.writeable = False
        return TrackFrame(
            t_ns=t_ns,
            targets=tuple(sorted(targets, key=lambda s: s.target_id)),
            transitions=tuple(transitions),
            particles_m=particles,
            particle_owner=owner,
        )

    def _snapshot(self, tid: int, tr: _Track, dt_s: float) -> TargetSnapshot:
        """Tracker ``tid`` as written out, ``dt_s`` after its estimate (constant velocity;
        a lost tracker where it is looked for, :meth:`_lost_prior_m`)."""
        if tr.phase is Phase.LOST:
            mean = self._lost_prior_m(tr).copy()
        else:
            mean = tr.mean_m + tr.vel_mps * dt_s
        if tr.limb is Limb.HEAD:
            mean[2] += self.cfg.head_centre_rise_m if tr.head_rise_m is None else tr.head_rise_m
        return TargetSnapshot(
            target_id=tid,
            person=tr.person,
            limb=tr.limb,
            phase=tr.phase,
            mean_m=mean,
            cov_m2=tr.cov_m2.copy(),
        )

    # ------------------------------------------------------------------ introspection

    def predicted_targets(self, t_ns: int) -> tuple[TargetSnapshot, ...]:
        """The live trackers as the last step left them, predicted to time ``t_ns``
        (constant velocity), in id order: for stages that run before this frame set's
        step (the arm trackers, when they feed candidates)."""
        dt_s = max(self._step_s(int(t_ns)), 0.0)
        return tuple(self._snapshot(tid, tr, dt_s) for tid, tr in sorted(self._tracks.items()))

    def _expected_hand_tracks(self) -> list[_Track]:
        """The trackers :meth:`expected_hands` reports, in its order."""
        limit = self.cfg.lifecycle.rescue_max_frames
        return [
            tr
            for tr in self._tracks.values()
            if tr.phase in ACTIVE
            and tr.is_hand is not False
            and not (limit and tr.phase is Phase.COMBINED and tr.rescued_frames >= limit)
        ]

    def expected_hands(self, t_ns: int) -> np.ndarray:
        """(E, 3) where the active trackers not typed as heads are predicted to be at time
        ``t_ns`` (constant velocity from their estimates), m: the candidate stage's feedback
        (heads are big blobs that rarely lose their candidate). Not a combined pair whose
        nearest candidate was a rescued one for ``rescue_max_frames`` frame sets in a row
        (hands approaching each other, whose blobs merge, are what rescuing is for)."""
        dt_s = max(self._step_s(int(t_ns)), 0.0)
        out = [tr.mean_m + tr.vel_mps * dt_s for tr in self._expected_hand_tracks()]
        return np.array(out).reshape(-1, 3)

    def expected_alone(self) -> np.ndarray:
        """(E,) bool, in :meth:`expected_hands`' order: the labelled hands in the normal
        state whose nearest candidate was one of their own at most
        ``lone_rescue_frames`` frame sets ago; the candidate stage spares them a candidate
        with no other hand beside them (``recon.rescue_expected``'s ``alone``)."""
        frames = self.cfg.lifecycle.lone_rescue_frames
        return np.array(
            [
                bool(frames)
                and tr.phase is Phase.NORMAL
                and tr.limb.is_hand
                and tr.since_own_support < frames
                for tr in self._expected_hand_tracks()
            ],
            dtype=bool,
        )

    def expected_crowns(self, t_ns: int) -> np.ndarray:
        """(H, 3) where the crowns (tops) of the active trackers labelled heads are predicted
        to be at time ``t_ns``, m: their reported centres raised by ``head_top_to_centre_m``
        (the candidate stage's feedback for p_o where people's silhouettes merge)."""
        dt_s = max(self._step_s(int(t_ns)), 0.0)
        rise_top = self.cfg.head_top_to_centre_m or CROWN_TO_CENTRE_M
        out = []
        for tr in self._tracks.values():
            if tr.limb is Limb.HEAD and tr.phase in ACTIVE:
                crown = tr.mean_m + tr.vel_mps * dt_s
                rise = self.cfg.head_centre_rise_m if tr.head_rise_m is None else tr.head_rise_m
                crown[2] += rise + rise_top
                out.append(crown)
        return np.array(out).reshape(-1, 3)

    @property
    def n_live(self) -> int:
        """Number of trackers that are not uninitialised."""
        return len(self._tracks)

    def person_facing(self, person: int) -> np.ndarray | None:
        """(2,) facing of person ``person`` (None if unknown): the accumulated facing
        evidence, turned onto the body axis once that is known; its length is the
        evidence's."""
        p = self._persons.get(person)
        if p is None:
            return None
        return np.array(lab.facing_on_axis(p.facing_ev, p.axis_ev, self.cfg.labelling.axis_min))
