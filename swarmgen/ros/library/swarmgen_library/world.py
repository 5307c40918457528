"""A continuous 2-D multi-robot world stepping by `dt` seconds, deterministic by construction.

Rules (docs/detailed.md, "The world"):
- The area is [0, width] x [0, height] metres. A body is a point (x, y, z). Each step moves it by
  its held velocity command times `dt` (explicit Euler, exact for constant velocities), then
  **clamps** it into the area (a body pushing into a wall slides along it) and keeps z >= 0.
  UGVs stay at z = 0.
- **Sub-steps.** Within a step the commands are constant, so the motion is known exactly at every
  instant; with `substeps` n > 1 the camera also looks at the n instants (k + s/n) * dt, s = 1..n
  (positions `x0 + v * (s/n) dt`, clamped; the last one is the step's own, `x0 + v * dt`, bit for
  bit). Commands, poses and the published camera stay per step: the step is the control period,
  the sub-step the camera's frame period (docs/detailed.md, "Sub-steps").
- A command is clipped to the robot's `max_speed`: the horizontal norm (direction kept), and the
  vertical part to +-max_speed. It is held until the next command.
- A camera sees the closed disc of radius `fov_radius` around the body's (x, y); a UAV's only
  while it is airborne (z >= `airborne_z`; 0, the default, means always), a UGV's always.
  Coverage: the area is divided into square cells of side `cell`; a cell is covered
  at the first frame (sub-step) at which its centre lies in the disc of a UAV's camera (step 0
  included, the start). A detection: a target that is in a camera's disc at a frame and was not
  at the previous frame (per robot); the world keeps each target's first detection time. What a
  camera reports for a step is every target it saw at any frame of that step.
- Time is `steps * dt` (never accumulated). Robots are stepped in the order given, with plain
  float arithmetic: the same spec and commands give the same trajectory, bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from .geometry import Area, Command, Pose, clip, finite, positive

Kind = Literal["uav", "ugv"]
NONE: frozenset[int] = frozenset()  # shared: most steps see no target


@dataclass(frozen=True)
class RobotSpec:
    """A robot: its name, kind, speed limit (m/s), camera and start position."""

    name: str
    kind: Kind
    max_speed: float
    fov_radius: float | None = None
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0

    def __post_init__(self) -> None:
        """Refuse values no body can have."""
        if not self.name:
            raise ValueError("a robot needs a name")
        if self.kind not in ("uav", "ugv"):
            raise ValueError(f"robot {self.name!r}: kind must be 'uav' or 'ugv', got {self.kind!r}")
        positive(f"robot {self.name!r} max_speed", self.max_speed)
        if self.fov_radius is not None:
            positive(f"robot {self.name!r} fov_radius", self.fov_radius)
        for axis in ("x", "y", "z"):
            finite(f"robot {self.name!r} {axis}", getattr(self, axis))


@dataclass(frozen=True)
class TargetSpec:
    """A target to find: its id and where it is (targets do not move)."""

    id: int
    x: float
    y: float


@dataclass(frozen=True)
class WorldSpec:
    """Everything a world starts from."""

    area: Area
    robots: tuple[RobotSpec, ...]
    targets: tuple[TargetSpec, ...] = ()
    cell: float = 1.0
    dt: float = 0.1
    airborne_z: float = 0.0  # a UAV's camera sees only at z >= this (a UAV on the ground: blind)
    substeps: int = 1  # camera frames per step (see the module docstring)

    def __post_init__(self) -> None:
        """Refuse duplicate names or ids, starts and targets outside the area, and a cell size
        that does not divide the area into whole cells."""
        positive("dt", self.dt)
        positive("cell", self.cell)
        if not isinstance(self.substeps, int) or self.substeps < 1:
            raise ValueError(f"substeps must be a whole number >= 1, got {self.substeps!r}")
        if finite("airborne_z", self.airborne_z) < 0:
            raise ValueError(f"airborne_z must be >= 0, got {self.airborne_z}")
        names = [r.name for r in self.robots]
        if len(set(names)) != len(names):
            raise ValueError(f"robot names must be unique: {names}")
        ids = [t.id for t in self.targets]
        if len(set(ids)) != len(ids):
            raise ValueError(f"target ids must be unique: {ids}")
        for robot in self.robots:
            if not self.area.contains(robot.x, robot.y) or robot.z < 0:
                raise ValueError(f"robot {robot.name!r} starts outside the area")
            if robot.kind == "ugv" and robot.z != 0:
                raise ValueError(f"robot {robot.name!r}: a UGV starts at z = 0")
        for target in self.targets:
            if not self.area.contains(finite("target x", target.x), finite("target y", target.y)):
                raise ValueError(f"target {target.id} lies outside the area")
        self.cells_across()

    def cells_across(self) -> tuple[int, int]:
        """The number of cells along x and y (ValueError unless whole)."""
        counts = []
        for side in (self.area.width, self.area.height):
            n = round(side / self.cell)
            if n < 1 or abs(n * self.cell - side) > 1e-9 * side:
                raise ValueError(f"cell {self.cell} does not divide the area side {side}")
            counts.append(n)
        return counts[0], counts[1]


@dataclass(frozen=True)
class Detection:
    """A target that came into a robot's camera view at step time `t`."""

    robot: str
    target: int
    x: float
    y: float
    t: float


