"""Synthetic multi-camera recordings with ground truth (``surveil synth``)."""
