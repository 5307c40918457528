"""`build`: RawModel -> Model. Gives the raw XMI tree its UML and swarm-profile meaning.

Resolution problems (dangling references, wrong kinds, expressions that do not parse) are
reported here, with the element's span; semantic rules live in `swarmgen.check`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Literal

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication
from swarmgen.ir import acyclic, expr
from swarmgen.ir.literals import (
    INTEGER_TEXT,
    BadLiteral,
    literal_text,
    literal_value,
    unrepresentable,
)
from swarmgen.ir.nodes import (
    DEFAULT_OUTCOMES,
    Behaviour,
    BehaviourCall,
    BehaviourKind,
    ConnectionRef,
    DataType,
    Event,
    FinalState,
    HardwareComponent,
    HardwareKind,
    Machine,
    MemberType,
    Model,
    OpaqueCode,
    Part,
    Property,
    PseudoKind,
    Pseudostate,
    Region,
    RosBinding,
    State,
    Swarm,
    Transition,
    Trigger,
    TriggerKind,
    Value,
    Vertex,
)
from swarmgen.names import identifier
from swarmgen.span import Span

_HARDWARE = {k.value: k for k in HardwareKind}
_BEHAVIOURS = {k.value: k for k in BehaviourKind}
_BEHAVIOUR_TAGS = frozenset({"requires", "outcomes", "emits", "rosKind", "rosName", "rosType"})
KNOWN_STEREOTYPES: dict[str, frozenset[str]] = {
    "Swarm": frozenset(),
    "SwarmMember": frozenset({"role"}),
    "Sensor": frozenset(),
    "Actuator": frozenset(),
    "Controller": frozenset(),
    "CommunicationInterface": frozenset({"communicationType", "communicationParams"}),
    "BehaviorLibrary": frozenset(),
    "SwarmEvent": frozenset({"sender", "scope"}),
    **{k: _BEHAVIOUR_TAGS for k in _BEHAVIOURS},
}
# Languages whose bodies are swarmgen's expression language; anything else is kept opaque.
OWN_LANGUAGES = frozenset({"", "swarmgen", "sg"})
_EVENT_TYPES = {"SignalEvent", "TimeEvent", "CallEvent", "ChangeEvent", "AnyReceiveEvent", "Signal"}


@dataclass
class _Builder:
    raw: RawModel
    diags: list[Diagnostic] = field(default_factory=list)
    stereo: dict[str, list[StereotypeApplication]] = field(default_factory=dict)
    behaviours: dict[str, Behaviour] = field(default_factory=dict)
    events_by_signal: dict[str, Event] = field(default_factory=dict)
    events_by_name: dict[str, Event] = field(default_factory=dict)

    # --- helpers

    def report(self, code: dg.Code, message: str, span: Span, hint: str | None = None) -> None:
        self.diags.append(dg.diag(code, message, span, hint=hint))

    def stereotype(self, element: RawElement, names: Iterable[str]) -> StereotypeApplication | None:
        wanted = set(names)
        apps = [a for a in self.stereo.get(element.id or "", []) if a.name in wanted]
        return apps[0] if apps else None

    def ref(
        self, element: RawElement, feature: str, kinds: set[str] | None = None
    ) -> RawElement | None:
        """Resolve a single-valued reference, reporting dangling and wrong-kind references,
        and several values where UML allows one (`source="_a _b"` used to take `_a`)."""
        values = element.ref_values(feature)
        if len(values) > 1:
            self.several(element, feature, values)
            return None
        return self._resolve(element, feature, values[0], kinds) if values else None

    def several(self, element: RawElement, feature: str, values: list[str]) -> None:
        shown = " ".join(values[:3]) + (" ..." if len(values) > 3 else "")
        self.report(
            dg.SEVERAL_REFS,
            f"{element.uml_type or element.feature} {_label(element)}: {feature} names "
            f"{len(values)} elements ({shown}); it takes exactly one",
            element.span,
            hint=f"keep one id in {feature}",
        )

    def refs(
        self, element: RawElement, feature: str, kinds: set[str] | None = None
    ) -> list[RawElement]:
        found = (self._resolve(element, feature, v, kinds) for v in element.ref_values(feature))
        return [f for f in found if f is not None]

    def _resolve(
        self, element: RawElement, feature: str, value: str, kinds: set[str] | None
    ) -> RawElement | None:
        target = self.raw.resolve(value)
        if target is None:
            if _is_external(value):
                return None
            self.report(
                dg.DANGLING_REF,
                f"{element.uml_type or element.feature} '{element.name}': {feature} '{value}' "
                "names no element of the model",
                element.span,
                hint="the referenced element was deleted or lives in a file that was not exported",
            )
            return None
        if kinds is not None and target.uml_type not in kinds:
            self.report(
                dg.WRONG_REF_KIND,
                f"{feature} of '{element.name}' is a {target.uml_type or target.feature} "
                f"'{target.name}', expected {' or '.join(sorted(kinds))}",
                element.span,
            )
            return None
        return target

    def type_name(self, element: RawElement) -> str | None:
        values = element.ref_values("type")
        if len(values) > 1:
            self.several(element, "type", values)
            return None
        for value in values:
            target = self.raw.resolve(value)
            if target is not None:
                return target.name or None
            # pathmap://.../UMLPrimitiveTypes.library.uml#Real, OMG uml.xml#Integer
            if "#" in value:
                return value.rsplit("#", 1)[1] or None
            self._resolve(element, "type", value, None)  # reports the dangling reference
        return None

    def prop(self, element: RawElement) -> Property:
        type_name = self.type_name(element)
        return Property(
            id=element.id or element.span.path,
            name=element.name,
            ident=identifier(element.name),
            type=type_name,
            default=self._default(element, type_name),
            span=element.span,
        )

    def _default(self, element: RawElement, type_name: str | None) -> Value:
        """The default, if generated code can hold it exactly and it is of the declared type
        (an Integer `abc` or `1e3` used to become a string literal, a Boolean `yes` false)."""
        spec = element.first("defaultValue")
        if spec is None:
            return None
        value = literal_value(spec)
        if not isinstance(value, BadLiteral):
            bad = unrepresentable(value, type_name)
            if bad is None:
                return value
            value = bad
        self.report(
            dg.BAD_DEFAULT,
            f"default value {_short(literal_text(spec))} of '{element.name}' {value.problem}",
            element.span,
            hint=value.hint,
        )
        return None

    # --- stereotypes

    def index_stereotypes(self) -> None:
        for app in self.raw.stereotypes:
            known = KNOWN_STEREOTYPES.get(app.name)
            if known is None:
                self.report(
                    dg.UNKNOWN_STEREOTYPE,
                    f"stereotype '{app.name}' is not part of the swarm profile; ignored",
                    app.span,
                )
                continue
            for tag in sorted(set(app.tags) - known):
                self.report(dg.UNKNOWN_TAG, f"«{app.name}» has no tag '{tag}'; ignored", app.span)
            for base in app.base_ids:
                if self.raw.resolve(base) is None:
                    self.report(
                        dg.DANGLING_REF,
                        f"«{app.name}» is applied to '{base}', which names no element",
                        app.span,
                    )
                self.stereo.setdefault(base, []).append(app)

    def tag_choice(
        self, app: StereotypeApplication, tag: str, allowed: tuple[str, ...]
    ) -> str | None:
        value = app.tags.get(tag, "").strip()
        if not value:
            return None
        if value not in allowed:
            self.report(
                dg.BAD_TAG_VALUE,
                f"«{app.name}» {tag}='{value}' is not one of {', '.join(allowed)}",
                app.span,
            )
            return None
        return value


def _label(element: RawElement) -> str:
    """How a message names an element: by name, else (transitions rarely have one) by id."""
    return f"'{element.name}'" if element.name else (element.id or element.span.path)


def _is_external(value: str) -> bool:
    """hrefs into other files (profiles, UML libraries) are not ours to resolve."""
    if "#" not in value:
        return False
    file_part = value.split("#", 1)[0]
    return bool(file_part)


def build(raw: RawModel) -> tuple[Model, list[Diagnostic]]:
    """Build the IR from the raw model; returns it with the diagnostics of resolution."""
    b = _Builder(raw)
    b.index_stereotypes()
    elements = list(raw.elements())
    classes = [e for e in elements if e.uml_type in {"Class", "Component"}]
    ancestry = _ancestry(b, classes)
    hardware_classes = {e.id for e in classes if e.id and b.stereotype(e, _HARDWARE)}
    b.diags += acyclic.class_cycles(raw, elements, hardware_classes)
    datatypes = tuple(_datatype(b, e) for e in elements if e.uml_type == "DataType")
    hardware = tuple(h for e in classes if (h := _hardware(b, e, ancestry)) is not None)
    hardware_ids = {h.id for h in hardware}
    members = tuple(m for e in classes if (m := _member(b, e, hardware_ids)) is not None)
    member_ids = {m.id for m in members}
    swarms = tuple(s for e in classes if (s := _swarm(b, e, member_ids)) is not None)
    for e in elements:
        if e.uml_type == "Operation" and (beh := _behaviour(b, e)) is not None:
            b.behaviours[beh.id] = beh
    for e in elements:
        if e.uml_type == "Signal":
            event = _event(b, e)
            b.events_by_signal[event.id] = event
            b.events_by_name.setdefault(event.name, event)
    machines = tuple(
        _machine(b, e) for e in elements if e.uml_type in {"StateMachine", "ProtocolStateMachine"}
    )
    uses_profile = any(a.name in KNOWN_STEREOTYPES for a in raw.stereotypes)
    model = Model(
        name=raw.roots[0].name if raw.roots else "",
        source=raw.file,
        exporter=raw.exporter,
        datatypes=datatypes,
        hardware=hardware,
        member_types=members,
        swarms=swarms,
        behaviours=tuple(b.behaviours.values()),
        events=tuple(b.events_by_signal.values()),
        machines=machines,
        uses_profile=uses_profile,
    )
    return model, b.diags


# --- structure


def _ancestry(b: _Builder, classes: list[RawElement]) -> dict[str, tuple[str, ...]]:
    """For every class id: the names of itself and all its ancestors (UML generalisation)."""
    parents: dict[str, list[RawElement]] = {}
    for cls in classes:
        parents[cls.id or ""] = [
            g for gen in cls.kids("generalization") if (g := b.ref(gen, "general")) is not None
        ]
    result: dict[str, tuple[str, ...]] = {}
    for cls in classes:
        seen: dict[str, str] = {}
        stack = [cls]
        while stack:
            current = stack.pop()
            if (current.id or "") in seen:
                continue
            seen[current.id or ""] = current.name
            stack.extend(parents.get(current.id or "", []))
        result[cls.id or ""] = tuple(sorted(set(seen.values())))
    return result


def _datatype(b: _Builder, element: RawElement) -> DataType:
    return DataType(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        fields=tuple(b.prop(a) for a in element.kids("ownedAttribute")),
        span=element.span,
    )


def _hardware(
    b: _Builder, element: RawElement, ancestry: dict[str, tuple[str, ...]]
) -> HardwareComponent | None:
    app = b.stereotype(element, _HARDWARE)
    if app is None:
        return None
    generals = [
        g for gen in element.kids("generalization") if (g := b.ref(gen, "general")) is not None
    ]
    return HardwareComponent(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        kind=_HARDWARE[app.name],
        generals=tuple(g.name for g in generals),
        capabilities=ancestry.get(element.id or "", (element.name,)),
        parameters=tuple(b.prop(a) for a in element.kids("ownedAttribute") if not _is_part(a)),
        communication_type=app.tags.get("communicationType") or None,
        communication_params=app.tags.get("communicationParams") or None,
        span=element.span,
    )


def _is_part(attribute: RawElement) -> bool:
    return attribute.attrs.get("aggregation") == "composite"


def _part(b: _Builder, attribute: RawElement, target: RawElement) -> Part:
    return Part(
        name=attribute.name,
        type_id=target.id or "",
        type_name=target.name,
        count=_count(b, attribute),
        span=attribute.span,
    )


def _count(b: _Builder, attribute: RawElement) -> int:
    upper = attribute.first("upperValue")
    if upper is None:
        return 1
    text = upper.attrs.get("value", "1").strip()
    # ASCII digits only: str.isdigit() also takes `²`, which int() refuses (an internal error)
    if INTEGER_TEXT.fullmatch(text) and text[0] not in "+-" and len(text) <= 18:
        return int(text)
    b.report(
        dg.BAD_MULTIPLICITY,
        f"part '{attribute.name}' has multiplicity {_short(text)}; a swarm needs a fixed count",
        attribute.span,
        hint="set the upper multiplicity to the number of members, e.g. 4",
    )
    return 1


def _member(b: _Builder, element: RawElement, hardware_ids: set[str]) -> MemberType | None:
    app = b.stereotype(element, {"SwarmMember"})
    if app is None:
        return None
    parts: list[Part] = []
    data: list[Property] = []
    for attribute in element.kids("ownedAttribute"):
        target = b.ref(attribute, "type")
        if (
            target is not None
            and (target.id in hardware_ids or _is_part(attribute))
            and (target.uml_type in {"Class", "Component"})
        ):
            parts.append(_part(b, attribute, target))
        else:
            data.append(b.prop(attribute))
    return MemberType(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        role=app.tags.get("role") or None,
        hardware=tuple(parts),
        data=tuple(data),
        machine=_classifier_machine(b, element),
        span=element.span,
    )


def _classifier_machine(b: _Builder, element: RawElement) -> str | None:
    chosen = b.ref(element, "classifierBehavior", {"StateMachine"})
    if chosen is not None:
        return chosen.id
    owned = [e for e in element.kids("ownedBehavior") if e.uml_type == "StateMachine"]
    if not owned:
        b.report(
            dg.MEMBER_WITHOUT_MACHINE,
            f"member type '{element.name}' owns no state machine, so it has no behaviour",
            element.span,
            hint="add a state machine to the class (its classifierBehavior)",
        )
        return None
    return owned[0].id


def _swarm(b: _Builder, element: RawElement, member_ids: set[str]) -> Swarm | None:
    if b.stereotype(element, {"Swarm"}) is None:
        return None
    parts = []
    for attribute in element.kids("ownedAttribute"):
        target = b.ref(attribute, "type")
        if target is not None and target.id in member_ids:
            parts.append(_part(b, attribute, target))
    return Swarm(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        members=tuple(parts),
        span=element.span,
    )


# --- library and events


def _behaviour(b: _Builder, element: RawElement) -> Behaviour | None:
    app = b.stereotype(element, _BEHAVIOURS)
    if app is None:
        return None
    params = list(element.kids("ownedParameter"))
    inputs = [p for p in params if p.attrs.get("direction", "in") in {"in", "inout"}]
    outputs = [p for p in params if p.attrs.get("direction", "in") in {"out", "inout", "return"}]
    extra = app.tags.get("outcomes", "").replace(",", " ").split()
    outcomes = tuple(dict.fromkeys((*DEFAULT_OUTCOMES, *extra)))
    for outcome in outcomes:
        _check_outcome_name(b, element, app, outcome)
    ros_kind = b.tag_choice(app, "rosKind", ("action", "service", "topic"))
    ros = None
    if ros_kind is not None:
        ros = RosBinding(
            kind=ros_kind,
            name=app.tags.get("rosName") or None,
            type=app.tags.get("rosType") or None,
        )
    return Behaviour(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        kind=_BEHAVIOURS[app.name],
        library=_library_name(b, element),
        inputs=tuple(b.prop(p) for p in inputs),
        outputs=tuple(b.prop(p) for p in outputs),
        outcomes=outcomes,
        requires=tuple(_requires(b, app)),
        emits=tuple(dict.fromkeys(app.tags.get("emits", "").replace(",", " ").split())),
        ros=ros,
        span=element.span,
    )


def _check_outcome_name(
    b: _Builder, element: RawElement, app: StereotypeApplication, outcome: str
) -> None:
    """An outcome travels by its own name (the behaviour returns `lost.far`) as a token of the
    event `done.invoke.<state>.<outcome>`: SCXML matches event descriptors by dot-separated
    prefix, so `lost.far` fired the `lost` transition. Only names that are their own
    identifier are safe in every engine and in SMACH's outcome keys (docs/profile.md)."""
    if identifier(outcome) == outcome:
        return
    b.report(
        dg.BAD_OUTCOME_NAME,
        f"outcome '{outcome}' of '{element.name}' is not a plain name: outcomes are matched as "
        "SCXML event tokens, where '.' separates tokens and '*' matches any",
        app.span,
        hint=f"rename it to '{identifier(outcome)}' (letters, digits and '_', not a reserved word)",
    )


