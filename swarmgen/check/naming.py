"""Names in generated code and files: two model names that become one identifier, and names
that make file names or paths Windows cannot hold."""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from typing import Protocol

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import ModelIndex
from swarmgen.names import ros_name
from swarmgen.span import Span


class _Named(Protocol):
    @property
    def name(self) -> str: ...
    @property
    def ident(self) -> str: ...
    @property
    def span(self) -> Span: ...


def check_collisions(model: Model) -> list[Diagnostic]:
    """Report model names that collide once made identifiers, and unsafe file names."""
    found: list[Diagnostic] = []
    found += _collisions("member type", model.member_types)
    found += _collisions("behaviour", model.behaviours)
    found += _collisions("event", model.events)
    found += _collisions("state machine", model.machines)
    for event in model.events:
        found += _collisions(f"field of event '{event.name}'", event.fields)
    for member in model.member_types:
        found += _collisions(f"member data of '{member.name}'", member.data)
    for behaviour in model.behaviours:
        found += _collisions(f"input of '{behaviour.name}'", behaviour.inputs)
        found += _collisions(f"output of '{behaviour.name}'", behaviour.outputs)
    return found


def _collisions(what: str, items: Iterable[_Named]) -> list[Diagnostic]:
    first: dict[str, _Named] = {}
    found = []
    for item in items:
        other = first.setdefault(item.ident, item)
        if other is item:
            continue
        same = other.name == item.name
        values = {"what": what, "name": item.name}
        if not same:
            values |= {"other": other.name, "ident": item.ident}
        found.append(
            dg.NAME_COLLISION.at(
                item.span,
                "twice" if same else dg.DEFAULT,
                notes=[dg.NAME_COLLISION.note("other-at", where=other.span.location())],
                **values,
            )
        )
    return found


# --- output paths: names decide file names (docs/profile.md, "Names that become files")

# Device names Windows reserves in every directory, with any extension (`con.scxml`, `Aux.action`).
_RESERVED_FILE = re.compile(r"(?:con|prn|aux|nul|com[0-9]|lpt[0-9])", re.IGNORECASE)
PATH_LIMIT = 260  # Windows' MAX_PATH, drive and output directory included
OUTPUT_DIR_ALLOWANCE = 60  # what we leave for the `-o` directory (`C:\Users\...\generated\sar\`)
# The longest fixed file name under a generated package (the vendored runtime).
_LONGEST_RUNTIME_FILE = "_runtime/simulated.py"


def check_output_paths(model: Model) -> list[Diagnostic]:
    """A name that makes a file Windows cannot create (`con.py`) or a path Windows cannot
    open: warnings naming the element and the output path, for models shared across systems."""
    found: list[Diagnostic] = []
    for what, name, span, paths in _named_paths(model):
        reserved = [p for p in paths if _reserved(p)]
        if reserved:
            found.append(
                dg.RESERVED_FILE_NAME.at(
                    span,
                    notes=[dg.RESERVED_FILE_NAME.note("also", files=", ".join(reserved[1:]))]
                    if len(reserved) > 1
                    else [],
                    what=what,
                    name=name,
                    file=reserved[0],
                )
            )
        longest = max(paths, key=len)
        if len(longest) > PATH_LIMIT - OUTPUT_DIR_ALLOWANCE:
            found.append(
                dg.PATH_TOO_LONG.at(
                    span, what=what, name=name, path=longest, length=len(longest), limit=PATH_LIMIT
                )
            )
    return found


def _reserved(path: str) -> bool:
    return any(_RESERVED_FILE.fullmatch(part.split(".", 1)[0]) for part in path.split("/"))


def _named_paths(model: Model) -> Iterator[tuple[str, str, Span, list[str]]]:
    """(kind, name, span, generated paths) of each element whose name makes a path: the
    layout the backends write (scxml/, asyncio/, smach/, rclpy/, diagrams/), mirrored here
    because a check may not import them."""
    index = ModelIndex(model)
    swarm = ros_name(model.name or "swarm")
    nodes = f"rclpy/{swarm}_nodes/{swarm}_nodes"
    yield (
        "model",
        model.name,
        Span(file=model.source, path=model.name),
        [
            f"{nodes}/{_LONGEST_RUNTIME_FILE}",
            f"asyncio/{swarm}_swarm/__main__.py",
            f"rclpy/{swarm}_nodes/launch/{swarm}.launch.py",
        ],
    )
    for member in model.member_types:
        if member.machine in index.machines:
            yield "member type", member.name, member.span, _chart_paths(member.ident, nodes, swarm)
    wrapped = {s for m in model.machines for s in index.submachines(m)}
    run = {m.id for member in model.member_types for m in index.member_machines(member)}
    for machine in model.machines:
        paths = [f"diagrams/{machine.ident}.mmd"]
        if machine.id not in wrapped and machine.id not in run:
            paths += _chart_paths(machine.ident, nodes, swarm)
        yield "state machine", machine.name, machine.span, paths
    called = {b.id for m in model.machines for b in index.behaviours_of(m)}
    for behaviour in model.behaviours:
        if behaviour.id in called:
            action = _camel(behaviour.ident)
            yield (
                "behaviour",
                behaviour.name,
                behaviour.span,
                [f"rclpy/{swarm}_interfaces/action/{action}.action"],
            )


def _chart_paths(ident: str, nodes: str, swarm: str) -> list[str]:
    module = ros_name(ident)
    return [
        f"scxml/{ident}.scxml",
        f"asyncio/{swarm}_swarm/{module}.py",
        f"smach/{swarm}_swarm/{module}.py",
        f"{nodes}/{module}.py",
    ]


def _camel(ident: str) -> str:
    """The ROS action type of a behaviour, as the rclpy backend names it (`move_to` -> MoveTo)."""
    text = "".join(p[:1].upper() + p[1:] for p in re.split(r"[^0-9A-Za-z]+", ident) if p)
    return text if text[:1].isalpha() else f"B{text}"
