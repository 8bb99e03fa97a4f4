"""Score an output MCAP against a recording's ground truth (``surveil eval``).

Matching, in short (docs/evaluation.md has the full story):

- Targets: each ``/targets`` message is aligned to the nearest ground-truth frame (within half
  a frame period). Per frame, predicted targets that are not ``lost`` are matched one-to-one
  to the true limbs present by the Hungarian method on 3D distance, pairs farther apart than
  ``gate_m`` being forbidden. Predicted person numbers are mapped to true persons once for the
  whole run (Hungarian on co-occurrence counts of matched, labelled pairs).
- Events: per activity, predicted and true events are matched one-to-one by the Hungarian
  method on the climax time difference, pairs farther apart than ``climax_tolerance_s``
  being forbidden.

Ratios with an empty denominator are ``None`` (printed ``-``), never a made-up 0 or 1.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from surveil.config import setting
from surveil.datatypes import LABEL_RE, ActivityEvent, Limb, Phase, parse_label
from surveil.errors import ConfigError
from surveil.io.ground_truth import GroundTruth, load_ground_truth
from surveil.io.mcap_reader import RunData, read_run

log = logging.getLogger(__name__)

DEFAULT_ACTIVITIES = ("clap", "handshake", "exchange", "pick", "place")
_FORBIDDEN = 1e9  # assignment cost of a gated-out pair (larger than any real cost)


@dataclass(frozen=True)
class EvalConfig:
    """Settings of ``surveil eval``."""

    gate_m: float = setting(
        0.25, "max distance of a target from the true limb it matches, m", min=0.0
    )
    min_views: int = setting(
        2, "a true limb counts for recall when this many cameras see it", min=0
    )
    climax_tolerance_s: float = setting(
        1.0, "max climax time difference of an event match, s", min=0.0
    )
    activities: tuple[str, ...] | None = setting(
        None,
        "activities to score (default: clap, handshake, exchange, pick, place and any "
        "activity in the MCAP)",
    )

    def __post_init__(self) -> None:
        if not self.gate_m > 0:
            raise ConfigError(f"eval: gate_m must be > 0 m, got {self.gate_m}")
        if self.min_views < 0:
            raise ConfigError(f"eval: min_views must be >= 0, got {self.min_views}")
        if not self.climax_tolerance_s >= 0:
            raise ConfigError(
                f"eval: climax_tolerance_s must be >= 0 s, got {self.climax_tolerance_s}"
            )


@dataclass(frozen=True, slots=True)
class TargetMetrics:
    """Target (head and hand) scores. Errors in mm; ``None`` where undefined.

    ``person_mapping`` maps predicted person labels to true ones (``{"p2": "p1"}``);
    ``id_switches_per_person_per_min`` is keyed by true person label.
    """

    n_frames_truth: int
    n_frames_scored: int
    n_frames_unaligned: int
    duration_s: float
    n_true_countable: int
    n_true_found: int
    recall: float | None
    n_matches: int
    head_error_mm_mean: float | None
    head_error_mm_median: float | None
    hand_error_mm_mean: float | None
    hand_error_mm_median: float | None
    n_false_targets: int
    false_targets_per_frame: float | None
    labelled_fraction: float | None
    limb_type_accuracy: float | None
    left_right_accuracy: float | None
    person_consistency: float | None
    label_accuracy: float | None
    person_mapping: dict[str, str]
    id_switches: int
    id_switches_per_min: float | None
    id_switches_per_person_per_min: dict[str, float]


@dataclass(frozen=True, slots=True)
class ActivityScore:
    """Event scores of one activity; climax errors in ms; ``None`` where undefined."""

    activity: str
    n_true: int
    n_pred: int
    n_matched: int
    precision: float | None
    recall: float | None
    f1: float | None
    climax_error_ms_mean: float | None
    climax_error_ms_median: float | None
    direction_accuracy: float | None
    actors_accuracy: float | None
    climax_errors_ms: tuple[float, ...] = ()  # one per matched event (to pool over runs)
    n_direction: int = 0  # matched events with a true giver and taker
    n_direction_right: int = 0  # ... whose predicted from/to are right


@dataclass(frozen=True, slots=True)
class EventMetrics:
    """Per-activity scores and their micro-average (pooled counts)."""

    activities: tuple[ActivityScore, ...]
    n_true: int
    n_pred: int
    n_matched: int
    precision: float | None
    recall: float | None
    f1: float | None


@dataclass(frozen=True, slots=True)
class EvalReport:
    recording: str
    mcap: str
    mcap_complete: bool
    config: dict[str, Any]
    targets: TargetMetrics
    events: EventMetrics

    def to_dict(self) -> dict[str, Any]:
        """A JSON-safe dict (``None`` for undefined values, no NaN, plain ints/floats)."""
        return _jsonable(dataclasses.asdict(self))


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    return obj


# ---------------------------------------------------------------------------------------------
# small pure helpers


def ratio(num: float, den: float) -> float | None:
    """``num / den``, or None when ``den`` is 0.

    >>> ratio(1, 4), ratio(0, 0)
    (0.25, None)
    """
    return float(num) / den if den else None


def _mean_median(values: Sequence[float] | np.ndarray) -> tuple[float | None, float | None]:
    arr = np.asarray(values, dtype=np.float64)
    if arr.size == 0:
        return None, None
    return float(arr.mean()), float(np.median(arr))


def gated_assignment(cost: np.ndarray, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-cost one-to-one matching of rows and columns, pairs with cost > gate forbidden.

    Parameters
    ----------
    cost : (R, C) float
        Pair costs (non-negative; NaN = forbidden).
    gate : float
        Largest allowed cost.

    Returns
    -------
    rows, cols : (M,) int64
        Matched pairs, sorted by row.

    >>> gated_assignment(np.array([[0.1, 0.2], [0.15, 5.0]]), 1.0)
    (array([0, 1]), array([1, 0]))
    >>> gated_assignment(np.zeros((0, 3)), 1.0)
    (array([], dtype=int64), array([], dtype=int64))
    """
    empty = np.zeros(0, dtype=np.int64)
    if cost.size == 0:
        return empty, empty
    allowed = np.isfinite(cost) & (cost <= gate)
    if not allowed.any():
        return empty, empty
    rows, cols = linear_sum_assignment(np.where(allowed, cost, _FORBIDDEN))
    keep = allowed[rows, cols]
    return rows[keep].astype(np.int64), cols[keep].astype(np.int64)


