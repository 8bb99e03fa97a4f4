"""Is a change's gain more than the seed noise? Two sets of runs compared cell by cell.

The event figures of one run flip with almost any change of its inputs (a pixel of one
blob, the tracker's seed), so a total over a few runs moves by a few events on its own
(docs/benchmarks.md, session 25). Comparing two settings on the same recordings and seeds
pairs the runs: each (recording, seed) cell gives one difference, B minus A. The cells
that differ are what the change did or what noise did; a sign test over them and a
bootstrap interval of the total say how far that total can be told from zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats


@dataclass(frozen=True)
class PairedDifference:
    """B minus A over paired cells.

    n_cells : cells compared
    n_higher, n_lower : cells where B is above / below A
    total : sum over the cells of B - A
    low, high : bootstrap interval of ``total`` (cells resampled with replacement), at
        ``level``
    level : the interval's confidence level
    p_sign : two-sided sign test of "B above A as often as below", over the cells that
        differ (1.0 when none differ)
    """

    n_cells: int
    n_higher: int
    n_lower: int
    total: float
    low: float
    high: float
    level: float
    p_sign: float

    def summary(self, what: str) -> str:
        """One line for a report, ``what`` naming the per-cell figure."""
        return (
            f"B - A, {what}: total {self.total:+g} over {self.n_cells} runs "
            f"({100 * self.level:.0f} % bootstrap interval {self.low:+g} to {self.high:+g}); "
            f"B higher in {self.n_higher}, lower in {self.n_lower} (sign test p = "
            f"{self.p_sign:.2f})"
        )


def paired_difference(
    a: np.ndarray, b: np.ndarray, *, level: float = 0.9, n_resamples: int = 9999, seed: int = 0
) -> PairedDifference:
    """Compare per-cell figures ``a`` and ``b`` ((n,) each, cell i of both from the same
    recording and seed).

    The bootstrap treats cells as independent. Seeds of one recording share its images, so
    the interval is narrower than one over new recordings would be: read it as the noise of
    the tracker's seeds, and judge held-out recordings separately.

    >>> r = paired_difference(np.array([3, 2, 2, 0]), np.array([4, 2, 2, 0]))
    >>> r.total, r.n_higher, r.n_lower, r.p_sign
    (1.0, 1, 0, 1.0)
    """
    a = np.asarray(a, dtype=np.float64).ravel()
    b = np.asarray(b, dtype=np.float64).ravel()
    if a.shape != b.shape:
        raise ValueError(f"a has {a.size} cells and b {b.size}: they must be paired")
    d = b - a
    n_higher, n_lower = int((d > 0).sum()), int((d < 0).sum())
    total = float(d.sum())
    if not d.any():
        low = high = 0.0
    else:
        boot = stats.bootstrap(
            (d,),
            np.sum,
            confidence_level=level,
            n_resamples=n_resamples,
            method="percentile",
            rng=np.random.default_rng(seed),
        )
        low = float(boot.confidence_interval.low)
        high = float(boot.confidence_interval.high)
    p = stats.binomtest(n_higher, n_higher + n_lower).pvalue if n_higher + n_lower else 1.0
    return PairedDifference(d.size, n_higher, n_lower, total, low, high, level, float(p))
