"""Settings of the 3-D candidate stage (paper 004 eq. 19, 25-27; docs/candidates.md).

Defaults tuned with ``benchmarks/candidates_tune.py`` (a grid over the widths and the
threshold on the demo, handshake and exchange scenes; docs/candidates.md, "Tuning").
"""

from __future__ import annotations

from dataclasses import dataclass

from surveil.config import setting


@dataclass(frozen=True, slots=True)
class CrownConfig:
    """Head candidates from the silhouettes' crowns (``[candidates.crowns]``)."""

    enabled: bool = setting(
        True,
        "add a head candidate where at least min_views views' silhouette crowns meet and no "
        "skin candidate lies within skin_clear_m (docs/candidates.md, 'Crowns')",
    )
    crown_height_m: float = setting(
        1.75,
        "a crown's assumed height above the floor, m: a peak's line of sight meets it at the "
        "depth that turns the peak's size from pixels to metres",
        min=0.1,
    )
    min_rise_m: float = setting(
        0.05,
        "a crown rises at least this above the silhouette's top edge on either side (its "
        "prominence: the higher of the lowest points between it and the next higher point of "
        "the edge to the left and to the right), m",
        min=0.0,
    )
    width_depth_m: float = setting(
        0.06, "a crown's width is measured this far below its top, m", min=0.0
    )
    min_width_m: float = setting(0.06, "... and lies between this and max_width_m, m", min=0.0)
    max_width_m: float = setting(
        0.3, "... (a head is about 0.15 m wide; a raised fist narrower; shoulders wider), m"
    )
    top_to_centre_m: float = setting(
        0.125,
        "a head's centre lies this far below its crown (with hair), m; the lines of sight are "
        "moved down by the head's extent across them, this vertically",
        min=0.0,
    )
    half_width_m: float = setting(
        0.09, "... and this horizontally (a line of sight looking straight down), m", min=0.0
    )
    max_gap_m: float = setting(
        0.05,
        "two moved lines of sight make a point when their half gap is at most this, m",
        min=0.0,
    )
    min_z_m: float = setting(1.0, "a head's centre lies at least this high, m", min=0.0)
    max_z_m: float = setting(2.1, "... and at most this high, m", min=0.0)
    outside_px: float = setting(
        3.0,
        "a view sees a point outside the silhouettes when its projection is at least this far "
        "from every silhouette pixel, px",
        min=0.0,
    )
    max_outside_views: int = setting(
        1,
        "a point is dropped when more views than this see it outside the silhouettes (one "
        "view may miss a head camouflaged against the wall behind it)",
        min=0,
    )
    merge_radius_m: float = setting(
        0.1, "points closer than this to the strongest pair's are one head, m", min=0.0
    )
    min_views: int = setting(3, "a head's points must come from at least this many views", min=2)
    skin_clear_m: float = setting(
        0.25,
        "a crown candidate is added only where no skin candidate lies within this, m: a "
        "head's skin candidate (face, neck) lies 4-15 cm from its centre, and the tracker "
        "measures the rise from it (docs/tracking.md, 'Head centre')",
        min=0.0,
    )
    prior: float = setting(
        0.6,
        "the prior p(Z) of a crown candidate, unitless: a fixed value, as the skin pairs' p_o "
        "and p_t do not apply to lines of sight that pass over the head",
        min=0.0,
        max=1.0,
    )

    def __post_init__(self) -> None:
        if self.min_width_m > self.max_width_m:
            raise ValueError(
                f"min_width_m ({self.min_width_m}) must not exceed max_width_m "
                f"({self.max_width_m})"
            )
        if self.min_z_m > self.max_z_m:
            raise ValueError(f"min_z_m ({self.min_z_m}) must not exceed max_z_m ({self.max_z_m})")