def person_mapping(pred_person: np.ndarray, true_person: np.ndarray) -> dict[int, int]:
    """Map predicted person numbers to true ones by the Hungarian method on co-occurrence
    counts (each predicted person to at most one true person and vice versa).

    >>> person_mapping(np.array([2, 2, 2, 1, 1]), np.array([1, 1, 2, 2, 2]))
    {1: 2, 2: 1}
    """
    preds, p_idx = np.unique(pred_person, return_inverse=True)
    trues, t_idx = np.unique(true_person, return_inverse=True)
    if preds.size == 0:
        return {}
    counts = np.zeros((len(preds), len(trues)), dtype=np.int64)
    np.add.at(counts, (p_idx, t_idx), 1)
    rows, cols = linear_sum_assignment(counts, maximize=True)
    pairs = zip(rows, cols, strict=True)
    return {int(preds[r]): int(trues[c]) for r, c in pairs if counts[r, c] > 0}


# ---------------------------------------------------------------------------------------------
# targets


def align_frames(truth_t_ns: np.ndarray, pred_t_ns: np.ndarray, fps: float) -> np.ndarray:
    """For each predicted frame, the index of the ground-truth frame it scores against, or -1.

    A predicted frame aligns to the nearest true frame within half a frame period; when two
    predicted frames align to one true frame, only the nearer one is kept.

    >>> align_frames(np.array([0, 100, 200]), np.array([2, 90, 95, 260, 500]), fps=1e7)
    array([ 0, -1,  1, -1, -1])
    """
    out = np.full(len(pred_t_ns), -1, dtype=np.int64)
    if len(truth_t_ns) == 0 or len(pred_t_ns) == 0:
        return out
    half = 0.5e9 / fps
    if len(truth_t_ns) == 1:
        nearest = np.zeros(len(pred_t_ns), dtype=np.int64)
    else:
        right = np.clip(np.searchsorted(truth_t_ns, pred_t_ns), 1, len(truth_t_ns) - 1)
        left = right - 1
        pick_left = np.abs(pred_t_ns - truth_t_ns[left]) <= np.abs(truth_t_ns[right] - pred_t_ns)
        nearest = np.where(pick_left, left, right)
    dt = np.abs(pred_t_ns - truth_t_ns[nearest]).astype(np.float64)
    taken: set[int] = set()
    for k in np.argsort(dt, kind="stable"):
        g = int(nearest[k])
        if dt[k] <= half and g not in taken:
            taken.add(g)
            out[k] = g
    return out


