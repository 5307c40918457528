"""Scenario files: every world parameter of a simulation, as JSON (standard library only).

    {
      "name": "coverage",
      "world": {"width": 201, "height": 201, "view": 1},   and "views": {"UAV": 2}, a type's own
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

import difflib
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import field, replace
from pathlib import Path
from typing import Any

from swarmgen import jsonfile
from swarmgen.console import shown
from swarmgen.errors import SwarmgenError
from swarmgen.records import dataclass
from swarmgen.sim.limits import (
    MAX_LIST,
    MAX_MEMBER_RUNS,
    MAX_MEMBERS,
    MAX_PATCH_RUNS,
    MAX_REPS,
    MAX_RUNS,
    MAX_SEED,
    MAX_SIDE,
    MAX_TARGETS,
    MAX_TICK_MS,
    MAX_TICKS,
    MAX_VIEW,
    SCENARIO_BYTES,
    STAMP_NS,
)

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


class ScenarioError(SwarmgenError):
    """A scenario file that cannot be used (a user error)."""


class SimulationError(SwarmgenError):
    """The model or scenario cannot be simulated (a user error)."""


@dataclass(frozen=True)
class Placement:
    """How a member type's members start: layout, spacing and headings."""

    layout: str = "south"
    spacing: float = 4.0
    headings: str = "fan"


@dataclass(frozen=True)
class StationEvent:
    """An event the ground station sends to the swarm at a tick."""

    tick: int
    event: str
    data: dict[str, Any] | None = None


@dataclass(frozen=True)
class Scenario:
    """A simulation scenario: world, swept member counts, targets, station events, timings."""

    name: str
    description: str = ""
    width: int = 201
    height: int = 201
    view: int = 1
    # a member type's own view radius (a swept camera `fovRadius`, `sim.params`); else `view`
    views: dict[str, int] = field(default_factory=dict)
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
    detailed: dict[str, Any] = field(default_factory=dict)  # `sim.detailed.params` reads it

    def placement_of(self, member_type: str) -> Placement:
        """The placement of a member type, else of `*`, else the default."""
        return self.placement.get(member_type) or self.placement.get("*") or Placement()

    def view_of(self, member_type: str) -> int:
        """The view radius (patches) of a member type: its own, else the world's."""
        return self.views.get(member_type, self.view)

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
        """A copy with the given member counts, targets, repetitions or seed (command-line overrides)."""
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
        """The scenario as scenario-file JSON."""
        return {
            "name": self.name,
            "description": self.description,
            "world": {
                "width": self.width,
                "height": self.height,
                "view": self.view,
                **({"views": self.views} if self.views else {}),
            },
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
            **({"detailed": self.detailed} if self.detailed else {}),
        }


_KEYS = {
    "name", "description", "world", "members", "placement", "targets", "target_positions",
    "station", "clock_origin", "timing", "allocation", "library", "stop", "stop_level",
    "max_ticks", "reps", "seed", "coverage_levels", "target_levels", "detailed",
}  # fmt: skip


def resolve(name_or_path: str) -> Path:
    """`coverage`, `sar` (shipped) or a path to a scenario file."""
    shipped = SHIPPED / f"{name_or_path}.json"
    # os.path.isfile: a name too long for a file name is not an error here, just not shipped
    if "/" not in name_or_path and not name_or_path.endswith(".json") and os.path.isfile(shipped):
        return shipped
    path = Path(name_or_path)
    if not name_or_path or not os.path.lexists(path):
        names = ", ".join(sorted(p.stem for p in SHIPPED.glob("*.json")))
        raise ScenarioError(f"no scenario '{shown(name_or_path)}': give a file or one of: {names}")
    return path


def load(name_or_path: str) -> Scenario:
    """The scenario named (a shipped one) or at a path; ScenarioError naming the file otherwise."""
    path = resolve(name_or_path)
    try:
        payload = jsonfile.load(path, SCENARIO_BYTES)
        return parse(payload, default_name=path.stem)
    except (jsonfile.JsonError, ScenarioError) as err:
        message = str(err)
        prefix = shown(path)
        raise ScenarioError(
            message if message.startswith(prefix) else f"{prefix}: {message}"
        ) from None


