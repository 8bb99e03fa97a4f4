"""The pure state machine (paper 004 Fig. 1), stepped frame by frame."""

from __future__ import annotations

import pytest

from surveil.datatypes import Phase
from surveil.tracking import Evidence, LifecycleConfig, next_phase

CFG = LifecycleConfig(lost_frames=3, combined_lost_frames=5, retire_s=2.0, retire_unlabelled_s=0.5)


def walk(phase: Phase, evidence: list[Evidence]) -> list[str]:
    out = []
    for ev in evidence:
        phase = next_phase(phase, ev, CFG)
        out.append(phase.value)
    return out


def test_uninitialised_waits_for_confirmation():
    assert walk(Phase.UNINITIALISED, [Evidence(), Evidence(confirmed=True), Evidence()]) == [
        "uninitialised",
        "unlabelled",
        "unlabelled",
    ]


def test_labelled_tracker_becomes_normal_then_lost_then_reacquired():
    seq = [Evidence(labelled=True)] + [Evidence(misses=m) for m in (1, 2, 3)]
    seq += [
        Evidence(lost_for_s=0.3),
        Evidence(lost_for_s=0.4, reacquired=True, ever_labelled=True),
    ]
    seq += [Evidence(labelled=True)]
    assert walk(Phase.UNLABELLED, seq) == [
        "normal",
        "normal",
        "normal",
        "lost",
        "lost",
        "unlabelled",
        "normal",
    ]


def test_combine_and_separate():
    seq = [Evidence(partner_id=4), Evidence(misses=3), Evidence(separated=True)]
    # a combined pair coasts through short gaps (combined_lost_frames > lost_frames)
    assert walk(Phase.NORMAL, seq) == ["combined", "combined", "unlabelled"]


def test_combined_pair_is_lost_after_a_long_gap():
    assert next_phase(Phase.COMBINED, Evidence(misses=5), CFG) is Phase.LOST


def test_drift_is_lost_not_combined():
    assert next_phase(Phase.NORMAL, Evidence(partner_id=2, drifted=True), CFG) is Phase.LOST


@pytest.mark.parametrize("phase", [Phase.NORMAL, Phase.UNLABELLED])
def test_a_tracker_paired_as_it_runs_out_of_support_combines(phase):
    """The manager pairs a tracker that lost its support only when it met the other (its
    candidate merged into the other's): it combines rather than being lost; unpaired, the
    same misses lose it."""
    misses = CFG.lost_frames
    assert next_phase(phase, Evidence(misses=misses, partner_id=2), CFG) is Phase.COMBINED
    assert next_phase(phase, Evidence(misses=misses), CFG) is Phase.LOST


@pytest.mark.parametrize(
    ("ever_labelled", "lost_for_s", "expected"),
    [
        (False, 0.4, Phase.UNLABELLED),
        (False, 0.5, Phase.UNINITIALISED),
        (True, 1.9, Phase.UNLABELLED),
        (True, 2.0, Phase.UNINITIALISED),
    ],
)
def test_retirement_beats_reacquisition_and_depends_on_labelling(
    ever_labelled, lost_for_s, expected
):
    ev = Evidence(lost_for_s=lost_for_s, ever_labelled=ever_labelled, reacquired=True)
    assert next_phase(Phase.LOST, ev, CFG) is expected


def test_misses_beat_labelling():
    assert next_phase(Phase.UNLABELLED, Evidence(misses=3, labelled=True), CFG) is Phase.LOST