def _persistent_assignment(
    dist: np.ndarray,
    tracker_ids: np.ndarray,
    true_idx: np.ndarray,
    previous: dict[int, int],
    cfg: EvalConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """One frame's matching as CLEAR MOT defines it (Bernardin and Stiefelhagen 2008): a true
    limb keeps the tracker it was last matched to while that tracker is within the gate; the
    rest are matched by :func:`gated_assignment`. Without the first step, two trackers near one
    limb would trade the match back and forth and count a switch every time.

    Parameters
    ----------
    dist : (R, C) float -- distances, predicted rows x present true limbs, m
    tracker_ids : (R,) int -- tracker id of each predicted row
    true_idx : (C,) int -- label index of each present true limb
    previous : true label index -> tracker id of its last match
    cfg : EvalConfig

    Returns
    -------
    rows, cols : (M,) int64, sorted by row

    >>> d = np.array([[0.05, 0.9], [0.02, 0.9]])
    >>> _persistent_assignment(d, np.array([7, 8]), np.array([0, 1]), {0: 7}, EvalConfig())
    (array([0]), array([0]))
    >>> _persistent_assignment(d, np.array([7, 8]), np.array([0, 1]), {}, EvalConfig())
    (array([1]), array([0]))
    >>> d2 = np.array([[0.05, 0.1], [0.9, 0.2]])   # both limbs last had tracker 7
    >>> _persistent_assignment(d2, np.array([7, 8]), np.array([0, 1]), {0: 7, 1: 7},
    ...                        EvalConfig())
    (array([0, 1]), array([0, 1]))
    """
    row_of = {int(t): i for i, t in enumerate(tracker_ids)}
    kept_r: list[int] = []
    kept_c: list[int] = []
    # closest first: two limbs whose last matches were the same tracker cannot both keep it
    prev_rows = [(row_of.get(previous.get(int(j), -1)), c) for c, j in enumerate(true_idx)]
    prev_rows = [(r, c) for r, c in prev_rows if r is not None and dist[r, c] <= cfg.gate_m]
    for r, c in sorted(prev_rows, key=lambda rc: dist[rc[0], rc[1]]):
        if r not in kept_r:
            kept_r.append(r)
            kept_c.append(c)
    free_r = np.setdiff1d(np.arange(dist.shape[0]), kept_r)
    free_c = np.setdiff1d(np.arange(dist.shape[1]), kept_c)
    r, c = gated_assignment(dist[np.ix_(free_r, free_c)], cfg.gate_m)
    rows = np.concatenate([np.array(kept_r, dtype=np.int64), free_r[r]])
    cols = np.concatenate([np.array(kept_c, dtype=np.int64), free_c[c]])
    order = np.argsort(rows, kind="stable")
    return rows[order].astype(np.int64), cols[order].astype(np.int64)


@dataclass(frozen=True, slots=True)
class TargetMatches:
    """Matched (true limb, predicted row) pairs over all scored frames, in frame order."""

    gt_frame: np.ndarray  # (M,) index into the ground truth's frames
    true_idx: np.ndarray  # (M,) index into gt.labels
    pred_row: np.ndarray  # (M,) row of RunData targets


def _match_targets(
    gt: GroundTruth, run: RunData, cfg: EvalConfig
) -> tuple[TargetMatches, np.ndarray, int, int, int, int]:
    """Per-frame gated Hungarian matching. Returns (matches, scored gt frames, countable,
    found, false targets, unaligned)."""
    aligned = align_frames(gt.t_ns, run.frame_t_ns, gt.fps)
    lost = Phase.LOST.code
    n_views = gt.n_views
    gf, tj, pr = [], [], []
    scored = []
    n_countable = n_found = n_false = 0
    previous: dict[int, int] = {}  # true limb -> tracker id it was last matched to
    for k in np.argsort(aligned, kind="stable"):
        g = int(aligned[k])
        if g < 0:
            continue
        scored.append(g)
        span = run.frame_rows(int(k))
        rows = np.arange(span.start, span.stop)
        rows = rows[
            (run.target_state[rows] != lost) & np.isfinite(run.target_pos_m[rows]).all(axis=1)
        ]
        true_pos = gt.positions_m[g]
        present = np.flatnonzero(np.isfinite(true_pos).all(axis=1))
        countable = n_views[g, present] >= cfg.min_views
        if rows.size and present.size:
            dist = cdist(run.target_pos_m[rows], true_pos[present])
            r, c = _persistent_assignment(dist, run.target_tracker[rows], present, previous, cfg)
        else:
            r = c = np.zeros(0, dtype=np.int64)
        previous.update(
            (int(present[ci]), int(run.target_tracker[rows[ri]]))
            for ri, ci in zip(r, c, strict=True)
        )
        order = np.argsort(c)
        r, c = r[order], c[order]
        gf.append(np.full(len(r), g, dtype=np.int64))
        tj.append(present[c])
        pr.append(rows[r])
        n_countable += int(countable.sum())
        n_found += int(countable[c].sum())
        n_false += int(rows.size - r.size)

    def cat(parts: list[np.ndarray]) -> np.ndarray:
        return np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, np.int64)

    matches = TargetMatches(cat(gf), cat(tj), cat(pr))
    n_unaligned = int(np.count_nonzero(aligned < 0))
    return matches, np.array(scored, dtype=np.int64), n_countable, n_found, n_false, n_unaligned