def _requires(b: _Builder, app: StereotypeApplication) -> list[str]:
    names = []
    for token in app.tags.get("requires", "").replace(",", " ").split():
        target = b.raw.resolve(token)  # an id is accepted as well as a class name
        names.append(target.name if target is not None else token)
    return names


def _library_name(b: _Builder, element: RawElement) -> str:
    current = element.parent
    fallback = ""
    while current is not None:
        if current.uml_type == "Package":
            if b.stereotype(current, {"BehaviorLibrary"}) is not None:
                return current.name
            fallback = fallback or current.name
        current = current.parent
    return fallback


def _event(b: _Builder, element: RawElement) -> Event:
    app = b.stereotype(element, {"SwarmEvent"})
    sender = scope = None
    if app is not None:
        sender = b.tag_choice(app, "sender", ("station", "member"))
        scope = b.tag_choice(app, "scope", ("local", "swarm"))
    return Event(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        fields=tuple(b.prop(a) for a in element.kids("ownedAttribute")),
        sender=sender,
        scope=scope,
        swarm_event=app is not None,
        span=element.span,
    )


# --- state machines


@dataclass
class _MachineContext:
    transitions: list[RawElement] = field(default_factory=list)
    vertices: dict[str, RawElement] = field(default_factory=dict)


def _machine(b: _Builder, element: RawElement) -> Machine:
    ctx = _MachineContext()
    regions = _regions(b, element, ctx)
    points = _connection_points(b, element, ctx)
    owner = element.parent if element.feature == "ownedBehavior" else None
    attributes = list(owner.kids("ownedAttribute")) if owner is not None else []
    data = tuple(b.prop(a) for a in attributes if not _is_part(a))
    transitions = tuple(t for raw in ctx.transitions if (t := _transition(b, raw, ctx)) is not None)
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


