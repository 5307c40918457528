"""The world file of the world node (JSON), read and validated without ROS.

Every error is a `WorldFileError` whose message starts with the path of the bad field
(`robots[1].max_speed: must be > 0, got -1`), so the world node prints one line and exits 2.
The fields and their defaults are in docs/detailed.md, "The world node".
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .geometry import Area
from .world import RobotSpec, TargetSpec, WorldSpec

NS_PER_S = 1_000_000_000
AIRBORNE_Z = 0.5  # metres: a UAV's camera sees from this altitude up (on the ground: blind)


class WorldFileError(ValueError):
    """A world file that cannot be read or holds a bad field (the message names it)."""


@dataclass(frozen=True)
class RobotTopics:
    """Where a robot's topics live: its namespace and the extra topics its pose goes to."""

    name: str
    namespace: str
    pose_topics: tuple[str, ...] = ()


@dataclass(frozen=True)
class Stop:
    """When a run ends: a coverage share, every target rescued, or simulated seconds."""

    time_s: float
    coverage: float | None = None
    all_rescued: bool = False


@dataclass(frozen=True)
class WorldFile:
    """A validated world file."""

    spec: WorldSpec
    topics: tuple[RobotTopics, ...]
    stop: Stop
    output: Path
    seed: int = 0
    step_timeout_s: float = 1.0
    start_timeout_s: float = 30.0
    settle_s: float = 0.05
    settle_reporters: int = 0
    status_readers: int = 0  # `/world/status` subscribers the start and the final status wait for
    status_every: int = 10
    sample_every: int = 1
    executor: str = "events"
    cmd_type: str = "twist_stamped"
    reporters: tuple[str, ...] = ()  # the exact barrier's reporters (`by`); none: settling
    barrier_timeout_s: float = 1.0

    @property
    def barrier(self) -> bool:
        """Steps end on the exact barrier (docs/detailed.md, "The lockstep barrier")."""
        return bool(self.reporters)

    @property
    def dt_ns(self) -> int:
        """The step in integer nanoseconds (stamps are k * dt_ns, exact)."""
        return round(self.spec.dt * NS_PER_S)