def match_targets(gt: GroundTruth, run: RunData, cfg: EvalConfig) -> TargetMatches:
    """The (true limb, predicted row) pairs that the scores are computed over, in frame
    order: for diagnostics that split the errors (``benchmarks/error_breakdown.py``)."""
    return _match_targets(gt, run, cfg)[0]


NEW_TRACKER_S = 0.5  # a tracker younger than this at a switch was started for the limb


@dataclass(frozen=True, slots=True)
class IdentitySwitch:
    """One identity switch: a true limb matched to ``to_tracker`` after ``from_tracker``.

    t_s : float -- time of the first frame matched to the new tracker, s (ground truth's clock)
    limb : str -- the true limb's label
    from_tracker, to_tracker : int -- tracker ids
    unmatched_s : float -- how long the limb went unmatched in between (0: consecutive frames)
    from_phase : str -- the old tracker's phase then ("normal", "lost", ...), or "gone" when
        it is no longer in the output
    to_age_s : float -- how long the new tracker had existed then, s
    """

    t_s: float
    limb: str
    from_tracker: int
    to_tracker: int
    unmatched_s: float
    from_phase: str
    to_age_s: float

    @property
    def kind(self) -> str:
        """What the switch says about the tracker: ``"not re-acquired"`` (the old tracker was
        lost or gone and a new one was started: the lost tracker did not find its limb
        again), ``"taken over"`` (the old tracker was lost or gone and an older tracker, one
        that was following something else, took the limb) or ``"drifted"`` (the old tracker
        still runs but no longer follows the limb: it slid onto another target, or two
        trackers swapped)."""
        if self.from_phase in ("lost", "gone"):
            return "not re-acquired" if self.to_age_s < NEW_TRACKER_S else "taken over"
        return "drifted"


def identity_switches(gt: GroundTruth, run: RunData, cfg: EvalConfig) -> list[IdentitySwitch]:
    """Every identity switch of a run (those that ``TargetMetrics.id_switches`` counts), in
    the order of the true limbs, then of time."""
    return _switches(gt, run, _match_targets(gt, run, cfg)[0])


def _switches(gt: GroundTruth, run: RunData, m: TargetMatches) -> list[IdentitySwitch]:
    """:func:`identity_switches` of a run's matches: the changes of the tracker matched to each
    true limb between consecutive matched frames (frames without a match are skipped, as in
    CLEAR MOT)."""
    phase_of = {p.code: p.value for p in Phase}
    trackers, first_row = np.unique(run.target_tracker, return_index=True)  # rows by frame
    first_frame = dict(zip(trackers.tolist(), run.target_frame[first_row].tolist(), strict=True))
    out = []
    for j, label in enumerate(gt.labels):
        sel = np.flatnonzero(m.true_idx == j)  # matches are in frame order
        ids = run.target_tracker[m.pred_row[sel]]
        for k in np.flatnonzero(ids[1:] != ids[:-1]):
            a, b = int(ids[k]), int(ids[k + 1])
            frame = int(run.target_frame[m.pred_row[sel[k + 1]]])
            span = run.frame_rows(frame)
            rows = np.arange(span.start, span.stop)
            old = rows[run.target_tracker[rows] == a]
            t0_ns, t1_ns = gt.t_ns[m.gt_frame[sel[k]]], gt.t_ns[m.gt_frame[sel[k + 1]]]
            out.append(
                IdentitySwitch(
                    t_s=float(t1_ns) * 1e-9,
                    limb=label,
                    from_tracker=a,
                    to_tracker=b,
                    unmatched_s=max(round(float(t1_ns - t0_ns) * 1e-9 * gt.fps) - 1, 0) / gt.fps,
                    from_phase=(
                        phase_of.get(int(run.target_state[old[0]]), "?") if old.size else "gone"
                    ),
                    to_age_s=float(run.frame_t_ns[frame] - run.frame_t_ns[first_frame[b]]) * 1e-9,
                )
            )
    return out


