"""What the state machine diagrams show, independent of the output format: one `Diagram` per
state machine, computed once from the IR so that Mermaid and DOT agree.

Every text here is the model's own (raw, unescaped); each renderer escapes it for its format.
Ids are safe identifiers (`[A-Za-z0-9_]`, from `names.identifier`), unique in their diagram and
allocated in model order, so the output is deterministic.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import field
from enum import StrEnum

from swarmgen import expr
from swarmgen.errors import SwarmgenError
from swarmgen.graph.labels import ACTIVITY_LIMIT, actions_text, clip, transition_label
from swarmgen.graph.structure import COMPOSITION_STEM
from swarmgen.graph.styles import BEHAVIOUR_STYLES
from swarmgen.ir import nodes as ir
from swarmgen.ir.query import ModelIndex, connection_owner
from swarmgen.names import IdAllocator, identifier
from swarmgen.records import dataclass


class GraphError(SwarmgenError):
    """The diagrams cannot be drawn as asked (an unknown member type, Graphviz missing)."""

    verbatim = True  # its messages list choices over several lines, written for the terminal


class Shape(StrEnum):
    """How a state is drawn; a pseudostate is drawn by its own `ir.PseudoKind`."""

    STATE = "state"
    FINAL = "final"


# --- state machines


@dataclass(frozen=True)
class Vertex:
    """A vertex as drawn: its shape, label lines and, for a composite, its regions and points."""

    id: str
    name: str  # the model's name
    shape: Shape | ir.PseudoKind
    kind: ir.BehaviourKind | None = None  # of the behaviour its doActivity runs
    lines: tuple[str, ...] = ()  # more label lines: `do ...`, `entry / ...`, `submachine ...`
    link: str | None = None  # stem of the submachine's diagram
    regions: tuple[Region, ...] = ()  # non-empty: a composite state, drawn as a cluster
    points: tuple[Vertex, ...] = ()  # its entry and exit points

    @property
    def composite(self) -> bool:
        """Whether the vertex is a composite state (drawn as a cluster)."""
        return bool(self.regions)


@dataclass(frozen=True)
class Region:
    """A region of a composite state (or of the machine) and its vertices."""

    id: str
    name: str
    vertices: tuple[Vertex, ...]


@dataclass(frozen=True)
class Edge:
    """A transition as drawn: source and target ids and its label parts."""

    source: str
    target: str
    parts: tuple[str, ...]  # `event`, `[guard]`, `/ effect`: the parts that are there

    @property
    def label(self) -> str:
        """The label parts as one line."""
        return " ".join(self.parts)


@dataclass(frozen=True)
class Diagram:
    """Everything one state machine diagram shows, with the lookups renderers need."""

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
        """Every region, the top-level ones first."""
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
        return Vertex(vid, pseudo.name, pseudo.kind)

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
            text = actions_text(actions, opaque)
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
