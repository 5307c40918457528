"""A reader of Modelio's native files (docs/modelio-input.md): one `.exml` file, or a `.ramc`
model component (a zip of them, read in memory by `modelio_zip`), into a raw model of the UML
shape the XMI reader gives, so the unchanged pipeline (IR, checks, every backend) runs on it.

Read: classes (their attributes are the data of the machines they own), state machines with
their regions, states, submachine states, pseudostates, final states, transitions (trigger,
guard, effect), internal transitions, and the Entry/Do/Exit internal transitions Modelio uses
for a state's behaviours; events by name. Not in the native files: the swarm profile (member
types, hardware, swarms, library behaviours), so every top-level machine becomes a chart of its
own, as for a plain SCXML document (SG069 note). Chosen by content (`frontend.formats`): the root
element `EXT`, or a zip's magic bytes.
"""

from __future__ import annotations

import re
from dataclasses import field
from pathlib import Path
from typing import Any

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Code, Diagnostic, Severity
from swarmgen.frontend import modelio_zip
from swarmgen.frontend.modelio_graph import MObject, Ref, index_objects, read_ext
from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication
from swarmgen.frontend.safexml import InputError, decoded, parse_safely
from swarmgen.frontend.scxml_raw import Builder
from swarmgen.records import dataclass

Loaded = tuple[RawModel | None, list[Diagnostic]]
Parsed = tuple[etree._ElementTree, str, str]  # (tree, source text, shown name)

_PSEUDO_KINDS = {
    "Standard.InitialPseudoState": "initial",
    "Standard.ChoicePseudoState": "choice",
    "Standard.JunctionPseudoState": "junction",
    "Standard.ForkPseudoState": "fork",
    "Standard.JoinPseudoState": "join",
    "Standard.ShallowHistoryPseudoState": "shallowHistory",
    "Standard.DeepHistoryPseudoState": "deepHistory",
    "Standard.TerminatePseudoState": "terminate",
    "Standard.EntryPointPseudoState": "entryPoint",
    "Standard.ExitPointPseudoState": "exitPoint",
}
_VERTICES = {"Standard.State", "Standard.FinalState", *_PSEUDO_KINDS}
# Modelio writes a state's entry, do and exit behaviours as internal transitions of these names.
_SLOTS = {"entry": "entry", "do": "doActivity", "exit": "exit"}
# Objects read as UML classes: their attributes are data, their operations may be behaviours.
_CLASSIFIERS = {"Standard.Class", "Standard.Node", "Standard.Interface", "Standard.Component"}
# Documentation owned by an object (notes, tagged values): not part of the behaviour.
_DOCUMENTATION = {"Descriptor", "Tag"}
# Modelio's predefined types (FOREIGNIDs into its base library) that swarmgen has primitives for.
_PRIMITIVES = {
    **dict.fromkeys(("integer", "int", "short", "long", "byte"), "Integer"),
    **dict.fromkeys(("float", "double", "real"), "Real"),
    **dict.fromkeys(("boolean", "bool"), "Boolean"),
    **dict.fromkeys(("string", "char"), "String"),
}


def from_tree(tree: etree._ElementTree, text: str, shown: str) -> Loaded:
    """The raw model of one parsed `.exml` file (`text`: its decoded source, for columns)."""
    return _read([(tree, text, shown)], shown)


def from_archive(data: bytes, shown: str) -> Loaded:
    """The raw model of a `.ramc` archive's `.exml` members (spans name `archive!member`)."""
    try:
        parsed: list[Parsed] = []
        for member in modelio_zip.read_archive(data, shown):
            name = modelio_zip.member_file(shown, member.name)
            tree = parse_safely(member.data, name)
            text = decoded(member.data, tree.docinfo.encoding or "utf-8", name)
            parsed.append((tree, text, name))
    except InputError as err:
        return None, [err.diagnostic]
    return _read(parsed, shown)


def _read(files: list[Parsed], shown: str) -> Loaded:
    index: dict[str, RawElement] = {}
    stereotypes: list[StereotypeApplication] = []
    diagnostics: list[Diagnostic] = []
    builders = [
        Builder(name, text.splitlines(), index, stereotypes, diagnostics) for _, text, name in files
    ]
    try:
        roots = [
            read_ext(b, tree.getroot()) for b, (tree, _, _) in zip(builders, files, strict=True)
        ]
        model = _Reader(builders[0], index_objects(roots), shown).read()
    except InputError as err:
        return None, [err.diagnostic]
    if any(d.severity == Severity.ERROR for d in diagnostics):
        return None, diagnostics
    return model, diagnostics