def score_targets(
    gt: GroundTruth, run: RunData, cfg: EvalConfig
) -> tuple[TargetMetrics, dict[int, int]]:
    """Target metrics and the predicted -> true person-number mapping."""
    m, scored, n_countable, n_found, n_false, n_unaligned = _match_targets(gt, run, cfg)
    true_parsed = [parse_label(lab) for lab in gt.labels]
    true_person = np.array([p for p, _ in true_parsed], dtype=np.int64)
    true_limb = np.array([int(limb) for _, limb in true_parsed], dtype=np.int64)

    err_mm = 1000.0 * np.linalg.norm(
        run.target_pos_m[m.pred_row] - gt.positions_m[m.gt_frame, m.true_idx], axis=1
    )
    t_limb = true_limb[m.true_idx]
    t_person = true_person[m.true_idx]
    p_limb = run.target_limb[m.pred_row].astype(np.int64)
    p_person = run.target_person[m.pred_row]
    is_head = t_limb == Limb.HEAD
    head_mean, head_median = _mean_median(err_mm[is_head])
    hand_mean, hand_median = _mean_median(err_mm[~is_head])

    labelled = (p_person > 0) & (p_limb != Limb.UNKNOWN)
    limb_ok = (p_limb == Limb.HEAD) == (t_limb == Limb.HEAD)
    hands = labelled & (p_limb != Limb.HEAD) & (t_limb != Limb.HEAD)
    mapping = person_mapping(p_person[labelled], t_person[labelled])
    mapped = np.array([mapping.get(int(p), -1) for p in p_person], dtype=np.int64)

    n_scored = len(scored)
    duration_s = n_scored / gt.fps
    switches_by_person: dict[str, int] = {f"p{p}": 0 for p in sorted(set(true_person))}
    switches = _switches(gt, run, m)
    total_switches = len(switches)
    for sw in switches:
        switches_by_person[f"p{parse_label(sw.limb)[0]}"] += 1
    minutes = duration_s / 60.0
    metrics = TargetMetrics(
        n_frames_truth=len(gt.frames),
        n_frames_scored=n_scored,
        n_frames_unaligned=n_unaligned,
        duration_s=duration_s,
        n_true_countable=n_countable,
        n_true_found=n_found,
        recall=ratio(n_found, n_countable),
        n_matches=len(err_mm),
        head_error_mm_mean=head_mean,
        head_error_mm_median=head_median,
        hand_error_mm_mean=hand_mean,
        hand_error_mm_median=hand_median,
        n_false_targets=n_false,
        false_targets_per_frame=ratio(n_false, n_scored),
        labelled_fraction=ratio(labelled.sum(), len(labelled)),
        limb_type_accuracy=ratio((limb_ok & labelled).sum(), labelled.sum()),
        left_right_accuracy=ratio((hands & (p_limb == t_limb)).sum(), hands.sum()),
        person_consistency=ratio((labelled & (mapped == t_person)).sum(), labelled.sum()),
        label_accuracy=ratio(
            (labelled & (mapped == t_person) & (p_limb == t_limb)).sum(), len(labelled)
        ),
        person_mapping={f"p{k}": f"p{v}" for k, v in sorted(mapping.items())},
        id_switches=total_switches,
        id_switches_per_min=ratio(total_switches, minutes),
        id_switches_per_person_per_min=(
            {p: n / minutes for p, n in switches_by_person.items()} if minutes else {}
        ),
    )
    return metrics, mapping


# ---------------------------------------------------------------------------------------------
# events


