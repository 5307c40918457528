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

import hashlib
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from swarmgen.verify.system import Step, SwarmState, System, canonical

DEFAULT_MAX_STATES = 200_000
DEFAULT_MAX_DEPTH = 10_000


@dataclass(frozen=True)
class Budget:
    """Where the search stops: states discovered, and the depth of the states it expands."""

    max_states: int = DEFAULT_MAX_STATES
    max_depth: int = DEFAULT_MAX_DEPTH
    symmetry: bool = True


@dataclass
class Search:
    """What a search found; state number n is the n-th state discovered (0 the initial)."""

    seen: dict[bytes, int] = field(default_factory=dict)  # the visited set: digest -> number
    parent: list[int] = field(default_factory=list)
    step: list[Step | None] = field(default_factory=list)
    depth: list[int] = field(default_factory=list)
    expanded: int = 0
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
    """The visited set's key: 128 bits of BLAKE2b over the state's bytes (deterministic)."""
    return hashlib.blake2b(state.key(), digest_size=16).digest()


def explore(
    system: System, budget: Budget, progress: Callable[[str], None] | None = None
) -> Search:
    """Every state reachable from the initial one, breadth first, within the budget."""
    search = Search()
    for kind in system.kinds:  # what starting the machine entered
        search.entered[kind.name] = set(kind.started)
    seen = search.seen
    first = _key(system, system.initial(), budget)
    seen[digest(first)] = 0
    search.parent.append(-1)
    search.step.append(None)
    search.depth.append(0)
    frontier: deque[tuple[int, SwarmState]] = deque([(0, first)])
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
        successors = _expand(system, search, seen, frontier, number, state, budget)
        if state.aborted:
            search.aborted[number] = successors
    if progress is not None:
        progress(_line(search, 0, search.max_depth))
    return search


def _expand(
    system: System,
    search: Search,
    seen: dict[bytes, int],
    frontier: deque[tuple[int, SwarmState]],
    number: int,
    state: SwarmState,
    budget: Budget,
) -> list[int]:
    """Discover the successors of one state; their numbers."""
    search.expanded += 1
    successors: list[int] = []
    for step in system.steps(state):
        after, effect = system.apply(state, step)
        if effect.changed and effect.source not in ("", "station"):
            search.received.add(effect.event)
        search.sent.update(effect.sent)
        if effect.entered:
            kind = system.kinds[system.types[effect.member]].name
            search.entered.setdefault(kind, set()).update(effect.entered)
        key = _key(system, after, budget)
        code = digest(key)
        known = seen.get(code)
        if known is None:
            known = search.states
            seen[code] = known
            search.parent.append(number)
            search.step.append(step)
            search.depth.append(search.depth[number] + 1)
            frontier.append((known, key))
        successors.append(known)
    return successors


def _observe(system: System, search: Search, number: int, state: SwarmState) -> None:
    """Record what the properties read of a state about to be expanded."""
    for index, member in enumerate(state.members):
        kind = system.kinds[system.types[index]].name
        search.entered.setdefault(kind, set()).update(member.engine.config)
    if system.finished(state):
        search.finished.add(number)
        return
    if not system.quiescent(state):
        return
    search.stuck.add(number)
    if state.aborted not in search.deadlocks and not system.station_moves(state):
        search.deadlocks[state.aborted] = number


def _key(system: System, state: SwarmState, budget: Budget) -> SwarmState:
    return canonical(system, state)[0] if budget.symmetry else state


def _line(search: Search, frontier: int, depth: int) -> str:
    return f"verify: {search.states:,} states, depth {depth}, frontier {frontier:,}"
