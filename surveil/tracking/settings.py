"""Settings of the multi-target 3-D tracking stage (paper 004 sections 4, 5, 5.2, 7.1).

Three groups, nested in :class:`TrackingConfig` (TOML table ``[tracking]`` with sub-tables
``filter``, ``lifecycle`` and ``labelling``):

- :class:`FilterConfig` -- the per-target SIR filters: particle count, motion noise, the width
  of the candidate likelihood (eq. 17);
- :class:`LifecycleConfig` -- the finite state machine of Fig. 1: initialisation, combining,
  separating, losing and retiring trackers;
- :class:`LabellingConfig` -- head / hand typing, person grouping, left / right.

Defaults were chosen for 15 fps input and people standing or walking in a room, and checked
with ``benchmarks/tracking_bench.py`` on the synthetic recordings (docs/benchmarks.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from surveil.config import setting
from surveil.tracking.head_centre import CROWN_TO_CENTRE_M


@dataclass(frozen=True, slots=True)
class FilterConfig:
    """One SIR filter per target: constant-velocity prediction, eq. 17 likelihood."""

    n_particles: int = setting(200, "particles per target", min=10, max=100_000)
    accel_std_hand_mps2: float = setting(
        8.0, "acceleration noise of hands and untyped targets (fast, abrupt), m/s^2", min=0.0
    )
    reset_fraction: float = setting(
        0.2,
        "share of hand particles predicted with a fresh velocity instead (hands stop, start "
        "and turn abruptly: a two-component mixture prior, docs/tracking.md)",
        min=0.0,
        max=1.0,
    )
    reset_speed_std_mps: float = setting(
        0.8, "std of each component of that fresh velocity, m/s", min=0.0
    )
    accel_std_head_mps2: float = setting(
        2.0, "acceleration noise of heads (slow, smooth), m/s^2", min=0.0
    )
    position_jitter_m: float = setting(
        0.005, "extra random-walk position noise per step (keeps diversity), m", min=0.0
    )
    max_speed_mps: float = setting(
        4.0, "particle speeds are clipped to this (hands move up to ~3 m/s), m/s", min=0.1
    )
    max_dt_s: float = setting(
        0.5, "a longer gap between frame sets is predicted as this long, s", min=0.001
    )
    sigma_m: float = setting(
        0.03, "sigma of N(x; Z_c, sigma^2) in the likelihood (eq. 17), m", min=1e-4
    )
    exclusion: bool = setting(
        True,
        "share each candidate among the targets that claim it (by their predicted clouds) "
        "instead of letting it support every target fully: a target cannot feed on a "
        "candidate another target explains better (not in the paper; docs/tracking.md)",
    )
    lost_claim_s: float = setting(
        0.0,
        "a labelled target lost at most this long still claims its share of the candidates "
        "near where it is looked for (exclusion): a neighbour's tracker cannot slide onto "
        "its candidate when it shows again, s (0 = only active targets claim)",
        min=0.0,
    )
    lost_claim_std_m: float = setting(
        0.05,
        "... the spread of such a lost target's claim around that position, m",
        min=1e-3,
    )
    heads_only_for_heads: bool = setting(
        True,
        "a candidate marked head_only (a crown head, docs/candidates.md 'Crowns') supports "
        "no tracker typed as a hand, starts no hand's re-acquisition and parts no pair of "
        "hands (docs/tracking.md, 'Typed candidates')",
    )
    clutter_level: float = setting(
        1e-3,
        "constant added to the unnormalised likelihood (no candidate = flat weights), unitless",
        min=0.0,
    )
    init_spread_m: float = setting(
        0.02, "std of the particle cloud drawn around a new or re-acquired target, m", min=0.0
    )
    init_speed_std_mps: float = setting(
        0.3, "std of the initial particle velocities, m/s", min=0.0
    )


@dataclass(frozen=True, slots=True)
class LifecycleConfig:
    """The tracker state machine (paper 004 section 5.2, Fig. 1)."""

    init_prior_min: float = setting(
        0.3,
        "only candidates with a prior p(Z) at least this start or re-acquire a tracker",
        min=0.0,
        max=1.0,
    )
    init_confirm_frames: int = setting(
        3,
        "consecutive frame sets an unexplained candidate must persist to start or re-acquire "
        "a tracker",
        min=1,
    )
    init_gate_m: float = setting(
        0.12, "a candidate continues a pending one of the previous set within this, m", min=0.0
    )
    explained_radius_m: float = setting(
        0.15, "a candidate this close to a live tracker's estimate is explained by it, m", min=0.0
    )
    max_trackers: int = setting(24, "no new tracker starts while this many are live", min=1)
    rescue_max_frames: int = setting(
        2,
        "a combined pair whose nearest candidate was kept only because it was expected there "
        "(recon.rescue_expected) for this many consecutive frame sets is no longer expected "
        "by the candidate stage until a candidate of its own supports it again: a pair left "
        "on a ghost where two hands' lines of sight cross would otherwise rescue that ghost "
        "in every frame set. Approaching hands, whose blobs merge, are always expected "
        "(0 = no limit)",
        min=0,
    )
    lone_rescue_frames: int = setting(
        1,
        "a labelled hand in the normal state is spared a candidate by explaining away "
        "(recon.rescue_expected) with no other hand beside it, for this many frame sets "
        "after its nearest candidate was last one of its own: a ghost that claimed its blob "
        "would otherwise take its candidate for a frame; a tracker left on a ghost, which "
        "only rescuing keeps, gets none. 2 cost held-out events (docs/candidates.md; "
        "0 = off)",
        min=0,
    )
    combine_distance_m: float = setting(
        0.10, "two trackers whose estimates come closer than this combine, m", min=0.0
    )
    hand_merge_distance_m: float = setting(
        0.3,
        "two hands of people (labelled or waiting for their side) also combine when one of "
        "them has lost its support this close to the other: their blobs merged, or the "
        "hand going behind the other was hidden and its tracker lagged (0.23-0.27 m behind "
        "on handshake and exchange; docs/tracking.md), m",
        min=0.0,
    )
    separate_distance_m: float = setting(
        0.20,
        "a combined pair separates when its two modes (candidates) are farther apart than this, m",
        min=0.0,
    )
    separate_gate_m: float = setting(
        0.45,
        "a combined pair's modes are candidates within this of its estimate (hands parting "
        "at 2 m/s are ~25 cm from it after two frame sets), m",
        min=0.0,
    )
    separate_min_prior: float = setting(
        0.2, "a candidate with a prior p(Z) below this is not a mode of a combined pair", min=0.0
    )
    mode_gate_m: float = setting(
        0.15,
        "a combined pair's modes count as the same two targets in consecutive frame sets "
        "when each moved at most this; otherwise the count of frames apart restarts (a "
        "stray candidate near joined hands must not part them), m",
        min=0.0,
    )
    own_pair_third_hand_s: float = setting(
        0.5,
        "a combined pair of one person's two hands separates onto an unlabelled hand tracker "
        "of that person, tracked since before the pair joined and out of every other "
        "person's reach, that has been this long at least separate_distance_m from the pair "
        "and about as well supported (within labelling.contest_margin): the person has a "
        "third hand, so the pair was a hand and a ghost (0 = never), s",
        min=0.0,
    )
    home_hand_s: float = setting(
        0.05,
        "a combined pair of two people's hands separates onto an unlabelled hand tracker, "
        "started after the join, that is clearly one owner's while that owner's other hand is "
        "tracked elsewhere, out of the other owner's reach and about as well supported, for "
        "this long: that owner's hand went home from the pair (0 = never), s",
        min=0.0,
    )
    pair_seed_gate_m: float = setting(
        0.6,
        "a new candidate that appeared this close to a combined pair (and is at least "
        "separate_distance_m from it) is one of its targets leaving: the pair separates onto "
        "it instead of a new tracker starting there, m",
        min=0.0,
    )
    seed_within_reach: bool = setting(
        True,
        "a pair of unattached hands, or of one person's, within arm_reach_m of a tracked head "
        "does not part on a seed beyond every tracked head's reach (arm_reach_m + "
        "person_margin_m): no hand of a tracked person is there (handshake take 102, seed 1: "
        "a ghost 15 cm above the floor, 1.3 m from the head)",
    )
    held_views: int = setting(
        3,
        "a combined pair with a candidate within explained_radius_m of its estimate that "
        "this many cameras or more support is held there: its two targets did not both "
        "leave it at once (two views alone may be a ghost where two departing hands' lines "
        "of sight cross), so it parts on one seed at most (0 = no test)",
        min=0,
    )
    out_of_reach_frames: int = setting(
        3,
        "a combined pair of two people's hands whose estimate has been farther than "
        "arm_reach_m + person_margin_m from one owner's head for this many consecutive frame "
        "sets separates without a second mode: it followed the other hand home while the "
        "first went unseen; that hand is restarted where the pair joined (0 = off)",
        min=0,
    )
    leave_speed_mps: float = setting(
        3.0,
        "the fastest a target leaves a combined pair: a seed where an unexplained candidate "
        "already was sooner before or after the pair joined than a hand this fast could get "
        "there is not one of the pair's targets, m/s",
        min=0.1,
    )
    separate_frames: int = setting(
        2, "consecutive frame sets the modes must stay apart before separating", min=1
    )
    separate_gain_m: float = setting(
        0.08,
        "a combined pair separates only once its modes moved this much farther apart since "
        "they first appeared (parting targets do; a stray candidate beside joined hands does "
        "not move away from them), m",
        min=0.0,
    )
    separate_far_m: float = setting(
        0.3,
        "a combined pair whose two modes have stayed at least this far apart for "
        "separate_far_frames frame sets, without closing in by separate_gain_m, separates "
        "although they did not move apart: a hand that left the pair unseen comes back "
        "already apart (0 = off), m",
        min=0.0,
    )
    separate_far_frames: int = setting(
        4,
        "consecutive frame sets the modes must stay separate_far_m apart (a stray candidate "
        "beside joined hands flickers; a hand back at rest stays)",
        min=1,
    )
    unjoin_gate_m: float = setting(
        0.15,
        "a pair that combined while its trackers were combine_distance_m or more apart (one "
        "had lost its candidate) and whose two modes, from at most unjoin_within_s after the "
        "join, stay (separate_frames, gaining less than separate_gain_m) this close to where "
        "its two trackers were then, never met: it separates, each tracker where it was, and "
        "no coincidence is reported (0 = off), m",
        min=0.0,
    )
    rejoin_never_met_s: float = setting(
        1.0,
        "two trackers whose pair parted as never met and that combine again within this long "
        "count as joined apart, with where they parted as their places for the never-met "
        "test (hands held near each other, whose trackers drift together again; 0 = off), s",
        min=0.0,
    )
    unjoin_within_s: float = setting(
        0.5,
        "how soon after a join the modes that say its targets never met must appear (the "
        "weaker hand's candidate may flicker for a few frame sets first), s",
        min=0.0,
    )
    slid_hand_gate_m: float = setting(
        0.5,
        "a labelled hand's tracker within this of a confirmed seed that lies farther out from "
        "its head (by slid_hand_gain_m) where, relative to that head, the tracker itself stood "
        "within slid_hand_within_s (slid_hand_stood_m), slid up its arm or onto its shirt: it "
        "is drawn again around the seed instead of a new tracker starting there (0 = off), m",
        min=0.0,
    )
    slid_hand_gain_m: float = setting(
        0.05, "see slid_hand_gate_m: how much farther from the head the seed must be, m", min=0.0
    )
    slid_hand_within_s: float = setting(
        1.5,
        "see slid_hand_gate_m: how recently the tracker stood there (at most its estimate "
        "history, 30 frame sets: 2 s at 15 fps), s",
        min=0.0,
    )
    slid_hand_stood_m: float = setting(
        0.12,
        "see slid_hand_gate_m: how close, relative to the head, the tracker stood to the seed, m",
        min=0.0,
    )
    lost_level: float = setting(
        0.05,
        "a tracker whose best particle's support max_i sum_c exp(-d_ic^2/2s^2) p(Z_c) stays "
        "below this is unsupported, unitless",
        min=0.0,
    )
    drift_window_frames: int = setting(
        2,
        "a tracker unsupported in any of its last this many frame sets that comes within "
        "combine_distance_m of another has drifted onto it: lost, not combined",
        min=0,
    )
    lost_frames: int = setting(
        3, "consecutive unsupported frame sets before a tracker is lost", min=1
    )
    combined_lost_frames: int = setting(
        8,
        "consecutive unsupported frame sets before a combined pair is lost (joined hands are "
        "often hidden for a few frames; the pooled cloud coasts through)",
        min=1,
    )
    reacquire_gate_m: float = setting(
        0.25,
        "a lost target is re-acquired by a candidate within this of its last position, m",
        min=0.0,
    )
    reacquire_near_m: float = setting(
        0.0,
        "a lost target is re-acquired at once (no init_confirm_frames wait) by a candidate "
        "within this of its last position: the last position is the prior that makes one "
        "observation enough (a still hand whose candidate flickers); 0 = off, m",
        min=0.0,
    )
    reacquire_prior_min: float = setting(
        0.3,
        "a lost target may also be re-acquired by a candidate with a prior p(Z) this weak "
        "(below init_prior_min), persisting init_confirm_frames within its gate: its last "
        "position is the prior that makes a weak observation enough (section 5.2); the "
        "default, init_prior_min, is off, unitless",
        min=0.0,
        max=1.0,
    )
    reacquire_speed_mps: float = setting(
        0.5, "the re-acquisition gate grows by this per second lost, m/s", min=0.0
    )
    reacquire_hand_speed_mps: float = setting(
        2.0,
        "... but a person's hand's gate grows by this per second since it was last supported: "
        "a hand swung at 2-3 m/s outruns its tracker and is lost 0.2-0.4 s later, 0.4-1.0 m "
        "from where it was last supported, m/s",
        min=0.0,
    )
    reacquire_max_m: float = setting(1.0, "the re-acquisition gate never exceeds this, m", min=0.0)
    reacquire_unsupported: bool = setting(
        True,
        "a person's labelled hand whose tracker was unsupported in one of its last "
        "drift_window_frames frame sets is re-acquired like a lost one (matched together with "
        "the lost trackers, from where it was last supported before that miss), by a "
        "confirmed seed within its head's arm_reach_m: the hand shows again where its "
        "tracker is not, and before it is lost a new tracker would start on it (an identity "
        "switch) or a lost tracker take it",
    )
    reacquire_supported: bool = setting(
        True,
        "reacquire_unsupported also restarts a tracker that is supported again in this frame "
        "set (slid onto something beside the hand); false: only one that no candidate "
        "supports now (a hand swung up past the face drew its tracker onto a ghost 0.4 m "
        "away while its tracker followed it 20 cm behind)",
    )
    reacquire_bridge: bool = setting(
        False,
        "a lost target is also re-acquired by a seed whose run of init_confirm_frames frame "
        "sets skipped single frame sets (a hand reaching past the edge of a table, its "
        "candidate there two frame sets in three); starting a new tracker still needs an "
        "unbroken run",
    )
    reacquire_supported_near_m: float = setting(
        0.10,
        "with reacquire_supported on, a tracker supported in this frame set is not restarted "
        "while a candidate lies within this distance of its estimate: it follows its hand (a "
        "hand swung up past the face, 5-8 cm behind its candidate, was restarted on a ghost "
        "0.4 m away; trackers slid onto something beside the hand sit 17-18 cm from every "
        "candidate); 0 = no such exception, m",
        min=0.0,
    )
    reacquire_with_body: bool = setting(
        True,
        "a lost hand of a person whose head is tracked is re-acquired around its last position "
        "moved (horizontally) as far as the head moved since, and is not retired after "
        "retire_s while the head is tracked: a hand goes where its body goes (a person who "
        "walks off carrying a box hidden from all but one camera)",
    )
    reacquire_own_body: bool = setting(
        True,
        "a lost hand of a person whose head is tracked is not re-acquired by a candidate that "
        "another tracked head claims (nearer to it by labelling.person_margin_m than to the "
        "hand's own head): a hand hidden while two people's hands met must not come back on "
        "the other person's hand",
    )
    reacquire_above_head_m: float = setting(
        0.3,
        "a lost hand is not re-acquired by a candidate this close to a tracked head's "
        "estimate and above it, unless it was lost within reacquire_gate_m of it or moving "
        "towards it (a hand at or rising to the face): a head can show two candidates (face "
        "and crown) and the one just beyond explained_radius_m is a seed, which a hand lost "
        "for a while, its gate grown, would take (held-out pick_place take 102 at 12.2 s: the "
        "hand then stayed combined with its head, and its own tracker unlabelled, to the "
        "end); 0 = off, m",
        min=0.0,
    )
    merge_lost_s: float = setting(
        0.6,
        "a hand of a person lost at most this long is re-acquired onto another person's hand "
        "(or its own person's other hand) that reaches its coasted position: the two hands' "
        "blobs merged as they met, so its candidate vanished; 0 = off, s",
        min=0.0,
    )
    merge_lost_distance_m: float = setting(
        0.2,
        "... when it coasted within this of that hand (growing by reacquire_speed_mps per "
        "second coasted), m",
        min=0.0,
    )
    merge_coast_s: float = setting(
        0.3,
        "a lost hand's position is extrapolated from its last supported one with its velocity "
        "there for at most this long, s",
        min=0.0,
    )
    merge_reach_m: float = setting(
        0.6,
        "... and only onto a hand this close to its last supported position, m",
        min=0.0,
    )
    met_by_other: bool = setting(
        True,
        "a hand that lost its support beside another hand has also met it when the other, "
        "still supported, came towards where it was last seen at merge_closing_mps or faster "
        "over approach_window_s (the hand going behind the other was hidden before it "
        "moved: exchange, seed 0)",
    )
    merge_closing_mps: float = setting(
        0.3,
        "... that it was approaching at least this fast before its miss began (how much "
        "closer the two came over approach_window_s); also required of a hand that combines "
        "with another by hand_merge_distance_m or that comes within combine_distance_m of "
        "another soon after a miss (one that slid onto a still hand has not met it), m/s",
        min=-1e9,
    )
    approach_window_s: float = setting(
        0.3, "... measured over this long before the miss, s", min=0.0
    )
    retire_s: float = setting(
        3.0, "a labelled tracker lost for this long is retired (removed), s", min=0.0
    )
    retire_unlabelled_s: float = setting(
        0.6, "a never-labelled tracker lost for this long is retired, s", min=0.0
    )
    retire_unclaimed_s: float = setting(
        0.0,
        "a tracker never labelled this long after its start is retired: at most a head and two "
        "hands belong to a person, so it tracks a ghost (mismatched blob pair, skin-coloured "
        "clothing) or clutter; 0 = never (the default since the candidate stage explains "
        "ghosts away: retiring then cost more real hands than ghosts), s",
        min=0.0,
    )


@dataclass(frozen=True, slots=True)
class LabellingConfig:
    """Head / hand typing, person grouping, left / right (paper 004 sections 5.2 and 7.1)."""

    head_z_mid_m: float = setting(
        1.3, "height above the floor where the height cue is neutral, m", min=0.0
    )
    head_z_scale_m: float = setting(
        0.1, "height change that moves the height cue by one log-odds unit, m", min=1e-3
    )
    cue_clip: float = setting(3.0, "every cue's log-odds is clipped to +-this", min=0.1)
    below_radius_m: float = setting(
        0.45, "horizontal radius in which another target above means 'I am a hand', m", min=0.0
    )
    below_dz_min_m: float = setting(
        0.2,
        "another target this much higher (and not more than below_dz_max_m) is above, m",
        min=0.0,
    )
    below_dz_max_m: float = setting(1.2, "see below_dz_min_m, m", min=0.0)
    below_llr: float = setting(
        3.0, "log-odds against 'head' when another target is right above", min=0.0
    )
    rel_v_mid: float = setting(
        0.15, "relative silhouette height where the silhouette cue is neutral, unitless"
    )
    rel_v_scale: float = setting(
        0.04, "rel_v change that moves the silhouette cue by one log-odds unit", min=1e-4
    )
    hand_speed_mps: float = setting(
        0.8, "a target faster than this (smoothed) gets speed_llr against 'head', m/s", min=0.0
    )
    speed_llr: float = setting(1.5, "log-odds against 'head' of a fast target", min=0.0)
    evidence_alpha: float = setting(
        0.3, "weight of the newest frame in the smoothed type evidence", min=0.01, max=1.0
    )
    decide_llr: float = setting(
        1.5, "smoothed log-odds needed to type a target as head (>= +) or hand (<= -)", min=0.0
    )
    min_frames: int = setting(3, "frame sets a tracker is observed before it is typed", min=1)
    body_heights: tuple[float, ...] = setting(
        (0.5, 0.75),
        "a new head needs a body: points under it at these fractions of its height (hips and "
        "chest; the knees fall between the legs or on dark trousers)",
    )
    body_tolerance_px: float = setting(
        4.0, "a body point this close to a silhouette counts as inside it, px", min=0.0
    )
    body_fail_frames: int = setting(
        3, "a would-be head that fails the body check this often is never a head", min=1
    )
    body_support_min: float = setting(
        1.0,
        "fraction of the cameras seeing the column under a new head that must show it inside "
        "a silhouette (0 = no check)",
        min=0.0,
        max=1.0,
    )
    arm_reach_m: float = setting(
        0.95, "a hand belongs to a head at most this far away (3-D), m", min=0.0
    )
    person_margin_m: float = setting(
        0.15,
        "the nearest head must be this much closer than the second to claim a hand, m",
        min=0.0,
    )
    owner_margin_m: float = setting(
        0.2,
        "a combined pair of two people's hands parts by their owners (each mode to the hand "
        "whose head is nearer) when that assignment is this much shorter in summed distance "
        "than the other; otherwise by the angle rule (0 = angle rule only), m",
        min=0.0,
    )
    own_hands_by_sides: bool = setting(
        True,
        "a combined pair of one person's left and right hands parts by the person's sides "
        "(the mode farther to the person's left for the left hand, from its facing) where "
        "the facing tells them apart; otherwise, and with false, by the paper's angle rule "
        "(docs/tracking.md, 'combined -> unlabelled')",
    )
    reach_revise_s: float = setting(
        0.5,
        "a hand out of its person's reach (arm_reach_m + person_margin_m) and within another's "
        "for this long loses its label and is attached anew (0 = never), s",
        min=0.0,
    )
    astray_at_join: bool = setting(
        True,
        "a hand about to combine while out of its person's reach and within another's (as "
        "for reach_revise_s) loses its label at once: a join is a decision point, and a hand "
        "cannot meet anything beyond its own body's reach",
    )
    contest_s: float = setting(
        0.5,
        "an unlabelled hand tracker that out-supports one of a person's hands this long takes "
        "its slot (0 = never), s",
        min=0.0,
    )
    contest_margin: float = setting(
        0.2, "... by this much smoothed likelihood level (0-1)", min=0.0
    )
    contest_by_owner: bool = setting(
        True,
        "... or that is clearly its person's (the nearest head by person_margin_m) while one of "
        "the person's hands is nearer another person's head than its own by person_margin_m "
        "(and the challenger is clearly more the person's: see labelling.owned_elsewhere; a "
        "ghost on another body, as strong as a real hand, holding the slot)",
    )
    contest_demotes: bool = setting(
        True,
        "a hand that loses its slot in a contest counts as a stray until it is labelled again: "
        "a person's tracker or a combined pair that meets it does not combine with it",
    )
    contest_side_m: float = setting(
        0.1,
        "a challenger this far to one side of its person's head (along the facing direction's "
        "left axis, once the facing evidence reaches facing_min) cannot take the slot of a "
        "hand this far to the other side (0 = no side check), m",
        min=0.0,
    )
    redecide_sides: bool = setting(
        True,
        "a hand that takes a slot by ownership (contest_by_owner) does not inherit the "
        "holder's side: the person's two hands are sided afresh from the facing direction "
        "(the holder's side was decided where the ghost was)",
    )
    contest_alpha: float = setting(
        0.1, "weight of the newest frame in the smoothed likelihood level", min=0.01, max=1.0
    )
    yield_lost_s: float = setting(
        0.5,
        "a person's hand lost this long gives its slot to an unlabelled hand tracker that "
        "would join the person but for it; the lost tracker is retired (0 = never), s",
        min=0.0,
    )
    duplicate_head_m: float = setting(
        0.3,
        "a head-like target this close (horizontally) to a known head is not a head, m",
        min=0.0,
    )
    facing_decay: float = setting(
        0.97, "per-frame decay of the accumulated facing evidence", min=0.0, max=1.0
    )
    facing_min: float = setting(
        0.5, "facing evidence needed before left / right are decided", min=0.0
    )
    lr_max_wait_s: float = setting(
        1.5, "decide left / right by the best guess after this long anyway, s", min=0.0
    )
    lr_margin_m: float = setting(
        0.04,
        "a lone hand must be this far left or right of the head to be decided early, m",
        min=0.0,
    )
    lr_revise_evidence: float = setting(
        1.0,
        "facing evidence needed to overturn decided left / right labels (0 = never revise)",
        min=0.0,
    )
    lr_revise_margin_m: float = setting(
        0.05,
        "the labelled left hand must be this far right of the right hand to count against, m",
        min=0.0,
    )
    lr_revise_lone_m: float = setting(
        0.15,
        "with one of a person's hands tracked, it must be this far on the other label's "
        "side of the head to count against (0 = only with both hands tracked), m",
        min=0.0,
    )
    lr_revise_s: float = setting(
        1.0, "... for this long before the two hands' sides are swapped, s", min=0.0
    )
    walk_speed_mps: float = setting(
        0.6,
        "head speed above which the walking direction is facing evidence, m/s (the filter's "
        "velocity of a standing head exceeds 0.3 m/s in 1-3 % of frames; docs/tracking.md)",
        min=0.0,
    )
    social_weight: float = setting(
        0.05, "facing evidence per frame towards the nearest other person's head", min=0.0
    )
    social_range_m: float = setting(
        2.5, "another person within this range draws the facing evidence, m", min=0.0
    )
    face_weight: float = setting(
        1.0,
        "facing evidence per frame from where the face is seen: towards the cameras that see "
        "more skin around the head than the others, this times the difference in skin share "
        "(0 = off)",
        min=0.0,
    )
    face_radius_m: float = setting(
        0.1,
        "the skin share is taken over the square of this half-side around the head, m",
        min=0.01,
    )
    axis_weight: float = setting(
        1.0,
        "evidence per frame on the body's front-back axis from how wide the silhouette is "
        "across the shoulders in three or more views; the facing takes the axis's angle and "
        "the facing evidence's sign (0 = off)",
        min=0.0,
    )
    axis_contrast: float = setting(
        0.3,
        "a fitted width contrast (squared widths' swing over their mean) this large gives "
        "the full axis_weight, a smaller one proportionally less",
        min=0.01,
    )
    axis_decay: float = setting(
        0.8, "per-frame decay of the accumulated body-axis evidence", min=0.0, max=1.0
    )
    axis_min: float = setting(
        1.0, "body-axis evidence needed before the facing takes the axis's angle", min=0.0
    )
    axis_max_width_m: float = setting(
        0.8,
        "a silhouette wider than this across the shoulders is two people merged and says "
        "nothing on the axis, m",
        min=0.1,
    )


@dataclass(frozen=True, slots=True)
class TrackingConfig:
    """All settings of the tracking stage (``[tracking]`` with sub-tables)."""

    filter: FilterConfig = setting(
        default_factory=FilterConfig, doc="per-target SIR filters (eq. 9-17)"
    )
    lifecycle: LifecycleConfig = setting(
        default_factory=LifecycleConfig, doc="tracker state machine (Fig. 1)"
    )
    labelling: LabellingConfig = setting(
        default_factory=LabellingConfig, doc="head / hand, person, left / right labels"
    )
    one_view_prior: float = setting(
        0.0,
        "a labelled hand that no candidate explains but a blob at its projection shows gets a "
        "candidate there (the pull's point from its prediction, blob_pull_* settings) with "
        "this prior, so that a hand seen by one camera is not lost (0 = off), unitless",
        min=0.0,
        max=1.0,
    )
    blob_pull_sigma_px: float = setting(
        8.0,
        "a labelled hand's reported point is pulled onto the blobs at its projection, each a "
        "line of sight with this error in pixels (0 = off: the filter's estimate; chosen at "
        "640x480); docs/tracking.md, 'Hands pulled onto their blobs', px",
        min=0.0,
    )
    blob_pull_gate_px: float = setting(
        25.0,
        "a blob pulls a hand when its centroid lies this close to the hand's projection, px",
        min=0.0,
    )
    blob_pull_hand_end_sigma_px: float = setting(
        1.0,
        "... a bare forearm's line goes through its hand end, with this error where two or "
        "more of the hand's views have one: the tracker follows the forearm's centre of "
        "mass, ~15 cm from the hand, and the hand ends must outweigh that estimate (only "
        "with blobs.arm_hand_end = 'report'; docs/tracking.md, 'Hands pulled onto their "
        "blobs'), px",
        min=0.01,
    )
    blob_pull_lone_hand_end_sigma_px: float = setting(
        3.0,
        "... and with this error where only one view has one (a blob taken for a forearm by "
        "mistake, two hands joined, would pull the hand far across that view's line), px",
        min=0.01,
    )
    blob_pull_floor_m: float = setting(
        0.05,
        "added to the spread of the filter's particles (a standard deviation) in the prior of "
        "the pull, m",
        min=0.001,
    )
    head_centre_rise_m: float = setting(
        0.04,
        "a head target's reported position is its skin point raised by this much where the "
        "silhouettes do not tell how much (head_top_to_centre_m): the skin a head shows is "
        "the face (or the neck and ears from behind), below the head's centre under the "
        "hair; docs/tracking.md, 'Head centre', m",
        min=-0.2,
        max=0.2,
    )
    head_top_to_centre_m: float = setting(
        CROWN_TO_CENTRE_M,
        "a head's centre lies this far below the top of its silhouettes (the crown with its "
        "hair: an adult head is about 23 cm from chin to crown); the rise of each head above "
        "its skin point is measured from the silhouettes with it (0 = off: always "
        "head_centre_rise_m), m",
        min=0.0,
        max=0.3,
    )
    head_rise_max_m: float = setting(
        0.2,
        "a view whose silhouette top puts a head's centre below its skin point or more than "
        "this above it says nothing about the head (a raised hand or a taller person on top, "
        "hair camouflaged against the wall), m",
        min=0.0,
        max=0.5,
    )
    head_rise_tau_s: float = setting(
        0.5,
        "time constant of the smoothing of each head's measured rise (it changes as the "
        "person turns: face, cheek, neck), s",
        min=0.0,
    )