def _misplaced(b: _Builder, element: RawElement, what: str, hint: str) -> None:
    b.report(
        dg.UNEXPECTED_ELEMENT,
        f"{element.feature} {_label(element)} is a {element.uml_type or 'element of unknown type'}, "
        f"but {what}",
        element.span,
        hint=hint,
    )


def _regions(b: _Builder, owner: RawElement, ctx: _MachineContext) -> tuple[Region, ...]:
    for region in owner.kids("region"):
        if region.uml_type != "Region":
            _misplaced(b, region, "only a Region may stand there", "make it a uml:Region")
    return tuple(_region(b, r, ctx) for r in owner.kids("region"))


def _connection_points(
    b: _Builder, owner: RawElement, ctx: _MachineContext
) -> tuple[Pseudostate, ...]:
    points = []
    for point in owner.kids("connectionPoint"):
        if point.uml_type != "Pseudostate" or point.attrs.get("kind") not in _POINT_KINDS:
            _misplaced(
                b,
                point,
                "connection points are entryPoint and exitPoint pseudostates",
                "move it into a region, or make it an entry or exit point",
            )
            continue
        points.append(_pseudostate(b, point, ctx))
    return tuple(points)


_POINT_KINDS = {PseudoKind.ENTRY_POINT.value, PseudoKind.EXIT_POINT.value}
_VERTEX_TYPES = {"State", "FinalState", "Pseudostate"}


