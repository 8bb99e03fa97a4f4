"""Close-view arm trackers: elbows and hands from an arm model per person (papers 001, 004).

See docs/armpose.md. ``ArmTracker.step`` takes the 3D tracker's targets and the cameras'
observations and returns one ``ArmPose`` per tracked person.
"""

from surveil.armpose.settings import ArmPoseConfig
from surveil.armpose.tracker import ArmTracker

__all__ = ["ArmPoseConfig", "ArmTracker"]
