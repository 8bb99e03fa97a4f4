"""The per-tracker finite state machine of paper 004 section 5.2 (Fig. 1), as a pure function.

States (:class:`surveil.datatypes.Phase`) and the transitions :func:`next_phase` makes:

==============  ==============================================  ==============
from            when                                            to
==============  ==============================================  ==============
uninitialised   an unexplained strong candidate persisted       unlabelled
unlabelled      unsupported for ``lost_frames`` frame sets      lost
unlabelled      drifted onto another tracker (see below)        lost
unlabelled      its estimate came within ``combine_distance``   combined
                of another tracker's
unlabelled      the labelling cues gave it a full label         normal
normal          unsupported for ``lost_frames``, or drifted     lost
normal          close to another tracker (as above)             combined
normal          its label was taken off (a hand out of its      unlabelled
                person's reach, in another's)
combined        unsupported for ``combined_lost_frames``        lost
                (pooled level of the pair)
combined        the two modes stayed apart                      unlabelled
lost            retired: lost for ``retire_s`` (or              uninitialised
                ``retire_unlabelled_s`` if never labelled)
lost            a candidate near its last position re-acquired  unlabelled
                it, or (a hand) it met another hand unseen
==============  ==============================================  ==============

Choices where the paper is silent, written down here:

- A lost tracker returns to *unlabelled* (it "behaves like an uninitialised one", and an
  initialised tracker is unlabelled), but keeps its label; the labelling step then moves it
  to *normal* at once, so labels are stable for the life of the track.
- Retiring is the transition lost -> uninitialised: the tracker returns to the pool (the
  manager removes it). Its id is never reused.
- Drift (section 5.2: "when a desired candidate point is not available, the particles tend to
  approach other candidate points which represent other targets"): a tracker that was
  unsupported in one of its last ``drift_window_frames`` frame sets and now comes within the
  combine distance of another tracker has most likely slid onto that target's candidates; it
  is lost rather than combined, so that a real coincidence (both trackers supported while
  approaching) is not confused with a tracker that lost its own target.
- A tracker that never joined a person and comes within the combine distance of a tracker of
  a person is a duplicate of that target or a ghost beside it (a mismatched blob pair): it is
  treated as drifted (lost), and the person's tracker does not combine with it.
- A hand lost just before it meets another hand (their blobs merged, so its candidate
  vanished) is re-acquired onto that hand when the other reaches its coasted position; the
  two combine in the next frame set (the manager's ``_merge_lost``).
- Labels are stable but not final: a hand that stays out of its person's reach and within
  another person's has its label taken off (normal -> unlabelled) and is attached anew. The
  paper's labelling runs once per track; a pair of two people's hands parted the wrong way
  round would otherwise carry both people's labels swapped for the rest of the recording.
- Losing support beats every other transition (a combined pair with no candidate is lost,
  both trackers at once, since they share one pooled likelihood level), but one: a tracker
  the manager pairs with another combines even if it runs out of support in the same frame
  set. The manager pairs a tracker that has lost its support only when it met the other
  (approached it, or the other came to where it was last seen; one that slid onto it has
  drifted): its candidate vanished because its blobs merged with the other's, which is the
  combined state's premise. Before session 53 it was lost, and the meeting opened no event
  (exchange, seed 0: the taker's hand, hidden going behind the giver's, missed three frame
  sets while the giver's hand came to it, and was 9 cm from it at the third).
"""

from __future__ import annotations

from dataclasses import dataclass

from surveil.datatypes import Phase
from surveil.tracking.settings import LifecycleConfig


@dataclass(frozen=True, slots=True)
class Evidence:
    """What the manager measured about one tracker in this step.

    confirmed : bool -- (uninitialised) its seed candidate persisted long enough
    misses : int -- consecutive frame sets with a likelihood level below ``lost_level``
    drifted : bool -- recently unsupported and now on top of another tracker
    partner_id : int | None -- (unlabelled/normal) the tracker it is paired with to combine
    separated : bool -- (combined) the two modes stayed apart long enough
    labelled : bool -- it has a full label (person and limb)
    reacquired : bool -- (lost) a candidate near its last position was found
    lost_for_s : float -- (lost) time since it was lost, s
    ever_labelled : bool -- it had a full label at some point
    label_revoked : bool -- (normal) its label was taken off: it tracks another person's hand
    """

    confirmed: bool = False
    misses: int = 0
    drifted: bool = False
    partner_id: int | None = None
    separated: bool = False
    labelled: bool = False
    reacquired: bool = False
    lost_for_s: float = 0.0
    ever_labelled: bool = False
    label_revoked: bool = False


def next_phase(phase: Phase, ev: Evidence, cfg: LifecycleConfig) -> Phase:
    """The tracker's phase after this step (paper 004 Fig. 1; table in the module docstring).

    Parameters
    ----------
    phase : Phase
        Current phase.
    ev : Evidence
        This step's measurements.
    cfg : LifecycleConfig

    Returns
    -------
    Phase

    Examples
    --------
    >>> cfg = LifecycleConfig(lost_frames=3)
    >>> next_phase(Phase.NORMAL, Evidence(misses=3), cfg)
    <Phase.LOST: 'lost'>
    >>> next_phase(Phase.NORMAL, Evidence(partner_id=4), cfg)
    <Phase.COMBINED: 'combined'>
    """
    match phase:
        case Phase.UNINITIALISED:
            return Phase.UNLABELLED if ev.confirmed else phase
        case Phase.UNLABELLED | Phase.NORMAL if ev.drifted:
            return Phase.LOST
        case Phase.UNLABELLED | Phase.NORMAL if ev.partner_id is not None:
            return Phase.COMBINED
        case Phase.UNLABELLED | Phase.NORMAL if ev.misses >= cfg.lost_frames:
            return Phase.LOST
        case Phase.COMBINED if ev.misses >= cfg.combined_lost_frames:
            return Phase.LOST
        case Phase.UNLABELLED:
            return Phase.NORMAL if ev.labelled else phase
        case Phase.NORMAL:
            return Phase.UNLABELLED if ev.label_revoked else phase
        case Phase.COMBINED:
            return Phase.UNLABELLED if ev.separated else phase
        case Phase.LOST:
            retire_s = cfg.retire_s if ev.ever_labelled else cfg.retire_unlabelled_s
            if ev.lost_for_s >= retire_s:
                return Phase.UNINITIALISED
            return Phase.UNLABELLED if ev.reacquired else phase
    raise AssertionError(f"unhandled phase {phase}")  # unreachable: programming error
