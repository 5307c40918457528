"""SCXML semantics, once: the W3C SCXML 1.0 interpretation algorithm (Appendix D) over a `Chart`.

Synchronous and deterministic: `start()` and `send(event)` each run a complete macrostep.
Behaviours, timers and the swarm bus are the host's business (see `member.py`); the engine tells
the host when a state's behaviour must start (end of the macrostep that entered it, like an
SCXML `<invoke>`) or be cancelled (when the state is exited), and drops the outcome events of
cancelled activations.
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from swarmgen.runtime.chart import (
    FINALIZE_PREFIX,
    OUTCOME_PREFIX,
    STEP_BOUND,
    Call,
    Chart,
    Context,
    Node,
    StepBoundExceeded,
    Transition,
    fill_fields,
    record,
)
from swarmgen.runtime.configuration import (
    document_order,
    entry_set,
    exit_set,
    in_final,
    is_descendant,
    recorded_history,
)
from swarmgen.runtime.host import Event, Host, NullHost

__all__ = ["FINALIZE_PREFIX", "OUTCOME_PREFIX", "STEP_BOUND", "Engine", "Event", "Host", "NullHost"]


@dataclass
class Engine:
    """One member's statechart being interpreted: its configuration, data and event queues."""

    chart: Chart
    host: Host = field(default_factory=NullHost)
    member_id: str = ""
    clock: Callable[[], float] = time.time
    on_error: Callable[[str, BaseException], None] | None = None

    def __post_init__(self) -> None:
        self.data = self.chart.fresh_data()
        self.ctx = Context(self, self.data)
        self.config: set[Node] = set()
        self.internal: deque[Event] = deque()
        self.history: dict[Node, list[Node]] = {}
        self.running = False
        self.finished = False
        self._to_invoke: set[Node] = set()
        self._activation: dict[Node, int] = {}
        self._ids = itertools.count(1)
        self._active_ids: frozenset[str] | None = None
        self._atomic: list[Node] | None = None  # atomic states of the configuration, in order
        self.error_count = 0  # error.execution events raised so far (traces report them)
        # The step bound (docs/semantics.md): bounded transitions taken since the count last
        # restarted, whether that count's error was raised, and the input that restarted it.
        self._steps = 0
        self._bound_hit = False
        self._input: Event | None = None
        self._bounded = any(t.bounded for n in self.chart.nodes.values() for t in n.transitions)

    # --- public

    def start(self) -> None:
        """Enter the initial configuration (one macrostep)."""
        self.running = True
        root = self.chart.root
        if root.initial is None:
            raise ValueError(f"chart {self.chart.name} has no initial state")
        self._enter_states([root.initial])
        self._macrostep()

    def send(self, event: Event) -> None:
        """Process one external event completely (one macrostep)."""
        if not self.running:
            return
        if event.origin is not None and not self._current_activation(event.origin):
            return  # the outcome of a behaviour that was cancelled: discarded
        template = self.chart.events.get(event.name)
        if template:  # the value rule: a declared field the sender left out holds its default
            event.data = fill_fields(event.data, template)
        self.ctx.event = event
        enabled = self._select_transitions(event)
        if enabled:
            self._microstep(enabled)
        self._macrostep()

    def make_event(
        self, name: str, data: Mapping[str, Any] | None = None, sender: str = "", **extra: Any
    ) -> Event:
        """A new event from this engine: the next id, the clock's time."""
        return Event(
            name,
            record(data) if data is not None else None,
            next(self._ids),
            self.clock(),
            sender,
            **extra,
        )

    def active(self) -> list[str]:
        """Ids of all active states (atomic and compound), sorted."""
        return sorted(node.id for node in self.config)

    def activation(self, node_id: str) -> int:
        """The current activation number of a state's behaviour (outcome events carry it)."""
        node = self.chart.nodes.get(node_id)
        return self._activation.get(node, 0) if node is not None else 0

    @property
    def bounded_steps(self) -> int:
        """The step bound's count: bounded transitions taken (or refused) since it restarted."""
        return self._steps

    def is_active(self, node_id: str) -> bool:
        """Whether the state with this id is in the configuration."""
        if self._active_ids is None:
            self._active_ids = frozenset(n.id for n in self.config)
        return node_id in self._active_ids

    # --- services for actions (Context)

    def raise_internal(self, name: str, data: Mapping[str, Any] | None) -> None:
        """`raise e`: the internal queue. `raise e(f = ...)` carries data, which SCXML can only
        do with `<send target="#_internal">`, and Qt SCXML queues that after the external events
        already waiting: so does swarmgen (docs/semantics.md), through the host's own queue."""
        if data is None:
            self.internal.append(self.make_event(name, None, self.member_id, kind="internal"))
        else:
            self.host.deliver(self.make_event(name, data, self.member_id, kind="raised"))

    def send_swarm(self, name: str, data: Mapping[str, Any] | None) -> None:
        """`send e`: the event goes to the swarm, through the host."""
        self.host.send_swarm(self.make_event(name, data, self.member_id))

    # --- the algorithm

    def _macrostep(self) -> None:
        while self.running:
            enabled = self._select_transitions(None)
            if not enabled:
                if not self.internal:
                    break
                event = self.internal.popleft()
                self.ctx.event = event
                enabled = self._select_transitions(event)
            if enabled:
                self._microstep(enabled)
        self._start_calls()

    def _start_calls(self) -> None:
        for node in sorted(self._to_invoke, key=document_order):
            if node in self.config and node.call is not None:
                activation = self._activation.get(node, 0) + 1
                self._activation[node] = activation
                args = self._arguments(node, node.call)
                self.host.start_call(
                    node, node.call, args if isinstance(args, dict) else {}, activation
                )
        self._to_invoke.clear()

    def _arguments(self, node: Node, call: Call) -> dict[str, Any]:
        """A behaviour's inputs. An input that cannot be computed is the host's business (the
        SCXML document does not evaluate `<sg:arg>`), so it raises no error.execution."""
        try:
            args = call.args(self.ctx)
        except Exception as err:
            if self.on_error is not None:
                self.on_error(f"arguments of {node.id}", err)
            return {}
        return args if isinstance(args, dict) else {}

    def _current_activation(self, origin: tuple[str, int]) -> bool:
        node = self.chart.nodes.get(origin[0])
        return node is not None and node in self.config and self._activation.get(node) == origin[1]

    def _atomic_states(self) -> list[Node]:
        if self._atomic is None:
            self._atomic = sorted((n for n in self.config if n.is_atomic), key=document_order)
        return self._atomic

    def _select_transitions(self, event: Event | None) -> list[Transition]:
        enabled: list[Transition] = []
        name = None if event is None else event.name
        for state in self._atomic_states():
            for owner, candidates in state.chain_candidates(name):
                chosen = self._first_enabled(owner, candidates)
                if chosen is not None:
                    if chosen not in enabled:
                        enabled.append(chosen)
                    break
        return self._remove_conflicts(enabled) if len(enabled) > 1 else enabled

    def _first_enabled(self, owner: Node, candidates: tuple[Transition, ...]) -> Transition | None:
        if self._bounded and self.ctx.event is not self._input:
            self._restart_count(self.ctx.event)
        for transition in candidates:
            if (
                transition.cond is None
                or self._guarded(transition.cond, f"guard in {owner.id}") is True
            ) and (not transition.bounded or self._step_allowed(owner)):
                return transition
        return None

    def _restart_count(self, event: Event | None) -> None:
        """The step bound's count restarts when the first transition is considered under a new
        input from outside (not an event the member raised itself), as `$sg.tick(_event)` at
        the head of every cond of the SCXML document restarts it in Qt SCXML."""
        if event is not None and event.kind == "external":
            self._input = event
            self._steps, self._bound_hit = 0, False

    def _step_allowed(self, owner: Node) -> bool:
        """The step bound, checked after the guard held (as `$sg.spin()` ends the SCXML cond):
        the STEP_BOUND+1st bounded transition of the macrostep raises error.execution and is not
        taken; later ones are silently disabled until the next external event."""
        self._steps += 1
        if self._steps <= STEP_BOUND:
            return True
        if not self._bound_hit:
            self._bound_hit = True
            message = f"more than {STEP_BOUND} steps without an external event"
            self._error(f"step bound in {owner.id}", StepBoundExceeded(message))
        return False

    def _remove_conflicts(self, enabled: list[Transition]) -> list[Transition]:
        filtered: list[Transition] = []
        exit_sets: dict[int, set[Node]] = {}
        for t1 in enabled:
            exits1 = exit_sets.setdefault(id(t1), self._exit_set([t1]))
            preempted = False
            to_remove: list[Transition] = []
            for t2 in filtered:
                if exits1 & exit_sets[id(t2)]:
                    if is_descendant(t1.source, t2.source):
                        to_remove.append(t2)
                    else:
                        preempted = True
                        break
            if not preempted:
                filtered = [t for t in filtered if t not in to_remove]
                filtered.append(t1)
        return filtered

    def _microstep(self, enabled: list[Transition]) -> None:
        self._exit_states(enabled)
        for transition in enabled:
            self._run(transition.action, f"transition from {transition.source.id}")
        self._enter_states(enabled)
        self._active_ids = None
        self._atomic = None

    def _exit_set(self, transitions: Iterable[Transition]) -> set[Node]:
        return exit_set(transitions, self.config, self.history)

    def _exit_states(self, enabled: list[Transition]) -> None:
        to_exit = sorted(self._exit_set(enabled), key=document_order, reverse=True)
        self._to_invoke.difference_update(to_exit)
        for state in to_exit:
            for child in state.children:
                if child.kind == "history":
                    self.history[child] = recorded_history(child, state, self.config)
        for state in to_exit:
            self._leave(state)
            self.config.discard(state)
        self._active_ids = None
        self._atomic = None

    def _leave(self, state: Node) -> None:
        """Cancel a state's behaviour and timers and run its exit actions."""
        if state.call is not None and state in self._activation:
            self.host.cancel_call(state, self._activation[state])
            self._activation[state] += 1  # late outcomes of this activation are stale
        for event, _ in state.timers:
            self.host.cancel_timer(state, event)
        self._run(state.onexit, f"exit of {state.id}")

    def _enter_states(self, enabled: list[Transition]) -> None:
        entry = entry_set(enabled, self.history)
        for state in sorted(entry.to_enter, key=document_order):
            self.config.add(state)
            self._active_ids = None
            self._atomic = None
            self._to_invoke.add(state)
            self._run(state.onentry, f"entry of {state.id}")
            for event, delay in state.timers:
                self.host.start_timer(state, event, delay)
            if state in entry.default_entry and state.initial is not None:
                self._run(state.initial.action, f"initial transition of {state.id}")
            if state in entry.history_content:
                self._run(entry.history_content[state].action, f"history default in {state.id}")
            if state.kind == "final":
                self._reached_final(state)

    def _reached_final(self, state: Node) -> None:
        parent = state.parent
        if parent is None or parent.kind == "scxml":
            self.running = False
            self.finished = True
            self._exit_everything()
            return
        self.internal.append(self.make_event(f"done.state.{parent.id}", kind="platform"))
        grandparent = parent.parent
        if (
            grandparent is not None
            and grandparent.kind == "parallel"
            and all(in_final(c, self.config) for c in grandparent.children if c.kind != "history")
        ):
            self.internal.append(self.make_event(f"done.state.{grandparent.id}", kind="platform"))

    def _exit_everything(self) -> None:
        """The machine is done: behaviours are cancelled and exit actions run; the final
        configuration stays visible (as Qt SCXML reports it) for traces."""
        for state in sorted(self.config, key=document_order, reverse=True):
            self._leave(state)
        self._to_invoke.clear()
        self.internal.clear()

    # --- executable content

    def _run(self, action: Callable[[Context], None] | None, where: str) -> None:
        if action is None:
            return
        try:
            action(self.ctx)
        except Exception as err:  # SCXML: an error stops the block and raises error.execution
            self._error(where, err)
        self._active_ids = None

    def _guarded(self, function: Callable[[Context], Any], where: str) -> Any:
        try:
            return function(self.ctx)
        except Exception as err:  # a guard that cannot be evaluated is false (SCXML 5.9)
            self._error(where, err)
            return None

    def _error(self, where: str, err: BaseException) -> None:
        self.error_count += 1
        # no data, as in Qt SCXML: `where` and the error go to the host (`on_error`)
        self.internal.append(self.make_event("error.execution", None, kind="platform"))
        if self.on_error is not None:
            self.on_error(where, err)