def _region(b: _Builder, element: RawElement, ctx: _MachineContext) -> Region:
    for transition in element.kids("transition"):
        if transition.uml_type != "Transition":
            _misplaced(
                b, transition, "only a Transition may stand there", "make it a uml:Transition"
            )
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


def _vertex(b: _Builder, element: RawElement, ctx: _MachineContext) -> Vertex | None:
    """A region's subvertex. Anything else standing there (a `uml:StateMachine`, a
    ConnectionPointReference) is an error: dropping it, as swarmgen once did with a warning,
    left transitions and initial pseudostates pointing at nothing."""
    if element.uml_type not in _VERTEX_TYPES:
        _misplaced(
            b,
            element,
            "a region holds states, final states and pseudostates",
            "a state machine used inside another is a submachine state: a uml:State with "
            'submachine="<machine id>"',
        )
        return None
    if element.uml_type == "Pseudostate" and element.attrs.get("kind") in _POINT_KINDS:
        _misplaced(
            b,
            element,
            f"an {element.attrs['kind']} belongs to the connectionPoint list of a state or machine",
            "make it a connectionPoint of the state or machine it enters or leaves",
        )
        return None
    if element.id:
        ctx.vertices[element.id] = element
    if element.uml_type == "FinalState":
        _final_content(b, element)
        return FinalState(id=element.id or element.span.path, name=element.name, span=element.span)
    if element.uml_type == "Pseudostate":
        return _pseudostate(b, element, ctx)
    return _state(b, element, ctx)


