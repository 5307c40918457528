"""The behaviour controller protocol and the motion behaviours: move-to, take-off, land,
positioning.

A controller is the algorithm of one behaviour, free of ROS and of the world: it is started
with the body's pose, then stepped once per control period with the pose it is given, and
returns the velocity command to hold until the next step. `done` is the outcome once it has
one (then it commands zero); `outputs` are the behaviour's result fields. `stop()` (preemption)
ends it and returns the zero command, so motion stops from the next world step on.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

from .geometry import ZERO, Command, Pose, positive, towards

SUCCEEDED, ABORTED, PREEMPTED = "succeeded", "aborted", "preempted"


@runtime_checkable
class Controller(Protocol):
    """What every behaviour controller offers."""

    moves: bool  # False: a sensing behaviour, whose (zero) command is never sent

    def start(self, pose: Pose, t: float) -> None:
        """Begin at simulated time `t` from `pose`."""

    def step(self, pose: Pose, t: float) -> Command:
        """The command to hold from `t` on, given the body's pose at `t`."""

    @property
    def done(self) -> str | None:
        """The outcome once the behaviour has ended, else None."""

    @property
    def outputs(self) -> Mapping[str, Any]:
        """The behaviour's result fields (meaningful once `done`)."""

    def stop(self) -> Command:
        """Preempt: end now (outcome `preempted` unless already done); the zero command."""


class Base:
    """Shared bookkeeping: the outcome, the outputs, the start time, preemption."""

    moves = True

    def __init__(self) -> None:
        """Not started, no outcome."""
        self._done: str | None = None
        self._outputs: dict[str, Any] = {}
        self.started: float | None = None

    def start(self, pose: Pose, t: float) -> None:
        """Begin: forget any earlier outcome."""
        self._done = None
        self._outputs = {}
        self.started = t

    @property
    def done(self) -> str | None:
        """The outcome once ended."""
        return self._done

    @property
    def outputs(self) -> Mapping[str, Any]:
        """The result fields."""
        return dict(self._outputs)

    def finish(self, outcome: str, **outputs: Any) -> Command:
        """End with an outcome (the first one counts) and outputs; the zero command."""
        if self._done is None:
            self._done = outcome
            self._outputs.update(outputs)
        return ZERO

    def stop(self) -> Command:
        """Preempted: no further motion."""
        return self.finish(PREEMPTED)


class MoveTo(Base):
    """Straight to a goal at max speed; `succeeded` within `tolerance` metres (3-D)."""

    def __init__(
        self, x: float, y: float, z: float | None, max_speed: float, dt: float, tolerance: float
    ) -> None:
        """`z` None keeps the altitude the body has when it starts."""
        super().__init__()
        self.goal = (x, y, z)
        self.max_speed = positive("max_speed", max_speed)
        self.dt = positive("dt", dt)
        self.tolerance = positive("tolerance", tolerance)
        self._z = 0.0 if z is None else z

    def start(self, pose: Pose, t: float) -> None:
        """Head for the goal from here."""
        super().start(pose, t)
        if self.goal[2] is None:
            self._z = pose.z

    def step(self, pose: Pose, t: float) -> Command:
        """Towards the goal; zero and `succeeded` once within tolerance."""
        if self._done is not None:
            return ZERO
        x, y, _ = self.goal
        command, distance = towards(pose, x, y, self._z, self.max_speed, self.dt)
        if distance <= self.tolerance:
            return self.finish(SUCCEEDED)
        return command


class TakeOff(MoveTo):
    """Straight up (or down) to an altitude above where the body stands; then `succeeded`."""

    def __init__(self, altitude: float, max_speed: float, dt: float, tolerance: float) -> None:
        """Climb to `altitude` metres."""
        super().__init__(0.0, 0.0, altitude, max_speed, dt, tolerance)

    def start(self, pose: Pose, t: float) -> None:
        """The goal is straight above (below) the body."""
        super().start(pose, t)
        self.goal = (pose.x, pose.y, self.goal[2])


class Land(TakeOff):
    """Straight down to the ground (z = 0); then `succeeded`."""

    def __init__(self, max_speed: float, dt: float, tolerance: float) -> None:
        """Descend to z = 0."""
        super().__init__(0.0, max_speed, dt, tolerance)


class Positioning(MoveTo):
    """Go to a pose and hold it there until preempted (it never ends by itself)."""

    def step(self, pose: Pose, t: float) -> Command:
        """Towards the pose; correct any drift once there."""
        if self._done is not None:
            return ZERO
        x, y, _ = self.goal
        command, distance = towards(pose, x, y, self._z, self.max_speed, self.dt)
        return ZERO if distance <= self.tolerance else command
