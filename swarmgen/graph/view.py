"""What the diagrams show, independent of the output format: one `Diagram` per state machine and
one `Composition` per model, computed once from the IR so that Mermaid and DOT agree.

Every text here is the model's own (raw, unescaped); each renderer escapes it for its format.
Ids are safe identifiers (`[A-Za-z0-9_]`, from `names.identifier`), unique in their diagram and
allocated in model order, so the output is deterministic.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from enum import StrEnum

from swarmgen.errors import SwarmgenError
from swarmgen.ir import expr
from swarmgen.ir import nodes as ir
from swarmgen.ir.query import ModelIndex, connection_owner
from swarmgen.ir.query import composition as swarm_composition
from swarmgen.names import IdAllocator, identifier, one_line

COMPOSITION_STEM = "swarm"
GUARD_LIMIT = 40
EFFECT_LIMIT = 60
TRIGGER_LIMIT = 40
ACTIVITY_LIMIT = 48


class GraphError(SwarmgenError):
    """The diagrams cannot be drawn as asked (an unknown member type, Graphviz missing)."""


class Shape(StrEnum):
    STATE = "state"
    FINAL = "final"
    INITIAL = "initial"
    CHOICE = "choice"
    JUNCTION = "junction"
    FORK = "fork"
    JOIN = "join"
    SHALLOW_HISTORY = "shallowHistory"
    DEEP_HISTORY = "deepHistory"
    TERMINATE = "terminate"
    ENTRY_POINT = "entryPoint"
    EXIT_POINT = "exitPoint"


@dataclass(frozen=True)
class Style:
    fill: str
    stroke: str
    title: str  # the legend's words


# Pastel fills with a darker border of the same hue, readable with black text.
BEHAVIOUR_STYLES: dict[ir.BehaviourKind, Style] = {
    ir.BehaviourKind.COMPLEX: Style("#f8cecc", "#b85450", "complex behaviour"),
    ir.BehaviourKind.SWARM_BEHAVIOR: Style("#d5e8d4", "#82b366", "swarm behaviour"),
    ir.BehaviourKind.SWARM_FUNCTION: Style("#dae8fc", "#6c8ebf", "swarm function"),
    ir.BehaviourKind.HARDWARE_FUNCTION: Style("#fff2cc", "#d6b656", "hardware function"),
}
NEUTRAL = Style("#f5f5f5", "#666666", "no behaviour")
COMPOSITE = Style("#ffffff", "#666666", "composite state")
REGION = Style("#ffffff", "#999999", "region")

HARDWARE_STYLES: dict[ir.HardwareKind, Style] = {
    ir.HardwareKind.SENSOR: Style("#e1d5e7", "#9673a6", "sensor"),
    ir.HardwareKind.ACTUATOR: Style("#ffe6cc", "#d79b00", "actuator"),
    ir.HardwareKind.CONTROLLER: Style("#eeeeee", "#666666", "controller"),
    ir.HardwareKind.COMMUNICATION_INTERFACE: Style("#d0eeee", "#3c8c8c", "communication interface"),
}
SWARM_STYLE = Style("#ffffff", "#333333", "swarm")
MEMBER_STYLE = Style("#ffffff", "#333333", "member type")
CLASS_STYLE = Style("#ffffff", "#999999", "class")


# --- state machines


@dataclass(frozen=True)
class Vertex:
    id: str
    name: str  # the model's name
    shape: Shape
    kind: ir.BehaviourKind | None = None  # of the behaviour its doActivity runs
    lines: tuple[str, ...] = ()  # more label lines: `do ...`, `entry / ...`, `submachine ...`
    link: str | None = None  # stem of the submachine's diagram
    regions: tuple[Region, ...] = ()  # non-empty: a composite state, drawn as a cluster
    points: tuple[Vertex, ...] = ()  # its entry and exit points

    @property
    def composite(self) -> bool:
        return bool(self.regions)


@dataclass(frozen=True)
class Region:
    id: str
    name: str
    vertices: tuple[Vertex, ...]


@dataclass(frozen=True)
class Edge:
    source: str
    target: str
    parts: tuple[str, ...]  # `event`, `[guard]`, `/ effect`: the parts that are there

    @property
    def label(self) -> str:
        return " ".join(self.parts)


@dataclass(frozen=True)
class Diagram:
    stem: str  # file name without suffix, unique in the model
    name: str  # the machine's name
    members: tuple[str, ...]  # member types that run it (directly or as a submachine)
    root: Vertex | None  # a synthetic composite holding the regions of a machine with several
    points: tuple[Vertex, ...]  # the machine's entry and exit points
    regions: tuple[Region, ...]  # top-level regions (inside `root` when it is set)
    edges: tuple[Edge, ...]
    region_of: dict[str, str] = field(default_factory=dict)  # vertex id -> region id
    owner_of: dict[str, str | None] = field(default_factory=dict)  # region id -> composite id

    def all_regions(self) -> list[Region]:
        found = list(self.regions)
        for vertex in self.vertices():
            found.extend(vertex.regions)
        return found

    def vertices(self) -> list[Vertex]:
        """Every vertex, parents before children (connection points after their owner)."""
        found: list[Vertex] = [*self.points]
        stack = [v for r in reversed(self.regions) for v in reversed(r.vertices)]
        while stack:
            vertex = stack.pop()
            found.append(vertex)
            found.extend(vertex.points)
            stack.extend(v for r in reversed(vertex.regions) for v in reversed(r.vertices))
        return found

    def kinds(self) -> list[ir.BehaviourKind]:
        """The behaviour kinds shown, in legend order."""
        shown = {v.kind for v in self.vertices()}
        return [k for k in BEHAVIOUR_STYLES if k in shown]

    def ancestors(self, vertex_id: str) -> list[str]:
        """Composite states that contain the vertex, innermost first."""
        found: list[str] = []
        region = self.region_of.get(vertex_id)
        while region is not None:
            owner = self.owner_of.get(region)
            if owner is None:
                break
            found.append(owner)
            region = self.region_of.get(owner)
        return found


def clip(text: str, limit: int) -> str:
    """One line, at most `limit` characters (an ellipsis marks the cut)."""
    flat = " ".join(one_line(text).split())
    return flat if len(flat) <= limit else flat[: limit - 1].rstrip() + "…"


def _args_text(args: Sequence[expr.Arg]) -> str:
    return ", ".join(f"{a.name} = {expr.to_text(a.value)}" for a in args)


def action_text(action: expr.Action) -> str:
    """An effect in the model's action language."""
    match action:
        case expr.Assign():
            return f"{action.target} = {expr.to_text(action.value)}"
        case expr.Raise() | expr.Send():
            verb = "raise" if isinstance(action, expr.Raise) else "send"
            args = f"({_args_text(action.args)})" if action.args else ""
            return f"{verb} {action.event}{args}"


