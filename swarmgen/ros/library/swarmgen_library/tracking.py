"""Target behaviours: tracking (follow a target until it is rescued or lost) and target
monitoring (turn what a camera sees into `targetFound` / `targetLost` reports)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from .controllers import SUCCEEDED, Base
from .geometry import ZERO, Command, Pose, positive, towards

TARGET_LOST = "targetLost"
TARGET_FOUND = "targetFound"


class Tracking(Base):
    """Fly to the target's last known position and hover over it at the body's altitude until
    told it is rescued (`succeeded`) or lost from view (`targetLost`)."""

    def __init__(
        self,
        target_id: int,
        max_speed: float,
        dt: float,
        position: tuple[float, float] | None = None,
    ) -> None:
        """`position`: where the target is known to be (None: hover until an update)."""
        super().__init__()
        self.target_id = target_id
        self.speed = positive("max_speed", max_speed)
        self.dt = positive("dt", dt)
        self.position = position
        self._z = 0.0

    def start(self, pose: Pose, t: float) -> None:
        """Keep the altitude the body has."""
        super().start(pose, t)
        self._z = pose.z

    def update(self, target_id: int, x: float, y: float) -> None:
        """The target was seen at (x, y) (`target_update`)."""
        if target_id == self.target_id:
            self.position = (x, y)

    def rescued(self, target_id: int) -> None:
        """The target was rescued (`targetRescued`): `succeeded`."""
        if target_id == self.target_id:
            self.finish(SUCCEEDED, target_id=target_id)

    def lost(self, target_id: int) -> None:
        """The target left the member's view (`targetLost`): that outcome."""
        if target_id == self.target_id:
            self.finish(TARGET_LOST, target_id=target_id)

    def step(self, pose: Pose, t: float) -> Command:
        """Towards the target's position (zero once above it)."""
        if self._done is not None or self.position is None:
            return ZERO
        command, _ = towards(pose, *self.position, self._z, self.speed, self.dt)
        return command


@dataclass(frozen=True)
class TargetEvent:
    """A report of target monitoring: `targetFound` or `targetLost`, where and when."""

    name: str
    target_id: int
    x: float
    y: float
    t: float


class TargetMonitoring(Base):
    """Reports each target that comes into the member's view and the swarm does not know yet
    (`targetFound`, once), and each tracked target that leaves it (`targetLost`). It never
    moves the body (`moves` False: its command is never sent) and runs until preempted."""

    moves = False

    def __init__(self) -> None:
        """Nothing known, nothing in view."""
        super().__init__()
        self.known: set[int] = set()  # reported by anybody, or rescued: never reported again
        self.tracked: set[int] = set()
        self._in_view: dict[int, tuple[float, float]] = {}

    def step(self, pose: Pose, t: float) -> Command:
        """No motion."""
        return ZERO

    def know(self, target_id: int) -> None:
        """The swarm knows the target (someone reported it, or it was rescued)."""
        self.known.add(target_id)
        self.tracked.discard(target_id)

    def forget(self, target_id: int) -> None:
        """The target may be reported again (its allocation was aborted)."""
        self.known.discard(target_id)
        self.tracked.discard(target_id)

    def track(self, target_id: int) -> None:
        """This member tracks the target: report when it leaves the view."""
        self.tracked.add(target_id)

    def observe(self, visible: Iterable[tuple[int, float, float]], t: float) -> list[TargetEvent]:
        """The targets (id, x, y) in view at `t`: the reports, by target id."""
        if self._done is not None:
            return []
        now = {target_id: (x, y) for target_id, x, y in visible}
        events = []
        for target_id in sorted(set(now) | set(self._in_view)):
            if target_id in now and target_id not in self.known:
                self.known.add(target_id)
                events.append(TargetEvent(TARGET_FOUND, target_id, *now[target_id], t))
            elif target_id not in now and target_id in self.tracked:
                self.tracked.discard(target_id)
                events.append(TargetEvent(TARGET_LOST, target_id, *self._in_view[target_id], t))
        self._in_view = now
        return events
