"""Settings of the carried-object stage (paper 004 sections 7.2-7.3; docs/carry.md).

Defaults are tuned on the synthetic recordings with ``benchmarks/carry_bench.py`` (people
3.5-4.5 m from 640x480 cameras, hands about 8 px across); the paper gives only n = 10 pixels
and delta = 3 degrees.
"""

from __future__ import annotations

from dataclasses import dataclass

from surveil.config import setting


@dataclass(frozen=True, slots=True)
class CarryConfig:
    """Hand regions, hue histograms, modes, reliability, fusion and the carry decision."""

    # --- hand region (section 7.2.1) and its radius adaptation (section 7.3) ---
    min_radius_m: float = setting(
        0.07, "smallest circle radius around a hand (projected with its depth), m", min=0.0
    )
    max_radius_m: float = setting(
        0.16, "largest circle radius the adaptive growth may reach, m", min=0.0
    )
    n_radius_steps: int = setting(
        5, "radii tried between the smallest and the largest circle", min=1, max=32
    )
    min_radius_px: float = setting(3.0, "floor of any projected radius, px", min=1.0)
    max_radius_px: float = setting(60.0, "ceiling of any projected radius, px", min=1.0)
    grow_stop_bg: float = setting(
        0.5,
        "stop growing at the first radius whose rim is this background fraction",
        min=0.0,
        max=1.0,
    )
    inside_bg: float = setting(
        0.2,
        "if no rim reaches this background fraction, use the smallest circle",
        min=0.0,
        max=1.0,
    )
    n_rim_samples: int = setting(64, "points sampled on the bounding circle (eq. 28)", min=8)
    blob_search_m: float = setting(
        0.08, "a hand's skin blob may lie this far from its projection (projected), m", min=0.0
    )
    # --- hue histogram and modes (section 7.2.2) ---
    hue_bins: int = setting(180, "bins of the hue histogram over [0, 360) (180 = 2 deg)", min=8)
    kde_sigma_deg: float = setting(
        5.0, "std of the circular Gaussian kernel smoothing the histogram, deg", min=0.0
    )
    min_saturation: float = setting(
        0.3, "pixels with a lower HSV saturation have no reliable hue (ignored)", min=0.0, max=1.0
    )
    min_value: float = setting(
        0.12, "pixels with a lower HSV value (too dark) have no reliable hue", min=0.0, max=1.0
    )
    mode_halfwidth_deg: float = setting(
        6.0, "delta: a mode's pixels have hue within +-delta of it (paper: ~3), deg", min=0.0
    )
    mode_min_pixels: int = setting(
        10, "n: a mode needs a connected region of this many pixels (paper: 10)", min=1
    )
    max_mode_extent: float = setting(
        2.5,
        "drop a mode whose patches extend to > this x their area in the circle (0 = off)",
        min=0.0,
    )
    mode_min_peak: float = setting(
        0.002, "smoothed-histogram maxima below this density (per bin) are not modes", min=0.0
    )
    # --- reliability (eq. 28) and fusion (eq. 29) ---
    rho_min: float = setting(0.1, "rho_min of eq. 28: reliability floor", min=0.0)
    window_s: float = setting(1.0, "length of the fusion window before now, s", min=0.0)
    max_window_samples: int = setting(
        128, "ring-buffer capacity per hand (camera-frame samples in the window)", min=1
    )
    pause_hidden: bool = setting(
        True,
        "a lost hand's window does not age while it is lost: re-acquired, it still holds what "
        "it held before, however long it was hidden (off: the window is the last window_s of "
        "the clock, so a hand hidden longer comes back with none)",
    )
    overlap_distance_m: float = setting(
        0.25, "two hands closer than this (3D) overlap: their windows freeze, m", min=0.0
    )
    separation_margin_m: float = setting(
        0.03, "hysteresis: they separate again beyond overlap_distance_m + this, m", min=0.0
    )
    subtract_clothing: bool = setting(
        True, "subtract the same person's other hand's distribution (dress colour)"
    )
    subtract_dress: bool = setting(
        True,
        "subtract the person's dress: the hues around their chest and hips, below the head "
        "(the other hand rarely sees the same clothing: it hangs by the trousers while the "
        "hand that gave an object away comes back to the shirt)",
    )
    dress_drops_m: tuple[float, ...] = setting(
        (0.39, 0.79), "dress regions are centred this far below the head centre (chest, hips), m"
    )
    dress_radius_m: float = setting(0.12, "radius of each dress region, m", min=0.01)
    dress_time_s: float = setting(
        2.0, "time constant of the dress distribution's running average, s", min=0.0
    )
    dress_interval_s: float = setting(
        0.3,
        "a person's dress is measured at most this often (it changes slowly; measuring every "
        "frame set cost ~3 ms per set), s",
        min=0.0,
    )
    dress_min_pixels: int = setting(
        30, "a dress region needs this many pixels with a hue to update the average", min=1
    )
    unknown_max_height_m: float = setting(
        1.4, "unlabelled (UNKNOWN-limb) targets below this height are analysed as hands, m"
    )
    # --- decision ---
    carry_mass: float = setting(
        0.06,
        "carrying if the strongest object mode holds this pdf mass (pixel share)",
        min=0.0,
        max=1.0,
    )
    mode_mass_halfwidth_deg: float = setting(
        15.0, "a fused mode's mass and hue are taken within +-this of its peak, deg", min=0.0
    )
    evidence_rho: float = setting(
        2.0, "summed reliability at which the confidence's evidence term reaches 63 %", min=1e-9
    )

    def __post_init__(self) -> None:
        if self.max_radius_m < self.min_radius_m:
            raise ValueError(
                f"max_radius_m must be >= min_radius_m ({self.min_radius_m}), "
                f"got {self.max_radius_m}"
            )
        if self.max_radius_px < self.min_radius_px:
            raise ValueError(
                f"max_radius_px must be >= min_radius_px ({self.min_radius_px}), "
                f"got {self.max_radius_px}"
            )
