"""Livelocks: transitions that, once taken, take each other forever without an external event.

Each machine is run symbolically, one microstep at a time, as the engine runs it (W3C's
algorithm, docs/semantics.md): after a microstep the first eventless transition of the atomic
state is taken, else the next internal event (a `raise` without data, a composite's
`done.state`) selects the first transition that matches it, innermost state first. A
situation (atomic state, internal queue) that comes back is an unconditional cycle: an error,
since every backend and Qt SCXML would spin in it (the step bound would end every macrostep
with error.execution). The run stops, reporting nothing, wherever the outcome depends on
something this check does not decide: a guard (also `else`), a behaviour, a timer, a
submachine, an orthogonal region, a history, fork or join. Those cycles are the step bound's
business at run time.

Completion transitions are not microsteps in themselves: from a state that runs a behaviour
they wait for its outcome, from a composite state for its final state (a loop only when the
final state is reached within the same run, which the simulation follows).
"""

from __future__ import annotations

from dataclasses import field

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import (
    FinalState,
    Machine,
    Model,
    PseudoKind,
    Pseudostate,
    State,
    Transition,
    TriggerKind,
    Vertex,
)
from swarmgen.ir.query import ModelIndex, Placed, initial_of, outgoing, walk
from swarmgen.names import event_name
from swarmgen.records import dataclass

MAX_QUEUE = 32  # internal events pending: past this the run is not followed further
_TRANSIENT = {PseudoKind.CHOICE, PseudoKind.JUNCTION}

Situation = tuple[str, tuple[str, ...]]  # (atomic vertex id, internal queue)


class _Undecided(Exception):
    """The next microstep depends on something this check does not decide."""


def check_livelocks(model: Model) -> list[Diagnostic]:
    """Report eventless transition cycles in single-region machines."""
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    for machine in model.machines:
        if len(machine.regions) == 1:
            found += _Run(index, machine).cycles()
    return found