def _final_content(b: _Builder, element: RawElement) -> None:
    """UML: a final state has no regions, no entry, exit or do behaviour, no submachine; the
    emitters would drop them without a word."""
    content = [f for f in ("region", "entry", "exit", "doActivity") if element.first(f) is not None]
    content += ["submachine"] if element.ref_values("submachine") else []
    if content:
        b.report(
            dg.BAD_FINAL_STATE,
            f"final state '{element.name}' has {', '.join(content)}; a final state has none",
            element.span,
            hint="make it an ordinary state followed by a final state",
        )


def _pseudostate(b: _Builder, element: RawElement, ctx: _MachineContext) -> Pseudostate:
    if element.id:
        ctx.vertices[element.id] = element
    kind_text = element.attrs.get("kind", "initial")
    known = kind_text in PseudoKind.__members__.values()
    if not known:
        b.report(
            dg.UNKNOWN_KIND,
            f"pseudostate '{element.name}' has kind '{kind_text}', which UML does not define",
            element.span,
            hint=f"use one of: {', '.join(k.value for k in PseudoKind)}",
        )
    kind = PseudoKind(kind_text) if known else PseudoKind.INITIAL
    return Pseudostate(
        id=element.id or element.span.path, name=element.name, kind=kind, span=element.span
    )


