"""Poses, velocity commands and the rectangular area every body and controller shares."""

from __future__ import annotations

import math
from dataclasses import dataclass


def finite(name: str, value: float) -> float:
    """`value` as a float, or ValueError when it is not a finite number."""
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return number


def positive(name: str, value: float) -> float:
    """`value` as a float, or ValueError when it is not finite and > 0."""
    number = finite(name, value)
    if number <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return number


@dataclass(frozen=True)
class Pose:
    """Where a body is: metres in the area's frame (origin at its south-west corner, z up)."""

    x: float
    y: float
    z: float = 0.0

    def distance_xy(self, x: float, y: float) -> float:
        """Horizontal distance to the point (x, y)."""
        return math.hypot(x - self.x, y - self.y)


@dataclass(frozen=True)
class Command:
    """A velocity command in m/s (what a `geometry_msgs/Twist`'s linear part carries)."""

    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0


ZERO = Command()


def clip(command: Command, max_speed: float) -> Command:
    """The command with its horizontal norm limited to `max_speed` (direction kept) and its
    vertical part limited to +-`max_speed`; non-finite parts are refused (ValueError)."""
    vx = finite("vx", command.vx)
    vy = finite("vy", command.vy)
    vz = finite("vz", command.vz)
    norm = math.hypot(vx, vy)
    if norm > max_speed:
        scale = max_speed / norm
        vx, vy = vx * scale, vy * scale
    vz = min(max(vz, -max_speed), max_speed)
    if (vx, vy, vz) == (command.vx, command.vy, command.vz):
        return command
    return Command(vx, vy, vz)


@dataclass(frozen=True)
class Area:
    """The rectangle [0, width] x [0, height] in metres; bodies never leave it."""

    width: float
    height: float

    def __post_init__(self) -> None:
        """Refuse an empty or non-finite area."""
        positive("area width", self.width)
        positive("area height", self.height)

    def contains(self, x: float, y: float) -> bool:
        """Whether (x, y) lies in the closed rectangle."""
        return 0.0 <= x <= self.width and 0.0 <= y <= self.height

    def clamp(self, x: float, y: float) -> tuple[float, float]:
        """The nearest point of the closed rectangle."""
        return min(max(x, 0.0), self.width), min(max(y, 0.0), self.height)


def towards(
    pose: Pose, x: float, y: float, z: float, speed: float, dt: float
) -> tuple[Command, float]:
    """The command that moves straight at `speed` to (x, y, z) without overshooting it within
    one step of `dt` seconds, and the remaining 3-D distance."""
    dx, dy, dz = x - pose.x, y - pose.y, z - pose.z
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    if distance == 0.0:
        return ZERO, 0.0
    # the last step covers just the rest: the body stops on the goal, not past it
    scale = min(speed, distance / dt) / distance
    return Command(dx * scale, dy * scale, dz * scale), distance