def parse(payload: Any, default_name: str = "scenario") -> Scenario:
    """A scenario from its JSON document; `ScenarioError` names the JSON path of a bad value."""
    try:
        return _parse(payload, default_name)
    except jsonfile.JsonError as err:
        raise ScenarioError(str(err)) from None


def _parse(payload: Any, default_name: str) -> Scenario:
    top = jsonfile.expect_object(payload, "$")
    jsonfile.check_keys(top, _KEYS, "$")
    world = _section(top, "world", {"width", "height", "view", "views"})
    width = _int(world, "width", 201, "$.world", 1, MAX_SIDE)
    height = _int(world, "height", 201, "$.world", 1, MAX_SIDE)
    view = _int(world, "view", 1, "$.world", 0, MAX_VIEW)
    target_positions = _positions(top.get("target_positions"), width, height)
    targets = _counts(top.get("targets", [0]), "$.targets", 0, MAX_TARGETS)
    if target_positions is not None:
        targets = [len(target_positions)]
    station = _station(top.get("station", []))
    origin = top.get("clock_origin")
    if origin is not None:
        jsonfile.expect_str(origin, "$.clock_origin")
        if not any(s.event == origin for s in station):
            raise ScenarioError(f"$.clock_origin: '{origin}' is not a station event")
    return Scenario(
        name=jsonfile.expect_str(top.get("name", default_name), "$.name"),
        description=jsonfile.expect_str(top.get("description", ""), "$.description"),
        width=width,
        height=height,
        view=view,
        views=_views(jsonfile.expect_object(world.get("views", {}), "$.world.views")),
        members=_members(_section(top, "members", None)),
        placement=_placements(_section(top, "placement", None)),
        targets=targets,
        target_positions=target_positions,
        station=station,
        clock_origin=origin,
        timing=_timing(_section(top, "timing", set(TIMING_DEFAULTS))),
        allocation=_choice(top, "allocation", "paired", ALLOCATIONS, "$"),
        library=_library(_section(top, "library", None)),
        stop=_choice(top, "stop", "coverage", STOPS, "$"),
        stop_level=_number(top, "stop_level", 1.0, "$", 0.0, 1.0),
        max_ticks=_int(top, "max_ticks", 5_000_000, "$", 1, MAX_TICKS),
        reps=_int(top, "reps", 50, "$", 1, MAX_REPS),
        seed=_int(top, "seed", 1, "$", 0, MAX_SEED),
        coverage_levels=_fractions(top, "coverage_levels", Scenario("x").coverage_levels),
        target_levels=_fractions(top, "target_levels", Scenario("x").target_levels),
        detailed=_section(top, "detailed", None),
    )


def _section(top: dict[str, Any], key: str, known: set[str] | None) -> dict[str, Any]:
    value = jsonfile.expect_object(top.get(key, {}), f"$.{key}")
    if known is not None:
        jsonfile.check_keys(value, known, f"$.{key}")
    return value


def _int(obj: dict[str, Any], key: str, default: int, base: str, low: int, high: int) -> int:
    return jsonfile.expect_int(obj.get(key, default), jsonfile.key_path(base, key), low, high)


def _number(
    obj: dict[str, Any], key: str, default: float, base: str, low: float, high: float
) -> float:
    where = jsonfile.key_path(base, key)
    return jsonfile.expect_number(obj.get(key, default), where, low, high, above=True)


def _counts(value: Any, where: str, low: int, high: int) -> list[int]:
    items = value if isinstance(value, list) else [value]
    if not items:
        raise ScenarioError(f"{where}: needs at least one count")
    if len(items) > MAX_LIST:
        raise ScenarioError(f"{where}: more than {MAX_LIST:,} counts")
    prefix = where if not isinstance(value, list) else None
    return [
        jsonfile.expect_int(v, prefix or f"{where}[{i}]", low, high) for i, v in enumerate(items)
    ]


def _views(section: dict[str, Any]) -> dict[str, int]:
    return {
        kind: jsonfile.expect_int(value, jsonfile.key_path("$.world.views", kind), 0, MAX_VIEW)
        for kind, value in section.items()
    }


