"""The scenario's `detailed` block: how the abstract world maps onto the continuous one.

    "detailed": {
      "patch_m": 0.4, "tick_s": 0.5,            one abstract patch and tick in metres, seconds
      "dt": 0.1, "cell_m": 0.4,                 the world's step and coverage cell
      "frame_s": 0.1,                           the cameras' frame period (at most; dt/n)
      "members": {"UAV": {"max_speed": 0.8, "fov_radius": 0.5, "kind": "uav"}},
      "time_limit_s": 3600, "wall_limit_s": 900, "settle_s": 0.05,
      "library": {"auction_window": 1.0}        the behaviour servers' parameters
    }

Every key is optional. The area is `width x height` patches of `patch_m`; starts, targets and
station times are the abstract scenario's, converted (a tick is `tick_s` simulated seconds),
so both levels of one scenario and seed place the same members and targets and draw the same
turn angles. A member type's speed limit and camera radius come from here, else from the model
(docs/detailed.md, "Running the detailed level").
"""

from __future__ import annotations

import math
from dataclasses import field
from typing import Any

from swarmgen import jsonfile
from swarmgen.records import dataclass
from swarmgen.sim.scenario import Scenario, ScenarioError

KINDS = ("uav", "ugv")
MEMBER_KEYS = {"max_speed", "fov_radius", "kind"}
KEYS = {
    "patch_m", "tick_s", "dt", "frame_s", "cell_m", "members", "time_limit_s", "wall_limit_s",
    "settle_s", "library",
}  # fmt: skip
MAX_SECONDS = 10 * 24 * 3600.0


@dataclass(frozen=True)
class MemberParams:
    """What the scenario says about one member type (None: the model decides)."""

    max_speed: float | None = None
    fov_radius: float | None = None
    kind: str | None = None


@dataclass(frozen=True)
class DetailedParams:
    """The `detailed` block, checked, with its defaults."""

    patch_m: float = 66.0 / 201  # the shipped scenarios' 201 patches are the paper's 66 m
    tick_s: float = 0.5  # the paper's abstract tick
    dt: float = 0.1
    frame_s: float = 0.1  # the cameras look at least this often (world sub-steps)
    cell_m: float | None = None  # None: one patch
    members: dict[str, MemberParams] = field(default_factory=dict)
    time_limit_s: float | None = None  # None: the scenario's max_ticks, converted
    wall_limit_s: float = 900.0
    settle_s: float = 0.05
    library: dict[str, float] = field(default_factory=dict)

    def seconds(self, ticks: float) -> float:
        """Abstract ticks as simulated seconds."""
        return ticks * self.tick_s

    def metres(self, patch: float) -> float:
        """A patch coordinate (patch centres at integers) as metres from the area's corner."""
        return (patch + 0.5) * self.patch_m

    @property
    def substeps(self) -> int:
        """Camera frames per world step: the fewest that keep the frame period <= `frame_s`
        (the step is the control period; a camera sees between two commands too)."""
        return max(1, math.ceil(self.dt / self.frame_s - 1e-9))

    @property
    def cell(self) -> float:
        """The coverage cell's side in metres."""
        return self.cell_m if self.cell_m is not None else self.patch_m

    def time_limit(self, scenario: Scenario) -> float:
        """The simulated seconds a run may take."""
        if self.time_limit_s is not None:
            return self.time_limit_s
        return min(self.seconds(scenario.max_ticks), MAX_SECONDS)


def detailed_params(scenario: Scenario) -> DetailedParams:
    """The scenario's `detailed` block (ScenarioError names the JSON path of a bad value)."""
    try:
        return _params(scenario.detailed)
    except jsonfile.JsonError as err:
        raise ScenarioError(str(err)) from None


def _params(raw: dict[str, Any]) -> DetailedParams:
    jsonfile.check_keys(raw, KEYS, "$.detailed")
    members = jsonfile.expect_object(raw.get("members", {}), "$.detailed.members")
    library = jsonfile.expect_object(raw.get("library", {}), "$.detailed.library")
    limit = raw.get("time_limit_s")
    return DetailedParams(
        patch_m=_positive(raw, "patch_m", 66.0 / 201),
        tick_s=_positive(raw, "tick_s", 0.5),
        dt=_positive(raw, "dt", 0.1),
        frame_s=_positive(raw, "frame_s", 0.1),
        cell_m=None if raw.get("cell_m") is None else _positive(raw, "cell_m", 1.0),
        members={kind: _member(kind, value) for kind, value in members.items()},
        time_limit_s=None if limit is None else _positive(raw, "time_limit_s", 1.0),
        wall_limit_s=_positive(raw, "wall_limit_s", 900.0),
        settle_s=_number(raw, "settle_s", 0.05, "$.detailed", low=0.0),
        library={
            key: _number(library, key, 0.0, "$.detailed.library", low=-math.inf) for key in library
        },
    )


def _member(kind: str, value: Any) -> MemberParams:
    where = jsonfile.key_path("$.detailed.members", kind)
    item = jsonfile.expect_object(value, where)
    jsonfile.check_keys(item, MEMBER_KEYS, where)
    body = item.get("kind")
    if body is not None and body not in KINDS:
        raise ScenarioError(f"{where}.kind: must be one of {', '.join(KINDS)}, got {body!r}")
    return MemberParams(
        max_speed=None if "max_speed" not in item else _positive(item, "max_speed", 1.0, where),
        fov_radius=None if "fov_radius" not in item else _positive(item, "fov_radius", 1.0, where),
        kind=body,
    )


def _positive(obj: dict[str, Any], key: str, default: float, base: str = "$.detailed") -> float:
    return _number(obj, key, default, base, low=0.0, above=True)


def _number(
    obj: dict[str, Any],
    key: str,
    default: float,
    base: str,
    *,
    low: float,
    above: bool = False,
) -> float:
    where = jsonfile.key_path(base, key)
    return jsonfile.expect_number(obj.get(key, default), where, low, MAX_SECONDS, above=above)
