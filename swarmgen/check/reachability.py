"""Reachability: states no path reaches, states with no way out, machines that never end.

The graph over-approximates what can happen (every transition may fire), so a state reported
unreachable is really unreachable. Machines used as submachines are analysed from their initial
states and entry points; states with no way out are reported only in machines that no
submachine state wraps (there, the wrapping state's transitions may leave).
"""

from __future__ import annotations

from collections import deque

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import (
    FinalState,
    Machine,
    Model,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    Transition,
)
from swarmgen.ir.query import ModelIndex, Placed, connection_owner, initial_of, outgoing, walk


def _initial_targets(leaving: dict[str, list[Transition]], region: Region) -> list[str]:
    return [t.target for p in initial_of(region) for t in leaving.get(p.id, [])]


def reachable(machine: Machine) -> set[str]:
    """Vertex ids that some run of the machine can enter."""
    placed = {p.vertex.id: p for p in walk(machine)}
    leaving = outgoing(machine)
    owners = connection_owner(machine)
    start = [t for region in machine.regions for t in _initial_targets(leaving, region)]
    start += [p.id for p in machine.connection_points if p.kind == PseudoKind.ENTRY_POINT]
    seen: set[str] = set()
    queue = deque(start)
    while queue:
        vertex_id = queue.popleft()
        if vertex_id in owners:  # a ConnectionPointReference: entering its submachine state
            vertex_id = owners[vertex_id].id
        if vertex_id in seen or vertex_id not in placed:
            continue
        seen.add(vertex_id)
        queue.extend(_successors(machine, placed[vertex_id], placed, leaving))
    return seen


def _successors(
    machine: Machine,
    where: Placed,
    placed: dict[str, Placed],
    leaving: dict[str, list],  # type: ignore[type-arg]
) -> list[str]:
    vertex = where.vertex
    found = [t.target for t in leaving.get(vertex.id, [])]
    if where.parent is not None:  # being here means the enclosing state is active
        found.append(where.parent.id)
    if isinstance(vertex, State):
        for region in vertex.regions:
            found += _initial_targets(leaving, region)
        for conn in vertex.connections:
            found += [t.target for t in leaving.get(conn.id, [])]
    if (
        isinstance(vertex, Pseudostate)
        and vertex.kind
        in {
            PseudoKind.SHALLOW_HISTORY,
            PseudoKind.DEEP_HISTORY,
        }
        and where.region is not None
    ):
        found += _initial_targets(leaving, where.region)
    return found


def check_reachability(model: Model) -> list[Diagnostic]:
    """Report unreachable states, states with no way out and machines that never end."""
    index = ModelIndex(model)
    wrapped = {s for m in model.machines for s in index.submachines(m)}
    found: list[Diagnostic] = []
    for machine in model.machines:
        reached = reachable(machine)
        placed = list(walk(machine))
        for where in placed:
            vertex = where.vertex
            if isinstance(vertex, State | FinalState) and vertex.id not in reached:
                found.append(
                    dg.UNREACHABLE_STATE.at(vertex.span, state=vertex.name, machine=machine.name)
                )
        if machine.id not in wrapped:
            found += _no_way_out(machine, placed, reached)
            found += _never_ends(index, machine, placed, reached)
    return found


def _no_way_out(machine: Machine, placed: list[Placed], reached: set[str]) -> list[Diagnostic]:
    sources = {t.source for t in machine.transitions}
    sources |= {
        c.id
        for p in placed
        if isinstance(p.vertex, State)
        for c in p.vertex.connections
        if c.id in sources
    }
    parents = {p.vertex.id: p.parent for p in placed}
    found = []
    for where in placed:
        state = where.vertex
        if (
            not isinstance(state, State)
            or state.regions
            or state.submachine
            or state.id not in reached
        ):
            continue
        chain: list[State] = [state]
        parent = parents.get(state.id)
        while parent is not None:
            chain.append(parent)
            parent = parents.get(parent.id)
        if not any(s.id in sources for s in chain):
            found.append(dg.NO_WAY_OUT.at(state.span, state=state.name, machine=machine.name))
    return found


def _never_ends(
    index: ModelIndex, machine: Machine, placed: list[Placed], reached: set[str]
) -> list[Diagnostic]:
    """Only for member behaviours: a member whose machine cannot end cannot be stopped cleanly."""
    if not any(m.machine == machine.id for m in index.model.member_types):
        return []
    top_finals = [
        v.id
        for region in machine.regions
        for v in region.vertices
        if isinstance(v, FinalState)
        or (isinstance(v, Pseudostate) and v.kind == PseudoKind.TERMINATE)
    ]
    terminates = any(
        isinstance(p.vertex, Pseudostate)
        and p.vertex.kind == PseudoKind.TERMINATE
        and p.vertex.id in reached
        for p in placed
    )
    if terminates or any(f in reached for f in top_finals):
        return []
    return [dg.NEVER_ENDS.at(machine.span, machine=machine.name)]