def _state(b: _Builder, element: RawElement, ctx: _MachineContext) -> State:
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
    entry = _actions_of(b, element.first("entry"), "entry action", opaque, "entry")
    exit_ = _actions_of(b, element.first("exit"), "exit action", opaque, "exit")
    return State(
        id=element.id or element.span.path,
        name=element.name,
        regions=_regions(b, element, ctx),
        submachine=submachine.id if submachine is not None else None,
        connection_points=_connection_points(b, element, ctx),
        connections=tuple(connections),
        activity=_activity(b, element.first("doActivity"), opaque),
        entry=entry,
        exit=exit_,
        opaque=tuple(opaque),
        span=element.span,
    )


def _bodies(element: RawElement) -> tuple[str, str]:
    """(language, text) of an OpaqueBehavior/OpaqueExpression; parallel lists joined."""
    languages = [lang.text for lang in element.kids("language")]
    bodies = [body.text for body in element.kids("body")]
    if not bodies and "body" in element.attrs:
        bodies = [element.attrs["body"]]
    return (languages[0].strip() if languages else ""), "\n".join(bodies)


def _is_own_language(language: str) -> bool:
    return language.strip().lower() in OWN_LANGUAGES


def _actions_of(
    b: _Builder,
    behaviour: RawElement | None,
    what: str,
    opaque: list[OpaqueCode],
    role: Literal["entry", "exit", "do", "effect"] = "effect",
) -> tuple[expr.Action, ...]:
    if behaviour is None:
        return ()
    language, text = _bodies(behaviour)
    if not text.strip():
        return ()
    if not _is_own_language(language):
        opaque.append(OpaqueCode(language=language, body=text, role=role, span=behaviour.span))
        b.report(
            dg.OPAQUE_CODE,
            f"{what} in language '{language}' is kept as text but not executed: {_short(text)}",
            behaviour.span,
            hint="write it in swarmgen's action language (no <language>) to have it run",
        )
        return ()
    try:
        return expr.parse_actions(text)
    except expr.ExprError as err:
        b.report(dg.EFFECT_SYNTAX, f"{what} {_quote_error(text, err)}", behaviour.span, err.hint)
        return ()


