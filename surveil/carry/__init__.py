"""Carried-object detection: hue modes around tracked hands (paper 004 sections 7.2-7.3)."""

from surveil.carry.analysis import (
    CarryAnalyser,
    HandSpot,
    HandView,
    analyse_hand_view,
    choose_radius,
    circle_box,
    find_hand_blob,
    hand_region,
    hand_view,
    is_analysed_hand,
    locate_hand,
    locate_hands,
    reliability,
    rim_background_fraction,
)
from surveil.carry.fusion import HueWindow, decide_carrying, fuse_distributions
from surveil.carry.hue import (
    connected_modes,
    find_modes,
    hue_histogram,
    pixel_hue_codes,
    region_mode_pdf,
    smooth_circular,
)
from surveil.carry.settings import CarryConfig

__all__ = [
    "CarryAnalyser",
    "CarryConfig",
    "HandSpot",
    "HandView",
    "HueWindow",
    "analyse_hand_view",
    "choose_radius",
    "circle_box",
    "connected_modes",
    "decide_carrying",
    "find_hand_blob",
    "find_modes",
    "fuse_distributions",
    "hand_region",
    "hand_view",
    "hue_histogram",
    "is_analysed_hand",
    "locate_hand",
    "locate_hands",
    "pixel_hue_codes",
    "region_mode_pdf",
    "reliability",
    "rim_background_fraction",
    "smooth_circular",
]
