"""Pure, vectorised SIR particle-filter maths (paper 004 sections 4.2, 5, 5.1).

All particles of all targets live in one array; the particles of target ``t`` are the
contiguous *block* ``starts[t]:starts[t + 1]`` (the last block runs to the end). Block
reductions use ``np.add.reduceat`` / ``np.maximum.reduceat``, so nothing here loops over
particles, and only the few pure-Python lines that build per-block offsets loop over targets.

State layout (:class:`Dim`): ``(x, y, z, vx, vy, vz)`` -- world frame, metres and m/s.

Every random function takes an ``np.random.Generator``; nothing uses global random state.
"""

from __future__ import annotations

import enum

import numpy as np

from surveil.validate import require_shape


class Dim(enum.IntEnum):
    """Columns of a particle state array ``(N, 6)``."""

    X = 0
    Y = 1
    Z = 2
    VX = 3
    VY = 4
    VZ = 5


POS = slice(0, 3)
VEL = slice(3, 6)
STATE_DIM = 6


def _check_starts(starts: np.ndarray, n: int) -> np.ndarray:
    starts = np.asarray(starts, dtype=np.intp)
    require_shape("starts", starts, (None,), np.integer)
    if len(starts) and (starts[0] != 0 or np.any(np.diff(starts) <= 0) or starts[-1] >= n):
        raise ValueError(
            f"starts must begin at 0 and increase strictly below n={n} (no empty block), "
            f"got {starts.tolist()}"
        )
    return starts


def block_sizes(starts: np.ndarray, n: int) -> np.ndarray:
    """(T,) number of particles of each block.

    >>> block_sizes(np.array([0, 3]), 5).tolist()
    [3, 2]
    """
    starts = np.asarray(starts, dtype=np.intp)
    return np.diff(np.append(starts, n))


def block_owner(starts: np.ndarray, n: int) -> np.ndarray:
    """(n,) intp: the block index of every particle.

    >>> block_owner(np.array([0, 3]), 5).tolist()
    [0, 0, 0, 1, 1]
    """
    starts = np.asarray(starts, dtype=np.intp)
    return np.repeat(np.arange(len(starts)), block_sizes(starts, n))


def predict_constant_velocity(
    states: np.ndarray,
    accel_std_mps2: np.ndarray | float,
    dt_s: float,
    rng: np.random.Generator,
    *,
    jitter_m: float = 0.0,
    max_speed_mps: float = np.inf,
) -> np.ndarray:
    """Sample x_k ~ p(x_k | x_{k-1}): constant velocity driven by white acceleration noise.

    For each particle, a ~ N(0, s_a^2 I) (s_a per particle: hands fast and abrupt, heads slow):

        p_k = p_{k-1} + v_{k-1} dt + a dt^2 / 2 + e,   e ~ N(0, jitter^2 I)
        v_k = v_{k-1} + a dt

    This is the prior used as the importance density (eq. 10) of the SIR filter.

    Parameters
    ----------
    states : (N, 6) float64
        ``(x, y, z, vx, vy, vz)``, metres and m/s, world frame.
    accel_std_mps2 : float or (N,) float64
        Acceleration noise std per particle, m/s^2.
    dt_s : float
        Time step, s (>= 0).
    rng : np.random.Generator
    jitter_m : float
        Std of an extra position random walk, metres.
    max_speed_mps : float
        Speeds are clipped to this, m/s.

    Returns
    -------
    (N, 6) float64
        New states (a new array).

    Examples
    --------
    >>> s = np.array([[0.0, 0, 1, 1, 0, 0]])
    >>> predict_constant_velocity(s, 0.0, 0.5, np.random.default_rng(0)).tolist()
    [[0.5, 0.0, 1.0, 1.0, 0.0, 0.0]]
    """
    require_shape("states", states, (None, STATE_DIM), np.floating)
    if not dt_s >= 0:
        raise ValueError(f"dt_s must be >= 0, got {dt_s}")
    n = len(states)
    s_a = np.broadcast_to(np.asarray(accel_std_mps2, dtype=np.float64), (n,))
    a = rng.standard_normal((n, 3)) * s_a[:, None]
    out = np.empty_like(states)
    v = states[:, VEL] + a * dt_s
    speed = np.linalg.norm(v, axis=1)
    too_fast = speed > max_speed_mps
    if too_fast.any():
        v[too_fast] *= (max_speed_mps / speed[too_fast])[:, None]
    out[:, POS] = states[:, POS] + states[:, VEL] * dt_s + 0.5 * a * dt_s * dt_s
    if jitter_m > 0:
        out[:, POS] += rng.standard_normal((n, 3)) * jitter_m
    out[:, VEL] = v
    return out


