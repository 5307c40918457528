"""Well-formedness of state machines that the lowering would turn into wrong output: where
initial and history transitions lead, what forks, joins, choices and junctions connect,
transitions into initial pseudostates, internal transitions, submachine states with regions.

UML states these rules (2.5.1, 14.5); each broke an output in its own way before it was
checked (docs/profile.md, "Ill-formed machines"): two states active in one region, a
`<transition>` with no target, a KeyError in the lowering, a choice that stays active.
"""

from __future__ import annotations

from collections.abc import Sequence

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import (
    Machine,
    Model,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    Transition,
)
from swarmgen.ir.query import Placed, connection_owner, incoming, outgoing, walk
from swarmgen.span import Span

# One level of a vertex's position: the state owning the region (None: the machine) and the
# region's id. A vertex's path runs from the machine's top region down to its own region.
Level = tuple[str | None, str]
_HISTORY = {PseudoKind.SHALLOW_HISTORY, PseudoKind.DEEP_HISTORY}
_BRANCHING = {PseudoKind.CHOICE, PseudoKind.JUNCTION}


class _Machine:
    """A machine's vertices with their positions, computed once for all its rules."""

    def __init__(self, machine: Machine) -> None:
        self.machine = machine
        self.placed: dict[str, Placed] = {p.vertex.id: p for p in walk(machine)}
        self.owners = connection_owner(machine)
        self.leaving = outgoing(machine)
        self.arriving = incoming(machine)
        self._paths: dict[str, tuple[Level, ...]] = {}

    def name(self, vertex_id: str) -> str:
        placed = self.placed.get(vertex_id)
        if placed is None:
            owner = self.owners.get(vertex_id)
            return owner.name if owner is not None else vertex_id
        return placed.vertex.name or (
            placed.vertex.kind.value if isinstance(placed.vertex, Pseudostate) else vertex_id
        )

    def path(self, vertex_id: str) -> tuple[Level, ...]:
        """The regions that hold the vertex, outermost first; a connection point (of a state,
        or a ConnectionPointReference) stands where its state stands."""
        found = self._paths.get(vertex_id)
        if found is not None:
            return found
        levels: list[Level] = []
        current: str | None = vertex_id
        while current is not None:
            placed = self.placed.get(current)
            if placed is None:  # a ConnectionPointReference: where its submachine state is
                owner = self.owners.get(current)
                current = owner.id if owner is not None else None
                continue
            if placed.region is not None:
                levels.append((placed.parent.id if placed.parent else None, placed.region.id))
            current = placed.parent.id if placed.parent is not None else None
        found = tuple(reversed(levels))
        self._paths[vertex_id] = found
        return found

    def conflict(self, ends: Sequence[str]) -> tuple[int, int] | None:
        """Two of the vertices (by index) that cannot be active together, or None when every
        pair parts in two different regions of one state (or of the machine): SCXML's legal
        target set. One pass over the paths as a tree of regions, not a test per pair (a fork
        into 1,000 regions)."""
        first: dict[tuple[Level, ...], int] = {}  # a region -> the first vertex inside it
        ended: dict[tuple[Level, ...], int] = {}  # a region -> the vertex that stands in it
        owner: dict[tuple[Level, ...], tuple[str | None, int]] = {}  # the state its regions part
        for i, end in enumerate(ends):
            path = self.path(end)
            for k in range(1, len(path) + 1):
                prefix, parent = path[:k], path[: k - 1]
                if prefix in ended:  # another vertex stands in a region that holds this one
                    return ended[prefix], i
                if k == len(path) and prefix in first:  # two in one region
                    return first[prefix], i
                seen = owner.setdefault(parent, (path[k - 1][0], i))
                if seen[0] != path[k - 1][0]:  # in two different states of one region
                    return seen[1], i
                first.setdefault(prefix, i)
            ended[path] = i
        return None

    def inside(self, vertex_id: str, region: Region) -> bool:
        return any(level[1] == region.id for level in self.path(vertex_id))