def map_label(label: str | None, mapping: dict[int, int]) -> str | None:
    """A predicted target label in true person numbers (unchanged when ``mapping`` is empty;
    ``?``-prefixed when its person has no counterpart, so that it never compares equal).

    >>> map_label("p2/left_hand", {2: 1}), map_label("p3/head", {2: 1}), map_label("t4", {})
    ('p1/left_hand', '?p3/head', 't4')
    """
    if label is None or not mapping:
        return label
    m = LABEL_RE.match(label)
    if m is None or m["person"] is None:
        return label
    true = mapping.get(int(m["person"]))
    return f"p{true}/{m['limb']}" if true is not None else f"?{label}"


def score_activity(
    activity: str,
    truth: Sequence[ActivityEvent],
    pred: Sequence[ActivityEvent],
    cfg: EvalConfig,
    mapping: dict[int, int],
) -> ActivityScore:
    """Match one activity's events by climax time and score them."""
    t_climax = np.array([e.climax_ns for e in truth], dtype=np.float64).reshape(-1, 1)
    p_climax = np.array([e.climax_ns for e in pred], dtype=np.float64).reshape(1, -1)
    cost_s = np.abs(t_climax - p_climax) / 1e9
    ti, pi = gated_assignment(cost_s.reshape(len(truth), len(pred)), cfg.climax_tolerance_s)
    n_tp = len(ti)
    n_fp, n_fn = len(pred) - n_tp, len(truth) - n_tp
    mean_ms, median_ms = _mean_median(1000.0 * cost_s[ti, pi] if n_tp else [])
    n_dir = n_dir_ok = n_act_ok = 0
    for a, b in zip(ti, pi, strict=True):
        t, p = truth[a], pred[b]
        if {map_label(x, mapping) for x in p.actors} == set(t.actors):
            n_act_ok += 1
        if t.from_actor is not None and t.to_actor is not None:
            n_dir += 1
            n_dir_ok += (
                map_label(p.from_actor, mapping) == t.from_actor
                and map_label(p.to_actor, mapping) == t.to_actor
            )
    return ActivityScore(
        activity=activity,
        n_true=len(truth),
        n_pred=len(pred),
        n_matched=n_tp,
        precision=ratio(n_tp, n_tp + n_fp),
        recall=ratio(n_tp, n_tp + n_fn),
        f1=ratio(2 * n_tp, 2 * n_tp + n_fp + n_fn),
        climax_error_ms_mean=mean_ms,
        climax_error_ms_median=median_ms,
        direction_accuracy=ratio(n_dir_ok, n_dir),
        actors_accuracy=ratio(n_act_ok, n_tp),
        climax_errors_ms=tuple(float(x) for x in 1000.0 * cost_s[ti, pi]) if n_tp else (),
        n_direction=n_dir,
        n_direction_right=int(n_dir_ok),
    )


def score_events(
    truth: Sequence[ActivityEvent],
    pred: Sequence[ActivityEvent],
    cfg: EvalConfig,
    mapping: dict[int, int],
) -> EventMetrics:
    """Per-activity and micro-averaged event scores."""
    if cfg.activities is not None:
        activities = tuple(cfg.activities)
    else:
        extra = sorted({e.activity for e in pred} - set(DEFAULT_ACTIVITIES))
        activities = DEFAULT_ACTIVITIES + tuple(extra)
    scores = tuple(
        score_activity(
            a,
            [e for e in truth if e.activity == a],
            [e for e in pred if e.activity == a],
            cfg,
            mapping,
        )
        for a in activities
    )
    n_true = sum(s.n_true for s in scores)
    n_pred = sum(s.n_pred for s in scores)
    n_tp = sum(s.n_matched for s in scores)
    return EventMetrics(
        activities=scores,
        n_true=n_true,
        n_pred=n_pred,
        n_matched=n_tp,
        precision=ratio(n_tp, n_pred),
        recall=ratio(n_tp, n_true),
        f1=ratio(2 * n_tp, n_pred + n_true),
    )


# ---------------------------------------------------------------------------------------------


