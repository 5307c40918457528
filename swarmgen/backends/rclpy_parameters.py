"""How model values travel in the rclpy backend's private action fields (`field_type`,
`FieldView`) and in the ROS parameters of a generated member node (`PARAMETERS`): member data
defaults, the hardware model (read only) and each behaviour's declared `rosKind`/`rosName`/
`rosType` (read only metadata). Names the runtime declares itself (`behaviours.<key>.timeout_s`
of service and topic bindings) are reserved, so no generated parameter takes them."""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from typing import Any

from swarmgen.backends.pyrender import py_literal
from swarmgen.backends.rclpy_messages import DataMessages, field_name
from swarmgen.chart.model import BehaviourInfo, Chart
from swarmgen.ir.nodes import Model, Value
from swarmgen.ir.primitives import primitive
from swarmgen.names import IdAllocator, ros_name
from swarmgen.records import dataclass
from swarmgen.ros.idl_bind import Renames
from swarmgen.ros.interfaces import interface_type

_NO_MESSAGES: Mapping[str, str] = {}


def field_type(
    type_name: str | None,
    many: bool = False,
    enumerations: Collection[str] = (),
    messages: Mapping[str, str] = _NO_MESSAGES,
) -> str:
    """How a value of a model type travels in a ROS field of the private action: float64,
    int64, bool, string, enum (a string field holding the literal's name), a message of a
    data type (`messages`: model type -> `swarm_interfaces/Pose`), an array of these for a
    sequence (`float64[]`; `string[]` of literals), or json (a string field carrying JSON:
    data types without a message, untyped values, and sequences of either)."""
    if type_name is not None and type_name in messages:
        return f"{messages[type_name]}{'[]' if many else ''}"
    if many:
        element = field_type(type_name, False, enumerations)
        if element == "json":
            return "json"
        return f"{'string' if element == 'enum' else element}[]"
    if type_name is not None and type_name in enumerations:
        return "enum"
    if primitive(type_name) is None:
        return "json"
    return interface_type(type_name)


@dataclass(frozen=True)
class FieldView:
    """One behaviour argument or output as a field of its ROS action."""

    name: str  # the model's identifier (argument / output)
    field: str  # ROS field name
    type: str  # float64, int64, bool, string, enum, json, or an array `float64[]` (`field_type`)
    model_type: str | None  # `T[]` for a sequence of T (as `interfaces.interface_type` reads it)
    renames: Renames = ()  # a data type's keys its message's fields spell otherwise


def field_view(
    info: BehaviourInfo,
    parameter: tuple[str, str | None],
    taken: set[str],
    enumerations: frozenset[str],
    messages: DataMessages | None = None,
) -> FieldView:
    """One input or output of a private action: its field name and how its value travels
    (a data type of `messages` as its message, with its renames)."""
    ident, type_ = parameter
    many = ident in info.sequences
    model_type = f"{type_ or ''}[]" if many else type_
    types = messages.types if messages is not None else _NO_MESSAGES
    kind = field_type(type_, many, enumerations, types)
    renames = messages.renames.get(type_ or "", ()) if messages is not None else ()
    return FieldView(ident, field_name(ident, taken), kind, model_type, renames)


def parameter_type(
    type_name: str | None, many: bool = False, enumerations: Collection[str] = ()
) -> str:
    """The type of a node parameter holding a model value: as `field_type`, but a sequence is
    a JSON string and an enumeration a string (parameters carry no arrays of data here)."""
    if many:
        return "json"
    found = field_type(type_name, False, enumerations)
    return "string" if found == "enum" else found


def _parameter(name: str, type_: str, default: Value, **extra: Any) -> str:
    options = "".join(f", {k}={v!r}" for k, v in extra.items() if v not in (None, False, ""))
    return f"Parameter({name!r}, {type_!r}, {py_literal(default)}{options})"


def member_parameters(
    model: Model, chart: Chart, runs_as: Mapping[str, str], reserved: Iterable[str] = ()
) -> list[str]:
    """`Parameter(...)` literals of a member node; `runs_as` says per behaviour (model name)
    how it runs (for the description), `reserved` are names the runtime declares."""
    taken = IdAllocator()
    for name in reserved:
        taken.claim(name)
    enums = {e.name for e in model.enumerations}
    member = next((m for m in model.member_types if m.name == chart.member), None)
    many = {p.ident for p in member.data if p.many} if member is not None else set()
    found = [
        _parameter(
            taken.claim(f"data.{ros_name(item.id)}"),
            parameter_type(item.type, item.id in many, enums),
            item.initial,
            data=item.id,
            description=f"member data {item.name} ({_type_text(item.type, item.id in many)})",
        )
        for item in chart.data
    ]
    found += _hardware_parameters(model, chart, taken, enums)
    for info in chart.behaviours:
        prefix = f"behaviours.{ros_name(info.name)}"
        for key in ("ros_kind", "ros_name", "ros_type"):
            value = getattr(info, key)
            if value:
                found.append(
                    _parameter(
                        taken.claim(f"{prefix}.{key}"),
                        "string",
                        value,
                        read_only=True,
                        description=f"declared by the model; {runs_as[info.name]}",
                    )
                )
    return found


def _hardware_parameters(
    model: Model, chart: Chart, taken: IdAllocator, enums: Collection[str]
) -> list[str]:
    """The member's hardware: part counts, component parameters and communication settings."""
    member = next((m for m in model.member_types if m.name == chart.member), None)
    components = {h.id: h for h in model.hardware}
    found = []
    for part in member.hardware if member is not None else ():
        prefix = f"hardware.{ros_name(part.name)}"
        found.append(
            _parameter(
                taken.claim(f"{prefix}.count"),
                "int64",
                part.count,
                read_only=True,
                description=f"{part.name}: {part.count} x {part.type_name}",
            )
        )
        component = components.get(part.type_id)
        if component is None:
            continue
        for prop in component.parameters:
            found.append(
                _parameter(
                    taken.claim(f"{prefix}.{ros_name(prop.ident)}"),
                    parameter_type(prop.type, prop.many, enums),
                    prop.default,
                    read_only=True,
                    description=f"{component.name}.{prop.name} ({prop.type or 'untyped'})",
                )
            )
        for key in ("communication_type", "communication_params"):
            value = getattr(component, key)
            if value is not None:
                found.append(
                    _parameter(taken.claim(f"{prefix}.{key}"), "string", value, read_only=True)
                )
    return found


def _type_text(type_name: str | None, many: bool) -> str:
    """A datum's type as a parameter description says it (`Real[*]` for a sequence)."""
    return f"{type_name or 'untyped'}{'[*]' if many else ''}"
