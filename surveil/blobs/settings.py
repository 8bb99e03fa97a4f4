"""Configuration of the per-camera blob stage (paper 004 sections 6.1-6.2).

Frozen dataclasses built with :func:`surveil.config.setting`, so :func:`surveil.config.
from_table` validates them from TOML. (To be moved into ``surveil/config.py``.)
"""

from __future__ import annotations

from dataclasses import dataclass

from surveil.config import setting


@dataclass(frozen=True)
class BackgroundConfig:
    """Background subtraction and person silhouettes (section 6.1)."""

    history_frames: int = setting(300, "MOG2 history length, frames", min=1)
    var_threshold: float = setting(16.0, "MOG2 squared Mahalanobis threshold", min=0.0)
    learning_frames: int = setting(30, "frame sets of the run's initial learning phase", min=0)
    late_learning_frames: int = setting(
        5,
        "shortest learning phase of a camera that starts after the run's learning phase "
        "(it learns what it sees first, people included)",
        min=1,
    )
    learning_rate_initial: float = setting(
        -1.0, "MOG2 rate during learning (-1 = automatic 1/n)", min=-1.0, max=1.0
    )
    learning_rate: float = setting(
        0.0005,
        "MOG2 rate after learning (with background_ratio 0.7 a still person is absorbed "
        "after about 700 frames; 0.002 absorbed one in 4 s)",
        min=0.0,
        max=1.0,
    )
    background_ratio: float = setting(
        0.7,
        "MOG2 backgroundRatio: weight a colour mode needs to count as background",
        min=0.05,
        max=1.0,
    )
    model_scale: float = setting(
        0.5,
        "frames are shrunk by this factor for MOG2 and the morphology, the mask is scaled "
        "back (0.5: about 3x faster; silhouettes are blobs of tens of pixels anyway)",
        min=0.1,
        max=1.0,
    )
    open_px: int = setting(
        0,
        "elliptical opening kernel diameter, px (0 = none; at model_scale 0.5 even 3 px erased "
        "arms held away from the body, which are 1-2 px wide in the shrunk mask)",
        min=0,
    )
    close_px: int = setting(9, "elliptical closing kernel diameter, px (0 = none)", min=0)
    min_person_area_px: int = setting(400, "smallest silhouette kept, px", min=0)
    protect_people: bool = setting(
        True,
        "after the learning phase, silhouettes that hold a tracked person's head or hand are "
        "not learnt into the background (without it, people who stay in one place fade "
        "from the foreground within a minute)",
    )
    protect_after_s: float = setting(
        20.0,
        "a person's silhouettes are protected once the person has been tracked this long, s "
        "(MOG2 at learning_rate needs about 47 s to absorb a still person; before this, the "
        "model runs as MOG2 does by itself)",
        min=0.0,
    )
    people_update_every: int = setting(
        4,
        "while people are protected the model learns every this many frames, at that many "
        "times learning_rate (each learning step costs one more MOG2 pass)",
        min=1,
    )
    people_margin_px: int = setting(
        6,
        "protected silhouettes are grown by this much before the model learns around them, "
        "px (their outline flickers)",
        min=0,
    )
    shadows_on_floor_only: bool = setting(
        False,
        "a pixel MOG2 calls shadow counts as shadow only where the camera sees the floor "
        "(its line of sight meets z = 0 inside the cameras' footprint grown by "
        "floor_margin_m); elsewhere it is foreground. People cast their shadows on the "
        "floor; dark skin or hair in front of a dark wall or door has the wall's hue and "
        "less brightness, which MOG2 takes for a shadow, and the head drops out of the "
        "silhouette",
    )
    floor_margin_m: float = setting(
        0.5,
        "the floor is the convex hull of the cameras' positions (x, y) grown by this, m "
        "(cameras hang on the walls or in the corners of the room)",
        min=0.0,
    )
    gain_compensation: bool = setting(
        True,
        "before MOG2, each frame's colour channels are scaled so that the pixels the model "
        "last found to be background match its background image: slow illumination drift and "
        "a camera's automatic exposure do not turn the floor into foreground "
        '(docs/blobs.md, "Illumination drift")',
    )
    gain_every_frames: int = setting(
        3,
        "the gain is estimated every this many frames and applied to every frame (light "
        "changes over seconds; an estimate costs about 0.35 ms, a third of MOG2)",
        min=1,
    )
    edges_every_frames: int = setting(
        15,
        "the background image's gradients (for the blob stage's ghost test) are recomputed "
        "every this many frames: the background changes slowly, and reading it from MOG2 costs "
        "about 0.7 ms",
        min=1,
    )