class _Body:
    """The mutable state of one robot (slots: the step loop reads these millions of times)."""

    __slots__ = ("camera", "cmd", "in_view", "min_z", "radius", "seen", "spec", "x", "y", "z")

    def __init__(self, spec: RobotSpec, airborne_z: float) -> None:
        self.spec = spec
        self.x, self.y, self.z = float(spec.x), float(spec.y), float(spec.z)
        self.cmd = Command()
        self.camera = spec.fov_radius is not None
        self.radius = spec.fov_radius or 0.0
        self.in_view = NONE  # in view at the last frame
        self.seen = NONE  # seen at any frame of the last step (what its camera reports)
        # the lowest z its camera sees from: a UGV's camera is always on (it stays at z = 0)
        self.min_z = airborne_z if spec.kind == "uav" else 0.0

    @property
    def looking(self) -> bool:
        """Whether its camera sees now (switched on, and airborne for a UAV)."""
        return self.camera and self.z >= self.min_z


class World:
    """The world of one run; see the module docstring for its rules."""

    def __init__(self, spec: WorldSpec) -> None:
        """A world at time 0: bodies at their starts, the starts' coverage recorded."""
        self.spec = spec
        self.area = spec.area
        self.dt = spec.dt
        self.steps = 0
        self.nx, self.ny = spec.cells_across()
        self._bodies = {r.name: _Body(r, spec.airborne_z) for r in spec.robots}
        self._order = [self._bodies[r.name] for r in spec.robots]
        self.substeps = spec.substeps
        self._frame = 0  # frames since the start: steps * substeps at step boundaries
        self._cell_frame = [-1] * (self.nx * self.ny)  # first frame a cell was covered
        self.covered_cells = 0
        self._targets = {t.id: t for t in spec.targets}
        self._buckets: dict[int, list[TargetSpec]] = {}
        for target in spec.targets:
            self._buckets.setdefault(self._cell_of(target.x, target.y), []).append(target)
        self._first_seen: dict[int, float] = {}
        for body in self._order:
            self._cover(body)
            body.in_view = body.seen = self._seen_by(body)
            self._note_seen(body.in_view, 0.0)

    # --- queries

    @property
    def time(self) -> float:
        """Simulated seconds since the start."""
        return self.steps * self.dt

    def pose(self, robot: str) -> Pose:
        """Where a robot is."""
        body = self._body(robot)
        return Pose(body.x, body.y, body.z)

    def held(self, robot: str) -> Command:
        """The (clipped) command a robot holds."""
        return self._body(robot).cmd

    def visible(self, robot: str) -> tuple[TargetSpec, ...]:
        """The targets a robot's camera saw during the last step (at any frame), by id."""
        return tuple(self._targets[i] for i in sorted(self._body(robot).seen))

    def coverage(self) -> float:
        """The share of cells covered so far."""
        return self.covered_cells / len(self._cell_frame)

    def cell_times(self) -> list[float | None]:
        """When each cell was first covered (None: never), row by row from the south-west."""
        return [None if f < 0 else self._frame_time(f) for f in self._cell_frame]

    def first_detections(self) -> dict[int, float]:
        """Each detected target's first detection time."""
        return dict(self._first_seen)

    # --- control

    def command(self, robot: str, vx: float, vy: float, vz: float = 0.0) -> Command:
        """Hold a velocity command (clipped to the robot's max speed; a UGV's vz is dropped).
        Returns the command as held. Non-finite values are refused (ValueError)."""
        body = self._body(robot)
        held = clip(Command(vx, vy, 0.0 if body.spec.kind == "ugv" else vz), body.spec.max_speed)
        body.cmd = held
        return held

    def set_camera(self, robot: str, on: bool) -> None:
        """Switch a robot's camera (a robot without one stays blind); off, it sees nothing."""
        body = self._body(robot)
        body.camera = on and body.spec.fov_radius is not None
        if not body.camera:
            body.in_view = body.seen = NONE

    def step(self) -> tuple[Detection, ...]:
        """Advance by dt: move and clamp every body, look at every frame, record coverage; the
        new detections, in frame order, then robot order."""
        n, dt = self.substeps, self.dt
        starts = [(body, body.x, body.y, body.z) for body in self._order]
        for body in self._order:
            body.seen = NONE
        found: list[Detection] = []
        for s in range(1, n + 1):
            tau = dt if s == n else dt * s / n  # the last frame is the step's own pose, exactly
            for body, x0, y0, z0 in starts:
                self._place(body, x0, y0, z0, tau)
            self._frame += 1
            self._look(found)
        self.steps += 1
        return tuple(found)

    def _place(self, body: _Body, x0: float, y0: float, z0: float, tau: float) -> None:
        """A body where its held command takes it `tau` seconds after (x0, y0, z0), clamped."""
        cmd, width, height = body.cmd, self.area.width, self.area.height
        x = x0 + cmd.vx * tau
        y = y0 + cmd.vy * tau
        body.x = 0.0 if x < 0.0 else width if x > width else x
        body.y = 0.0 if y < 0.0 else height if y > height else y
        z = z0 + cmd.vz * tau
        body.z = z if z > 0.0 else 0.0

    def _look(self, found: list[Detection]) -> None:
        """One camera frame of every body: coverage, then the targets that came into view."""
        t = self._frame_time(self._frame)
        for body in self._order:
            if not body.looking:
                body.in_view = NONE  # seen again once it looks: a new detection then
                continue
            self._cover(body)
            now = self._seen_by(body)
            for target_id in sorted(now - body.in_view) if now else ():
                target = self._targets[target_id]
                found.append(Detection(body.spec.name, target_id, target.x, target.y, t))
            body.in_view = now
            if now:
                body.seen = body.seen | now
                self._note_seen(now, t)

    def _frame_time(self, frame: int) -> float:
        """A frame's time: a step boundary's is k * dt, exactly as `time`."""
        steps, within = divmod(frame, self.substeps)
        return steps * self.dt if within == 0 else frame * self.dt / self.substeps

    # --- internals

    def _body(self, robot: str) -> _Body:
        try:
            return self._bodies[robot]
        except KeyError:
            raise KeyError(f"no robot {robot!r} in this world") from None

    def _cell_of(self, x: float, y: float) -> int:
        c = self.spec.cell
        i = min(int(x / c), self.nx - 1)
        j = min(int(y / c), self.ny - 1)
        return j * self.nx + i

    def _span(self, centre: float, radius: float, count: int) -> range:
        """The cell indices whose centres can lie within `radius` of `centre` on one axis."""
        c = self.spec.cell
        low = max(0, math.ceil((centre - radius) / c - 0.5))
        high = min(count - 1, math.floor((centre + radius) / c - 0.5))
        return range(low, high + 1)

    def _cover(self, body: _Body) -> None:
        """Mark the cells whose centres the UAV's camera disc holds."""
        if not body.looking or body.spec.kind != "uav":
            return
        c, r2 = self.spec.cell, body.radius * body.radius
        x, y, nx, cells = body.x, body.y, self.nx, self._cell_frame
        for j in self._span(y, body.radius, self.ny):
            dy = (j + 0.5) * c - y
            row = j * nx
            for i in self._span(x, body.radius, nx):
                if cells[row + i] < 0:
                    dx = (i + 0.5) * c - x
                    if dx * dx + dy * dy <= r2:
                        cells[row + i] = self._frame
                        self.covered_cells += 1

    def _seen_by(self, body: _Body) -> frozenset[int]:
        """The ids of the targets in the body's camera disc (buckets: the cells it overlaps)."""
        if not body.looking or not self._buckets:
            return NONE
        c, r = self.spec.cell, body.radius
        x, y, r2 = body.x, body.y, r * r
        low_i, high_i = max(0, int((x - r) / c)), min(self.nx - 1, int((x + r) / c))
        low_j, high_j = max(0, int((y - r) / c)), min(self.ny - 1, int((y + r) / c))
        seen = []
        for j in range(low_j, high_j + 1):
            for i in range(low_i, high_i + 1):
                for target in self._buckets.get(j * self.nx + i, ()):
                    dx, dy = target.x - x, target.y - y
                    if dx * dx + dy * dy <= r2:
                        seen.append(target.id)
        return frozenset(seen) if seen else NONE

    def _note_seen(self, ids: frozenset[int], t: float) -> None:
        for target_id in ids:
            self._first_seen.setdefault(target_id, t)