def evaluate(recording_dir: Path, mcap_path: Path, cfg: EvalConfig) -> EvalReport:
    """Score ``mcap_path`` against the ground truth of ``recording_dir``.

    Parameters
    ----------
    recording_dir : Path
        Recording directory holding ``ground_truth/``.
    mcap_path : Path
        Output MCAP of ``surveil run`` (a truncated one is scored up to its last chunk).
    cfg : EvalConfig

    Returns
    -------
    EvalReport

    Raises
    ------
    InputError
        If the recording has no (readable) ground truth or the MCAP cannot be read.
    """
    gt = load_ground_truth(Path(recording_dir))
    run = read_run(Path(mcap_path))
    targets, mapping = score_targets(gt, run, cfg)
    if targets.n_frames_unaligned:
        log.warning(
            "%s: %d /targets messages have no ground-truth frame within half a frame "
            "period; not scored",
            mcap_path,
            targets.n_frames_unaligned,
        )
    events = score_events(gt.events, run.events, cfg, mapping)
    return EvalReport(
        recording=str(recording_dir),
        mcap=str(mcap_path),
        mcap_complete=run.complete,
        config=dataclasses.asdict(cfg),
        targets=targets,
        events=events,
    )


# ---------------------------------------------------------------------------------------------
# text report


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], indent: str = "  ") -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = []
    for r in [header, *rows]:
        right = zip(r[1:], widths[1:], strict=True)
        cells = [r[0].ljust(widths[0])] + [c.rjust(w) for c, w in right]
        lines.append(indent + "  ".join(cells).rstrip())
    return "\n".join(lines)


def format_report(report: EvalReport) -> str:
    """The report as aligned plain-text tables (``-`` = undefined)."""
    t, ev, cfg = report.targets, report.events, report.config
    head = [
        f"surveil eval: {report.mcap} vs {report.recording}"
        + ("" if report.mcap_complete else " (MCAP truncated: scored up to its last chunk)"),
        "",
        f"targets: {t.n_frames_scored} of {t.n_frames_truth} frames scored "
        f"({t.n_frames_unaligned} unaligned), gate {cfg['gate_m']} m, "
        f"recall over limbs seen by >= {cfg['min_views']} cameras",
    ]
    rows = [
        ("recall", _fmt(t.recall), f"{t.n_true_found}/{t.n_true_countable}"),
        (
            "head error mean / median (mm)",
            f"{_fmt(t.head_error_mm_mean, 1)} / {_fmt(t.head_error_mm_median, 1)}",
            "",
        ),
        (
            "hand error mean / median (mm)",
            f"{_fmt(t.hand_error_mm_mean, 1)} / {_fmt(t.hand_error_mm_median, 1)}",
            "",
        ),
        ("false targets per frame", _fmt(t.false_targets_per_frame), str(t.n_false_targets)),
        ("labelled fraction", _fmt(t.labelled_fraction), f"of {t.n_matches} matches"),
        ("limb type accuracy", _fmt(t.limb_type_accuracy), ""),
        ("left/right accuracy", _fmt(t.left_right_accuracy), ""),
        ("person consistency", _fmt(t.person_consistency), ""),
        ("label accuracy", _fmt(t.label_accuracy), f"of {t.n_matches} matches"),
        ("identity switches per min", _fmt(t.id_switches_per_min, 2), str(t.id_switches)),
    ]
    rows += [
        (f"  switches per min, {p}", _fmt(v, 2), "")
        for p, v in t.id_switches_per_person_per_min.items()
    ]
    mapping = ", ".join(f"{k} -> {v}" for k, v in t.person_mapping.items()) or "-"
    rows.append(("person mapping (predicted -> true)", mapping, ""))
    out = head + [_table(("metric", "value", "count"), rows)]
    out += ["", f"events: climax tolerance {cfg['climax_tolerance_s']} s"]
    ev_rows = [
        (
            s.activity,
            str(s.n_true),
            str(s.n_pred),
            str(s.n_matched),
            _fmt(s.precision),
            _fmt(s.recall),
            _fmt(s.f1),
            _fmt(s.climax_error_ms_mean, 0),
            _fmt(s.climax_error_ms_median, 0),
            _fmt(s.direction_accuracy),
            _fmt(s.actors_accuracy),
        )
        for s in ev.activities
    ]
    ev_rows.append(
        (
            "all (micro)",
            str(ev.n_true),
            str(ev.n_pred),
            str(ev.n_matched),
            _fmt(ev.precision),
            _fmt(ev.recall),
            _fmt(ev.f1),
            "",
            "",
            "",
            "",
        )
    )
    out.append(
        _table(
            (
                "activity",
                "true",
                "pred",
                "matched",
                "precision",
                "recall",
                "f1",
                "climax ms mean",
                "median",
                "direction",
                "actors",
            ),
            ev_rows,
        )
    )
    return "\n".join(out)
