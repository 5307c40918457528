"""Swarm composition: member counts and ROS names that would collide at run time."""

from __future__ import annotations

from collections.abc import Iterable

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import composition
from swarmgen.names import ros_name
from swarmgen.span import Span

# Members of one type in all swarms together (docs/profile.md). The ROS launch file names every
# member: compiling 1,000 takes about 6 s, 10,000 about a minute (measured, mostly formatting).
MAX_MEMBERS = 1_000


def check_counts(model: Model) -> list[Diagnostic]:
    """Every part needs at least one member, even where other parts of its type make the
    summed count (`query.composition`) positive: an empty part is a mistake, not a no-op.
    A type's summed count is at most MAX_MEMBERS."""
    found = [
        dg.BAD_COUNT.at(
            part.span,
            part=part.name,
            swarm=swarm.name,
            count=part.count,
            type=part.type_name,
        )
        for swarm in model.swarms
        for part in swarm.members
        if part.count < 1
    ]
    return found + _too_many(model)


def _too_many(model: Model) -> list[Diagnostic]:
    """Generated code and the simulator make one member object per member (a launch entry, a
    task): a count of 10^9 validated clean and then exhausted memory in `compile`."""
    found = []
    for type_name, total in composition(model).items():
        if total <= MAX_MEMBERS:
            continue
        parts = [
            (swarm, part)
            for swarm in model.swarms
            for part in swarm.members
            if part.type_name == type_name
        ]
        swarm, largest = max(parts, key=lambda sp: sp[1].count)
        if len(parts) == 1:
            found.append(
                dg.TOO_MANY_MEMBERS.at(
                    largest.span, swarm=swarm.name, total=total, type=type_name, limit=MAX_MEMBERS
                )
            )
            continue
        found.append(
            dg.TOO_MANY_MEMBERS.at(
                largest.span,
                "summed",
                notes=[dg.TOO_MANY_MEMBERS.note("part", part=largest.name, count=largest.count)],
                swarm=swarm.name,
                total=total,
                type=type_name,
                limit=MAX_MEMBERS,
                parts=len(parts),
            )
        )
    return found


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
                dg.ROS_NAME_COLLISION.at(
                    behaviour.span,
                    "types",
                    notes=[
                        dg.ROS_NAME_COLLISION.note("at", name=other[0], where=other[2].location())
                    ],
                    other=other[0],
                    behaviour=behaviour.name,
                    ros=behaviour.ros.name,
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
                dg.ROS_NAME_COLLISION.at(
                    span,
                    notes=[
                        dg.ROS_NAME_COLLISION.note("at", name=other[0], where=other[1].location())
                    ],
                    what=what,
                    other=other[0],
                    name=name,
                    ros=ros,
                )
            )
    return found
