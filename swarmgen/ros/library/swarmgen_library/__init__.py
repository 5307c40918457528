"""swarmgen's behaviour library for the detailed simulation: the ROS-free core.

A continuous 2-D multi-robot world (`world`) and the algorithms of the SAR library behaviours
(`controllers`, `coverage`, `tracking`, `auction`), in the standard library only. It imports as
`swarmgen_library` (the ament_python package's root on sys.path, or installed by colcon) and as
`swarmgen.ros.library.swarmgen_library` inside swarmgen: every import here is relative.
See docs/detailed.md.
"""

from .auction import Auctioneer, AuctionOpen, AuctionResult, Bid, Bidder, winner
from .controllers import (
    ABORTED,
    PREEMPTED,
    SUCCEEDED,
    Controller,
    Land,
    MoveTo,
    Positioning,
    TakeOff,
)
from .coverage import LocalCoverage, RandomDirection
from .geometry import ZERO, Area, Command, Pose
from .rng import Stream, member_key
from .tracking import TARGET_FOUND, TARGET_LOST, TargetEvent, TargetMonitoring, Tracking
from .world import Detection, RobotSpec, TargetSpec, World, WorldSpec

__all__ = [
    "ABORTED",
    "PREEMPTED",
    "SUCCEEDED",
    "TARGET_FOUND",
    "TARGET_LOST",
    "ZERO",
    "Area",
    "AuctionOpen",
    "AuctionResult",
    "Auctioneer",
    "Bid",
    "Bidder",
    "Command",
    "Controller",
    "Detection",
    "Land",
    "LocalCoverage",
    "MoveTo",
    "Pose",
    "Positioning",
    "RandomDirection",
    "RobotSpec",
    "Stream",
    "TakeOff",
    "TargetEvent",
    "TargetMonitoring",
    "TargetSpec",
    "Tracking",
    "World",
    "WorldSpec",
    "member_key",
    "winner",
]
