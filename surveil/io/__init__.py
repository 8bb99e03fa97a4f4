"""Everything that reads or writes files: calibration, recordings, ground truth, MCAP."""
