"""One detailed run, planned from the model and the scenario: the world file, the servers file
and the launcher's arguments (docs/detailed.md, "Running the detailed level"). Pure.

What the model decides, the generated code decides the same way: member namespaces are the
launcher's (`<module>_<n>`), a behaviour's endpoint and type are the rclpy backend's binding
(`private_views`), so the servers serve exactly what the unmodified nodes call. A member type
is a `uav` when it calls the library's `TakeOff` (it flies), else a `ugv`; its speed limit is
the scenario's, else its member datum `maxSpeed`, else its hardware's `maxSpeed`; its camera
radius the scenario's, else its hardware's `fovRadius` (none: no camera).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from swarmgen.backends.rclpy_backend import (
    BehaviourView,
    interfaces_package,
    member_modules,
    nodes_package,
    private_views,
)
from swarmgen.backends.rclpy_declared import declared_bindings
from swarmgen.chart.model import Chart
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import ModelIndex
from swarmgen.records import dataclass
from swarmgen.ros.idl_index import InterfaceIndex
from swarmgen.sim.batch import Config, run_draws
from swarmgen.sim.detailed.params import DetailedParams, MemberParams
from swarmgen.sim.grid import Geometry, fan_headings, south_line
from swarmgen.sim.scenario import Scenario, SimulationError

FLYING = "TakeOff"  # calling it makes a member type a uav
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
SERVERS_NAME = "servers"  # the `by` of the servers' barrier reports
LAUNCHER_NAME = "swarm_launcher"  # the launcher's station node: the swarm's reporter


@dataclass(frozen=True)
class MemberKind:
    """A member type as the detailed level runs it."""

    member_type: str
    module: str  # the launcher's node name: namespaces are `<module>_<n>`, flags `--<module>`
    kind: str  # uav | ugv
    max_speed: float
    fov_radius: float | None
    behaviours: dict[str, dict[str, Any]]  # the servers file's entries
    pose_topics: tuple[str, ...]  # subscribed PoseStamped topics the world also publishes


@dataclass(frozen=True)
class RunPlan:
    """The files and arguments of one run."""

    world: dict[str, Any]
    servers: dict[str, Any]
    launcher: list[str]  # arguments after `python -m <nodes>.launch_swarm`
    package: str  # the nodes package
    origin_s: float  # simulated time reported as 0 (the scenario's clock origin)
    members: int


class Planner:
    """Plans every run of a scenario on one model (the member kinds are decided once)."""

    def __init__(
        self,
        model: Model,
        charts: Sequence[Chart],
        index: InterfaceIndex | None,
        scenario: Scenario,
        params: DetailedParams,
    ) -> None:
        self.model, self.scenario, self.params = model, scenario, params
        members = [c for c in charts if c.member is not None]
        names = sorted({b.name for chart in members for b in chart.behaviours})
        own = (interfaces_package(model), nodes_package(model))
        views = private_views(model, tuple(charts), declared_bindings(model, names, index, own))
        modules = member_modules(charts)
        query = ModelIndex(model)  # built once: every member type reads its hardware from it
        self.kinds = {
            c.member or "": _member_kind(query, c, modules[c.name], views, scenario, params)
            for c in members
        }

    def plan(self, config: Config, rep: int) -> RunPlan:
        """The world and servers files and the launcher arguments of one repetition."""
        scenario, params = self.scenario, self.params
        key, targets = run_draws(scenario, config, rep)
        robots, members = self._robots(config)
        world = {
            "area": {"width": scenario.width * params.patch_m,
                     "height": scenario.height * params.patch_m},
            "cell": params.cell, "dt": params.dt, "substeps": params.substeps,
            "seed": key, "robots": robots,
            "targets": [
                {"id": n + 1, "x": params.metres(x), "y": params.metres(y)}
                for n, (x, y) in enumerate(targets)
            ],
            "stop": self._stop(bool(targets)),
            "settle_s": params.settle_s, "output": "result.json",
            # the exact barrier: the servers process and the swarm launcher's reporter
            "reporters": [SERVERS_NAME, LAUNCHER_NAME],
        }  # fmt: skip
        servers = {
            "dt": params.dt, "area": world["area"], "seed": key, "name": SERVERS_NAME,
            "events": {
                "type": f"{interfaces_package(self.model)}/msg/Event", "topic": "/swarm/events",
                "declared": sorted(e.name for e in self.model.events),
            },
            "params": dict(params.library), "members": members,
        }  # fmt: skip
        counts = dict(config.counts)
        launcher = ["--no-simulation", "--trace", "--events"]
        for kind in self.kinds.values():
            launcher += [f"--{kind.module}", str(counts.get(kind.member_type, 0))]
        station = ",".join(f"{s.event}@{params.seconds(s.tick):g}" for s in scenario.station)
        if station:
            launcher += ["--station", station]
        origin = params.seconds(scenario.origin_tick())
        return RunPlan(world, servers, launcher, nodes_package(self.model), origin, len(members))

    def _robots(self, config: Config) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
        """The world's robots and the servers' members, in model order."""
        geometry = Geometry(self.scenario.width, self.scenario.height, self.scenario.view)
        robots, members = [], []
        for member_type, count in config.counts:
            kind = self.kinds.get(member_type)
            if kind is None or count == 0:
                continue
            place = self.scenario.placement_of(member_type)
            xs, ys = south_line(count, geometry, place.spacing)
            north = [math.pi / 2] * count
            heads = list(fan_headings(count)) if place.headings == "fan" else north
            for n in range(count):
                name = f"{kind.module}_{n + 1}"
                robot: dict[str, Any] = {
                    "name": name, "namespace": name, "kind": kind.kind,
                    "max_speed": kind.max_speed,
                    "start": [self.params.metres(float(xs[n])), self.params.metres(float(ys[n]))],
                    "pose_topics": list(kind.pose_topics),
                }  # fmt: skip
                if kind.fov_radius is not None:
                    robot["fov_radius"] = kind.fov_radius
                robots.append(robot)
                heading = {"heading": float(heads[n])}
                members.append({
                    "namespace": name, "kind": kind.kind, "max_speed": kind.max_speed,
                    "behaviours": {
                        b: {**entry, "params": {**entry.get("params", {}), **heading}}
                        if entry.get("algorithm") == "Coverage" else entry
                        for b, entry in kind.behaviours.items()
                    },
                })  # fmt: skip
        return robots, members

    def _stop(self, has_targets: bool) -> dict[str, Any]:
        """The world's stop condition: the scenario's, within its time limit."""
        scenario = self.scenario
        stop: dict[str, Any] = {
            "time_s": self.params.time_limit(scenario) + self.params.seconds(scenario.origin_tick())
        }
        if scenario.stop == "coverage":
            stop["coverage"] = scenario.stop_level
        elif scenario.stop == "rescued" and has_targets:
            stop["all_rescued"] = True
        return stop


def _member_kind(
    index: ModelIndex,
    chart: Chart,
    module: str,
    views: dict[str, BehaviourView],
    scenario: Scenario,
    params: DetailedParams,
) -> MemberKind:
    """How a member type runs at the detailed level (the module docstring's rules)."""
    member_type = chart.member or chart.name
    given = params.members.get(member_type, MemberParams())
    model = index.model
    member = next(m for m in model.member_types if m.name == member_type)
    hardware = index.hardware_parameters(member)
    data = {p.name: p.default for p in member.data}
    speed = (
        given.max_speed
        or _number(data.get("maxSpeed"))
        or _number(hardware["maxSpeed"].default if "maxSpeed" in hardware else None)
    )
    if speed is None or speed <= 0:
        raise SimulationError(
            f"member type {member_type}: no speed limit (a `maxSpeed` datum or hardware "
            f"parameter, or `detailed.members.{member_type}.max_speed` in the scenario)"
        )
    fov = given.fov_radius or _number(
        hardware["fovRadius"].default if "fovRadius" in hardware else None
    )
    behaviours: dict[str, dict[str, Any]] = {}
    poses: list[str] = []
    for info in chart.behaviours:
        view = views[info.name]
        entry = _served(view, model, scenario.library.get(info.name, info.name))
        behaviours[info.name] = entry
        if entry["kind"] == "topic" and entry["rosType"] == POSE_TYPE and not info.inputs:
            poses.append(view.ros_name)
    flies = any(b.name == FLYING for b in chart.behaviours)
    return MemberKind(
        member_type, module, given.kind or ("uav" if flies else "ugv"), float(speed),
        fov, behaviours, tuple(poses),
    )  # fmt: skip


def _served(view: BehaviourView, model: Model, algorithm: str) -> dict[str, Any]:
    """The servers file's entry of a behaviour: its endpoint and type as the node calls it,
    and the library algorithm serving it (the scenario's `library` alias, else its name)."""
    declared = view.declared
    if declared is not None:
        b = declared.binding
        entry = {"kind": b.kind, "rosName": view.ros_name, "rosType": b.type}
    else:
        entry = {
            "kind": "action", "rosName": view.ros_name,
            "rosType": f"{interfaces_package(model)}/action/{view.action}",
        }  # fmt: skip
    entry["algorithm"] = algorithm
    return entry


def _number(value: Any) -> float | None:
    """A model default as a number, if it is one."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)
