"""The lowering's shared state: the machine copies (one per submachine path) and their readable
vertex ids, decided once per chart before any node is built."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import field

from swarmgen.chart import values
from swarmgen.ir.nodes import (
    Behaviour,
    FinalState,
    Machine,
    MemberType,
    Property,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    Transition,
    Vertex,
)
from swarmgen.ir.query import ModelIndex, Placed, incoming, outgoing, walk
from swarmgen.names import IdAllocator, identifier, qualified
from swarmgen.records import dataclass

SKIPPED = {PseudoKind.INITIAL, PseudoKind.JOIN, PseudoKind.TERMINATE}  # no node of their own

Instance = tuple[str, ...]  # ids of the submachine states that lead to a machine's copy
Key = tuple[Instance, str]  # one copy of one vertex


@dataclass
class Copy:
    """One machine's copy under one submachine path, with its lookup tables."""

    machine: Machine
    instance: Instance
    placed: dict[str, Placed]
    leaving: dict[str, list[Transition]]
    arriving: dict[str, list[Transition]]
    parents: dict[str, str | None]  # vertex id -> id of the state holding it
    joins: tuple[str, ...] = ()  # ids of the join pseudostates, found once (not per state)


@dataclass
class Context:
    """What lowering one chart has decided so far: copies, ids, data, behaviours used."""

    index: ModelIndex
    root: Machine
    member: MemberType | None
    ids: IdAllocator = field(default_factory=IdAllocator)
    vertex_ids: dict[Key, str] = field(default_factory=dict)
    copies: dict[Instance, Copy] = field(default_factory=dict)
    data: dict[str, Property] = field(default_factory=dict)
    terminate_id: str | None = None
    used_behaviours: dict[str, Behaviour] = field(default_factory=dict)

    def _copy(self, machine: Machine, instance: Instance) -> Copy:
        if instance not in self.copies:
            placed = {p.vertex.id: p for p in walk(machine)}
            parents = {vid: (p.parent.id if p.parent else None) for vid, p in placed.items()}
            joins = tuple(
                vid
                for vid, p in placed.items()
                if isinstance(p.vertex, Pseudostate) and p.vertex.kind == PseudoKind.JOIN
            )
            self.copies[instance] = Copy(
                machine, instance, placed, outgoing(machine), incoming(machine), parents, joins
            )
        return self.copies[instance]

    def _allocate(self, machine: Machine, instance: Instance) -> None:
        """Give every vertex copy a readable id: its name if unique, else the shortest unique
        qualified suffix (`GoToZone__Moving`)."""
        chains: dict[Key, list[str]] = {}
        self._chains(machine, instance, [], chains)
        for length in range(1, max((len(ch) for ch in chains.values()), default=0) + 1):
            pending = {k: ch for k, ch in chains.items() if k not in self.vertex_ids}
            counts: dict[str, int] = {}
            for chain in pending.values():
                candidate = qualified(*chain[-length:])
                counts[candidate] = counts.get(candidate, 0) + 1
            for key, chain in pending.items():
                candidate = qualified(*chain[-length:])
                if counts[candidate] == 1 and (candidate not in self.ids or length == len(chain)):
                    self.vertex_ids[key] = self.ids.claim(candidate)
        for key, chain in chains.items():
            if key not in self.vertex_ids:
                self.vertex_ids[key] = self.ids.claim(qualified(*chain))

    def _chains(
        self, machine: Machine, instance: Instance, prefix: list[str], out: dict[Key, list[str]]
    ) -> None:
        copy = self._copy(machine, instance)
        if len(machine.regions) > 1 and not instance:
            prefix = [*prefix, machine.ident]
            out[(instance, f"{machine.id}#parallel")] = prefix
        for point in machine.connection_points:
            out[(instance, point.id)] = [*prefix, _vertex_name(point)]
        self._region_chains(copy, machine.regions, instance, prefix, out)

    def _region_chains(
        self,
        copy: Copy,
        regions: Sequence[Region],
        instance: Instance,
        prefix: list[str],
        out: dict[Key, list[str]],
    ) -> None:
        for number, region in enumerate(regions):
            region_prefix = prefix
            if len(regions) > 1:
                region_prefix = [*prefix, identifier(region.name, f"region{number + 1}")]
                out[(instance, region.id)] = region_prefix
            for vertex in region.vertices:
                if isinstance(vertex, Pseudostate) and vertex.kind in SKIPPED:
                    continue
                chain = [*region_prefix, _vertex_name(vertex)]
                out[(instance, vertex.id)] = chain
                if isinstance(vertex, State):
                    for point in vertex.connection_points:
                        out[(instance, point.id)] = [*chain, _vertex_name(point)]
                    if vertex.submachine and vertex.submachine in self.index.machines:
                        sub = self.index.machines[vertex.submachine]
                        self._chains(sub, (*instance, vertex.id), chain, out)
                    else:
                        self._region_chains(copy, vertex.regions, instance, chain, out)

    def _id(self, instance: Instance, vertex_id: str) -> str:
        return self.vertex_ids[(instance, vertex_id)]

    def _initial(self, prop: Property) -> object:
        return values.initial(prop, self.index.datatypes, enums=self.index.enumerations)

    def _initial_and_blank(self, prop: Property) -> tuple[object, object]:
        """A datum's initial value and what an output not given writes into it."""
        held = self._initial(prop)
        enums = self.index.enumerations
        return held, values.blank(prop, held, self.index.datatypes, enums)


def _vertex_name(vertex: Vertex) -> str:
    if vertex.name:
        return identifier(vertex.name)
    if isinstance(vertex, FinalState):
        return "final"
    if isinstance(vertex, Pseudostate):
        return identifier(vertex.kind.value)
    return "state"