@dataclass(frozen=True, slots=True)
class CandidateConfig:
    """Widths, thresholds and merging of the candidate prior p(Z) = p_o * p_t * p_b."""

    sigma_rel_v: float = setting(
        0.1, "p_o width (eq. 25): std of the relative-v difference, unitless", min=1e-6
    )
    rel_v_to_floor: bool = setting(
        True,
        "p_o measures a blob's relative v down to the floor under Z instead of down to its "
        "silhouette's bottom row, which is not the feet where legs are hidden (behind a table, "
        "by another person, in a late camera); not in the paper (docs/candidates.md)",
    )
    tops_from_heads: bool = setting(
        True,
        "p_o takes the top of a silhouette that holds two or more tracked heads from the "
        "crown of the head nearest to Z (the tracker's feedback) instead of the silhouette's "
        "top row, which there is the tallest person's (docs/candidates.md)",
    )
    headless_top_m: float = setting(
        0.5,
        "with tops_from_heads: a silhouette that holds no tracked head but has one's centre "
        "above its top row, within its columns and this near Z horizontally, takes that "
        "head's crown row as its top for p_o (a head the background model lost: dark hair "
        "against a dark door); 0 = off (docs/candidates.md)",
        min=0.0,
    )
    sigma_gap_m: float = setting(
        0.02, "p_t width (eq. 26): std of the half gap d between lines of sight, m", min=1e-6
    )
    sigma_silhouette_px: float = setting(
        6.0, "p_b width (eq. 27): std of the distance outside a silhouette, px", min=1e-6
    )
    silhouette_drop_worst: bool = setting(
        False,
        "p_b leaves out the worst camera's term where >= 3 cameras see Z (one camera with a "
        "failed background model must not veto every candidate); off: it raised false "
        "candidates on the demo from 4.4 to 6.3 per frame set for no recall",
    )
    term_threshold: float = setting(
        0.1, "each of p_o, p_t, p_b must reach this (paper: 0.1)", min=0.0, max=1.0
    )
    prior_threshold: float = setting(
        0.2, "p(Z) = p_o * p_t * p_b must reach this (paper: 0.1)", min=0.0, max=1.0
    )
    merge_radius_m: float = setting(
        0.08, "candidates closer than this merge into the stronger one, m", min=0.0
    )
    merge_boost: float = setting(
        0.5, "fraction of a merged (weaker) prior added to the stronger one", min=0.0, max=1.0
    )
    max_gap_m: float = setting(
        0.1, "candidates with a larger half gap d are dropped outright, m", min=0.0
    )
    min_z_m: float = setting(
        -0.05, "candidates below this height (under the floor) are dropped, m", max=0.0
    )
    min_pair_foreground_share: float = setting(
        0.0,
        "a blob pair is dropped when neither blob has this share of its pixels foreground to "
        "the background model (docs/candidates.md, 'Scenery pairs'): lines of sight through "
        "skin-coloured scenery inside silhouettes. 0 = off; 0.2 cleans the tracks where "
        "furniture is skin-coloured",
        min=0.0,
        max=1.0,
    )
    explain_away: bool = setting(
        True,
        "drop ghosts: a candidate whose blobs are mostly claimed by better-supported ones "
        "(each blob explains one point; docs/candidates.md). Not in the paper: it removed 70 % "
        "of the false candidates on the exchange and demo scenes for 4 points of recall",
    )
    expected_radius_m: float = setting(
        0.2,
        "explaining away spares the strongest candidate within this of a tracked target's "
        "predicted position that has no other (a hand whose blob merged with another limb's "
        "in most views); 0 = off, m",
        min=0.0,
    )
    rescue_pair_m: float = setting(
        0.35,
        "... only for a target with another expected within this (their blobs can merge; a "
        "lone tracker on a ghost would rescue it forever), m",
        min=0.0,
    )
    rescue_alone_radius_m: float = setting(
        0.2,
        "... and for a lone hand the tracker marks (tracking.lifecycle.lone_rescue_frames), "
        "the strongest candidate within this instead of expected_radius_m, m",
        min=0.0,
    )
    expected_prior_threshold: float = setting(
        0.1,
        "the product threshold for a candidate within expected_gate_m of a tracked hand's "
        "predicted position (a hand whose terms each pass but whose product is low: a "
        "merged silhouette's top in one view); prior_threshold or more = off. Not in the "
        "paper (docs/candidates.md)",
        min=0.0,
        max=1.0,
    )
    expected_gate_m: float = setting(0.1, "... within this of the predicted position, m", min=0.0)
    support_radius_px: float = setting(
        8.0,
        "a blob whose centroid is within this of a candidate's projection supports it, px",
        min=0.0,
    )
    refine_min_views: int = setting(
        3,
        "a candidate that this many cameras support (explain_away's support: needs "
        "explain_away on) moves to the least-squares point of those views' lines of sight "
        "instead of its pair's midpoint (0 = never; 2 or more). Not in the paper "
        '(docs/candidates.md, "Refined from all views")',
        min=0,
    )
    refine_outlier_m: float = setting(
        0.03,
        "lines of sight farther than this from the first least-squares point are left out of "
        "a second solve (a supporting blob of another limb), m",
        min=0.0,
    )
    crowns: CrownConfig = setting(
        default_factory=CrownConfig,
        doc="head candidates from the silhouettes' crowns (docs/candidates.md, 'Crowns')",
    )

    def __post_init__(self) -> None:
        if self.refine_min_views == 1:
            raise ValueError(
                "refine_min_views must be 0 (off) or 2 or more: one line of sight has no "
                "least-squares point"
            )