def predict_velocity_reset(
    states: np.ndarray,
    speed_std_mps: float,
    dt_s: float,
    rng: np.random.Generator,
    *,
    jitter_m: float = 0.0,
) -> np.ndarray:
    """Sample the stop-and-go component of a hand's motion prior: a fresh velocity.

        v_k ~ N(0, s_v^2 I),   p_k = p_{k-1} + v_k dt + e,   e ~ N(0, jitter^2 I)

    The old velocity is forgotten: the hand stopped, started or turned within the step. A
    particle of this component that lands on a candidate d metres away carries the velocity
    d / dt -- the average over the step. The alternative, a wide acceleration noise on the
    constant-velocity model, gives the same particle 2 d / dt plus its old velocity, and a
    tracker that resampled onto it overshoots by d on the next step (docs/tracking.md).

    Parameters
    ----------
    states : (N, 6) float64
        ``(x, y, z, vx, vy, vz)``, metres and m/s, world frame.
    speed_std_mps : float
        s_v, std of each component of the new velocity, m/s.
    dt_s : float
        Time step, s (>= 0).
    rng : np.random.Generator
    jitter_m : float
        Std of an extra position random walk, metres.

    Returns
    -------
    (N, 6) float64
        New states (a new array).

    Examples
    --------
    >>> s = np.array([[0.0, 0, 1, 1, 0, 0]])
    >>> predict_velocity_reset(s, 0.0, 0.5, np.random.default_rng(0))[0, :4].tolist()
    [0.0, 0.0, 1.0, 0.0]
    """
    require_shape("states", states, (None, STATE_DIM), np.floating)
    if not dt_s >= 0:
        raise ValueError(f"dt_s must be >= 0, got {dt_s}")
    n = len(states)
    out = np.empty_like(states)
    out[:, VEL] = rng.standard_normal((n, 3)) * speed_std_mps
    out[:, POS] = states[:, POS] + out[:, VEL] * dt_s
    if jitter_m > 0:
        out[:, POS] += rng.standard_normal((n, 3)) * jitter_m
    return out


