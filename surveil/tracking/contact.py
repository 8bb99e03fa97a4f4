"""A combined pair's two reported points, half a contact gap either side of its estimate
(not in the paper).

While two targets are combined (section 5.2) one filter tracks both, so both trackers
report the same estimate: the one merged candidate lies between the two hands, and each
is reported about half their distance from where it is. Two hands in contact are not at one
point: their centres lie about a hand's thickness apart, each on its own side. The sides
are those of the two trackers before they joined (the angle rule's "before" vector, section
7.1, taken horizontally: hands meeting from two sides meet mostly horizontally, while the
vector's height is mostly their rise towards the meeting point). Only the reported points
move; the filter, its decisions and the front end's feedback do not. Measured in
docs/benchmarks.md (session 102).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from surveil.datatypes import Phase, TargetSnapshot


def side_direction(toward_partner_m: np.ndarray) -> np.ndarray | None:
    """(3,) unit horizontal vector along ``toward_partner_m`` (3,), or None where that has no
    horizontal length (one target straight above the other)."""
    flat = np.array([toward_partner_m[0], toward_partner_m[1], 0.0])
    norm = float(np.linalg.norm(flat))
    return None if norm < 1e-9 else flat / norm


def spread_combined(
    targets: tuple[TargetSnapshot, ...],
    toward_partner_m: Mapping[int, np.ndarray],
    gap_m: float,
) -> tuple[TargetSnapshot, ...]:
    """``targets`` with every combined target moved ``gap_m`` / 2 away from its partner.

    Parameters
    ----------
    targets : the tracking stage's output
    toward_partner_m : tracker id -> (3,) vector from that combined target towards its
        partner before they joined, m (``MultiTargetTracker.combined_sides``); targets not
        in it stay where they are
    gap_m : the distance between the two reported points of a pair, m (0: unchanged)

    Returns
    -------
    The targets in the same order; only combined ones in ``toward_partner_m`` moved.
    """
    if gap_m <= 0 or not toward_partner_m:
        return targets
    out = list(targets)
    for i, t in enumerate(targets):
        vec = toward_partner_m.get(t.target_id)
        if t.phase is not Phase.COMBINED or vec is None:
            continue
        side = side_direction(np.asarray(vec, np.float64))
        if side is None:
            continue
        out[i] = dataclasses.replace(t, mean_m=t.mean_m - 0.5 * gap_m * side)
    return tuple(out)
