"""Breadth-first search of the swarm's states: a hashed visited set, symmetry over members of
one type (canonical order), a budget of states and depth, and a progress line per level.

What the properties need is collected on the way: the first deadlocks (BFS: the shortest), the
states after the abort with their successors (for abort safety), every state each member type
entered, which events members sent and which deliveries changed their receiver. The search
stores, per state, only its digest, its parent and the step that reached it; the states
themselves live only in the frontier. Phase 2 (user properties, partial-order reduction) plugs
in here: an observer per property, and a reduced `System.steps`.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import field
from typing import TYPE_CHECKING

from swarmgen.records import dataclass
from swarmgen.verify.ample import ample
from swarmgen.verify.decouple import decoupled
from swarmgen.verify.system import Effect, Step, SwarmState, System, canonical_state

if TYPE_CHECKING:
    from swarmgen.verify.observe import Observer

DEFAULT_MAX_STATES = 200_000
DEFAULT_MAX_DEPTH = 10_000


@dataclass(frozen=True)
class Budget:
    """Where the search stops: states discovered, and the depth of the states it expands."""

    max_states: int = DEFAULT_MAX_STATES
    max_depth: int = DEFAULT_MAX_DEPTH
    symmetry: bool = True
    por: bool = True  # partial-order reduction (`ample`)
    decouple: bool = True  # stop at decoupled states after the abort (`decouple`)


@dataclass
class Search:
    """What a search found; state number n is the n-th state discovered (0 the initial)."""

    seen: dict[bytes, int] = field(default_factory=dict)  # the visited set: digest -> number
    parent: list[int] = field(default_factory=list)
    step: list[Step | None] = field(default_factory=list)
    depth: list[int] = field(default_factory=list)
    weight: list[int] = field(default_factory=list)  # events in flight (`System.weight`)
    expanded: int = 0
    reduced: int = 0  # states expanded by an ample set only (`ample`)
    bounded: bool = False  # the budget stopped it: states were left unexplored
    # the first deadlock before the abort (False) and after it (True): BFS, the shortest
    deadlocks: dict[bool, int] = field(default_factory=dict)
    stuck: set[int] = field(default_factory=set)  # no member can move (station aside), not final
    aborted: dict[int, list[int]] = field(default_factory=dict)  # after the abort: successors
    finished: set[int] = field(default_factory=set)  # every member final
    entered: dict[str, set[str]] = field(default_factory=dict)  # member type -> state ids
    sent: set[str] = field(default_factory=set)  # events members sent
    received: set[str] = field(default_factory=set)  # events that changed a receiver
    unexpanded: set[int] = field(default_factory=set)
    # after the abort, states whose members no longer interact (`decouple`): their members
    decoupled: dict[int, tuple[int, ...]] = field(default_factory=dict)
    locals_read: set[int] = field(default_factory=set)  # member values whose graphs were read
    lost: dict[str, tuple[int, Step]] = field(default_factory=dict)  # event -> first edge losing it
    symmetry: bool = True  # states were merged up to symmetry (the budget's choice)
    observed: set[int] = field(default_factory=set)  # member values whose states are entered

    @property
    def states(self) -> int:
        """States discovered."""
        return len(self.parent)

    @property
    def max_depth(self) -> int:
        """The depth of the deepest state discovered."""
        return max(self.depth, default=0)

    def path(self, number: int) -> list[Step]:
        """The steps from the initial state to state `number` (a shortest path)."""
        steps: list[Step] = []
        while number > 0:
            step = self.step[number]
            assert step is not None
            steps.append(step)
            number = self.parent[number]
        return steps[::-1]


def digest(state: SwarmState) -> bytes:
    """The visited set's key: the state's bytes (a few integers: member values are interned)."""
    return state.key()


def explore(
    system: System,
    budget: Budget,
    progress: Callable[[str], None] | None = None,
    observer: Observer | None = None,
) -> Search:
    """Every state reachable from the initial one (up to the reductions), breadth first,
    within the budget; `observer` sees every state and edge (user properties)."""
    search = Search(symmetry=budget.symmetry)
    for kind in system.kinds:  # what starting the machine entered
        search.entered[kind.name] = set(kind.started)
    first = _key(system, system.initial(), budget)
    search.seen[digest(first)] = 0
    if observer is not None:
        observer.discovered(0, first)
    search.parent.append(-1)
    search.step.append(None)
    search.depth.append(0)
    search.weight.append(system.weight(first))
    frontier: deque[tuple[int, SwarmState]] = deque([(0, first)])
    visible = observer.projection if observer is not None else None
    level = 0
    while frontier:
        number, state = frontier.popleft()
        depth = search.depth[number]
        if depth > level and progress is not None:
            level = depth
            progress(_line(search, len(frontier) + 1, level))
        _observe(system, search, number, state)
        if search.states >= budget.max_states:
            search.bounded = True
            search.unexpanded.add(number)
            search.unexpanded.update(n for n, _ in frontier)
            break
        if depth >= budget.max_depth:
            if system.steps(state):
                search.bounded = True
                search.unexpanded.add(number)
            continue
        if state.aborted and budget.decouple and _decoupled(system, search, number, state):
            continue
        reduced = ample(system, state, visible) if budget.por else None
        taken = reduced or system.steps(state)
        successors = _expand(system, search, frontier, number, state, budget, taken, observer)
        if reduced is not None and _may_close_cycle(search, number, successors):
            rest = [s for s in system.steps(state) if s not in reduced]
            successors += _expand(system, search, frontier, number, state, budget, rest, observer)
            taken, reduced = reduced + rest, None
        search.expanded += 1
        search.reduced += reduced is not None
        if observer is not None:
            observer.edges(number, state, successors, taken)
        if state.aborted:
            search.aborted[number] = [n for n, _ in successors]
    if progress is not None:
        progress(_line(search, 0, search.max_depth))
    return search


def _expand(
    system: System,
    search: Search,
    frontier: deque[tuple[int, SwarmState]],
    number: int,
    state: SwarmState,
    budget: Budget,
    steps: list[Step],
    observer: Observer | None = None,
) -> list[tuple[int, Effect]]:
    """Discover the successors of one state by `steps`: their numbers and the effects."""
    seen, parent, depth, weight = search.seen, search.parent, search.depth, search.weight
    deeper = depth[number] + 1
    symmetry = budget.symmetry
    successors: list[tuple[int, Effect]] = []
    for step in steps:
        after, effect = system.apply(state, step)
        if effect.changed and effect.source not in ("", "station"):
            search.received.add(effect.event)
        if effect.sent:
            search.sent.update(effect.sent)
        for name in effect.lost:
            search.lost.setdefault(name, (number, step))
        if effect.entered:
            kind = system.kinds[system.types[effect.member]].name
            search.entered.setdefault(kind, set()).update(effect.entered)
        key = canonical_state(system, after) if symmetry else after
        code = key.key()
        known = seen.get(code)
        if known is None:
            known = len(parent)
            seen[code] = known
            parent.append(number)
            search.step.append(step)
            depth.append(deeper)
            weight.append(system.weight(key))
            frontier.append((known, key))
            if observer is not None:
                observer.discovered(known, key)
        successors.append((known, effect))
    return successors


def _may_close_cycle(search: Search, number: int, successors: list[tuple[int, Effect]]) -> bool:
    """The cycle proviso for a state expanded by an ample set: expand it in full unless every
    cycle through its ample edges is sure to meet a fully expanded state (docs/verify.md).

    Ample steps send nothing, so along them the events in flight (`weight`) never grow: a cycle
    of reduced states keeps the weight constant, and with it every edge's depth would have to
    grow (breadth first, an edge goes at most one level deeper), which no cycle can. So an
    ample edge that lowers the weight or reaches a new level is safe; one that keeps the
    weight and goes back to a level already reached might close a cycle. A self-loop (a
    retried behaviour back where it was) is allowed when another ample edge leaves the state:
    the step it repeats changes nothing, and the other edge carries the run on."""
    depth, weight = search.depth[number], search.weight[number]
    leaving = [n for n, _ in successors if n != number]
    if not leaving:
        return True
    return any(search.depth[n] <= depth and search.weight[n] >= weight for n in leaving)


def _decoupled(system: System, search: Search, number: int, state: SwarmState) -> bool:
    """Stop at a state whose members no longer interact (`decouple`): record what their own
    graphs enter and receive."""
    graphs = decoupled(system, state.members)
    if graphs is None:
        return False
    search.decoupled[number] = state.members
    for index, graph in enumerate(graphs):
        value = state.members[index]
        if value in search.locals_read:
            continue
        search.locals_read.add(value)
        kind = system.kinds[system.types[index]].name
        search.entered.setdefault(kind, set()).update(graph.entered)
        search.sent.update(graph.sent)
        search.received.update(graph.received)
    return True


def _observe(system: System, search: Search, number: int, state: SwarmState) -> None:
    """Record what the properties read of a state about to be expanded (the states a member
    value is in: once per value)."""
    observed = search.observed
    for value in state.members:
        if value not in observed:
            observed.add(value)
            kind = system.kinds[system.value_type[value]].name
            search.entered.setdefault(kind, set()).update(system.values[value].engine.config)
    if system.finished(state):
        search.finished.add(number)
        return
    if not system.quiescent(state):
        return
    search.stuck.add(number)
    if state.aborted not in search.deadlocks and not system.station_moves(state):
        search.deadlocks[state.aborted] = number


def _key(system: System, state: SwarmState, budget: Budget) -> SwarmState:
    return canonical_state(system, state) if budget.symmetry else state


def _line(search: Search, frontier: int, depth: int) -> str:
    return f"verify: {search.states:,} states, depth {depth}, frontier {frontier:,}"
