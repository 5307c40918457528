"""Read-only queries over the IR shared by checks, emitters and backends."""

from __future__ import annotations

from collections.abc import Iterator
from functools import cached_property

from swarmgen.ir.nodes import (
    Behaviour,
    DataType,
    Enumeration,
    Event,
    Machine,
    MemberType,
    Model,
    Property,
    Pseudostate,
    Region,
    State,
    Transition,
    Vertex,
)
from swarmgen.records import dataclass


@dataclass(frozen=True)
class Placed:
    """A vertex with the region that holds it and the state that holds that region."""

    vertex: Vertex
    region: Region | None  # None for a machine's or a state's connection points
    parent: State | None  # None at a machine's top level


_WALKS: dict[int, tuple[Machine, list[Placed]]] = {}


def walk(machine: Machine) -> list[Placed]:
    """Every vertex of the machine (not of its submachines), parents before children.

    Memoised by identity (the IR is immutable): every check walks every machine."""
    cached = _WALKS.get(id(machine))
    if cached is not None and cached[0] is machine:
        return cached[1]
    if len(_WALKS) > 256:
        _WALKS.clear()
    placed = list(_walk_machine(machine))
    _WALKS[id(machine)] = (machine, placed)
    return placed


def _walk_machine(machine: Machine) -> Iterator[Placed]:
    for point in machine.connection_points:
        yield Placed(point, None, None)
    for region in machine.regions:
        yield from _walk_region(region, None)


def _walk_region(region: Region, parent: State | None) -> Iterator[Placed]:
    for vertex in region.vertices:
        yield Placed(vertex, region, parent)
        if isinstance(vertex, State):
            for point in vertex.connection_points:
                yield Placed(point, None, vertex)
            for sub in vertex.regions:
                yield from _walk_region(sub, vertex)


class ModelIndex:
    """Lookups by id, built once per model (`ModelIndex(model)` returns the cached index of the
    last model it was asked for: every check shares it)."""

    _last: ModelIndex | None = None

    def __new__(cls, model: Model) -> ModelIndex:
        """The cached index when `model` is the last one indexed, else a new one."""
        last = cls._last
        if last is not None and last.model is model:
            return last
        index = super().__new__(cls)
        index._setup(model)
        cls._last = index
        return index

    def __init__(self, model: Model) -> None:
        pass  # see _setup: __new__ returns a cached index

    def placed(self, machine: Machine) -> list[Placed]:
        """`walk(machine)`, computed once per machine."""
        found = self._placed.get(machine.id)
        if found is None or found[0] is not machine:
            found = (machine, walk(machine))
            self._placed[machine.id] = found
        return found[1]

    def _setup(self, model: Model) -> None:
        self._placed: dict[str, tuple[Machine, list[Placed]]] = {}
        self._submachines: dict[str, list[str]] = {}
        self.model = model
        self.machines: dict[str, Machine] = {m.id: m for m in model.machines}
        self.behaviours: dict[str, Behaviour] = {b.id: b for b in model.behaviours}
        self.events: dict[str, Event] = {e.id: e for e in model.events}
        self.datatypes: dict[str, DataType] = {d.name: d for d in model.datatypes}
        self.enumerations: dict[str, Enumeration] = {e.name: e for e in model.enumerations}
        self.events_by_name: dict[str, Event] = {}
        for event in model.events:
            self.events_by_name.setdefault(event.name, event)

    def submachines(self, machine: Machine) -> list[str]:
        """Ids of the submachines the machine's states use, computed once per machine."""
        found = self._submachines.get(machine.id)
        if found is None:
            found = [
                p.vertex.submachine
                for p in self.placed(machine)
                if isinstance(p.vertex, State) and p.vertex.submachine
            ]
            self._submachines[machine.id] = found
        return found

    def reachable_machines(self, root: Machine) -> list[Machine]:
        """The machine and every machine it uses as a submachine, transitively, cycle-safe."""
        seen: dict[str, Machine] = {}
        stack = [root]
        while stack:
            machine = stack.pop()
            if machine.id in seen:
                continue
            seen[machine.id] = machine
            stack.extend(
                self.machines[s] for s in reversed(self.submachines(machine)) if s in self.machines
            )
        return list(seen.values())

    @cached_property
    def data_scope(self) -> dict[str, dict[str, Property]]:
        """Member data visible in each machine: its context's attributes, the attributes of
        every member type that runs it (directly or as a submachine), and behaviour outputs."""
        scope: dict[str, dict[str, Property]] = {
            m.id: {p.name: p for p in m.data} for m in self.model.machines
        }
        for member in self.model.member_types:
            root = self.machines.get(member.machine or "")
            if root is None:
                continue
            for machine in self.reachable_machines(root):
                for prop in member.data:
                    scope[machine.id].setdefault(prop.name, prop)
        for machine in self.model.machines:
            for behaviour in self.behaviours_of(machine):
                for out in behaviour.outputs:
                    scope[machine.id].setdefault(out.name, out)
        return scope

    def behaviours_of(self, machine: Machine) -> list[Behaviour]:
        """The library behaviours the machine's states run, in walk order."""
        found = []
        for placed in walk(machine):
            vertex = placed.vertex
            if isinstance(vertex, State) and vertex.activity is not None:
                behaviour = self.behaviours.get(vertex.activity.behaviour)
                if behaviour is not None:
                    found.append(behaviour)
        return found

    def hardware_parameters(self, member: MemberType) -> dict[str, Property]:
        """Parameters of the member type's hardware components, by name (first part wins)."""
        components = {h.id: h for h in self.model.hardware}
        found: dict[str, Property] = {}
        for part in member.hardware:
            component = components.get(part.type_id)
            if component is not None:
                for parameter in component.parameters:
                    found.setdefault(parameter.name, parameter)
        return found

    def capabilities(self, member: MemberType) -> dict[str, str]:
        """Capability (class name, own or inherited) -> the part that provides it."""
        components = {h.id: h for h in self.model.hardware}
        found: dict[str, str] = {}
        for part in member.hardware:
            component = components.get(part.type_id)
            names = component.capabilities if component is not None else (part.type_name,)
            for name in names:
                found.setdefault(name, part.name)
        return found

    def members_running(self, machine: Machine) -> list[MemberType]:
        """The member types whose behaviour uses the machine (as root or submachine)."""
        return [m for m in self.model.member_types if machine in self.member_machines(m)]

    def member_machines(self, member: MemberType) -> list[Machine]:
        """The member type's machine and every submachine it uses."""
        root = self.machines.get(member.machine or "")
        return self.reachable_machines(root) if root is not None else []


