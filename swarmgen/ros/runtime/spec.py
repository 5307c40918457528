"""What generated member modules declare: a member type, its behaviours and its parameters."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ...runtime.chart import Chart


@dataclass(frozen=True, slots=True)
class Field:
    """A behaviour input or output: its model identifier, its ROS field and how it is encoded.

    `type` is the ROS field type (`float64`, `int64`, `bool`, `string`), `enum` (a `string`
    field holding a literal's name; empty: not given), an array of one of these (`float64[]`,
    `string[]` for enumerations: a model sequence) or `json`: a `string` field carrying the
    JSON text of a value of no declared type or a sequence of them, or a message of the
    interface package (`swarm_interfaces/Pose`, an array `swarm_interfaces/Pose[]`): a model
    DataType. `renames` are its model keys that the message's fields name otherwise
    (`(("posX", "pos_x", ()),)`, nested: the third item), passed to encode/decode. `enums`
    names the enumeration fields inside a message value (`(("mode", "search"),)`: model key,
    first literal; nested: pairs), whose empty strings decode as that literal.
    """

    name: str
    field: str
    type: str
    renames: tuple[tuple[str, str, tuple[Any, ...]], ...] = ()
    enums: Any = ()


@dataclass(frozen=True, slots=True)
class Binding:
    """A behaviour bound to a declared ROS 2 interface (`bindings.py` runs it).

    `type` is the ROS type triple (`geometry_msgs`, `msg`, `PoseStamped`); `kind` is `action`,
    `service` or `topic` (with `direction` `publish` or `subscribe`). `inputs` map behaviour
    inputs to field paths of the goal, request or message (`target_pose.pose.position.x`),
    `outputs` field paths of the result, response or message to behaviour outputs. A non-empty
    `outcome` names a field giving the outcome: a string naming it, or a bool (false: aborted).
    `timeout_s` (None: the kind's default) is the default of the ROS parameter
    `behaviours.<key>.timeout_s`. An empty field path is the whole goal, request or message.
    `renames` gives, per input or output, the dict keys of its value that the ROS fields name
    otherwise: `("input", "target", (("posX", "pos_x", ()),))` (nested: the third item).
    """

    kind: str
    type: tuple[str, str, str]
    ros_name: str  # relative to the member's namespace
    inputs: tuple[tuple[str, str], ...] = ()  # (input, field path)
    outputs: tuple[tuple[str, str], ...] = ()  # (field path, output)
    outcome: str = ""
    timeout_s: float | None = None
    direction: str = ""  # topics only
    key: str = ""  # the behaviour's parameter name (lower snake case); "" derives one
    renames: tuple[tuple[str, str, tuple[Any, ...]], ...] = ()  # (input|output, name, renames)
    # (output, blanks): its enumeration values, whose empty strings read as the first literal
    # (`convert.filled`: a literal, or (model key, blanks) pairs of a data type's fields)
    enums: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True, slots=True)
class BehaviourSpec:
    """A behaviour of the library as a ROS 2 action of the interface package."""

    name: str  # the model's behaviour name (what `Call.behaviour` holds)
    action: str  # action type in the interface package
    ros_name: str  # action name, relative to the member's namespace
    kind: str  # ComplexBehavior, SwarmBehavior, SwarmFunction, HardwareFunction
    inputs: tuple[Field, ...] = ()
    outputs: tuple[Field, ...] = ()
    outcomes: tuple[str, ...] = ()
    # rosKind, rosName, rosType as the model declares them ("" when absent): metadata only
    declared: tuple[str, str, str] = ("", "", "")
    # the declared interface it runs on; None: the action `action` of the interface package
    binding: Binding | None = None


@dataclass(frozen=True, slots=True)
class Parameter:
    """A ROS parameter of the member node; `data` names the member data item it initialises."""

    name: str
    type: str  # float64, int64, bool, string or json (a string parameter holding JSON)
    default: Any
    data: str | None = None
    read_only: bool = False
    description: str = ""


@dataclass(frozen=True, slots=True)
class MemberSpec:
    """A member type: its chart, its node name, its events' scopes, behaviours and parameters."""

    member_type: str  # the model's member type name
    chart_name: str  # identifier of the member type (module, script keys)
    node_name: str  # ROS node name (lower snake case)
    interfaces: str  # the interface package
    build: Callable[[], Chart]
    event_scopes: Mapping[str, str]  # event this member sends -> "swarm" or "local"
    behaviours: Mapping[str, BehaviourSpec]
    parameters: tuple[Parameter, ...] = ()


def namespace_id(namespace: str, fallback: str) -> str:
    """The default member id of a node: its namespace (`/uav_1` -> `uav_1`), else `fallback`."""
    return namespace.strip("/").replace("/", "_") or fallback


def index_of(member_id: str) -> int:
    """`uav_3` -> 3 (members are numbered from 1 within their type); 1 when there is no number."""
    tail = member_id.rsplit("_", 1)[-1]
    return int(tail) if tail.isdigit() else 1
