"""surveil: multi-camera 3D tracking of heads and hands, carried objects and activity events.

Conventions used everywhere (see ``surveil.datatypes``): SI units with unit suffixes in names,
world frame right-handed with Z up and the floor at Z = 0, OpenCV camera frames, timestamps as
integer nanoseconds on the recording clock, hue in degrees.
"""

__version__ = "0.1.0"
