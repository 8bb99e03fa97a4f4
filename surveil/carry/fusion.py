"""Fusion of per-camera, per-frame hue distributions and the carry decision (paper 004
section 7.3, eq. 29).

Pure functions plus :class:`HueWindow`, a fixed-capacity ring buffer of one hand's recent
distributions (memory does not grow with time).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surveil.carry.hue import bin_centres_deg, circular_distance_deg
from surveil.validate import require_shape


def fuse_distributions(pdfs: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Reliability-weighted average of hue distributions (eq. 29, "beamforming").

    p_j(c) = sum_k sum_m rho_jmk p_jmk(c) / sum_k sum_m rho_jmk

    Parameters
    ----------
    pdfs : (N, B) float
        One distribution per (camera, frame) sample of the window.
    rho : (N,) float
        Their reliabilities (eq. 28), non-negative.

    Returns
    -------
    (B,) float64
        The fused distribution; all zeros when there is no sample or no weight.

    >>> fuse_distributions(np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([3.0, 1.0])).tolist()
    [0.75, 0.25]
    """
    p = np.asarray(pdfs, np.float64)
    w = np.asarray(rho, np.float64)
    require_shape("pdfs", p, (None, None), np.floating)
    require_shape("rho", w, (len(p),), np.floating)
    if np.any(w < 0):
        raise ValueError(f"rho must be non-negative, got min {w.min()}")
    total = w.sum()
    if len(p) == 0 or total <= 0:
        return np.zeros(p.shape[1])
    # eq. 29
    return w @ p / total


def subtract_distribution(pdf: np.ndarray, other: np.ndarray) -> np.ndarray:
    """``max(pdf - other, 0)``: remove what the person's other hand also sees (the dress).

    >>> subtract_distribution(np.array([0.5, 0.2, 0.3]), np.array([0.1, 0.4, 0.3])).tolist()
    [0.4, 0.0, 0.0]
    """
    return np.maximum(np.asarray(pdf, np.float64) - np.asarray(other, np.float64), 0.0)


@dataclass(frozen=True, slots=True)
class CarryDecision:
    """The decision on one fused distribution.

    carrying : bool
    hue_deg : float | None -- hue of the strongest mode (None when the pdf is empty)
    mass : float -- pdf mass within +-halfwidth of that mode (a share of the region's pixels)
    confidence : float -- 0..1
    """

    carrying: bool
    hue_deg: float | None
    mass: float
    confidence: float


def decide_carrying(
    pdf: np.ndarray,
    total_rho: float,
    *,
    carry_mass: float,
    halfwidth_deg: float,
    evidence_rho: float,
) -> CarryDecision:
    """Does a hand carry an object? The strongest mode of its fused distribution decides.

    The mode's mass is the pdf mass within ``+-halfwidth_deg`` of the highest bin and its hue
    the circular mean of that mass; the hand carries when the mass reaches ``carry_mass``.
    The confidence multiplies how far the mass is from the threshold (relative, capped at 1)
    by how much evidence the window holds, ``1 - exp(-total_rho / evidence_rho)``.

    Parameters
    ----------
    pdf : (B,) float
        Fused (and optionally clothing-subtracted) distribution, not renormalised.
    total_rho : float
        Sum of the reliabilities fused into it.
    carry_mass, halfwidth_deg, evidence_rho : float
        ``CarryConfig.carry_mass``, ``mode_mass_halfwidth_deg``, ``evidence_rho``.

    >>> pdf = np.zeros(180); pdf[59:62] = 0.05
    >>> d = decide_carrying(pdf, 5.0, carry_mass=0.06, halfwidth_deg=15, evidence_rho=2.0)
    >>> d.carrying, round(d.hue_deg, 1), round(d.mass, 2)
    (True, 120.0, 0.15)
    """
    p = np.asarray(pdf, np.float64)
    require_shape("pdf", p, (None,), np.floating)
    evidence = 1.0 - float(np.exp(-max(total_rho, 0.0) / evidence_rho))
    if len(p) == 0 or not np.any(p > 0):
        return CarryDecision(False, None, 0.0, evidence)  # nothing coloured: surely empty
    centres = bin_centres_deg(len(p))
    peak = int(np.argmax(p))
    near = circular_distance_deg(centres, centres[peak]) <= halfwidth_deg
    mass = float(p[near].sum())
    angles = np.radians(centres[near])
    hue = float(np.degrees(np.arctan2(p[near] @ np.sin(angles), p[near] @ np.cos(angles))))
    margin = min(1.0, abs(mass - carry_mass) / max(carry_mass, 1e-12))
    return CarryDecision(mass >= carry_mass, hue % 360.0, mass, evidence * margin)


class HueWindow:
    """Ring buffer of one hand's recent (time, reliability, distribution) samples.

    Each sample has two times: when it was taken (:meth:`oldest_ns`) and its age on the
    window's clock, which :meth:`pause` holds still (a hidden hand's evidence does not age).

    Parameters
    ----------
    capacity : int
        Samples kept at most (older ones are overwritten).
    n_bins : int
        B, the length of each distribution.
    """

    def __init__(self, capacity: int, n_bins: int) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be >= 1, got {capacity}")
        self._t_ns = np.zeros(capacity, np.int64)  # on the window's clock
        self._taken_ns = np.zeros(capacity, np.int64)
        self._rho = np.zeros(capacity)
        self._pdfs = np.zeros((capacity, n_bins))
        self._n = 0
        self._head = 0  # next slot to write

    def __len__(self) -> int:
        return self._n

    def clear(self) -> None:
        """Forget every sample (the window restarts)."""
        self._n = 0
        self._head = 0

    def push(self, t_ns: int, rho: float, pdf: np.ndarray) -> None:
        """Add one sample, overwriting the oldest when full."""
        cap = len(self._rho)
        self._t_ns[self._head] = t_ns
        self._taken_ns[self._head] = t_ns
        self._rho[self._head] = rho
        self._pdfs[self._head] = pdf
        self._head = (self._head + 1) % cap
        self._n = min(self._n + 1, cap)

    def pause(self, duration_ns: int) -> None:
        """Let ``duration_ns`` pass without ageing the samples: they count in :meth:`fused`
        for that much longer (the window holds the last ``window_ns`` of time in which the
        hand was looked at, not of the clock)."""
        self._t_ns[: self._n] += duration_ns

    def fused(self, t_ns: int, window_ns: int) -> tuple[np.ndarray, float]:
        """Eq. 29 over the samples with ``t_ns - window_ns < t <= t_ns``.

        Returns
        -------
        pdf : (B,) float64
        total_rho : float
            The summed reliability of the samples used (0 when none).
        """
        sel = self._in_window(t_ns, window_ns)
        rho = self._rho[sel]
        return fuse_distributions(self._pdfs[sel], rho), float(rho.sum())

    def oldest_ns(self, t_ns: int, window_ns: int) -> int | None:
        """When the oldest sample :meth:`fused` would use at ``t_ns`` was taken (None: none)."""
        sel = self._in_window(t_ns, window_ns)
        return int(self._taken_ns[sel].min()) if sel.any() else None

    def _in_window(self, t_ns: int, window_ns: int) -> np.ndarray:
        """(capacity,) bool: the slots holding samples with ``t_ns - window_ns < t <= t_ns``."""
        # writing restarts at slot 0 after a clear, so the first n slots hold the samples
        valid = np.arange(len(self._rho)) < self._n
        return valid & (self._t_ns > t_ns - window_ns) & (self._t_ns <= t_ns)