def _members(section: dict[str, Any]) -> dict[str, list[int] | str]:
    members: dict[str, list[int] | str] = {}
    for kind, value in section.items():
        where = jsonfile.key_path("$.members", kind)
        if isinstance(value, str):
            if not value.startswith("=") or len(value) < 2:
                raise ScenarioError(f'{where}: a string must be "=TYPE" (the same count as TYPE)')
            members[kind] = value
        else:
            members[kind] = _counts(value, where, 0, MAX_MEMBERS)
    return members


def _placements(section: dict[str, Any]) -> dict[str, Placement]:
    placement = {}
    for kind, value in section.items():
        where = jsonfile.key_path("$.placement", kind)
        item = jsonfile.expect_object(value, where)
        jsonfile.check_keys(item, {"layout", "spacing", "headings"}, where)
        placement[kind] = Placement(
            _choice(item, "layout", "south", LAYOUTS, where),
            _number(item, "spacing", 4.0, where, 0.0, float(MAX_SIDE)),
            _choice(item, "headings", "fan", HEADINGS, where),
        )
    return placement


def _choice(
    obj: dict[str, Any], key: str, default: str, choices: tuple[str, ...], base: str
) -> str:
    where = jsonfile.key_path(base, key)
    value = jsonfile.expect_str(obj.get(key, default), where)
    if value not in choices:
        raise ScenarioError(f"{where}: '{value}': choose one of {', '.join(choices)}")
    return value


def _positions(value: Any, width: int, height: int) -> list[tuple[int, int]] | None:
    if value is None:
        return None
    items = jsonfile.expect_list(value, "$.target_positions")
    if len(items) > min(MAX_TARGETS, width * height):
        raise ScenarioError(f"$.target_positions: more targets than patches ({width * height:,})")
    positions = []
    for i, item in enumerate(items):
        where = f"$.target_positions[{i}]"
        if not isinstance(item, list) or len(item) != 2:
            raise ScenarioError(f"{where}: expected a patch [x, y], {jsonfile.got(item)}")
        x = jsonfile.expect_int(item[0], f"{where}[0]", 0, width - 1)
        y = jsonfile.expect_int(item[1], f"{where}[1]", 0, height - 1)
        positions.append((x, y))
    if len(set(positions)) != len(positions):
        raise ScenarioError("$.target_positions: two targets on the same patch")
    return positions


def _station(value: Any) -> list[StationEvent]:
    items = jsonfile.expect_list(value, "$.station")
    if len(items) > MAX_LIST:
        raise ScenarioError(f"$.station: more than {MAX_LIST:,} events")
    station = []
    for i, item in enumerate(items):
        where = f"$.station[{i}]"
        entry = jsonfile.expect_object(item, where)
        jsonfile.check_keys(entry, {"tick", "event", "data"}, where)
        if "event" not in entry:
            raise ScenarioError(f"{where}: needs `event` (and `tick`)")
        data = entry.get("data")
        if data is not None:
            jsonfile.expect_object(data, f"{where}.data")
        station.append(
            StationEvent(
                _int(entry, "tick", 0, where, 0, MAX_TICKS),
                jsonfile.expect_str(entry["event"], f"{where}.event", empty=False),
                data,
            )
        )
    return station


def _timing(section: dict[str, Any]) -> dict[str, int]:
    timing = dict(TIMING_DEFAULTS)
    for key in section:
        if key == "tick_ms":
            timing[key] = _int(section, key, 1000, "$.timing", 1, MAX_TICK_MS)
        else:
            timing[key] = _int(section, key, 0, "$.timing", 0, MAX_TICKS)
    return timing


def _library(section: dict[str, Any]) -> dict[str, str]:
    return {
        k: jsonfile.expect_str(v, jsonfile.key_path("$.library", k), empty=False)
        for k, v in section.items()
    }


def _fractions(top: dict[str, Any], key: str, default: list[float]) -> list[float]:
    items = jsonfile.expect_list(top.get(key, default), f"$.{key}", empty=False)
    if len(items) > MAX_LIST:
        raise ScenarioError(f"$.{key}: more than {MAX_LIST:,} levels")
    return [
        jsonfile.expect_number(v, f"$.{key}[{i}]", 0.0, 1.0, above=False)
        for i, v in enumerate(items)
    ]


