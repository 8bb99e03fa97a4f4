"""Multi-target 3-D tracking of heads and hands (paper 004 sections 4, 5, 7.1).

Parallel SIR particle filters, one per target, sharing the candidate points (eq. 17), with a
per-tracker finite state machine (uninitialised / unlabelled / normal / combined / lost) and
head / hand / person / left-right labelling. See docs/tracking.md.
"""

from surveil.tracking.lifecycle import Evidence, next_phase
from surveil.tracking.manager import MultiTargetTracker
from surveil.tracking.settings import (
    FilterConfig,
    LabellingConfig,
    LifecycleConfig,
    TrackingConfig,
)

__all__ = [
    "Evidence",
    "FilterConfig",
    "LabellingConfig",
    "LifecycleConfig",
    "MultiTargetTracker",
    "TrackingConfig",
    "next_phase",
]