@dataclass
class _Run:
    index: ModelIndex
    machine: Machine
    placed: dict[str, Placed] = field(init=False)
    leaving: dict[str, list[Transition]] = field(init=False)
    settled: set[Situation] = field(default_factory=set)  # leads to no (new) cycle
    reported: set[frozenset[str]] = field(default_factory=set)

    def __post_init__(self) -> None:
        self.placed = {p.vertex.id: p for p in walk(self.machine)}
        self.leaving = {
            source: sorted(ts, key=lambda t: isinstance(t.guard, expr.Else))  # lowering's order
            for source, ts in outgoing(self.machine).items()
        }
        self.step_limit = 4 * len(self.machine.transitions) + 16

    # --- the runs

    def cycles(self) -> list[Diagnostic]:
        """Runs from each vertex entered with nothing queued, and from each transition out of
        an atomic vertex (whatever its trigger: its effect may raise what starts a loop)."""
        found = []
        for start in self._starts():
            diagnostic = self._follow(start)
            if diagnostic is not None:
                found.append(diagnostic)
        return found

    def _starts(self) -> list[Situation]:
        starts: list[Situation] = []
        for vertex_id, placed in self.placed.items():
            if not isinstance(placed.vertex, State | Pseudostate) or self._orthogonal(vertex_id):
                continue
            leaving: list[Transition | None] = [None]  # entering the vertex, nothing queued
            if isinstance(placed.vertex, Pseudostate) or not (
                placed.vertex.regions or placed.vertex.submachine
            ):  # an atomic vertex: its transitions' effects may start a loop
                leaving += [t for t in self.leaving.get(vertex_id, []) if t.guard is None]
            for transition in leaving:
                try:
                    if transition is None:
                        starts.append(self._enter(vertex_id, []))
                    else:
                        starts.append(self._take(transition, vertex_id, []))
                except _Undecided:
                    continue
        return starts

    def _follow(self, start: Situation) -> Diagnostic | None:
        """Microsteps from `start` until the run settles, depends on something undecided, or
        comes back to a situation it has been in (a cycle, reported once)."""
        seen: dict[Situation, int] = {start: 0}
        taken: list[Transition] = []
        situation = start
        try:
            for _ in range(self.step_limit):
                if situation in self.settled:
                    break
                step = self._next(situation)
                if step is None:
                    break
                transition, situation = step
                taken.append(transition)
                if situation in seen:
                    self.settled.update(seen)
                    return self._report(taken[seen[situation] :])
                seen[situation] = len(taken)
        except _Undecided:
            pass
        self.settled.update(seen)
        return None

    def _next(self, situation: Situation) -> tuple[Transition, Situation] | None:
        """The next microstep (W3C: eventless transitions first, then the internal queue)."""
        atomic, queue = situation
        eventless = [t for t in self.leaving.get(atomic, []) if self._eventless(t)]
        if eventless:
            return eventless[0], self._take(eventless[0], atomic, list(queue))
        pending = list(queue)
        while pending:
            event = pending.pop(0)
            chosen = self._select(atomic, event)
            if chosen is not None:
                return chosen, self._take(chosen, atomic, pending)
        return None

    def _select(self, atomic: str, event: str) -> Transition | None:
        """The transition an internal event takes: the first that matches it, innermost state
        first (None: the event is dropped)."""
        for owner in self._chain(atomic):
            for transition in self.leaving.get(owner, []):
                if self._matches(transition, owner, event):
                    if transition.guard is not None:
                        raise _Undecided
                    return transition
        return None

    # --- one microstep

    def _take(self, transition: Transition, atomic: str, queue: list[str]) -> Situation:
        if transition.guard is not None or transition.kind == "local":
            raise _Undecided
        if transition.kind == "internal" and transition.source == transition.target:
            queue += self._raised(transition.effect)  # no exit, no entry
            return self._situation(atomic, queue)
        target = transition.target
        if target not in self.placed or self._orthogonal(target):
            raise _Undecided  # a connection point reference, or an orthogonal region
        domain = self._domain(transition.source, target)
        for state in self._chain(atomic):
            if state == domain:
                break
            queue += self._raised(self._state(state).exit if self._is_state(state) else ())
        queue += self._raised(transition.effect)
        chain = self._chain(target)
        entered = chain[: chain.index(domain)] if domain is not None else chain
        for vertex_id in reversed(entered[1:]):  # the ancestors on the way down, outermost first
            queue += self._raised(self._state(vertex_id).entry)
        return self._enter(target, queue)

    def _enter(self, vertex_id: str, queue: list[str]) -> Situation:
        """Enter a vertex (its entry actions, then by default down to an atomic vertex)."""
        vertex = self.placed[vertex_id].vertex
        if isinstance(vertex, FinalState):
            parent = self.placed[vertex_id].parent
            if parent is None:
                raise _Undecided  # the machine ends (or its submachine state completes)
            return self._situation(vertex_id, [*queue, _done(parent.id)])
        if isinstance(vertex, Pseudostate):
            if vertex.kind not in _TRANSIENT:
                raise _Undecided
            return self._situation(vertex_id, queue)
        if vertex.submachine or vertex.connection_points or len(vertex.regions) > 1:
            raise _Undecided
        queue = [*queue, *self._raised(vertex.entry)]
        if not vertex.regions:
            return self._situation(vertex_id, queue)
        initials = initial_of(vertex.regions[0])
        first = self.leaving.get(initials[0].id, []) if initials else []
        if not first or first[0].target not in self.placed:
            raise _Undecided
        inner = self.placed[first[0].target]
        if inner.parent is None or inner.parent.id != vertex_id:
            raise _Undecided  # an initial transition deeper down: not followed
        return self._enter(first[0].target, [*queue, *self._raised(first[0].effect)])

    def _situation(self, atomic: str, queue: list[str]) -> Situation:
        if len(queue) > MAX_QUEUE:
            raise _Undecided
        return atomic, tuple(queue)

    # --- the model's structure

    def _is_state(self, vertex_id: str) -> bool:
        return isinstance(self.placed[vertex_id].vertex, State)

    def _state(self, vertex_id: str) -> State:
        vertex = self.placed[vertex_id].vertex
        assert isinstance(vertex, State)
        return vertex

    def _chain(self, vertex_id: str) -> list[str]:
        """The vertex and the states that hold it, innermost first."""
        chain = [vertex_id]
        parent = self.placed[vertex_id].parent
        while parent is not None:
            chain.append(parent.id)
            parent = self.placed[parent.id].parent
        return chain

    def _orthogonal(self, vertex_id: str) -> bool:
        """In (or being) a state with several regions: other regions may take part."""
        return any(
            self._is_state(v) and len(self._state(v).regions) > 1 for v in self._chain(vertex_id)
        )

    def _domain(self, source: str, target: str) -> str | None:
        """W3C's domain: the innermost state holding source and target (None: the machine)."""
        holders = self._chain(target)[1:]
        for state in self._chain(source)[1:]:
            if state in holders:
                return state
        return None

    def _eventless(self, transition: Transition) -> bool:
        """Taken without any event: no trigger, from a pseudostate or a simple state that runs
        no behaviour (from a behaviour's state it waits for the outcome; from a composite
        state it is its completion, `done.state`)."""
        if transition.triggers:
            return False
        vertex = self.placed[transition.source].vertex
        if isinstance(vertex, Pseudostate) or transition.eventless:
            return True
        return isinstance(vertex, State) and not (
            vertex.regions or vertex.submachine or vertex.activity
        )

    def _matches(self, transition: Transition, owner: str, event: str) -> bool:
        if not transition.triggers:
            vertex = self.placed[owner].vertex
            return (
                not transition.eventless
                and isinstance(vertex, State)
                and bool(vertex.regions)
                and event == _done(owner)
            )
        for trigger in transition.triggers:
            if trigger.kind == TriggerKind.ANY:
                return True
            if trigger.kind in {TriggerKind.EVENT, TriggerKind.CALL}:
                declared = self.index.events.get(trigger.event or "")
                name = declared.ident if declared is not None else event_name(trigger.name)
                if name == event:
                    return True
        return False

    def _raised(self, actions: tuple[expr.Action, ...]) -> list[str]:
        """Events these actions put on the internal queue: `raise e` of an event without fields.
        One with fields (always carried) or arguments goes after the external events waiting:
        an input from outside may come first and end a loop through it, so it is left to the
        step bound (a loop that never ends its macrostep never lets it be taken either)."""
        found = []
        for action in expr.flat(actions):
            if (
                isinstance(action, expr.Raise)
                and not action.args
                and action.delay is None
                and action.target is None
                and action.event is not None  # (a computed name: unknown here)
                and action.content is None
            ):
                event = self.index.events_by_name.get(action.event)
                if event is None or not event.fields:
                    found.append(event.ident if event is not None else event_name(action.event))
        return found

    # --- the report

    def _name(self, vertex_id: str) -> str:
        vertex: Vertex = self.placed[vertex_id].vertex
        if vertex.name:
            return vertex.name
        return vertex.kind.value if isinstance(vertex, Pseudostate) else "(unnamed)"

    def _report(self, cycle: list[Transition]) -> Diagnostic | None:
        key = frozenset(t.id for t in cycle)
        if key in self.reported:
            return None
        self.reported.add(key)
        first = min(range(len(cycle)), key=lambda i: (cycle[i].span.line, cycle[i].span.col))
        cycle = cycle[first:] + cycle[:first]
        names = [self._name(t.source) for t in cycle] + [self._name(cycle[0].source)]
        shown = " -> ".join(names)
        return dg.LIVELOCK.at(
            cycle[0].span,
            notes=[
                dg.LIVELOCK.note("then", source=self._name(t.source), where=t.span.location())
                for t in cycle[1:]
            ],
            loop=shown,
        )


def _done(state_id: str) -> str:
    return f"done.state:{state_id}"  # a composite's completion (`:` is in no identifier)