def _actions_text(actions: Iterable[expr.Action], opaque: Iterable[ir.OpaqueCode]) -> str:
    parts = [action_text(a) for a in actions]
    parts += [f"<{o.language} code>" for o in opaque]
    return "; ".join(parts)


def trigger_text(trigger: ir.Trigger) -> str:
    if trigger.kind == ir.TriggerKind.TIME and trigger.delay_ms is not None:
        return f"after {trigger.delay_ms} ms"
    if trigger.kind == ir.TriggerKind.ANY:
        return "*"
    return trigger.name


def transition_label(transition: ir.Transition) -> tuple[str, ...]:
    """`event`, `[guard]`, `/ effect` (the parts that are there), each one line and clipped."""
    parts: list[str] = []
    triggers = ", ".join(trigger_text(t) for t in transition.triggers)
    if triggers:
        parts.append(clip(triggers, TRIGGER_LIMIT))
    guard = expr.to_text(transition.guard) if transition.guard is not None else None
    guard = guard or transition.guard_text
    if guard:
        parts.append(f"[{clip(guard, GUARD_LIMIT)}]")
    opaque = [o for o in transition.opaque if o.role == "effect"]
    effect = _actions_text(transition.effect, opaque)
    if effect:
        parts.append(f"/ {clip(effect, EFFECT_LIMIT)}")
    return tuple(parts)


