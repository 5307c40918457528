"""The servers file (JSON) the behaviour servers read: members, their behaviours' declared
interfaces and algorithms, the swarm's event type and topics, the algorithms' parameters.

    {"dt": 0.1, "area": {"width": 66, "height": 66}, "seed": 1, "name": "servers_uav",
     "events": {"type": "search_and_rescue_interfaces/msg/Event", "topic": "/swarm/events",
                "declared": ["targetFound", "targetAssigned", "targetRescued"]},
     "auction_topic": "/swarm/auction",
     "params": {"tolerance": 0.05, ...},                       # PARAMS, all optional
     "members": [{"namespace": "uav_1", "kind": "uav", "max_speed": 0.8,
                  "behaviours": {"TakeOff": {"kind": "action", "rosName": "cmd/takeoff",
                                             "rosType": "cpswarm_msgs/action/Takeoff",
                                             "algorithm": "TakeOff", "params": {}}}}]}

`algorithm` defaults to the behaviour's name; a behaviour's `params` override the file's.
`name` is the `by` of the process's step reports (default `servers_` + the first member's
namespace): stable from run to run, and distinct for processes serving disjoint members.
Everything is checked here; a bad file raises `ConfigError` naming the member and behaviour.
"""

from __future__ import annotations

import importlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .geometry import Area

# The algorithms' parameters and their defaults (seconds and metres of simulated time/space).
PARAMS: dict[str, float] = {
    "tolerance": 0.05,  # MoveTo / TakeOff / Land: arrived within this 3-D distance
    "auction_window": 1.0,  # TaskAllocation: bids are taken for this long
    "bid_grace": 1.0,  # TaskBidding: wait this long past the deadline for the result
    "bid_timeout": 5.0,  # TaskBidding: abort when no auction opens for the target by then
    "rescue_s": 1.0,  # Rescue: time spent at the target
    "spacing": 1.0,  # LocalCoverage: metres between the spiral's turns
    "local_duration": 30.0,  # LocalCoverage: aborted after this long
    "heading": 1.5707963267948966,  # Coverage: the first leg's direction (radians from east)
    "single_target": 0.0,  # Coverage: 1 = succeed on the member's first find
}


class ConfigError(ValueError):
    """The servers file is unreadable or names something that does not exist."""


@dataclass(frozen=True)
class BehaviourConfig:
    """One behaviour of a member: its declared interface and the algorithm serving it."""

    name: str
    kind: str  # action | service | topic
    ros_name: str
    ros_type: str  # pkg/action|srv|msg/Name
    algorithm: str
    params: dict[str, float]


@dataclass(frozen=True)
class MemberConfig:
    """A member: its namespace (the robot's name in the world), kind, speed and behaviours."""

    namespace: str
    kind: str
    max_speed: float
    behaviours: dict[str, BehaviourConfig]


@dataclass(frozen=True)
class ServersConfig:
    """The whole servers file."""

    dt: float
    area: Area
    seed: int
    event_type: str
    event_topic: str
    declared_events: frozenset[str]
    auction_topic: str
    members: tuple[MemberConfig, ...]
    params: dict[str, float] = field(default_factory=dict)
    name: str = "servers"
    clients_timeout_s: float = 15.0  # wall seconds to wait for every server's client


def _number(where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{where}: a number is needed, got {value!r}")
    return float(value)


def _seed(value: Any) -> int:
    """The run key, exactly: a 64-bit integer does not survive a float (53 bits)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ConfigError(f"seed: a whole number >= 0 is needed, got {value!r}")
    return value


def _params(where: str, raw: Any, base: dict[str, float]) -> dict[str, float]:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: params must be an object")
    unknown = sorted(set(raw) - set(PARAMS))
    if unknown:
        raise ConfigError(f"{where}: unknown params {unknown} (known: {sorted(PARAMS)})")
    return {**base, **{k: _number(f"{where}.{k}", v) for k, v in raw.items()}}


def _behaviour(where: str, name: str, raw: Any, base: dict[str, float]) -> BehaviourConfig:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: a behaviour must be an object")
    kind = raw.get("kind")
    if kind not in ("action", "service", "topic"):
        raise ConfigError(f"{where}: kind must be action, service or topic, got {kind!r}")
    ros_type = str(raw.get("rosType", ""))
    if ros_type.count("/") != 2:
        raise ConfigError(f"{where}: rosType must be pkg/action|srv|msg/Name, got {ros_type!r}")
    if not raw.get("rosName"):
        raise ConfigError(f"{where}: rosName is missing")
    return BehaviourConfig(
        name=name,
        kind=kind,
        ros_name=str(raw["rosName"]),
        ros_type=ros_type,
        algorithm=str(raw.get("algorithm", name)),
        params=_params(where, raw.get("params", {}), base),
    )


def _member(index: int, raw: Any, base: dict[str, float]) -> MemberConfig:
    if not isinstance(raw, dict) or not raw.get("namespace"):
        raise ConfigError(f"members[{index}]: an object with a namespace is needed")
    namespace = str(raw["namespace"]).strip("/")
    behaviours = raw.get("behaviours", {})
    if not isinstance(behaviours, dict):
        raise ConfigError(f"member {namespace}: behaviours must be an object")
    return MemberConfig(
        namespace=namespace,
        kind=str(raw.get("kind", "uav")),
        max_speed=_number(f"member {namespace}: max_speed", raw.get("max_speed")),
        behaviours={
            name: _behaviour(f"member {namespace}, behaviour {name}", name, spec, base)
            for name, spec in behaviours.items()
        },
    )


def parse(raw: Any) -> ServersConfig:
    """The servers file's content (parsed JSON) as a `ServersConfig`."""
    if not isinstance(raw, dict):
        raise ConfigError("the servers file must hold a JSON object")
    area = raw.get("area", {})
    events = raw.get("events", {})
    params = _params("params", raw.get("params", {}), dict(PARAMS))
    try:
        shape = Area(
            _number("area.width", area.get("width")), _number("area.height", area.get("height"))
        )
    except (AttributeError, ValueError) as err:
        raise ConfigError(f"area: {err}") from None
    members = tuple(_member(i, m, params) for i, m in enumerate(raw.get("members", [])))
    names = [m.namespace for m in members]
    if not members or len(set(names)) != len(names):
        raise ConfigError(f"members: at least one, with unique namespaces, needed: {names}")
    return ServersConfig(
        dt=_number("dt", raw.get("dt", 0.1)),
        area=shape,
        seed=_seed(raw.get("seed", 0)),
        event_type=str(events.get("type", "")),
        event_topic=str(events.get("topic", "/swarm/events")),
        declared_events=frozenset(events.get("declared", [])),
        auction_topic=str(raw.get("auction_topic", "/swarm/auction")),
        members=members,
        params=params,
        name=str(raw.get("name") or f"servers_{members[0].namespace}"),
        clients_timeout_s=_number("clients_timeout_s", raw.get("clients_timeout_s", 15.0)),
    )


def load(path: Path) -> ServersConfig:
    """Read and check a servers file."""
    try:
        return parse(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, json.JSONDecodeError) as err:
        raise ConfigError(f"{path}: {err}") from None


def import_type(name: str) -> Any:
    """The rclpy class of `pkg/action|srv|msg/Name`, imported by name (ConfigError if absent)."""
    package, sub, type_name = name.split("/")
    try:
        return getattr(importlib.import_module(f"{package}.{sub}"), type_name)
    except (ImportError, AttributeError) as err:
        raise ConfigError(f"unknown ROS type {name}: {err}") from None
