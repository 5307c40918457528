"""Building state machines: regions, vertices, states with their actions and submachines."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.frontend.raw import RawElement
from swarmgen.ir.build_bodies import actions_of, activity_call
from swarmgen.ir.build_context import (
    Builder,
    is_part,
    label,
)
from swarmgen.ir.build_invoke import invokes_of
from swarmgen.ir.build_transitions import MachineContext, read_transition
from swarmgen.ir.nodes import (
    ConnectionRef,
    FinalState,
    Machine,
    OpaqueCode,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    Vertex,
)
from swarmgen.names import identifier


def read_machine(b: Builder, element: RawElement) -> Machine:
    """A state machine: its regions, connection points, transitions and its owner's data."""
    ctx = MachineContext()
    regions = _regions(b, element, ctx)
    points = _connection_points(b, element, ctx)
    owner = element.parent if element.feature == "ownedBehavior" else None
    attributes = list(owner.kids("ownedAttribute")) if owner is not None else []
    data = tuple(b.prop(a) for a in attributes if not is_part(a))
    transitions = tuple(
        t for raw in ctx.transitions if (t := read_transition(b, raw, ctx)) is not None
    )
    return Machine(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name, "machine"),
        owner=owner.id if owner is not None else None,
        regions=regions,
        connection_points=points,
        transitions=transitions,
        data=data,
        span=element.span,
    )


def _misplaced(b: Builder, element: RawElement, variant: str, **values: str) -> None:
    """Report an element that does not belong where it stands (SG140, `variant` says why)."""
    kind = element.uml_type or "element of unknown type"
    b.diags.append(
        dg.UNEXPECTED_ELEMENT.at(
            element.span,
            variant,
            feature=element.feature,
            label=label(element),
            kind=kind,
            **values,
        )
    )


def _regions(b: Builder, owner: RawElement, ctx: MachineContext) -> tuple[Region, ...]:
    for region in owner.kids("region"):
        if region.uml_type != "Region":
            _misplaced(b, region, "not-a-region")
    return tuple(_region(b, r, ctx) for r in owner.kids("region"))


def _connection_points(
    b: Builder, owner: RawElement, ctx: MachineContext
) -> tuple[Pseudostate, ...]:
    points = []
    for point in owner.kids("connectionPoint"):
        if point.uml_type != "Pseudostate" or point.attrs.get("kind") not in _POINT_KINDS:
            _misplaced(b, point, "not-a-connection-point")
            continue
        points.append(_pseudostate(b, point, ctx))
    return tuple(points)


_POINT_KINDS = {PseudoKind.ENTRY_POINT.value, PseudoKind.EXIT_POINT.value}
_VERTEX_TYPES = {"State", "FinalState", "Pseudostate"}


def _region(b: Builder, element: RawElement, ctx: MachineContext) -> Region:
    for transition in element.kids("transition"):
        if transition.uml_type != "Transition":
            _misplaced(b, transition, "not-a-transition")
        ctx.transitions.append(transition)
    vertices: list[Vertex] = []
    for sub in element.kids("subvertex"):
        vertex = _vertex(b, sub, ctx)
        if vertex is not None:
            vertices.append(vertex)
    return Region(
        id=element.id or element.span.path,
        name=element.name,
        vertices=tuple(vertices),
        span=element.span,
    )


def _vertex(b: Builder, element: RawElement, ctx: MachineContext) -> Vertex | None:
    """A region's subvertex. Anything else standing there (a `uml:StateMachine`, a
    ConnectionPointReference) is an error: dropping it, as swarmgen once did with a warning,
    left transitions and initial pseudostates pointing at nothing."""
    if element.uml_type not in _VERTEX_TYPES:
        _misplaced(b, element, "not-a-vertex")
        return None
    if element.uml_type == "Pseudostate" and element.attrs.get("kind") in _POINT_KINDS:
        _misplaced(b, element, "point-in-region", point=element.attrs["kind"])
        return None
    if element.id:
        ctx.vertices[element.id] = element
    if element.uml_type == "FinalState":
        return _final_state(b, element)
    if element.uml_type == "Pseudostate":
        return _pseudostate(b, element, ctx)
    return _state(b, element, ctx)


