"""Reconstruction: pairs of camera views -> 3-D candidate points (paper 004 sections 5.1, 6.3)."""

from surveil.recon.candidates import make_candidates
from surveil.recon.settings import CandidateConfig
from surveil.recon.triangulate import closest_points

__all__ = ["CandidateConfig", "closest_points", "make_candidates"]
