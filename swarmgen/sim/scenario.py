"""Scenario files: every world parameter of a simulation, as JSON (standard library only).

    {
      "name": "coverage",
      "world": {"width": 201, "height": 201, "view": 1},
      "members": {"UAV": [1, 2, 4, 8], "UGV": 0},      count, list of counts (swept) or "=TYPE"
      "placement": {"*": {"layout": "south", "spacing": 4, "headings": "fan"}},
      "targets": [0],                                   counts (swept); or "target_positions"
      "station": [{"tick": 0, "event": "launch"}, {"tick": 10, "event": "missionStart"}],
      "clock_origin": "missionStart",                   times are reported from this event's tick
      "timing": {"takeoff": 5, ...},                    ticks of the timed behaviours
      "allocation": "paired",                           which bidding UGV an auction assigns
      "library": {"SelectRover": "TaskAllocation"},     model behaviour -> simulated behaviour
      "stop": "coverage", "stop_level": 1.0,            or "rescued" (all targets rescued)
      "max_ticks": 5000000, "reps": 50, "seed": 1,
      "coverage_levels": [0.5, ...], "target_levels": [0, 0.5, ...]   (0: the first target)
    }

The two scenarios of the paper are shipped in `swarmgen/sim/scenarios/` (`coverage`, `sar`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

SHIPPED = Path(__file__).resolve().parent / "scenarios"

TIMING_DEFAULTS: dict[str, int] = {
    "takeoff": 5,  # TakeOff
    "land": 5,  # Land
    "allocation": 1,  # TaskAllocation: an auction closes after this many ticks
    "bid_timeout": 10,  # TaskBidding gives up when no auction for its target closes
    "rescue": 0,  # Rescue, once the UGV is at the target
    "local_coverage": 10,  # LocalCoverage
    "default": 1,  # any other behaviour the model waits for
    "tick_ms": 1000,  # the length of a tick, for the model's `after` timers
}
LAYOUTS = ("south",)
HEADINGS = ("fan", "north")
ALLOCATIONS = ("paired", "nearest")
STOPS = ("coverage", "rescued", "ticks")


class ScenarioError(Exception):
    """A scenario file that cannot be used (a user error)."""


@dataclass(frozen=True)
class Placement:
    layout: str = "south"
    spacing: float = 4.0
    headings: str = "fan"


@dataclass(frozen=True)
class StationEvent:
    tick: int
    event: str
    data: dict[str, Any] | None = None


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str = ""
    width: int = 201
    height: int = 201
    view: int = 1
    members: dict[str, list[int] | str] = field(default_factory=dict)
    placement: dict[str, Placement] = field(default_factory=dict)
    targets: list[int] = field(default_factory=lambda: [0])
    target_positions: list[tuple[int, int]] | None = None
    station: list[StationEvent] = field(default_factory=list)
    clock_origin: str | None = None
    timing: dict[str, int] = field(default_factory=lambda: dict(TIMING_DEFAULTS))
    allocation: str = "paired"
    library: dict[str, str] = field(default_factory=dict)
    stop: str = "coverage"
    stop_level: float = 1.0
    max_ticks: int = 5_000_000
    reps: int = 50
    seed: int = 1
    coverage_levels: list[float] = field(
        default_factory=lambda: [0.5, 0.75, 0.875, 0.9375, 0.96875, 1.0]
    )
    target_levels: list[float] = field(default_factory=lambda: [0.0, 0.5, 0.75, 0.9, 1.0])
    given: tuple[str, ...] = ()  # member types named on the command line (must exist)

    def placement_of(self, member_type: str) -> Placement:
        return self.placement.get(member_type) or self.placement.get("*") or Placement()

    def origin_tick(self) -> int:
        """The tick reported as time 0: that of the `clock_origin` station event."""
        if self.clock_origin is None:
            return 0
        for item in self.station:
            if item.event == self.clock_origin:
                return item.tick
        return 0

    def with_overrides(
        self,
        members: dict[str, list[int]] | None = None,
        targets: list[int] | None = None,
        reps: int | None = None,
        seed: int | None = None,
    ) -> Scenario:
        changed = self
        if members:
            changed = replace(
                changed,
                members={**changed.members, **members},
                given=tuple(dict.fromkeys([*changed.given, *members])),
            )
        if targets is not None:
            changed = replace(changed, targets=list(targets), target_positions=None)
        if reps is not None:
            changed = replace(changed, reps=reps)
        if seed is not None:
            changed = replace(changed, seed=seed)
        return changed

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "description": self.description,
            "world": {"width": self.width, "height": self.height, "view": self.view},
            "members": self.members,
            "placement": {
                k: {"layout": p.layout, "spacing": p.spacing, "headings": p.headings}
                for k, p in self.placement.items()
            },
            "targets": self.targets,
            "target_positions": [list(p) for p in self.target_positions]
            if self.target_positions is not None
            else None,
            "station": [
                {"tick": s.tick, "event": s.event, **({"data": s.data} if s.data else {})}
                for s in self.station
            ],
            "clock_origin": self.clock_origin,
            "timing": self.timing,
            "allocation": self.allocation,
            "library": self.library,
            "stop": self.stop,
            "stop_level": self.stop_level,
            "max_ticks": self.max_ticks,
            "reps": self.reps,
            "seed": self.seed,
            "coverage_levels": self.coverage_levels,
            "target_levels": self.target_levels,
        }


_KEYS = {
    "name", "description", "world", "members", "placement", "targets", "target_positions",
    "station", "clock_origin", "timing", "allocation", "library", "stop", "stop_level",
    "max_ticks", "reps", "seed", "coverage_levels", "target_levels",
}  # fmt: skip


def resolve(name_or_path: str) -> Path:
    """`coverage`, `sar` (shipped) or a path to a scenario file."""
    shipped = SHIPPED / f"{name_or_path}.json"
    if "/" not in name_or_path and not name_or_path.endswith(".json") and shipped.is_file():
        return shipped
    path = Path(name_or_path)
    if not path.is_file():
        names = ", ".join(sorted(p.stem for p in SHIPPED.glob("*.json")))
        raise ScenarioError(f"no scenario '{name_or_path}': give a file or one of: {names}")
    return path


def load(name_or_path: str) -> Scenario:
    path = resolve(name_or_path)
    try:
        payload = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise ScenarioError(f"{path}: cannot read the scenario: {err}") from None
    except json.JSONDecodeError as err:
        raise ScenarioError(f"{path}:{err.lineno}:{err.colno}: not JSON: {err.msg}") from None
    try:
        return parse(payload, default_name=path.stem)
    except ScenarioError as err:
        raise ScenarioError(f"{path}: {err}") from None


def parse(payload: Any, default_name: str = "scenario") -> Scenario:
    if not isinstance(payload, dict):
        raise ScenarioError("a scenario is a JSON object")
    unknown = sorted(set(payload) - _KEYS)
    if unknown:
        raise ScenarioError(
            f"unknown key(s) {', '.join(unknown)}; known: {', '.join(sorted(_KEYS))}"
        )
    world = _object(payload, "world")
    unknown_world = sorted(set(world) - {"width", "height", "view"})
    if unknown_world:
        raise ScenarioError(f"world: unknown key(s) {', '.join(unknown_world)}")
    width = _int(world.get("width", 201), "world.width", 1)
    height = _int(world.get("height", 201), "world.height", 1)
    view = _int(world.get("view", 1), "world.view", 0)
    members: dict[str, list[int] | str] = {}
    for kind, value in _object(payload, "members").items():
        if isinstance(value, str):
            if not value.startswith("="):
                raise ScenarioError(f'members.{kind}: a string must be "=TYPE" (same count)')
            members[str(kind)] = value
        else:
            members[str(kind)] = _counts(value, f"members.{kind}")
    placement = {}
    for kind, value in _object(payload, "placement").items():
        if not isinstance(value, dict):
            raise ScenarioError(f"placement.{kind} must be an object")
        extra = sorted(set(value) - {"layout", "spacing", "headings"})
        if extra:
            raise ScenarioError(f"placement.{kind}: unknown key(s) {', '.join(extra)}")
        item = Placement(
            str(value.get("layout", "south")),
            float(value.get("spacing", 4.0)),
            str(value.get("headings", "fan")),
        )
        _choice(item.layout, LAYOUTS, f"placement.{kind}.layout")
        _choice(item.headings, HEADINGS, f"placement.{kind}.headings")
        placement[str(kind)] = item
    positions = payload.get("target_positions")
    target_positions: list[tuple[int, int]] | None = None
    if positions is not None:
        if not isinstance(positions, list) or not all(
            isinstance(p, list) and len(p) == 2 and all(isinstance(c, int) for c in p)
            for p in positions
        ):
            raise ScenarioError("target_positions must be a list of [x, y] patches")
        target_positions = [(p[0], p[1]) for p in positions]
        for x, y in target_positions:
            if not (0 <= x < width and 0 <= y < height):
                raise ScenarioError(f"target position [{x}, {y}] is outside the world")
    targets = _counts(payload.get("targets", [0]), "targets", 0)
    if target_positions is not None:
        targets = [len(target_positions)]
    station = []
    for number, item in enumerate(payload.get("station", []), start=1):
        if not isinstance(item, dict) or "event" not in item:
            raise ScenarioError(f"station event {number} needs `event` (and `tick`)")
        data = item.get("data")
        if data is not None and not isinstance(data, dict):
            raise ScenarioError(f"station event {number}: `data` must be an object")
        station.append(
            StationEvent(
                _int(item.get("tick", 0), f"station[{number}].tick", 0), str(item["event"]), data
            )
        )
    timing = dict(TIMING_DEFAULTS)
    for key, value in _object(payload, "timing").items():
        if key not in TIMING_DEFAULTS:
            raise ScenarioError(
                f"timing.{key}: unknown; known: {', '.join(sorted(TIMING_DEFAULTS))}"
            )
        timing[key] = _int(value, f"timing.{key}", 1 if key == "tick_ms" else 0)
    library = {str(k): str(v) for k, v in _object(payload, "library").items()}
    stop = str(payload.get("stop", "coverage"))
    _choice(stop, STOPS, "stop")
    allocation = str(payload.get("allocation", "paired"))
    _choice(allocation, ALLOCATIONS, "allocation")
    origin = payload.get("clock_origin")
    if origin is not None and not any(s.event == origin for s in station):
        raise ScenarioError(f"clock_origin '{origin}' is not a station event")
    levels = _fractions(
        payload.get("coverage_levels", Scenario("x").coverage_levels), "coverage_levels"
    )
    target_levels = _fractions(
        payload.get("target_levels", Scenario("x").target_levels), "target_levels"
    )
    stop_level = float(payload.get("stop_level", 1.0))
    if not 0 < stop_level <= 1:
        raise ScenarioError("stop_level must be in (0, 1]")
    return Scenario(
        name=str(payload.get("name", default_name)),
        description=str(payload.get("description", "")),
        width=width,
        height=height,
        view=view,
        members=members,
        placement=placement,
        targets=targets,
        target_positions=target_positions,
        station=station,
        clock_origin=None if origin is None else str(origin),
        timing=timing,
        allocation=allocation,
        library=library,
        stop=stop,
        stop_level=stop_level,
        max_ticks=_int(payload.get("max_ticks", 5_000_000), "max_ticks", 1),
        reps=_int(payload.get("reps", 50), "reps", 1),
        seed=_int(payload.get("seed", 1), "seed", 0),
        coverage_levels=levels,
        target_levels=target_levels,
    )


def _object(payload: dict[str, Any], key: str) -> dict[str, Any]:
    value = payload.get(key, {})
    if not isinstance(value, dict):
        raise ScenarioError(f"`{key}` must be an object")
    return value


def _int(value: Any, where: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ScenarioError(f"{where} must be an integer >= {minimum}")
    return value


def _counts(value: Any, where: str, minimum: int = 0) -> list[int]:
    items = value if isinstance(value, list) else [value]
    if not items:
        raise ScenarioError(f"{where} needs at least one count")
    return [_int(v, where, minimum) for v in items]


def _fractions(value: Any, where: str) -> list[float]:
    if not isinstance(value, list) or not value:
        raise ScenarioError(f"{where} must be a non-empty list of fractions")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, int | float) or not 0 <= v <= 1:
            raise ScenarioError(f"{where}: {v!r} is not a fraction in [0, 1]")
        out.append(float(v))
    return out


def _choice(value: str, choices: tuple[str, ...], where: str) -> None:
    if value not in choices:
        raise ScenarioError(f"{where} '{value}': choose one of {', '.join(choices)}")


def parse_members(text: str) -> dict[str, list[int]]:
    """`UAV=1,2,4,8` (several separated by ';' or given as repeated options)."""
    found: dict[str, list[int]] = {}
    for part in text.replace(";", " ").split():
        kind, sep, counts = part.partition("=")
        if not sep or not kind:
            raise ScenarioError(f"--members {part!r}: write TYPE=COUNT[,COUNT...]")
        found[kind] = parse_counts(counts, f"--members {kind}")
    return found


def parse_counts(text: str, where: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ScenarioError(
            f"{where}: {text!r} is not a comma-separated list of integers"
        ) from None
    if not values or any(v < 0 for v in values):
        raise ScenarioError(f"{where}: give one or more counts >= 0")
    return values