def candidate_log_likelihood(
    points_m: np.ndarray,
    cand_points_m: np.ndarray,
    cand_prior: np.ndarray,
    sigma_m: float,
    clutter: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Log-likelihood of every particle under eq. 17, for all particles in one array op.

    p(z_k | x) ∝ Σ_c N(x; Z_c, σ² I) · p(Z_c)     (eq. 17, indicator = 1 for every c)

    The Gaussian normalisation constant is the same for every particle and is dropped, so the
    *support* s(x) = Σ_c exp(-|x - Z_c|² / 2σ²) p(Z_c) lies in [0, Σ_c p(Z_c)] and is
    comparable between frames (it is the "likelihood level" the lifecycle thresholds).
    A constant ``clutter`` is added before the log: with no candidate near any particle the
    weights stay flat instead of degenerating.

    Parameters
    ----------
    points_m : (N, 3) float64
        Particle positions, metres.
    cand_points_m : (K, 3) float64
        Candidate points Z_c, metres.
    cand_prior : (K,) or (N, K) float64
        Their priors p(Z_c) in [0, 1]; (N, K) gives every particle its own weights (the
        manager's exclusion: a candidate's prior shared among the targets that claim it).
    sigma_m : float
        σ, metres.
    clutter : float
        Constant added to s(x) (>= 0).

    Returns
    -------
    log_lik : (N,) float64
        log(s(x) + clutter); ``-inf`` where both are 0.
    support : (N,) float64
        s(x).

    Examples
    --------
    >>> ll, s = candidate_log_likelihood(np.zeros((2, 3)), np.array([[0.0, 0, 0]]),
    ...                                  np.array([0.5]), 0.1)
    >>> s.tolist()
    [0.5, 0.5]
    """
    require_shape("points_m", points_m, (None, 3), np.floating)
    require_shape("cand_points_m", cand_points_m, (None, 3), np.floating)
    if np.ndim(cand_prior) == 2:
        require_shape("cand_prior", cand_prior, (len(points_m), len(cand_points_m)), np.floating)
    else:
        require_shape("cand_prior", cand_prior, (len(cand_points_m),), np.floating)
    if not sigma_m > 0:
        raise ValueError(f"sigma_m must be > 0, got {sigma_m}")
    n = len(points_m)
    if len(cand_points_m) == 0 or n == 0:
        support = np.zeros(n)
    else:
        # |x - Z|² = |x|² + |Z|² - 2 x·Z, one (N, K) matrix product
        d2 = (
            np.einsum("ij,ij->i", points_m, points_m)[:, None]
            + np.einsum("ij,ij->i", cand_points_m, cand_points_m)[None, :]
            - 2.0 * points_m @ cand_points_m.T
        )
        np.maximum(d2, 0.0, out=d2)
        # eq. 17: Σ_c exp(-d²/2σ²) p(Z_c)
        g = np.exp(d2 * (-0.5 / (sigma_m * sigma_m)))
        if np.ndim(cand_prior) == 2:
            support = np.einsum("ij,ij->i", g, cand_prior)
        else:
            support = g @ cand_prior
    with np.errstate(divide="ignore"):
        log_lik = np.log(support + clutter)
    return log_lik, support


def block_logsumexp(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(T,) log Σ exp(values) over each block; ``-inf`` for a block of ``-inf`` only.

    >>> np.round(block_logsumexp(np.log(np.array([1.0, 3.0, 2.0])), np.array([0, 2])), 6)
    array([1.386294, 0.693147])
    """
    values = np.asarray(values, dtype=np.float64)
    starts = _check_starts(starts, len(values))
    if len(starts) == 0:
        return np.zeros(0)
    peak = np.maximum.reduceat(values, starts)
    safe_peak = np.where(np.isfinite(peak), peak, 0.0)
    owner = block_owner(starts, len(values))
    with np.errstate(divide="ignore"):
        return np.log(np.add.reduceat(np.exp(values - safe_peak[owner]), starts)) + safe_peak


def block_normalise(log_w: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalise log weights within each block (w_k ∝ w_{k-1} p(z|x), eq. 11-12).

    A block whose weights are all zero (``-inf``) gets uniform weights and is reported as not
    explained -- degeneracy is a value, not an error.

    Parameters
    ----------
    log_w : (N,) float64
        Unnormalised log weights.
    starts : (T,) int
        First particle of each block.

    Returns
    -------
    log_w_norm : (N,) float64
        Σ_block exp(log_w_norm) = 1 for every block.
    explained : (T,) bool
        False where the block was degenerate.

    Examples
    --------
    >>> lw, ok = block_normalise(np.array([0.0, 0.0, -np.inf, -np.inf]), np.array([0, 2]))
    >>> np.exp(lw).tolist(), ok.tolist()
    ([0.5, 0.5, 0.5, 0.5], [True, False])
    """
    log_w = np.asarray(log_w, dtype=np.float64)
    starts = _check_starts(starts, len(log_w))
    n = len(log_w)
    total = block_logsumexp(log_w, starts)
    explained = np.isfinite(total)
    owner = block_owner(starts, n)
    sizes = block_sizes(starts, n)
    uniform = -np.log(sizes.astype(np.float64))
    out = np.where(explained[owner], log_w - np.where(explained, total, 0.0)[owner], 0.0)
    out = np.where(explained[owner], out, uniform[owner])
    return out, explained


def effective_sample_size(weights: np.ndarray) -> float:
    """N_eff = 1 / Σ_i (w_i)² for normalised weights (eq. 9).

    >>> effective_sample_size(np.full(8, 0.125)), effective_sample_size(np.eye(1, 10)[0])
    (8.0, 1.0)
    """
    weights = np.asarray(weights, dtype=np.float64)
    require_shape("weights", weights, (None,), np.floating)
    return float(1.0 / np.sum(weights * weights)) if len(weights) else 0.0


def block_effective_sample_size(log_w_norm: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(T,) N_eff (eq. 9) of each block of normalised log weights.

    >>> log_w = np.array([np.log(0.5), np.log(0.5), 0.0, -np.inf])
    >>> block_effective_sample_size(log_w, np.array([0, 2])).tolist()
    [2.0, 1.0]
    """
    w = np.exp(np.asarray(log_w_norm, dtype=np.float64))
    starts = _check_starts(starts, len(w))
    if len(starts) == 0:
        return np.zeros(0)
    return 1.0 / np.add.reduceat(w * w, starts)


def systematic_resample(
    weights: np.ndarray, rng: np.random.Generator, n_out: int | None = None
) -> np.ndarray:
    """Indices of the particles kept by systematic resampling.

    One uniform offset u ~ U[0, 1); positions (u + i)/M, i = 0..M-1, are looked up in the
    weights' CDF. With M = N, particle i is kept floor(N w_i) or ceil(N w_i) times (Douc et
    al. 2005).

    Parameters
    ----------
    weights : (N,) float64
        Non-negative, summing to 1 (renormalised if not).
    rng : np.random.Generator
    n_out : int, optional
        M, the number of indices to draw (default N).

    Returns
    -------
    (M,) intp

    Examples
    --------
    >>> systematic_resample(np.array([0.0, 1.0, 0.0]), np.random.default_rng(0)).tolist()
    [1, 1, 1]
    >>> systematic_resample(np.array([0.5, 0.5]), np.random.default_rng(0), 4).tolist()
    [0, 0, 1, 1]
    """
    weights = np.asarray(weights, dtype=np.float64)
    require_shape("weights", weights, (None,), np.floating)
    n = len(weights)
    m = n if n_out is None else int(n_out)
    if n == 0 or m == 0:
        return np.zeros(0, dtype=np.intp)
    if np.any(weights < 0) or not np.all(np.isfinite(weights)) or weights.sum() <= 0:
        raise ValueError("weights must be finite, non-negative and not all zero")
    cdf = np.cumsum(weights / weights.sum())
    cdf[-1] = 1.0  # round-off guard: every position must land inside the CDF
    positions = (rng.random() + np.arange(m)) / m
    return np.minimum(np.searchsorted(cdf, positions, side="right"), n - 1)


def block_systematic_resample(
    weights: np.ndarray, starts: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Systematic resampling of every block at once; each block keeps its particle count.

    The blocks' CDFs are shifted by the block index (block b's CDF runs over (b, b + 1]) and
    concatenated, so one ``searchsorted`` serves all targets. One uniform offset per block.

    Parameters
    ----------
    weights : (N,) float64
        Non-negative, normalised within each block.
    starts : (T,) int
        First particle of each block.
    rng : np.random.Generator

    Returns
    -------
    (N,) intp
        Global indices of the kept particles; block b's new particles come from block b.

    Examples
    --------
    >>> w = np.array([0.5, 0.5, 0.0, 1.0])
    >>> block_systematic_resample(w, np.array([0, 2]), np.random.default_rng(0)).tolist()
    [0, 1, 3, 3]
    """
    weights = np.asarray(weights, dtype=np.float64)
    require_shape("weights", weights, (None,), np.floating)
    n = len(weights)
    starts = _check_starts(starts, n)
    if n == 0:
        return np.zeros(0, dtype=np.intp)
    if np.any(weights < 0) or not np.all(np.isfinite(weights)):
        raise ValueError("weights must be finite and non-negative")
    owner = block_owner(starts, n)
    sizes = block_sizes(starts, n)
    sums = np.add.reduceat(weights, starts)
    if np.any(sums <= 0):
        raise ValueError(f"every block's weights must sum to > 0, got sums {sums.tolist()}")
    cdf = np.cumsum(weights / sums[owner])
    # per-block CDF: subtract what the previous blocks added, then shift by the block index
    offset = np.concatenate(([0.0], cdf[starts[1:] - 1])) if len(starts) > 1 else np.zeros(1)
    cdf = cdf - offset[owner] + owner
    ends = np.append(starts[1:], n) - 1
    cdf[ends] = np.arange(len(starts)) + 1.0  # round-off guard: every position lands inside
    u = rng.random(len(starts))
    local = np.arange(n) - starts[owner]
    positions = owner + (u[owner] + local) / sizes[owner]
    idx = np.searchsorted(cdf, positions, side="right")
    return np.minimum(idx, ends[owner])


def block_mean_cov(
    points: np.ndarray, log_w_norm: np.ndarray, starts: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean and covariance of each block (the posterior estimate, eq. 8).

    Parameters
    ----------
    points : (N, D) float64
    log_w_norm : (N,) float64
        Log weights normalised within each block.
    starts : (T,) int

    Returns
    -------
    mean : (T, D) float64
    cov : (T, D, D) float64

    Examples
    --------
    >>> m, c = block_mean_cov(np.array([[0.0], [2.0], [5.0]]), np.log([0.5, 0.5, 1.0]),
    ...                       np.array([0, 2]))
    >>> m.ravel().tolist(), c.ravel().tolist()
    ([1.0, 5.0], [1.0, 0.0])
    """
    points = np.asarray(points, dtype=np.float64)
    starts = _check_starts(starts, len(points))
    d = points.shape[1]
    if len(starts) == 0:
        return np.zeros((0, d)), np.zeros((0, d, d))
    w = np.exp(log_w_norm)
    owner = block_owner(starts, len(points))
    mean = np.add.reduceat(points * w[:, None], starts) / np.add.reduceat(w, starts)[:, None]
    diff = points - mean[owner]
    outer = (diff[:, :, None] * diff[:, None, :]) * w[:, None, None]
    cov = np.add.reduceat(outer, starts) / np.add.reduceat(w, starts)[:, None, None]
    return mean, cov


def claim_shares(
    means_m: np.ndarray,
    spreads_m2: np.ndarray,
    cand_points_m: np.ndarray,
    sigma_m: float,
    allowed: np.ndarray | None = None,
) -> np.ndarray:
    """(T, K) share of each candidate claimed by each target (columns sum to 1, or are 0
    where no target may claim the candidate).

    Target t claims candidate c in proportion to the density of Z_c under its predicted
    cloud widened by the candidate noise, N(Z_c; mu_t, (s_t^2 + sigma^2) I): with two targets
    near one candidate the nearer, tighter one takes most of it, and a lone target takes all.
    This is the exclusion principle of multi-target particle filters (MacCormick and Blake):
    without it a hand whose candidates vanished for a few frames is pulled onto the head beside
    it, whose candidate is fully explained by the head's own tracker.

    Parameters
    ----------
    means_m : (T, 3) float64 -- predicted means of the targets' clouds
    spreads_m2 : (T,) float64 -- their per-axis variances (mean of the three), m^2
    cand_points_m : (K, 3) float64
    sigma_m : float -- the likelihood's sigma
    allowed : (T, K) bool, optional -- which targets may claim which candidates (a crown
        head is no hand's); the others share what the disallowed would have taken

    Examples
    --------
    >>> shares = claim_shares(np.array([[0.0, 0, 0], [0.2, 0, 0]]), np.full(2, 1e-4),
    ...                       np.array([[0.01, 0, 0], [0.1, 0, 0]]), 0.03)
    >>> shares.round(2).tolist()
    [[1.0, 0.5], [0.0, 0.5]]
    """
    var = np.asarray(spreads_m2, dtype=np.float64)[:, None] + sigma_m * sigma_m  # (T, 1)
    d2 = np.square(means_m[:, None, :] - cand_points_m[None, :, :]).sum(axis=2)  # (T, K)
    log_dens = -0.5 * d2 / var - 1.5 * np.log(var)
    if allowed is not None:
        log_dens = np.where(allowed, log_dens, -np.inf)
    top = log_dens.max(axis=0, keepdims=True)
    dens = np.exp(log_dens - np.where(np.isfinite(top), top, 0.0))
    total = dens.sum(axis=0, keepdims=True)
    return dens / np.where(total > 0, total, 1.0)