def check_wellformed(model: Model) -> list[Diagnostic]:
    """Report vertices and regions the lowering would turn into wrong output."""
    found: list[Diagnostic] = []
    for machine in model.machines:
        m = _Machine(machine)
        found += _into_initial(m)
        found += _kinds(m)
        for placed in m.placed.values():
            vertex = placed.vertex
            if isinstance(vertex, State):
                found += _state_rules(m, vertex)
            elif isinstance(vertex, Pseudostate):
                found += _pseudostate_rules(m, placed, vertex)
        found += _region_names(machine.name, machine.regions)
        found += [
            dg.BAD_TARGET.at(t.span, "reenters", name=t.name, state=m.name(t.reenters))
            for t in machine.transitions
            if t.reenters is not None and not _holds_both(m, t, t.reenters)
        ]
    return found


def _holds_both(m: _Machine, transition: Transition, state: str) -> bool:
    """Whether `state` (a state, or the machine) holds the transition's source and target."""
    if state == m.machine.id:
        return True
    return all(
        any(level[0] == state for level in m.path(end))
        for end in (transition.source, transition.target)
    )


def _pseudostate_rules(m: _Machine, placed: Placed, vertex: Pseudostate) -> list[Diagnostic]:
    if vertex.kind in {PseudoKind.INITIAL, *_HISTORY} and placed.region is not None:
        return _default_target(m, vertex, placed.region)
    if vertex.kind == PseudoKind.FORK:
        return _fork(m, vertex)
    if vertex.kind == PseudoKind.JOIN:
        return _join(m, vertex)
    if vertex.kind in _BRANCHING:
        return _branching(m, vertex)
    if vertex.kind == PseudoKind.TERMINATE and m.leaving.get(vertex.id):
        return [
            dg.BAD_PSEUDOSTATE.at(m.leaving[vertex.id][0].span, "terminate", label=_label(vertex))
        ]
    return []


def _label(vertex: Pseudostate) -> str:
    return f"{vertex.kind.value} '{vertex.name}'" if vertex.name else vertex.kind.value


def _into_initial(m: _Machine) -> list[Diagnostic]:
    """UML: an initial pseudostate has no incoming transition. The lowering gives it no node
    (it becomes the region's `<initial>`), so such a transition had nowhere to go (KeyError)."""
    found = []
    for transition in m.machine.transitions:
        placed = m.placed.get(transition.target)
        if (
            placed is not None
            and isinstance(placed.vertex, Pseudostate)
            and placed.vertex.kind == PseudoKind.INITIAL
        ):
            variant = "itself" if transition.source == transition.target else dg.DEFAULT
            found.append(
                dg.ENTERS_INITIAL.at(
                    transition.span,
                    variant,
                    source=m.name(transition.source),
                    target=m.name(transition.target),
                )
            )
    return found


def _default_target(m: _Machine, vertex: Pseudostate, region: Region) -> list[Diagnostic]:
    """An initial (or a history's default) transition enters its own region: one pointing
    into a sibling region made two states of that region active at once."""
    found = []
    for transition in m.leaving.get(vertex.id, []):
        target = m.placed.get(transition.target)
        into_initial = (
            target is not None
            and isinstance(target.vertex, Pseudostate)
            and target.vertex.kind == PseudoKind.INITIAL
        )
        if into_initial or m.inside(transition.target, region):
            continue  # an initial target is SG143's
        found.append(
            dg.INITIAL_LEAVES_REGION.at(
                transition.span,
                notes=[dg.INITIAL_LEAVES_REGION.note("leaves-active")],
                kind=vertex.kind.value,
                region=region.name,
                target=m.name(transition.target),
            )
        )
    return found


def _fork(m: _Machine, vertex: Pseudostate) -> list[Diagnostic]:
    out = m.leaving.get(vertex.id, [])
    label = _label(vertex)
    found = [dg.BAD_FORK.at(t.span, "guard", label=label) for t in out if t.guard is not None]
    if len(out) == 1:
        found.append(_single(label, "outgoing", out[0].span))
    found += _orthogonal(m, label, "targets", [t.target for t in out], [t.span for t in out])
    return found