def load(path: Path) -> WorldFile:
    """Read and validate a world file; WorldFileError names the bad field."""
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise WorldFileError(f"{path}: cannot read: {err.strerror or err}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise WorldFileError(f"{path}: not JSON: {err}") from None
    return parse(raw, base=path.parent)


def parse(raw: Any, base: Path = Path(".")) -> WorldFile:
    """A WorldFile from decoded JSON; a relative `output` is taken from `base`."""
    top = _Fields(raw, "")
    dt = top.number("dt", 0.1, positive=True)
    if abs(dt * NS_PER_S - round(dt * NS_PER_S)) > 1e-3:
        raise WorldFileError(f"dt: must be a whole number of nanoseconds, got {dt!r}")
    area = _Fields(top.get("area"), "area")
    robots_raw = top.get("robots")
    if not isinstance(robots_raw, list) or not robots_raw:
        raise WorldFileError("robots: must be a non-empty list")
    robots, topics = zip(
        *(_robot(r, f"robots[{i}]") for i, r in enumerate(robots_raw)), strict=True
    )
    targets_raw = top.get("targets", [])
    if not isinstance(targets_raw, list):
        raise WorldFileError("targets: must be a list")
    targets = tuple(_target(t, f"targets[{i}]") for i, t in enumerate(targets_raw))
    namespaces = [t.namespace for t in topics]
    if len(set(namespaces)) != len(namespaces):
        raise WorldFileError(f"robots: namespaces must be unique, got {namespaces}")
    try:
        spec = WorldSpec(
            Area(area.number("width", positive=True), area.number("height", positive=True)),
            tuple(robots),
            targets,
            cell=top.number("cell", 1.0, positive=True),
            dt=dt,
            airborne_z=top.number("airborne_z", AIRBORNE_Z, low=0.0),
            substeps=top.integer("substeps", 1, low=1),
        )
    except ValueError as err:  # the core names the robot, target or field
        raise WorldFileError(str(err)) from None
    output = top.get("output")
    if not isinstance(output, str) or not output:
        raise WorldFileError("output: must be a file path (string)")
    writable(base / output)
    return WorldFile(
        spec=spec,
        topics=tuple(topics),
        stop=_stop(top.get("stop"), bool(targets)),
        output=base / output,
        seed=top.integer("seed", 0, low=0),
        step_timeout_s=top.number("step_timeout_s", 1.0, positive=True),
        start_timeout_s=top.number("start_timeout_s", 30.0, positive=True),
        settle_s=top.number("settle_s", 0.05, low=0.0),
        settle_reporters=top.integer("settle_reporters", 0, low=0),
        status_readers=top.integer("status_readers", 0, low=0),
        status_every=top.integer("status_every", 10, low=1),
        sample_every=top.integer("sample_every", 1, low=1),
        executor=_choice(top.raw, "executor", ("events", "single")),
        # one value left: plain Twist answers (no stamp) were dropped with the old servers
        cmd_type=_choice(top.raw, "cmd_type", ("twist_stamped",)),
        reporters=_names(top.raw.get("reporters", [])),
        barrier_timeout_s=top.number("barrier_timeout_s", 1.0, positive=True),
    )


def _names(raw: Any) -> tuple[str, ...]:
    """`reporters`: distinct non-empty strings."""
    if not isinstance(raw, list) or not all(isinstance(n, str) and n for n in raw):
        raise WorldFileError(f"reporters: must be a list of reporter names, got {raw!r}")
    if len(set(raw)) != len(raw):
        raise WorldFileError(f"reporters: names must be distinct, got {raw!r}")
    return tuple(raw)


def writable(path: Path) -> None:
    """WorldFileError unless the result can be written at `path` (checked before the run, so
    a run never ends without its result): the nearest existing folder must be a writable
    folder, and `path` not a folder."""
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if path.is_dir():
        raise WorldFileError(f"output: cannot write {path}: it is a folder")
    if not folder.is_dir():
        raise WorldFileError(f"output: cannot write {path}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):  # the file is replaced: its folder counts
        raise WorldFileError(f"output: cannot write {path}: permission denied")


def _choice(raw: dict[str, Any], key: str, names: tuple[str, ...]) -> str:
    """One of `names` (the first by default)."""
    value = raw.get(key, names[0])
    if value not in names:
        allowed = " or ".join(repr(n) for n in names)
        raise WorldFileError(f"{key}: must be {allowed}, got {value!r}")
    return str(value)


class _Fields:
    """Typed access to one JSON object's fields, errors prefixed with its path."""

    def __init__(self, raw: Any, where: str) -> None:
        if not isinstance(raw, dict):
            raise WorldFileError(f"{where or 'the world file'}: must be a JSON object")
        self.raw: dict[str, Any] = raw
        self.where = where

    def path(self, key: str) -> str:
        return f"{self.where}.{key}" if self.where else key

    def get(self, key: str, default: Any = None) -> Any:
        if key not in self.raw and default is None:
            raise WorldFileError(f"{self.path(key)}: missing")
        return self.raw.get(key, default)

    def number(
        self,
        key: str,
        default: float | None = None,
        *,
        positive: bool = False,
        low: float = -math.inf,
    ) -> float:
        value = self.raw.get(key, default)
        if value is None:
            raise WorldFileError(f"{self.path(key)}: missing")
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise WorldFileError(f"{self.path(key)}: must be a finite number, got {value!r}")
        if (positive and value <= 0) or value < low:
            bound = "> 0" if positive else f">= {low:g}"
            raise WorldFileError(f"{self.path(key)}: must be {bound}, got {value!r}")
        return float(value)

    def integer(self, key: str, default: int, *, low: int) -> int:
        value = self.raw.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise WorldFileError(f"{self.path(key)}: must be an integer >= {low}, got {value!r}")
        return value


def _robot(raw: Any, where: str) -> tuple[RobotSpec, RobotTopics]:
    fields = _Fields(raw, where)
    name = fields.get("name")
    if not isinstance(name, str) or not name.isidentifier():
        raise WorldFileError(f"{where}.name: must be a ROS name (letters, digits, _), got {name!r}")
    namespace = fields.raw.get("namespace", name)
    if not isinstance(namespace, str) or not all(p.isidentifier() for p in namespace.split("/")):
        raise WorldFileError(f"{where}.namespace: must be a ROS namespace, got {namespace!r}")
    kind = fields.get("kind", "uav")
    if kind not in ("uav", "ugv"):
        raise WorldFileError(f"{where}.kind: must be 'uav' or 'ugv', got {kind!r}")
    start = fields.raw.get("start", [0.0, 0.0, 0.0])
    if not isinstance(start, list) or len(start) not in (2, 3):
        raise WorldFileError(f"{where}.start: must be [x, y] or [x, y, z], got {start!r}")
    xyz = _Fields({"x": start[0], "y": start[1], "z": start[2] if len(start) == 3 else 0.0}, where)
    fov = fields.raw.get("fov_radius")
    extra = fields.raw.get("pose_topics", [])
    if not isinstance(extra, list) or not all(_topic_name(t) for t in extra):
        raise WorldFileError(f"{where}.pose_topics: must be a list of relative topic names")
    spec = RobotSpec(
        name,
        kind,
        fields.number("max_speed", positive=True),
        None if fov is None else fields.number("fov_radius", positive=True),
        xyz.number("x"),
        xyz.number("y"),
        xyz.number("z", low=0.0),
    )
    return spec, RobotTopics(name, namespace, tuple(extra))


def _topic_name(name: Any) -> bool:
    return isinstance(name, str) and all(p.isidentifier() for p in name.split("/"))


def _target(raw: Any, where: str) -> TargetSpec:
    fields = _Fields(raw, where)
    target_id = fields.get("id")
    if isinstance(target_id, bool) or not isinstance(target_id, int):
        raise WorldFileError(f"{where}.id: must be an integer, got {target_id!r}")
    return TargetSpec(target_id, fields.number("x"), fields.number("y"))


def _stop(raw: Any, has_targets: bool) -> Stop:
    fields = _Fields(raw, "stop")
    coverage = fields.raw.get("coverage")
    if coverage is not None:
        coverage = fields.number("coverage", positive=True)
        if coverage > 1:
            raise WorldFileError(f"stop.coverage: must be a share in (0, 1], got {coverage!r}")
    all_rescued = fields.raw.get("all_rescued", False)
    if not isinstance(all_rescued, bool):
        raise WorldFileError(f"stop.all_rescued: must be true or false, got {all_rescued!r}")
    if all_rescued and not has_targets:
        raise WorldFileError("stop.all_rescued: the world has no targets")
    return Stop(fields.number("time_s", positive=True), coverage, all_rescued)
