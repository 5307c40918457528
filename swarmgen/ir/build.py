"""`build`: RawModel -> Model. Gives the raw XMI tree its UML and swarm-profile meaning.

Resolution problems (dangling references, wrong kinds, expressions that do not parse) are
reported here, with the element's span; semantic rules live in `swarmgen.check`.

One module per concern, beside this one: `build_context` (the shared state, references),
`build_classes` (data types, hardware, members, swarms), `build_library` (behaviours, events),
`build_machines` (regions, vertices, states), `build_transitions` (triggers, guards) and
`build_bodies` (actions and doActivity calls).
"""

from __future__ import annotations

from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawModel
from swarmgen.ir import acyclic
from swarmgen.ir.build_classes import (
    class_ancestry,
    read_datatype,
    read_enumeration,
    read_hardware,
    read_member,
    read_swarm,
)
from swarmgen.ir.build_context import (
    HARDWARE_KINDS,
    KNOWN_STEREOTYPES,
    Builder,
)
from swarmgen.ir.build_library import read_behaviour, read_event
from swarmgen.ir.build_machines import read_machine
from swarmgen.ir.nodes import (
    Model,
)


def build(raw: RawModel) -> tuple[Model, list[Diagnostic]]:
    """Build the IR from the raw model; returns it with the diagnostics of resolution."""
    b = Builder(raw)
    b.index_stereotypes()
    elements = list(raw.elements())
    classes = [e for e in elements if e.uml_type in {"Class", "Component"}]
    ancestry = class_ancestry(b, classes)
    hardware_classes = {e.id for e in classes if e.id and b.stereotype(e, HARDWARE_KINDS)}
    b.diags += acyclic.class_cycles(raw, elements, hardware_classes)
    enumerations = tuple(read_enumeration(e) for e in elements if e.uml_type == "Enumeration")
    for enumeration in enumerations:  # before any property: defaults name their literals
        b.enumerations.setdefault(enumeration.name, enumeration)
    datatypes = tuple(read_datatype(b, e) for e in elements if e.uml_type == "DataType")
    hardware = tuple(h for e in classes if (h := read_hardware(b, e, ancestry)) is not None)
    hardware_ids = {h.id for h in hardware}
    members = tuple(m for e in classes if (m := read_member(b, e, hardware_ids)) is not None)
    member_ids = {m.id for m in members}
    swarms = tuple(s for e in classes if (s := read_swarm(b, e, member_ids)) is not None)
    for e in elements:
        if e.uml_type == "Operation" and (beh := read_behaviour(b, e)) is not None:
            b.behaviours[beh.id] = beh
    for e in elements:
        if e.uml_type == "Signal":
            event = read_event(b, e)
            b.events_by_signal[event.id] = event
            b.events_by_name.setdefault(event.name, event)
    machines = tuple(
        read_machine(b, e)
        for e in elements
        if e.uml_type in {"StateMachine", "ProtocolStateMachine"}
    )
    uses_profile = any(a.name in KNOWN_STEREOTYPES for a in raw.stereotypes)
    model = Model(
        name=raw.roots[0].name if raw.roots else "",
        source=raw.file,
        exporter=raw.exporter,
        datatypes=datatypes,
        enumerations=enumerations,
        hardware=hardware,
        member_types=members,
        swarms=swarms,
        behaviours=tuple(b.behaviours.values()),
        events=tuple(b.events_by_signal.values()),
        machines=machines,
        uses_profile=uses_profile,
    )
    return model, b.diags