def composition(model: Model) -> dict[str, int]:
    """Member type name -> number of members in the swarm: the counts of all parts of that type,
    summed over every part of every Swarm class (`uavs1: UAV[2]` and `uavs2: UAV[3]` make 5
    UAVs), in the order the types first appear. Computed here once so that every backend, the
    simulator and the composition diagram run the same swarm (a dict built part by part used to
    keep only the last part of a type). Types that no swarm contains are absent."""
    counts: dict[str, int] = {}
    for swarm in model.swarms:
        for part in swarm.members:
            counts[part.type_name] = counts.get(part.type_name, 0) + part.count
    return counts


def vertices_by_id(machine: Machine) -> dict[str, Placed]:
    """Every vertex of the machine (with its place) by id."""
    return {p.vertex.id: p for p in walk(machine)}


def connection_owner(machine: Machine) -> dict[str, State]:
    """ConnectionPointReference id -> the submachine state that carries it."""
    return {
        c.id: p.vertex
        for p in walk(machine)
        if isinstance(p.vertex, State)
        for c in p.vertex.connections
    }


def outgoing(machine: Machine) -> dict[str, list[Transition]]:
    """Transitions of the machine by source vertex id."""
    result: dict[str, list[Transition]] = {}
    for transition in machine.transitions:
        result.setdefault(transition.source, []).append(transition)
    return result


def incoming(machine: Machine) -> dict[str, list[Transition]]:
    """Transitions of the machine by target vertex id."""
    result: dict[str, list[Transition]] = {}
    for transition in machine.transitions:
        result.setdefault(transition.target, []).append(transition)
    return result


def initial_of(region: Region) -> list[Pseudostate]:
    """The region's initial pseudostates (a well-formed region has one)."""
    return [v for v in region.vertices if isinstance(v, Pseudostate) and v.kind == "initial"]


def sessions(model: Model) -> list[Model]:
    """The models of every `<invoke>`d document below this one (their own too), depth first:
    the checks run on each as on a model of its own."""
    found: list[Model] = []
    for machine in model.machines:
        for placed in walk(machine):
            if isinstance(placed.vertex, State):
                for invoke in placed.vertex.invokes:
                    found.append(invoke.session)
                    found += sessions(invoke.session)
    return found
