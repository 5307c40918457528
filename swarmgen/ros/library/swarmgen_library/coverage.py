"""Coverage behaviours: random-direction coverage of the whole area, local (spiral) coverage
around a point.

Random direction is the abstract world's rule (`swarmgen.sim.world`, `_turn`) on a continuous
body: fly straight at max speed until the next step would leave the area, then draw uniformly
random directions from the member's counter-based stream until one keeps the next step inside,
and fly that way (after 128 failed draws, vanishingly unlikely, head for the centre, as the
abstract world does). "The next step" is one control period `dt` at max speed, computed with
the world's own expression `x + vx * dt`, so a body on a leg never reaches a wall and is never
clamped.
"""

from __future__ import annotations

import math

from .controllers import ABORTED, SUCCEEDED, Base
from .geometry import ZERO, Area, Command, Pose, positive, towards
from .rng import Stream

DRAWS = 128  # the abstract world's 16 blocks of 8 candidate directions


def target_outputs(target_id: int, x: float, y: float) -> dict[str, object]:
    """The result fields of a coverage that ends on a find (cpswarm_msgs/Coverage's)."""
    return {"target_id": target_id, "target_pose": {"x": x, "y": y, "z": 0.0}}


class RandomDirection(Base):
    """Random-direction coverage; runs until preempted, or (`single_target`) until a find."""

    def __init__(
        self,
        area: Area,
        max_speed: float,
        dt: float,
        stream: Stream,
        heading: float = math.pi / 2,
        single_target: bool = False,
    ) -> None:
        """`heading`: the first leg's direction (radians from east, counter-clockwise)."""
        super().__init__()
        self.area = area
        self.speed = positive("max_speed", max_speed)
        self.dt = positive("dt", dt)
        self.stream = stream
        self.heading = float(heading)
        self.single_target = single_target
        self.turns = 0

    def _velocity(self) -> tuple[float, float]:
        return self.speed * math.cos(self.heading), self.speed * math.sin(self.heading)

    def _stays(self, pose: Pose, vx: float, vy: float) -> bool:
        return self.area.contains(pose.x + vx * self.dt, pose.y + vy * self.dt)

    def step(self, pose: Pose, t: float) -> Command:
        """Straight on, or a new random direction when the next step would leave the area.
        A restarted coverage goes on in its last direction, as the abstract world's does."""
        if self._done is not None:
            return ZERO
        vx, vy = self._velocity()
        if not self._stays(pose, vx, vy):
            self._turn(pose)
            vx, vy = self._velocity()
        return Command(vx, vy, 0.0)

    def _turn(self, pose: Pose) -> None:
        """Draw directions until one keeps the next step inside."""
        self.turns += 1
        for _ in range(DRAWS):
            angle = 2.0 * math.pi * self.stream.uniform()
            vx, vy = self.speed * math.cos(angle), self.speed * math.sin(angle)
            if self._stays(pose, vx, vy):
                self.heading = angle
                return
        cx, cy = self.area.width / 2 - pose.x, self.area.height / 2 - pose.y
        self.heading = math.atan2(cy, cx)

    def target_found(self, target_id: int, x: float, y: float) -> None:
        """A find by this member: with `single_target`, the coverage succeeds with it."""
        if self.single_target and self._done is None:
            self.finish(SUCCEEDED, **target_outputs(target_id, x, y))


class LocalCoverage(Base):
    """An outward Archimedean spiral around a point, `spacing` metres between turns, at max
    speed, for at most `duration` seconds (then `aborted`); `succeeded` on a find of its target
    (or of any target when it has none). A centre away from the body is approached first."""

    def __init__(
        self,
        area: Area,
        max_speed: float,
        dt: float,
        spacing: float,
        duration: float,
        centre: tuple[float, float] | None = None,
        target: int | None = None,
    ) -> None:
        """`centre` None: around where the body starts."""
        super().__init__()
        self.area = area
        self.speed = positive("max_speed", max_speed)
        self.dt = positive("dt", dt)
        self.b = positive("spacing", spacing) / (2.0 * math.pi)  # r = b * theta
        self.duration = positive("duration", duration)
        self.centre = centre
        self.target = target
        self.theta = 0.0
        self._z = 0.0

    def start(self, pose: Pose, t: float) -> None:
        """Begin at the centre of the spiral (theta 0)."""
        super().start(pose, t)
        if self.centre is None:
            self.centre = (pose.x, pose.y)
        self.theta = 0.0
        self._z = pose.z

    def reference(self) -> tuple[float, float]:
        """The spiral's point at the current angle, clamped into the area."""
        assert self.centre is not None
        r = self.b * self.theta
        cx, cy = self.centre
        return self.area.clamp(cx + r * math.cos(self.theta), cy + r * math.sin(self.theta))

    def step(self, pose: Pose, t: float) -> Command:
        """Follow the spiral; `aborted` once the time is up."""
        if self._done is not None:
            return ZERO
        if self.started is not None and t - self.started >= self.duration:
            return self.finish(ABORTED)
        x, y = self.reference()
        if pose.distance_xy(x, y) <= self.speed * self.dt:
            # on the spiral: advance its angle by one step's arc length (ds = sqrt(r²+b²) dθ)
            r = self.b * self.theta
            self.theta += self.speed * self.dt / math.hypot(r, self.b)
            x, y = self.reference()
        command, _ = towards(pose, x, y, self._z, self.speed, self.dt)
        return command

    def target_found(self, target_id: int, x: float, y: float) -> None:
        """A find: `succeeded` with it when it is the target looked for (or there is none)."""
        if self._done is None and self.target in (None, target_id):
            self.finish(SUCCEEDED, **target_outputs(target_id, x, y))