# --- the command line, and the limits of a whole sweep


def parse_members(text: str) -> dict[str, list[int]]:
    """`UAV=1,2,4,8` (several separated by ';' or given as repeated options)."""
    found: dict[str, list[int]] = {}
    for part in text.replace(";", " ").split():
        kind, sep, counts = part.partition("=")
        if not sep or not kind:
            raise ScenarioError(f"--members {shown(part)!r}: write TYPE=COUNT[,COUNT...]")
        found[kind] = parse_counts(counts, f"--members {shown(kind)}", 0, MAX_MEMBERS)
    if not found:
        raise ScenarioError("--members: write TYPE=COUNT[,COUNT...]")
    return found


def parse_counts(text: str, where: str, low: int = 0, high: int = MAX_TARGETS) -> list[int]:
    """`1,2,4` as counts in [low, high] (the limits are checked before anything runs)."""
    words = [v.strip() for v in text.split(",") if v.strip()]
    if len(words) > MAX_LIST:
        raise ScenarioError(f"{where}: more than {MAX_LIST:,} counts")
    try:
        values = [int(v) for v in words if v.isascii() and len(v) <= 20]
    except ValueError:
        values = []
    if not words or len(values) != len(words):
        raise ScenarioError(f"{where}: {shown(text)!r} is not a comma-separated list of integers")
    for value in values:
        if not low <= value <= high:
            raise ScenarioError(f"{where}: {value} is not a count from {low:,} to {high:,}")
    return values


def check(scenario: Scenario, types: Sequence[str], defaults: Mapping[str, int]) -> None:
    """The limits of the whole sweep, before anything runs: `types` are the model's member
    types with a state machine, `defaults` their swarm composition."""
    for kind in scenario.given:
        if kind not in types:
            close = difflib.get_close_matches(kind, types, n=1)
            hint = f"; did you mean {close[0]}?" if close else ""
            raise ScenarioError(
                f"--members {shown(kind)}: the model has no such member type{hint} "
                f"(it has: {', '.join(types)})"
            )
    sweeps: list[list[int]] = []
    for kind in types:
        spec = scenario.members.get(kind)
        if isinstance(spec, list):
            sweeps.append(spec)
        elif spec is None:
            sweeps.append([defaults.get(kind, 1)])
    largest = sum(max(s) for s in sweeps) if sweeps else 0
    follow = [s for s in scenario.members.values() if isinstance(s, str)]
    for spec in follow:  # "=UAV" doubles that type's count (at most)
        other = scenario.members.get(spec[1:])
        largest += max(other) if isinstance(other, list) else defaults.get(spec[1:], 0)
    _check_sweep(scenario, math.prod(len(s) for s in sweeps), largest)
    if sweeps and all(0 in s for s in sweeps):
        raise ScenarioError("a configuration of the sweep has no members: nothing to simulate")


def _check_sweep(scenario: Scenario, combinations: int, members: int) -> None:
    reps, patches = scenario.reps, scenario.width * scenario.height
    configurations = combinations * len(scenario.targets)
    problems = [
        (members, "members in a configuration", MAX_MEMBERS),
        (members * reps, f"members x repetitions ({members:,} x {reps:,})", MAX_MEMBER_RUNS),
        (patches * reps, f"patches x repetitions ({patches:,} x {reps:,})", MAX_PATCH_RUNS),
        (configurations * reps, f"runs ({configurations:,} configurations x {reps:,})", MAX_RUNS),
    ]
    for value, what, limit in problems:
        if value > limit:
            raise ScenarioError(
                f"{value:,} {what}: more than the limit of {limit:,} (docs/simulate.md)"
            )
    if max(scenario.targets) > patches:
        raise ScenarioError(
            f"{max(scenario.targets):,} targets: more than the {patches:,} patches of the world"
        )
    if scenario.max_ticks * scenario.timing["tick_ms"] * 1_000_000 > STAMP_NS:
        raise ScenarioError("max_ticks x tick_ms: the last tick is beyond 292 years of time")
