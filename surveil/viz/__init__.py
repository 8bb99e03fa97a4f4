"""Review in Rerun: the only package that imports ``rerun``.

- :mod:`surveil.viz.paths` -- entity paths
- :mod:`surveil.viz.blueprint` -- the review layout from the camera list
- :mod:`surveil.viz.rerun_log` -- ``RerunSink``, one FrameResult at a time into an .rrd
- :mod:`surveil.viz.review` -- an .rrd from an existing output MCAP plus its recording
- :mod:`surveil.viz.viewer` -- open, serve, verify and screenshot .rrd files

Import the submodules; this package imports nothing so that ``import surveil.viz`` is cheap.
"""