@dataclass
class _Pending:
    """A reference resolved once every file's objects are built: (object, element, target)."""

    obj: MObject
    element: RawElement
    ref: Ref


@dataclass
class _Reader:
    b: Builder
    objects: dict[str, MObject]
    shown: str
    signals: dict[str, str] = field(default_factory=dict)  # event name -> SignalEvent id
    classes: dict[str, RawElement] = field(default_factory=dict)
    operations: dict[str, RawElement] = field(default_factory=dict)
    machines: dict[str, RawElement] = field(default_factory=dict)
    vertices: dict[str, RawElement] = field(default_factory=dict)
    targets: list[_Pending] = field(default_factory=list)
    submachines: list[_Pending] = field(default_factory=list)
    calls: list[_Pending] = field(default_factory=list)
    behaviours: set[str] = field(default_factory=set)

    def read(self) -> RawModel:
        objects = list(self.objects.values())
        project = next((o for o in objects if o.mc == "Standard.Project"), None)
        name = project.name if project is not None else Path(self.shown).stem
        first = objects[0]
        self.model = first.b.make("Model", "Model", None, first.node, {"name": name})
        self.package = first.b.make(
            "packagedElement", "Package", self.model, first.node, {"name": name}
        )
        for obj in objects:
            if obj.mc == "Standard.Event":
                self.event(obj)
        for obj in objects:
            if obj.mc in _CLASSIFIERS:
                self.cls(obj)
        for obj in objects:
            if obj.mc == "Standard.StateMachine":
                self.machine(obj)
        self.resolve_targets()
        self.resolve_submachines()
        self.resolve_calls()
        self.profile_note()
        return RawModel(self.shown, [self.model], self.b.index, self.b.stereotypes, "modelio")

    def report(self, code: Code, obj: MObject, variant: str | None = None, **fields: Any) -> None:
        """A located diagnostic: at the raw element built from `obj` (its model path), else
        at the object itself."""
        built = self.b.index.get(obj.uid)
        span = built.span if built is not None else obj.span()
        found = code.at(span, variant, **fields) if variant else code.at(span, **fields)
        self.b.diagnostics.append(found)

    def event(self, obj: MObject) -> None:
        """A Modelio event: a signal of its name (events of one name are one signal)."""
        kind = obj.text("Kind") or "SignalEvent"
        if kind != "SignalEvent":
            self.report(dg.MODELIO_ASSUMED, obj, "event-kind", name=obj.name, kind=kind)
        self.event_id(obj.name, obj)

    def event_id(self, name: str, obj: MObject | None) -> str:
        if name not in self.signals:
            b, node = (obj.b, obj.node) if obj is not None else (self.b, None)
            signal = b.make("packagedElement", "Signal", self.package, node, {"name": name})
            event = b.make(
                "packagedElement",
                "SignalEvent",
                self.package,
                node,
                {"name": name, "signal": str(signal.id)},
            )
            self.signals[name] = str(event.id)
        return self.signals[name]

    def cls(self, obj: MObject) -> None:
        """A class: its attributes (the data of the machines it owns) and operations."""
        b = obj.b
        attrs = {"name": obj.name}
        element = b.make("packagedElement", "Class", self.package, obj.node, attrs, obj.uid)
        self.classes[obj.uid] = element
        for att in obj.owned("OwnedAttribute"):
            prop = b.make(
                "ownedAttribute", "Property", element, att.node, {"name": att.name}, att.uid
            )
            kind = att.link("Type")
            b.typed(prop, _PRIMITIVES.get(kind.name.lower()) if kind is not None else None, {})
            value = _literal(att.text("Value"))
            if value is not None:
                b.literal(prop, "defaultValue", value, att.node)
        for op in obj.owned("OwnedOperation"):
            self.operations[op.uid] = b.make(
                "ownedOperation", "Operation", element, op.node, {"name": op.name}, op.uid
            )

    def owner_of(self, obj: MObject) -> RawElement:
        """The class owning a machine: read, or named by the machine's PID only (a lone .exml)."""
        pid = obj.pid
        if pid is None or pid.mc != "Standard.Class":
            return self.package
        if pid.uid not in self.classes:
            self.classes[pid.uid] = obj.b.make(
                "packagedElement", "Class", self.package, pid.node, {"name": pid.name}, pid.uid
            )
        return self.classes[pid.uid]

    def machine(self, obj: MObject) -> None:
        owner = self.owner_of(obj)
        feature = "ownedBehavior" if owner.uml_type == "Class" else "packagedElement"
        element = obj.b.make(feature, "StateMachine", owner, obj.node, {"name": obj.name}, obj.uid)
        self.machines[obj.uid] = element
        for relation, kid in obj.comps:
            if relation == "Top" and kid.mc == "Standard.Region":
                self.region(kid, element)
            elif not (relation == "EComponent" and kid.mc == "Standard.Event"):
                self.unsupported(kid, relation)

    def region(self, obj: MObject, owner: RawElement) -> None:
        attrs = {"name": obj.name}
        element = obj.b.make("region", "Region", owner, obj.node, attrs, obj.uid)
        for relation, kid in obj.comps:
            if relation == "Sub" and kid.mc in _VERTICES:
                self.vertex(kid, element)
            else:
                self.unsupported(kid, relation)
        self.default_initial(obj, element, owner)

    def default_initial(self, obj: MObject, region: RawElement, owner: RawElement) -> None:
        """A region with states but no initial pseudostate is entered at its first state."""
        kids = list(region.kids("subvertex"))
        if any(k.attrs.get("kind") == "initial" for k in kids):
            return
        first = next((k for k in kids if k.uml_type == "State"), None)
        if first is None:
            return
        start = obj.b.make("subvertex", "Pseudostate", region, obj.node, {"name": "Initial"})
        start.attrs["kind"] = "initial"
        attrs = {"source": str(start.id), "target": str(first.id)}
        obj.b.make("transition", "Transition", region, obj.node, attrs)
        self.report(dg.MODELIO_ASSUMED, obj, "initial", owner=owner.name, state=first.name)

    def vertex(self, obj: MObject, region: RawElement) -> None:
        kind = _PSEUDO_KINDS.get(obj.mc)
        uml_type = "Pseudostate" if kind else obj.mc.removeprefix("Standard.")
        attrs = {"name": obj.name, **({"kind": kind} if kind else {})}
        element = obj.b.make("subvertex", uml_type, region, obj.node, attrs, obj.uid)
        self.vertices[obj.uid] = element
        state = uml_type == "State"
        for relation, kid in obj.comps:
            if relation == "OutGoing" and kid.mc == "Standard.Transition":
                self.transition(kid, element, region)
            elif state and relation == "Internal" and kid.mc == "Standard.InternalTransition":
                self.internal(kid, element, region)
            elif state and relation == "OwnedRegion" and kid.mc == "Standard.Region":
                self.region(kid, element)
            else:
                self.unsupported(kid, relation)
        sub = obj.link("SubMachine")
        if sub is not None and state:
            self.submachines.append(_Pending(obj, element, sub))

    def transition(
        self, obj: MObject, source: RawElement, region: RawElement, internal: bool = False
    ) -> RawElement:
        attrs = {"name": obj.name, "source": str(source.id)}
        if internal:  # UML: an internal transition is owned by its state's region, self-targeted
            attrs.update(kind="internal", target=str(source.id))
        element = obj.b.make("transition", "Transition", region, obj.node, attrs, obj.uid)
        target = obj.link("Target")
        if target is not None and not internal:
            self.targets.append(_Pending(obj, element, target))
        self.triggers(obj, element)
        guard = obj.text("Guard")
        if guard:
            constraint = obj.b.make("guard", "Constraint", element, obj.node)
            obj.b.make("specification", "OpaqueExpression", constraint, obj.node, {"body": guard})
        effect = obj.text("Effect")
        if effect:
            obj.b.make("effect", "OpaqueBehavior", element, obj.node, {"body": effect})
        if obj.link("Processed") is not None:
            self.unsupported(obj, "Processed")
        return element

    def triggers(self, obj: MObject, element: RawElement) -> None:
        """Trigger links (to events of the files read, else by the name the link gives), or
        else the `ReceivedEvents` text (Modelio's textual trigger)."""
        refs = [ref for relation, ref in obj.links if relation == "Trigger"]
        names: list[str] = []
        for ref in refs:
            event = self.objects.get(ref.uid)
            if event is None:
                self.report(dg.MODELIO_ASSUMED, obj, "event", name=ref.name, transition=obj.name)
            elif event.mc != "Standard.Event":
                self.dangling(obj, "Trigger", ref, "event")
                continue
            names.append(event.name if event is not None else ref.name)
        if not refs:
            names = [n.strip() for n in obj.text("ReceivedEvents").split(",") if n.strip()]
        for name in names:
            event_id = self.event_id(name, None)
            attrs = {"name": name, "event": event_id}
            obj.b.make("trigger", "Trigger", element, obj.node, attrs)

    def internal(self, obj: MObject, state: RawElement, region: RawElement) -> None:
        """`Entry`/`Do`/`Exit` internal transitions are the state's behaviours; any other is a
        UML internal transition."""
        slot = _SLOTS.get(obj.text("ReceivedEvents").lower())
        if slot is None or obj.link("Trigger") is not None:
            self.transition(obj, state, region, internal=True)
            return
        if state.first(slot) is not None:
            self.unsupported(obj, "Internal")
            return
        attrs = {"name": obj.name, **({"body": obj.text("Effect")} if obj.text("Effect") else {})}
        behaviour = obj.b.make(slot, "OpaqueBehavior", state, obj.node, attrs, obj.uid)
        called = obj.link("Processed")
        if called is not None and slot == "doActivity":
            self.calls.append(_Pending(obj, behaviour, called))
        elif called is not None:
            self.unsupported(obj, "Processed")

    def unsupported(self, obj: MObject, relation: str) -> None:
        if relation in _DOCUMENTATION:
            return
        kind = obj.mc.removeprefix("Standard.")
        self.report(
            dg.MODELIO_BAD_MODEL, obj, "unsupported", kind=kind, name=obj.name, relation=relation
        )

    def dangling(self, obj: MObject, relation: str, ref: Ref, kind: str) -> None:
        self.report(
            dg.MODELIO_BAD_MODEL,
            obj,
            "dangling",
            relation=relation,
            name=obj.name,
            uid=ref.uid,
            target=ref.name,
            kind=kind,
        )

    def resolve_targets(self) -> None:
        for p in self.targets:
            vertex = self.vertices.get(p.ref.uid)
            if vertex is None:
                self.dangling(p.obj, "Target", p.ref, "state or pseudostate")
            else:
                p.element.attrs["target"] = str(vertex.id)

    def resolve_submachines(self) -> None:
        for p in self.submachines:
            machine = self.machines.get(p.ref.uid)
            if machine is not None:
                p.element.attrs["submachine"] = str(machine.id)
            elif p.ref.uid in self.objects:
                self.dangling(p.obj, "SubMachine", p.ref, "state machine")
            else:
                self.report(
                    dg.MODELIO_ASSUMED, p.obj, "submachine", name=p.ref.name, state=p.obj.name
                )

    def resolve_calls(self) -> None:
        """An operation a Do calls: a library behaviour (no profile says what it is)."""
        for p in self.calls:
            state = p.obj.parent.name if p.obj.parent is not None else ""
            operation = self.operations.get(p.ref.uid)
            if operation is None:
                if p.ref.uid in self.objects:
                    self.dangling(p.obj, "Processed", p.ref, "operation")
                else:
                    self.report(
                        dg.MODELIO_ASSUMED, p.obj, "operation", name=p.ref.name, state=state
                    )
                continue
            p.element.attrs["specification"] = str(operation.id)
            if operation.id not in self.behaviours:
                self.behaviours.add(str(operation.id))
                self.b.stereotype("SwarmBehavior", "Operation", operation, {})
                self.report(
                    dg.MODELIO_ASSUMED,
                    p.obj,
                    "behaviour",
                    state=state,
                    operation=operation.name,
                    library=self.package.name,
                )

    def profile_note(self) -> None:
        used = {p.element.attrs.get("submachine") for p in self.submachines}
        top = [m for uid, m in self.machines.items() if uid not in used]
        names = ", ".join(f"'{m.name}'" for m in top) or "none"
        first = next((self.objects[uid] for uid in self.machines if uid not in used), None)
        obj = first or next(iter(self.objects.values()))
        self.report(dg.MODELIO_ASSUMED, obj, machines=names)


def _literal(text: str) -> bool | int | float | None:
    """An attribute's `Value` as a literal default (None: no value, or not a plain literal)."""
    if text in ("true", "false"):
        return text == "true"
    if _INTEGER.fullmatch(text):
        return int(text)
    if _REAL.fullmatch(text):
        return float(text)
    return None


_INTEGER = re.compile(r"[+-]?[0-9]{1,18}")
_REAL = re.compile(r"[+-]?([0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)([eE][+-]?[0-9]{1,3})?")