def _activity(
    b: _Builder, element: RawElement | None, opaque: list[OpaqueCode]
) -> BehaviourCall | None:
    if element is None:
        return None
    operation = b.ref(element, "specification")
    language, text = _bodies(element)
    if operation is None:
        if not element.ref_values("specification") and text.strip():
            opaque.append(OpaqueCode(language=language, body=text, role="do", span=element.span))
            b.report(
                dg.OPAQUE_CODE,
                f"doActivity {_short(text)} calls no library behaviour; kept as text, not executed",
                element.span,
                hint="set the doActivity's specification to a behaviour operation of the library",
            )
        return None
    behaviour = b.behaviours.get(operation.id or "")
    if behaviour is None:
        b.report(
            dg.UNKNOWN_BEHAVIOUR,
            f"doActivity calls '{operation.name}', which is not a library behaviour",
            element.span,
            hint="apply «ComplexBehavior», «SwarmBehavior», «SwarmFunction» or «HardwareFunction» "
            "to the operation",
        )
        return None
    bindings: tuple[expr.Binding, ...] = ()
    if text.strip():
        try:
            bindings = expr.parse_bindings(text)
        except expr.ExprError as err:
            b.report(
                dg.BINDING_ERROR,
                f"argument binding {_quote_error(text, err)}",
                element.span,
                err.hint,
            )
    return BehaviourCall(behaviour=behaviour.id, bindings=bindings, span=element.span)


def _short(text: str, limit: int = 60) -> str:
    flat = " ".join(text.split())
    return f"'{flat[: limit - 3]}...'" if len(flat) > limit else f"'{flat}'"


def _quote_error(text: str, err: expr.ExprError) -> str:
    lines = text.split("\n")  # ExprError counts lines by "\n" only
    line = lines[err.line] if err.line < len(lines) else text
    return f"{_short(line)}: {err.message} (column {err.col + 1})"


# --- transitions


def _transition(b: _Builder, element: RawElement, ctx: _MachineContext) -> Transition | None:
    source = b.ref(element, "source")
    target = b.ref(element, "target")
    if source is None or target is None:
        if not element.ref_values("source") or not element.ref_values("target"):
            b.report(
                dg.BAD_TARGET,
                f"transition '{element.name}' lacks a source or a target",
                element.span,
            )
        return None
    for end, which in ((source, "source"), (target, "target")):
        if end.id not in ctx.vertices:
            b.report(
                dg.BAD_TARGET,
                f"transition {which} '{end.name}' is a {end.uml_type or end.feature}, "
                "not a state of this machine",
                element.span,
            )
            return None
    source_behaviour = _source_behaviour(b, source)
    opaque: list[OpaqueCode] = []
    guard, guard_text = _guard(b, element)
    return Transition(
        id=element.id or element.span.path,
        name=element.name,
        source=source.id or "",
        target=target.id or "",
        triggers=tuple(
            t
            for raw in element.kids("trigger")
            if (t := _trigger(b, raw, source_behaviour)) is not None
        ),
        guard=guard,
        guard_text=guard_text,
        effect=_actions_of(b, element.first("effect"), "effect", opaque),
        opaque=tuple(opaque),
        kind=_transition_kind(b, element),
        span=element.span,
    )


_TRANSITION_KINDS: dict[str, Literal["external", "internal", "local"]] = {
    "external": "external",
    "internal": "internal",
    "local": "local",
}


def _transition_kind(b: _Builder, element: RawElement) -> Literal["external", "internal", "local"]:
    text = element.attrs.get("kind", "external")
    if text not in _TRANSITION_KINDS:
        b.report(
            dg.UNKNOWN_KIND,
            f"transition {_label(element)} has kind '{text}', which UML does not define",
            element.span,
            hint="use external, local or internal",
        )
    return _TRANSITION_KINDS.get(text, "external")


def _source_behaviour(b: _Builder, source: RawElement) -> Behaviour | None:
    activity = source.first("doActivity")
    if activity is None:
        return None
    values = activity.ref_values("specification")
    operation = b.raw.resolve(values[0]) if values else None
    return b.behaviours.get(operation.id or "") if operation is not None else None