def _final_state(b: Builder, element: RawElement) -> FinalState:
    """A final state; its entry and exit actions and its entry's `done(...)` (the done data)
    are swarmgen's extension, as SCXML's `<final>` has them (docs/semantics.md)."""
    _final_content(b, element)
    opaque: list[OpaqueCode] = []
    entry = actions_of(b, element.first("entry"), "entry action", opaque, "entry")
    exit_ = actions_of(b, element.first("exit"), "exit action", opaque, "exit")
    done = [a for a in entry if isinstance(a, expr.Done)]
    if len(done) > 1:
        b.diags.append(
            dg.EFFECT_SYNTAX.at(
                element.span,
                what=f"entry action of final state '{element.name}'",
                error="gives done(...) twice",
                hint="give the done data once",
            )
        )
    return FinalState(
        id=element.id or element.span.path,
        name=element.name,
        entry=tuple(a for a in entry if not isinstance(a, expr.Done)),
        exit=exit_,
        donedata=done[0].args if done else (),
        done_content=done[0].content if done else None,
        span=element.span,
    )


def _final_content(b: Builder, element: RawElement) -> None:
    """UML: a final state has no regions, no do behaviour, no submachine (entry and exit
    actions are swarmgen's extension); the emitters would drop them without a word."""
    content = [f for f in ("region", "doActivity") if element.first(f) is not None]
    content += ["submachine"] if element.ref_values("submachine") else []
    if content:
        b.diags.append(
            dg.BAD_FINAL_STATE.at(element.span, state=element.name, content=", ".join(content))
        )


def _pseudostate(b: Builder, element: RawElement, ctx: MachineContext) -> Pseudostate:
    if element.id:
        ctx.vertices[element.id] = element
    kind_text = element.attrs.get("kind", "initial")
    known = kind_text in PseudoKind.__members__.values()
    if not known:
        kinds = ", ".join(k.value for k in PseudoKind)
        b.diags.append(
            dg.UNKNOWN_KIND.at(
                element.span, "pseudostate", name=element.name, kind=kind_text, kinds=kinds
            )
        )
    kind = PseudoKind(kind_text) if known else PseudoKind.INITIAL
    return Pseudostate(
        id=element.id or element.span.path, name=element.name, kind=kind, span=element.span
    )


def _state(b: Builder, element: RawElement, ctx: MachineContext) -> State:
    submachine = b.ref(element, "submachine", {"StateMachine"})
    connections = []
    for conn in element.kids("connection"):
        if conn.id:
            ctx.vertices[conn.id] = conn
        connections.append(
            ConnectionRef(
                id=conn.id or conn.span.path,
                name=conn.name,
                entry=tuple(e.id or "" for e in b.refs(conn, "entry", {"Pseudostate"})),
                exit=tuple(e.id or "" for e in b.refs(conn, "exit", {"Pseudostate"})),
                span=conn.span,
            )
        )
    opaque: list[OpaqueCode] = []
    entry = actions_of(b, element.first("entry"), "entry action", opaque, "entry")
    exit_ = actions_of(b, element.first("exit"), "exit action", opaque, "exit")
    return State(
        id=element.id or element.span.path,
        name=element.name,
        regions=_regions(b, element, ctx),
        submachine=submachine.id if submachine is not None else None,
        connection_points=_connection_points(b, element, ctx),
        connections=tuple(connections),
        activity=activity_call(b, element.first("doActivity"), opaque),
        entry=entry,
        exit=exit_,
        opaque=tuple(opaque),
        invokes=invokes_of(b, element),
        span=element.span,
    )