_PSEUDO_SHAPES = {
    ir.PseudoKind.INITIAL: Shape.INITIAL,
    ir.PseudoKind.CHOICE: Shape.CHOICE,
    ir.PseudoKind.JUNCTION: Shape.JUNCTION,
    ir.PseudoKind.FORK: Shape.FORK,
    ir.PseudoKind.JOIN: Shape.JOIN,
    ir.PseudoKind.SHALLOW_HISTORY: Shape.SHALLOW_HISTORY,
    ir.PseudoKind.DEEP_HISTORY: Shape.DEEP_HISTORY,
    ir.PseudoKind.TERMINATE: Shape.TERMINATE,
    ir.PseudoKind.ENTRY_POINT: Shape.ENTRY_POINT,
    ir.PseudoKind.EXIT_POINT: Shape.EXIT_POINT,
}


def machine_stems(model: ir.Model) -> dict[str, str]:
    """Machine id -> file stem: its safe name, unique in the model even on a case-insensitive
    file system, never `swarm` (the composition diagram)."""
    taken = {COMPOSITION_STEM}
    stems: dict[str, str] = {}
    for machine in model.machines:
        base = machine.ident or identifier(machine.name, "machine")
        stem, n = base, 2
        while stem.lower() in taken:
            stem, n = f"{base}_{n}", n + 1
        taken.add(stem.lower())
        stems[machine.id] = stem
    return stems


class _Builder:
    def __init__(self, model: ir.Model, index: ModelIndex, stems: dict[str, str]) -> None:
        self.model = model
        self.index = index
        self.stems = stems
        self.ids = IdAllocator()
        self.vertex_ids: dict[str, str] = {}  # xmi id -> diagram id
        self.region_of: dict[str, str] = {}
        self.owner_of: dict[str, str | None] = {}

    def claim(self, name: str, fallback: str) -> str:
        return self.ids.claim(identifier(name, fallback))

    def diagram(self, machine: ir.Machine) -> Diagram:
        root: Vertex | None = None
        points = tuple(self.point(p) for p in machine.connection_points)
        root_id = self.claim(machine.name, "machine") if len(machine.regions) > 1 else None
        regions = tuple(self.region(r, root_id) for r in machine.regions)
        if root_id is not None:
            root = Vertex(root_id, machine.name, Shape.STATE, regions=regions)
        edges = tuple(self.edges(machine))
        members = tuple(m.name for m in self.index.members_running(machine))
        return Diagram(
            stem=self.stems[machine.id],
            name=machine.name,
            members=members,
            root=root,
            points=points,
            regions=regions,
            edges=edges,
            region_of=self.region_of,
            owner_of=self.owner_of,
        )

    def region(self, region: ir.Region, owner: str | None) -> Region:
        rid = self.ids.claim(f"{owner or 'top'}__{identifier(region.name, 'region')}", "region")
        self.owner_of[rid] = owner
        vertices = []
        for vertex in region.vertices:
            made = self.vertex(vertex, rid)
            vertices.append(made)
        return Region(rid, region.name, tuple(vertices))

    def point(self, pseudo: ir.Pseudostate, region: str | None = None) -> Vertex:
        vid = self.claim(pseudo.name, str(pseudo.kind))
        self.vertex_ids[pseudo.id] = vid
        if region is not None:
            self.region_of[vid] = region
        return Vertex(vid, pseudo.name, _PSEUDO_SHAPES[pseudo.kind])

    def vertex(self, vertex: ir.Vertex, region: str) -> Vertex:
        if isinstance(vertex, ir.Pseudostate):
            return self.point(vertex, region)
        vid = self.claim(vertex.name, vertex.type)
        self.vertex_ids[vertex.id] = vid
        self.region_of[vid] = region
        if isinstance(vertex, ir.FinalState):
            return Vertex(vid, vertex.name, Shape.FINAL)
        kind, lines = self.state_lines(vertex)
        link = self.stems.get(vertex.submachine) if vertex.submachine else None
        # A composite's own entry/exit points sit on its border (inside its cluster, in no
        # region: a pseudo-region owned by the state); others beside the state.
        inner = region
        if vertex.regions and vertex.connection_points:
            inner = self.ids.claim(f"{vid}__border")
            self.owner_of[inner] = vid
        points = tuple(self.point(p, inner) for p in vertex.connection_points)
        regions = tuple(self.region(r, vid) for r in vertex.regions)
        return Vertex(vid, vertex.name, Shape.STATE, kind, lines, link, regions, points)

    def state_lines(self, state: ir.State) -> tuple[ir.BehaviourKind | None, tuple[str, ...]]:
        kind = None
        lines: list[str] = []
        if state.activity is not None:
            behaviour = self.index.behaviours.get(state.activity.behaviour)
            name = behaviour.name if behaviour is not None else state.activity.behaviour
            kind = behaviour.kind if behaviour is not None else None
            bindings = ", ".join(
                f"{b.name} = {expr.to_text(b.value)}" for b in state.activity.bindings
            )
            lines.append(clip(f"do {name}({bindings})" if bindings else f"do {name}", 64))
        for role, actions in (("entry", state.entry), ("exit", state.exit)):
            opaque = [o for o in state.opaque if o.role == role]
            text = _actions_text(actions, opaque)
            if text:
                lines.append(f"{role} / {clip(text, ACTIVITY_LIMIT)}")
        if state.submachine:
            machine = self.index.machines.get(state.submachine)
            lines.append(f"submachine {machine.name if machine else state.submachine}")
        return kind, tuple(lines)

    def edges(self, machine: ir.Machine) -> list[Edge]:
        refs = connection_owner(machine)
        found = []
        for transition in machine.transitions:
            source = self.endpoint(transition.source, refs)
            target = self.endpoint(transition.target, refs)
            if source is None or target is None:
                continue  # a dangling reference: reported by the checks, not drawn
            found.append(Edge(source, target, transition_label(transition)))
        return found

    def endpoint(self, xmi_id: str, refs: dict[str, ir.State]) -> str | None:
        if xmi_id in self.vertex_ids:
            return self.vertex_ids[xmi_id]
        owner = refs.get(xmi_id)  # a connection point reference: drawn on its state
        return self.vertex_ids.get(owner.id) if owner is not None else None


