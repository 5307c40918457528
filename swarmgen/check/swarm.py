"""Swarm composition: member counts and ROS names that would collide at run time."""

from __future__ import annotations

from collections.abc import Iterable

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model
from swarmgen.names import ros_name
from swarmgen.span import Span


def check_counts(model: Model) -> list[Diagnostic]:
    """Every part needs at least one member, even where other parts of its type make the
    summed count (`query.composition`) positive: an empty part is a mistake, not a no-op."""
    return [
        dg.diag(
            dg.BAD_COUNT,
            f"part '{part.name}' of swarm '{swarm.name}' has {part.count} member(s) "
            f"of type '{part.type_name}'",
            part.span,
            hint="set the part's multiplicity to at least 1, or remove the part",
        )
        for swarm in model.swarms
        for part in swarm.members
        if part.count < 1
    ]


def check_ros_names(model: Model) -> list[Diagnostic]:
    """Member namespaces, behaviour interfaces and event names must stay distinct in ROS."""
    found = _collisions(
        "member types", ((m.name, ros_name(m.name), m.span) for m in model.member_types)
    )
    found += _collisions(
        "behaviours", ((b.name, ros_name(b.name), b.span) for b in model.behaviours)
    )
    found += _collisions("events", ((e.name, ros_name(e.name), e.span) for e in model.events))
    interfaces: dict[str, tuple[str, str | None, Span]] = {}
    for behaviour in model.behaviours:
        if behaviour.ros is None or not behaviour.ros.name:
            continue
        other = interfaces.setdefault(
            behaviour.ros.name, (behaviour.name, behaviour.ros.type, behaviour.span)
        )
        if other[0] != behaviour.name and other[1] != behaviour.ros.type:
            found.append(
                dg.diag(
                    dg.ROS_NAME_COLLISION,
                    f"behaviours '{other[0]}' and '{behaviour.name}' both use the ROS name "
                    f"'{behaviour.ros.name}' with different types",
                    behaviour.span,
                    notes=[f"'{other[0]}' is at {other[2].location()}"],
                    hint="give one of them another rosName",
                )
            )
    return found


def _collisions(what: str, items: Iterable[tuple[str, str, Span]]) -> list[Diagnostic]:
    first: dict[str, tuple[str, Span]] = {}
    found = []
    for name, ros, span in items:
        other = first.setdefault(ros, (name, span))
        if other[0] != name:
            found.append(
                dg.diag(
                    dg.ROS_NAME_COLLISION,
                    f"{what} '{other[0]}' and '{name}' both become the ROS name '{ros}'",
                    span,
                    notes=[f"'{other[0]}' is at {other[1].location()}"],
                    hint="rename one of them",
                )
            )
    return found