def _join(m: _Machine, vertex: Pseudostate) -> list[Diagnostic]:
    label = _label(vertex)
    out = m.leaving.get(vertex.id, [])
    into = m.arriving.get(vertex.id, [])
    found = []
    if len(out) != 1:
        found.append(dg.BAD_JOIN.at(vertex.span, "outgoing", label=label, count=len(out)))
    for transition in into:
        source = m.placed.get(transition.source)
        if source is None or not isinstance(source.vertex, State):
            found.append(
                dg.BAD_JOIN.at(
                    transition.span, "not-from-state", label=label, source=m.name(transition.source)
                )
            )
    if len(into) == 1:
        found.append(_single(label, "incoming", into[0].span))
    found += _orthogonal(m, label, "sources", [t.source for t in into], [t.span for t in into])
    return found


def _single(label: str, direction: str, span: Span) -> Diagnostic:
    return dg.SINGLE_BRANCH.at(span, label=label, direction=direction)


def _orthogonal(
    m: _Machine, label: str, what: str, ends: Sequence[str], spans: Sequence[Span]
) -> list[Diagnostic]:
    """Fork targets and join sources: pairwise in different regions of one state."""
    pair = m.conflict(ends)
    if pair is None:
        return []
    i, j = pair
    code = dg.BAD_FORK if what == "targets" else dg.BAD_JOIN
    return [
        code.at(
            spans[j],
            "not-orthogonal",
            notes=[code.note("other-at", where=spans[i].location())],
            what=what,
            first=m.name(ends[i]),
            second=m.name(ends[j]),
            label=label,
        )
    ]


def _branching(m: _Machine, vertex: Pseudostate) -> list[Diagnostic]:
    """A choice or junction whose guards can all be false stays active as a state in every
    engine (UML calls the model ill-formed): one branch must be `else` or unguarded."""
    out = m.leaving.get(vertex.id, [])
    if not out or any(_always(t) for t in out):
        return []  # no way out at all is SG116
    guards = [t.guard_text or "?" for t in out]
    return [
        dg.CHOICE_WITHOUT_ELSE.at(
            vertex.span,
            notes=[dg.CHOICE_WITHOUT_ELSE.note("guards", guards=", ".join(guards))],
            label=_label(vertex),
        )
    ]


def _always(transition: Transition) -> bool:
    guard = transition.guard
    return (
        guard is None
        or isinstance(guard, expr.Else)
        or (isinstance(guard, expr.Const) and guard.value is True)
    )


def _kinds(m: _Machine) -> list[Diagnostic]:
    """An internal transition does not leave its state; one to another state was emitted as
    an external transition."""
    return [
        dg.BAD_INTERNAL.at(t.span, source=m.name(t.source), target=m.name(t.target))
        for t in m.machine.transitions
        if t.kind == "internal" and t.source != t.target
    ]


def _state_rules(m: _Machine, state: State) -> list[Diagnostic]:
    found = _region_names(state.name, state.regions)
    if state.submachine and state.regions:
        found.append(dg.SUBMACHINE_WITH_REGIONS.at(state.span, state=state.name))
    return found


def _region_names(owner: str, regions: Sequence[Region]) -> list[Diagnostic]:
    """Region names appear in traces and diagrams (`sg:region`); two alike are ambiguous."""
    first: dict[str, Region] = {}
    found = []
    for region in regions:
        if not region.name:
            continue
        other = first.setdefault(region.name, region)
        if other is not region:
            found.append(
                dg.DUPLICATE_REGION_NAME.at(
                    region.span,
                    notes=[dg.DUPLICATE_REGION_NAME.note("other-at", where=other.span.location())],
                    owner=owner,
                    region=region.name,
                )
            )
    return found