@dataclass(frozen=True)
class SkinConfig:
    """Skin classifier training and its lookup table (section 6.2)."""

    lut_bits: int = setting(6, "bits per BGR channel of the lookup table (5 or 6)", min=5, max=6)
    threshold: float = setting(0.5, "skin probability threshold", min=0.0, max=1.0)
    camera_threshold: float = setting(
        0.1,
        "skin probability threshold of per-camera models: trained on a few frames of one "
        "camera, their skin region is narrow, so a low threshold keeps their recall near the "
        "generic model's (measured on held-out frames: 0.73-0.90 of skin kept at 0.5, 0.93-0.95 "
        "at 0.1, the generic model 0.85-0.98)",
        min=0.0,
        max=1.0,
    )
    bound_by_generic: bool = setting(
        True,
        "a per-camera model only removes colours from the generic model (the per-pixel AND of "
        "the two): colours its few training frames never showed as non-skin, such as an "
        "object first seen later, keep the generic model's answer",
    )
    max_iter: int = setting(200, "boosting iterations of the classifier", min=1)
    max_train_pixels: int = setting(200_000, "training pixels kept (random subset)", min=100)
    balanced: bool = setting(
        True,
        "train on equal skin and non-skin pixel counts (True: skin is later intersected with "
        "silhouettes, so recall matters more than the rare-skin prior); False: restore the "
        "true skin prior with sample weights",
    )
    background_fraction: float = setting(
        0.05,
        "fraction of the background (non-person) pixels of training frames used as negatives; "
        "person pixels (clothing, hair, objects) are all used",
        min=0.0,
        max=1.0,
    )