def diagrams(model: ir.Model, machines: Sequence[ir.Machine] | None = None) -> list[Diagram]:
    """One diagram per machine (all, or those given), in model order."""
    index = ModelIndex(model)
    stems = machine_stems(model)
    chosen = {m.id for m in machines} if machines is not None else None
    return [
        _Builder(model, index, stems).diagram(m)
        for m in model.machines
        if chosen is None or m.id in chosen
    ]


# --- swarm composition and hardware


class NodeKind(StrEnum):
    SWARM = "swarm"
    MEMBER = "member"
    HARDWARE = "hardware"
    CLASS = "class"  # a general class that is not a hardware component


@dataclass(frozen=True)
class Box:
    id: str
    name: str
    kind: NodeKind
    stereotype: str | None = None  # «Swarm», «Sensor», ...
    lines: tuple[str, ...] = ()
    hardware: ir.HardwareKind | None = None


@dataclass(frozen=True)
class Link:
    source: str
    target: str
    label: str
    generalisation: bool = False  # else a composite part


@dataclass(frozen=True)
class Composition:
    name: str  # the model's name
    boxes: tuple[Box, ...]
    links: tuple[Link, ...]

    def hardware_kinds(self) -> list[ir.HardwareKind]:
        shown = {b.hardware for b in self.boxes}
        return [k for k in HARDWARE_STYLES if k in shown]


def _part_label(part: ir.Part) -> str:
    return part.name if part.count == 1 else f"{part.name} [{part.count}]"


def _member_lines(model: ir.Model, member: ir.MemberType) -> tuple[str, ...]:
    """Role, machine and, when several swarm parts have this type, the swarm's total of it
    (`query.composition`, the count the backends and the simulator run): each part's arrow
    shows only its own count. One part: no total line, its arrow says it."""
    lines: list[str] = []
    if member.role:
        lines.append(f"role: {member.role}")
    machine = ModelIndex(model).machines.get(member.machine or "")
    if machine is not None:
        lines.append(f"machine: {machine.name}")
    parts = sum(p.type_name == member.name for s in model.swarms for p in s.members)
    if parts > 1:
        total = swarm_composition(model).get(member.name, 0)
        lines.append(f"members: {total} ({parts} parts)")
    return tuple(lines)


