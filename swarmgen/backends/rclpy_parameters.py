"""The ROS parameters of a generated member node (`PARAMETERS`): member data defaults, the
hardware model (read only) and each behaviour's declared `rosKind`/`rosName`/`rosType` (read
only metadata). Names the runtime declares itself (`behaviours.<key>.timeout_s` of service and
topic bindings) are reserved, so no generated parameter takes them."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from swarmgen.backends.pyrender import py_literal
from swarmgen.chart.model import Chart
from swarmgen.ir.nodes import Model, Value
from swarmgen.names import IdAllocator, ros_name
from swarmgen.ros.interfaces import interface_type


def field_type(type_name: str | None) -> str:
    """How a value of a model type travels in a ROS field: float64, int64, bool, string, or
    json (a string field carrying JSON: data types such as Pose, and untyped values)."""
    ros = interface_type(type_name)
    if ros == "string" and (type_name or "").strip().lower() != "string":
        return "json"
    return ros


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
    found = [
        _parameter(
            taken.claim(f"data.{ros_name(item.id)}"),
            field_type(item.type),
            item.initial,
            data=item.id,
            description=f"member data {item.name} ({item.type or 'untyped'})",
        )
        for item in chart.data
    ]
    found += _hardware_parameters(model, chart, taken)
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


def _hardware_parameters(model: Model, chart: Chart, taken: IdAllocator) -> list[str]:
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
                    field_type(prop.type) if prop.type else "json",
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
