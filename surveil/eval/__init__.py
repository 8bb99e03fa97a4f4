"""Scoring of output MCAP files against ground truth (``surveil eval``)."""