def _shown_hardware(
    model: ir.Model,
    member: ir.MemberType | None,
    by_id: dict[str, ir.HardwareComponent],
    by_name: dict[str, ir.HardwareComponent],
) -> list[ir.HardwareComponent]:
    """Every hardware class, or with `member` its parts' classes and their ancestors."""
    if member is None:
        return list(model.hardware)
    queue = [by_id[p.type_id] for p in member.hardware if p.type_id in by_id]
    seen: set[str] = set()
    while queue:
        component = queue.pop(0)
        if component.id in seen:
            continue
        seen.add(component.id)
        queue.extend(by_name[g] for g in component.generals if g in by_name)
    return [h for h in model.hardware if h.id in seen]


def _generalisations(
    shown: list[ir.HardwareComponent],
    by_name: dict[str, ir.HardwareComponent],
    box_of: dict[str, str],
    ids: IdAllocator,
    boxes: list[Box],
    links: list[Link],
) -> None:
    """Generalisation links of the shown hardware; a general class that is no hardware
    component gets a box of its own (appended after the others, in first-use order)."""
    extra: dict[str, str] = {}
    for component in shown:
        for general in component.generals:
            if general in by_name and by_name[general].id in box_of:
                target = box_of[by_name[general].id]
            else:
                if general not in extra:
                    extra[general] = ids.claim(f"type_{identifier(general, 'class')}")
                    boxes.append(Box(extra[general], general, NodeKind.CLASS))
                target = extra[general]
            links.append(Link(box_of[component.id], target, "", generalisation=True))


def composition(model: ir.Model, member: ir.MemberType | None = None) -> Composition:
    """Swarms -> member types (with counts) -> hardware parts (with kinds) -> generalisations.
    With `member`, only what concerns that member type."""
    ids = IdAllocator()
    members = [member] if member is not None else list(model.member_types)
    member_ids = {m.id for m in members}
    swarms = [
        s for s in model.swarms if member is None or any(p.type_id in member_ids for p in s.members)
    ]
    by_id = {h.id: h for h in model.hardware}
    by_name: dict[str, ir.HardwareComponent] = {}
    for component in model.hardware:
        by_name.setdefault(component.name, component)

    shown = _shown_hardware(model, member, by_id, by_name)
    boxes: list[Box] = []
    links: list[Link] = []
    box_of: dict[str, str] = {}
    for swarm in swarms:
        sid = ids.claim(f"swarm_{swarm.ident}")
        box_of[swarm.id] = sid
        boxes.append(Box(sid, swarm.name, NodeKind.SWARM, "Swarm"))
    for m in members:
        mid = ids.claim(f"member_{m.ident}")
        box_of[m.id] = mid
        boxes.append(Box(mid, m.name, NodeKind.MEMBER, "SwarmMember", _member_lines(model, m)))
    for component in shown:
        hid = ids.claim(f"hw_{component.ident}")
        box_of[component.id] = hid
        lines: list[str] = []
        if component.communication_type:
            lines.append(f"type: {component.communication_type}")
        boxes.append(
            Box(hid, component.name, NodeKind.HARDWARE, str(component.kind), tuple(lines),
                component.kind)
        )  # fmt: skip
    _generalisations(shown, by_name, box_of, ids, boxes, links)
    for swarm in swarms:
        for part in swarm.members:
            if part.type_id in box_of and part.type_id in member_ids:
                links.append(Link(box_of[swarm.id], box_of[part.type_id], _part_label(part)))
    for m in members:
        for part in m.hardware:
            if part.type_id in box_of:
                links.append(Link(box_of[m.id], box_of[part.type_id], _part_label(part)))
    # parts first, generalisations after: the order of the text follows the reading order
    links.sort(key=lambda link: link.generalisation)
    return Composition(model.name, tuple(boxes), tuple(links))
