"""Settings of the close-view arm trackers (papers 001 and 004; docs/armpose.md).

Paper 001 quantises the body's facing into 50 levels and starts with about 2000 particles
per arm and level, shrinking as the filter converges; here the levels are coarser and the
particle sets small and fixed, because every arm is also pulled towards the 3D tracker's
hand when that hand is tracked (``hand_sigma_m``), so the filters rarely search from
scratch. Defaults were chosen with ``benchmarks/arm_bench.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

from surveil.config import setting


@dataclass(frozen=True, slots=True)
class ArmPoseConfig:
    """The facing HMM, the arm particle filters and their likelihood."""

    enabled: bool = setting(False, "run the arm trackers (elbow and hand from the arm model)")
    n_facing: int = setting(
        24, "quantisation levels of the body's facing phi (HMM states; paper: 50)", min=4
    )
    facing_step_deg: float = setting(
        10.0, "std of the facing's change per frame set (HMM transition), deg", min=0.1
    )
    particles: int = setting(
        32, "particles per arm and facing level (paper: ~2000 shrinking)", min=4
    )
    shoulder_step_deg: float = setting(
        9.0, "std of the flexion and abduction random walk per frame set, deg", min=0.0
    )
    twist_step_deg: float = setting(
        12.0, "std of the upper arm's twist per frame set, deg", min=0.0
    )
    elbow_step_deg: float = setting(12.0, "std of the elbow's flexion per frame set, deg", min=0.0)
    jump_share: float = setting(
        0.02,
        "share of particles the motion prior draws anywhere within the joint limits",
        min=1e-6,
        max=0.5,
    )
    ik_share: float = setting(
        0.25,
        "share of particles drawn by inverse kinematics towards hand hypotheses",
        min=0.0,
        max=0.9,
    )
    ik_target_sd_m: float = setting(
        0.03, "std of the 3D noise added to an inverse-kinematics target, m", min=0.0
    )
    swivel_sd_deg: float = setting(
        30.0, "std of the elbow's swivel about the shoulder-hand axis in those draws, deg", min=0.0
    )
    midline_sigma_m: float = setting(
        0.15, "std of the pose prior against a hand reaching past the body's midline, m", min=0.01
    )
    # --- likelihood (paper 001 eq. 9-11, 13-14) ---
    alpha_px2: float = setting(
        0.01, "alpha of p1 = 1 / (1 + alpha d^2), d = hand to nearest hand blob, px^-2", min=0.0
    )
    p1_floor: float = setting(
        0.05, "p1 never falls below this (a hand hidden in a view still has an arm)", min=0.0
    )
    arm_samples: int = setting(
        6, "points along each arm (upper arm and forearm) tested against the foreground", min=1
    )
    inside_tol_px: float = setting(
        1.5, "an arm point within this distance of a silhouette counts as inside, px", min=0.0
    )
    p2_floor: float = setting(
        0.05, "p2 (share of arm points inside) never falls below this", min=0.0
    )
    shoulder_sigma_px: float = setting(
        6.0, "std of the shoulder term in the distance outside the silhouette, px", min=0.1
    )
    head_blob_m: float = setting(
        0.12, "blobs within this distance of a tracked head's projection are its, m", min=0.0
    )
    hand_sigma_m: float = setting(
        0.08, "std of the pull to the 3D tracker's hand (0 = off: paper 001 alone), m", min=0.0
    )
    max_distance_m: float = setting(
        8.0, "a camera farther than this from the head does not take part, m", min=0.0
    )
    retire_after_s: float = setting(
        1.0, "a person's arm trackers end when the head has been gone this long, s", min=0.0
    )
    # --- feeding the 3D tracker (not in the papers; docs/armpose.md) ---
    feed_candidates: bool = setting(
        False,
        "add the arm model's hands as 3D candidates where no two views give one (needs enabled)",
    )
    feed_prior: float = setting(
        0.4, "prior p(Z) of an arm model's hand candidate", min=0.0, max=1.0
    )
    feed_radius_m: float = setting(
        0.15,
        "an arm model's hand within this of a two-view candidate adds nothing (that "
        "candidate is the better estimate), m",
        min=0.0,
    )
    feed_min_views: int = setting(
        1,
        "an arm model's hand is added only when it lies on a blob that no candidate "
        "explains in at least this many views",
        min=1,
    )

    def __post_init__(self) -> None:
        if self.feed_candidates and not self.enabled:
            raise ValueError("feed_candidates needs the arm trackers: set enabled = true too")