def _guard(b: _Builder, element: RawElement) -> tuple[expr.Expr | None, str | None]:
    values = element.ref_values("guard")
    if values:
        constraint = b.ref(element, "guard", {"Constraint"})
    else:
        constraint = element.first("guard") or element.first("ownedRule")
    if constraint is None:
        return None, None
    text = _constraint_text(constraint)
    if not text.strip():
        return None, None
    try:
        return expr.parse_expr(text), text
    except expr.ExprError as err:
        b.report(dg.GUARD_SYNTAX, f"guard {_quote_error(text, err)}", constraint.span, err.hint)
        return None, text


def _constraint_text(constraint: RawElement) -> str:
    spec = constraint.first("specification")
    if spec is not None:
        if spec.uml_type == "OpaqueExpression":
            return _bodies(spec)[1]
        if "value" in spec.attrs:
            return spec.attrs["value"]
    return constraint.name


def _trigger(b: _Builder, element: RawElement, behaviour: Behaviour | None) -> Trigger | None:
    event = b.ref(element, "event", _EVENT_TYPES)
    if event is None:
        if element.ref_values("event"):
            return None  # already reported as dangling or of the wrong kind
        return _named_trigger(b, element, element.name, None, behaviour)
    kind = event.uml_type
    if kind == "TimeEvent":
        return _time_trigger(b, element, event)
    if kind == "CallEvent":
        operation = b.ref(event, "operation")
        name = operation.name if operation is not None else event.name
        return Trigger(kind=TriggerKind.CALL, name=name, span=element.span)
    if kind == "AnyReceiveEvent":
        return Trigger(kind=TriggerKind.ANY, name="*", span=element.span)
    if kind == "ChangeEvent":
        b.report(dg.UNSUPPORTED, "change events are not supported; trigger ignored", element.span)
        return None
    signal = event if kind == "Signal" else b.ref(event, "signal", {"Signal"})
    if signal is not None:
        return _named_trigger(b, element, signal.name, signal, behaviour)
    return _named_trigger(b, element, event.name or element.name, None, behaviour)


def _named_trigger(
    b: _Builder,
    element: RawElement,
    name: str,
    signal: RawElement | None,
    behaviour: Behaviour | None,
) -> Trigger | None:
    """Outcome first: a name its state's behaviour can produce is that outcome (docs/profile.md)."""
    if behaviour is not None and name in behaviour.outcomes:
        return Trigger(kind=TriggerKind.OUTCOME, name=name, span=element.span)
    event = (
        b.events_by_signal.get(signal.id or "")
        if signal is not None
        else b.events_by_name.get(name)
    )
    if event is not None:
        return Trigger(kind=TriggerKind.EVENT, name=event.name, event=event.id, span=element.span)
    if name in DEFAULT_OUTCOMES or behaviour is not None:
        return Trigger(kind=TriggerKind.OUTCOME, name=name, span=element.span)
    if not name:
        b.report(dg.UNKNOWN_EVENT, "trigger names no event", element.span)
        return None
    if b.raw.stereotypes and any(a.name == "SwarmEvent" for a in b.raw.stereotypes):
        b.report(
            dg.UNKNOWN_EVENT,
            f"trigger '{name}' names no «SwarmEvent» signal and no outcome",
            element.span,
            hint=f"declare a Signal «SwarmEvent» named '{name}', or check the spelling",
        )
        return None
    return Trigger(kind=TriggerKind.EVENT, name=name, span=element.span)


def _time_trigger(b: _Builder, element: RawElement, event: RawElement) -> Trigger | None:
    when = event.first("when")
    expression = when.first("expr") if when is not None else None
    value = literal_value(expression) if expression is not None else None
    if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
        b.report(
            dg.UNSUPPORTED,
            f"time event '{event.name}' has no constant delay; trigger ignored",
            element.span,
            hint="give the TimeEvent a TimeExpression with a LiteralInteger in milliseconds",
        )
        return None
    return Trigger(kind=TriggerKind.TIME, name=event.name, delay_ms=int(value), span=element.span)