@dataclass(frozen=True)
class BlobConfig:
    """Skin blobs inside silhouettes (section 6.2)."""

    min_blob_area_px: int = setting(16, "smallest blob kept, px", min=0)
    max_blob_area_rel: float = setting(
        0.03,
        "drop blobs larger than this times the square of the tallest silhouette's height in "
        "the frame (a head is ~0.01): skin-coloured clothing, not a head or hand (0 = keep all)",
        min=0.0,
    )
    split_min_delta: float = setting(
        0.04,
        "a too-big blob is split into its two chromaticity clusters (2-means on (r, g)) when "
        "their centres are at least this far apart: a face or hand joined to a pale shirt "
        "(0 = drop too-big blobs whole)",
        min=0.0,
    )
    blob_excess: float = setting(1.5, "lambda: keep ceil(lambda * 3 * N_h) largest", min=1.0)
    people_from_crowns: bool = setting(
        False,
        "N_h also counts the people the silhouettes' crowns show: the median over the frame "
        "set's views of each view's crowns ([candidates.crowns] finds them), which people "
        "standing close keep where their silhouettes merge (false = each view's silhouettes "
        "and a run's tracked heads only; off: it costs three_people events in a run; "
        "docs/blobs.md, 'How many people')",
    )
    silhouette_dilate_px: int = setting(3, "grow silhouettes by this radius, px", min=0)
    change_dilate_px: int = setting(
        -1,
        "blob pixels must also lie within this radius (px) of a pixel the background model "
        "found changed (foreground or shadow, before the clean-up): drops skin-coloured floor "
        "and wall that the closing and the dilation add to silhouettes (-1 = no such test)",
        min=-1,
    )
    min_foreground_share: float = setting(
        0.0,
        "a blob is dropped when less than this share of its pixels are foreground to the "
        "background model (shadows not counted, before the clean-up): skin-coloured scenery "
        "that the closing took into a silhouette, such as a wooden table's edge beside a hand "
        "(0 = no such test)",
        min=0.0,
        max=1.0,
    )
    min_changed_share: float = setting(
        0.0,
        "a blob is dropped when less than this share of its pixels changed to the background "
        "model (foreground or shadow, before the clean-up): skin-coloured furniture and floor "
        "that the closing took into a silhouette. Unlike min_foreground_share, a dark hand "
        "that MOG2 calls a shadow of the wall behind it counts as changed (0 = no such test)",
        min=0.0,
        max=1.0,
    )
    scenery_share: float = setting(
        0.5,
        "a blob is dropped when at least this share of its pixels are unchanged to the "
        "background model (neither foreground nor shadow, before the clean-up) and skin-coloured "
        "in its background image: skin-coloured scenery, such as a wooden table, that the "
        "closing took into a silhouette (0 = no such test)",
        min=0.0,
        max=1.0,
    )
    scenery_min_rel_v: float = setting(
        0.1,
        "... except blobs whose centroid lies above this fraction of their silhouette's height "
        "from its top, where the head is (a dark head in front of a skin-coloured board reads "
        "as unchanged scenery)",
        min=0.0,
        max=1.0,
    )
    ghost_edge_ratio: float = setting(
        0.45,
        "a blob is revealed background (a ghost: skin-coloured furniture under an object just "
        "taken away) when the image gradient along its silhouette outline is below this "
        "fraction of the background image's gradient there: the outline is an edge of the "
        "background, not of anything in front of it (0 = no such test)",
        min=0.0,
    )
    open_px: int = setting(
        3,
        "opening of the skin-inside-silhouette mask, elliptical kernel diameter in px of a "
        "640-pixel-wide frame; its radius scales with the width (none at 320 px) (0 = none): "
        "cuts the one- or two-pixel rims of colour fringes along silhouette edges that join "
        "heads and hands into one blob",
        min=0,
    )
    open_keeps_isolated: bool = setting(
        True,
        "a skin region that the opening would shrink below min_blob_area_px (a hand seen "
        "edge-on, two or three pixels wide) is kept whole where its silhouette has fewer than "
        "three blobs (a head and two hands) and its centroid lies in the band of a hanging "
        "hand (restore_min_rel_v..restore_max_rel_v); two such blobs never pair into a "
        "candidate",
    )
    restore_min_rel_v: float = setting(
        0.4,
        "a region open_keeps_isolated keeps becomes a blob only if its centroid's relative "
        "height in its silhouette (0 top, 1 bottom) is at least this",
        min=0.0,
        max=1.0,
    )
    restore_max_rel_v: float = setting(0.7, "... and at most this", min=0.0, max=1.0)

    arm_length_rel: float = setting(
        0.17,
        "a blob longer than this times its silhouette's height is a bare forearm with its hand "
        "(short sleeves: ~0.25 of a person's height, a hand alone ~0.11), whose hand end is "
        "found (arm_hand_end says what it is for; 0 = none: every blob is its centre of "
        "mass; docs/blobs.md, 'Bare forearms')",
        min=0.0,
    )
    arm_max_length_rel: float = setting(
        0.33,
        "... and shorter than this times its silhouette's height (a whole bare arm is ~0.33 "
        "of a person's height; longer blobs are colour fringes along the silhouette's edge "
        "or several limbs joined, whose ends are not hands)",
        min=0.0,
    )
    arm_min_width_rel: float = setting(
        0.035,
        "... and at least this wide times its silhouette's height, and at least as many "
        "pixels as a bar of arm_length_rel by this (a wrist is ~0.035 of a person's height; "
        "skin-coloured fringes along a table's edge inside a silhouette are thinner and "
        "sparser)",
        min=0.0,
    )
    arm_zone: bool = setting(
        True,
        "... and only a blob that ends above 0.8 of its silhouette's height from the top (a "
        "shin in skin-coloured trousers is as long and thin) and, if it reaches into the top "
        "0.1, lies beside the head (a face or an ear with its neck, seen from the side or "
        "behind, is too); false = anywhere in the silhouette, as before session 89",
    )
    arm_hand_end: str = setting(
        "report",
        "where a bare forearm's hand end goes (with arm_length_rel > 0): 'report' (the "
        "default) = the blob keeps its centre of mass and the hand end only pulls the "
        "tracker's reported hand points (BlobSet.hand_px, tracking.blob_pull_*); 'point' = "
        "it is the blob's point (centroids_px, rel_v: candidates and the tracker see it, "
        "the option before session 101); docs/blobs.md, 'Bare forearms'",
        choices=("point", "report"),
    )
    hand_length_rel: float = setting(
        0.11,
        "... the hand end: the centre of mass of the blob's last this much (times the "
        "silhouette's height) along its length, at the end farther from the silhouette's "
        "shoulder point (a hand is ~0.11 of a person's height)",
        min=0.0,
    )

    def __post_init__(self) -> None:
        if self.restore_min_rel_v > self.restore_max_rel_v:
            raise ValueError(
                f"restore_min_rel_v ({self.restore_min_rel_v}) must not exceed "
                f"restore_max_rel_v ({self.restore_max_rel_v}): the band would keep nothing"
            )

    def background_requests(self, foreground_share: bool = False) -> dict[str, bool]:
        """What this stage needs from ``BackgroundModel.step`` besides the silhouettes
        (``foreground_share``: a later stage reads ``BlobSet.foreground_share``)."""
        return {
            "changed": self.change_dilate_px >= 0
            or self.min_changed_share > 0
            or self.scenery_share > 0,
            "foreground": foreground_share or self.min_foreground_share > 0,
            "background_edges": self.ghost_edge_ratio > 0,
        }
