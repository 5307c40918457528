"""SCXML semantics, once: the W3C SCXML 1.0 interpretation algorithm (Appendix D) over a `Chart`.

Synchronous and deterministic: `start()` and `send(event)` each run a complete macrostep.
Behaviours, timers and the swarm bus are the host's business (see `member.py`); the engine tells
the host when a state's behaviour must start (end of the macrostep that entered it, like an
SCXML `<invoke>`) or be cancelled (when the state is exited), and drops the outcome events of
cancelled activations.
"""

from __future__ import annotations

import itertools
import logging
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from swarmgen.runtime.chart import (
    FINALIZE_PREFIX,
    OUTCOME_PREFIX,
    STEP_BOUND,
    Chart,
    CommunicationError,
    Context,
    Node,
    StepBoundExceeded,
    Transition,
    record,
)
from swarmgen.runtime.configuration import Chain, Configuration, Plan, Selection, Tables
from swarmgen.runtime.host import Event, Host, NullHost, system_variable
from swarmgen.runtime.microstep import document_order, in_final
from swarmgen.runtime.sends import Sends
from swarmgen.runtime.sessions import Sessions

__all__ = ["FINALIZE_PREFIX", "OUTCOME_PREFIX", "STEP_BOUND", "Engine", "Event", "Host", "NullHost"]


@dataclass
class Engine(Sends):
    """One member's statechart being interpreted: its configuration, data and event queues."""

    chart: Chart
    host: Host = field(default_factory=NullHost)
    member_id: str = ""
    clock: Callable[[], float] = time.time
    on_error: Callable[[str, BaseException], None] | None = None
    on_log: Callable[[str, Any], None] | None = None  # `log label, value` (else `logging`)

    def __post_init__(self) -> None:
        self.data = self.chart.fresh_data()
        self.ctx = Context(self, self.data)
        self.config: set[Node] = set()
        self.internal: deque[Event] = deque()
        self.history: dict[Node, tuple[Node, ...]] = {}
        self.running, self.finished = False, False
        self._to_invoke: set[Node] = set()
        self._activation: dict[Node, int] = {}
        self._ids = itertools.count(1)
        self._sends = 0  # delayed raises without a send id so far (their keys: `send.<n>`)
        self.session_id = f"{self.chart.name}:{self.member_id}"  # `_sessionid`
        if self.chart.tables is None:
            self.chart.tables = Tables(self.chart.nodes.values())
        self._tables: Tables = self.chart.tables
        self._inert = self._tables.inert_names  # names nothing reacts to, in any configuration
        # The value rule: a declared field the sender left out holds its default. Every declared
        # event's filler is made once per chart, so `send` finds it (or no filler) in one look-up.
        self._fillers = self._tables.fillers
        for name, template in self.chart.events.items():
            if template and name not in self._fillers:
                self._tables.filler(name, template)
        # The interned configuration, None while a microstep changes `config` (or after one
        # was interrupted by an exception): the next selection interns `config` again.
        self._cfg: Configuration | None = None
        self.error_count = 0  # error.execution events raised so far (traces report them)
        # The step bound (docs/semantics.md): bounded transitions taken since the count last
        # restarted, whether that count's error was raised, and the input that restarted it.
        self._steps, self._bound_hit, self._bounded = 0, False, self._tables.bounded
        self._input: Event | None = None
        # Invoked sessions (`sessions`): this engine's children, and where it sits when it is
        # one itself (the invoke ids from the member's session, its number and its parent's).
        self.sessions: Sessions | None = Sessions(self) if self._tables.invokes else None
        if self.sessions is None:  # a call less per event: `send` is `_step` itself
            self.send = self._step  # type: ignore[method-assign]
        self.path: tuple[str, ...] = ()
        self.root_host: Host = self.host
        self.serial = 0
        self.invokeid: str | None = None
        self.parent_sessions: Sessions | None = None

    # --- public

    def start(self) -> None:
        """Enter the initial configuration (one macrostep)."""
        self.running = True
        root = self.chart.root
        if root.initial is None:
            raise ValueError(f"chart {self.chart.name} has no initial state")
        self._cfg = None
        if self.sessions is not None:  # a child may send to it before the macrostep ends
            self._one_at_a_time(None)
            return
        self._enter(self._configuration().plan((root.initial,), self.history))
        self._macrostep()

    def _one_at_a_time(self, event: Event | None) -> None:
        """The start (`event` None) or one event, then the events that arrived during its
        macrostep: a host that processes what it is given at once (the ROS node) would run
        this engine inside its own macrostep when a child it starts sends to it."""
        sessions = self.sessions
        assert sessions is not None
        if sessions.stepping:
            if event is not None:
                sessions.waiting.append(event)
            return
        sessions.stepping = True
        try:
            initial = self.chart.root.initial
            if event is None and initial is not None:  # `start`, which checked `initial`
                self._enter(self._configuration().plan((initial,), self.history))
                self._macrostep()
            elif event is not None:
                self._step(event)
            while sessions.waiting and self.running:
                self._step(sessions.waiting.popleft())
        finally:
            sessions.stepping = False
            sessions.waiting.clear()

    def send(self, event: Event) -> None:
        """Process one external event completely (one macrostep)."""
        if self.sessions is not None:
            self._one_at_a_time(event)
        else:
            self._step(event)

    def _step(self, event: Event) -> None:
        if not self.running:
            return
        if event.to is not None and event.to != self.path:  # for an invoked session
            if self.sessions is not None and len(event.to) > len(self.path):
                self.sessions.route(event, event.to)
            return
        if event.origin is not None and not self._current_activation(event.origin):
            return  # the outcome of a behaviour that was cancelled: discarded
        name = event.name
        fill = self._fillers.get(name)
        if fill is not None:  # a declared event (the value rule)
            event.data = fill(event.data)
        self.ctx.event = event
        if self.sessions is not None and not self.sessions.received(event):
            return  # from a session that was cancelled: discarded
        cfg = self._cfg or self._configuration()
        selection = cfg.selections.get(name) or self._inert.get(name) or cfg.selection(name)
        now: Configuration | None = cfg
        if selection.chains:
            static = selection.static  # `_choose`'s answer where it evaluates and counts nothing
            enabled = self._choose(selection) if static is None or self._bounded else static
            if enabled:
                self._microstep(enabled, cfg)
                now = self._cfg
        # The rest of the macrostep: most events leave nothing eventless or internal to do.
        if now is None or now.eventless.chains or self.internal:
            self._macrostep()
        elif self._to_invoke:
            self._start_calls()
            if self.internal:  # an invoke that failed to start: error.execution
                self._macrostep()

    def make_event(
        self, name: str, data: Mapping[str, Any] | None = None, sender: str = "", **extra: Any
    ) -> Event:
        """A new event from this engine: the next id, the clock's time."""
        made = record(data) if data is not None else None
        return Event(name, made, next(self._ids), self.clock(), sender, **extra)

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
        node = self.chart.nodes.get(node_id)
        return node is not None and node in self.config

    # --- services for actions (Context)

    def raise_internal(self, name: str, data: Mapping[str, Any] | None) -> None:
        """`raise e`: the internal queue. `raise e(f = ...)` carries data, which SCXML can only
        do with `<send target="#_internal">`, and Qt SCXML queues that after the external events
        already waiting: so does swarmgen (docs/semantics.md), through the host's own queue."""
        if data is None:  # `make_event`'s, inlined: an outcome raises one per behaviour's end
            self.internal.append(
                Event(name, None, next(self._ids), self.clock(), self.member_id, None, "internal")
            )
        else:
            self.host.deliver(self.make_event(name, data, self.member_id, kind="raised"))

    def send_swarm(self, name: str, data: Mapping[str, Any] | None) -> None:
        """`send e`: the event goes to the swarm, through the host."""
        self.host.send_swarm(self.make_event(name, data, self.member_id))

    def system_variable(self, name: str, event: Event | None) -> Any:
        """`_event` (its W3C fields, docs/semantics.md), `_sessionid`, `_name`, `_ioprocessors`."""
        return system_variable(name, event, self.session_id, self.chart.name)

    def log(self, label: str, value: Any) -> None:
        """`log`: to `on_log` when the host set one, else to Python's `logging` (INFO, logger
        `swarmgen.log.<chart>`); it changes no state and no trace."""
        if self.on_log is not None:
            self.on_log(label, value)
        else:
            logging.getLogger(f"swarmgen.log.{self.chart.name}").info("%s: %r", label, value)

    def execution_error(self, where: str, err: BaseException) -> None:
        """An expression of executable content failed where the block goes on (an `if`
        condition): error.execution, counted and reported as every other."""
        self._error(where, err)

    def run_finalize(self, action: Callable[[Context], None], node: Node) -> None:
        """An invoke's `<finalize>`, on the event from its session being processed."""
        self._run(action, "finalize in", node)

    # --- the algorithm

    def _macrostep(self) -> None:
        """Microsteps until nothing is enabled, then the behaviours and invokes of the states
        entered start; an error that raised starts another round (W3C mainEventLoop)."""
        internal, inert = self.internal, self._inert
        while True:
            while self.running:  # the microsteps
                cfg = self._cfg or self._configuration()
                enabled = self._choose(cfg.eventless) if cfg.eventless.chains else ()
                if not enabled:
                    if not internal:
                        break
                    event = internal.popleft()
                    self.ctx.event = event
                    name = event.name
                    selection = cfg.selections.get(name) or inert.get(name) or cfg.selection(name)
                    if not selection.chains:
                        continue
                    static = selection.static
                    enabled = self._choose(selection) if static is None or self._bounded else static
                if enabled:
                    self._microstep(enabled, cfg)
            if not self._to_invoke:
                return
            self._start_calls()
            if not internal or not self.running:
                return

    def _start_calls(self) -> None:
        invoke = self._to_invoke
        config, activations, ctx, host = self.config, self._activation, self.ctx, self.host
        for node in (*invoke,) if len(invoke) == 1 else sorted(invoke, key=document_order):
            call = node.call
            if call is not None and node in config:
                activation = activations.get(node, 0) + 1
                activations[node] = activation
                # A behaviour's inputs. One that cannot be computed is the host's business (the
                # SCXML document does not evaluate `<sg:arg>`), so it raises no error.execution.
                try:
                    args = call.args(ctx)
                except Exception as err:
                    args = self._unusable_arguments(node, err)
                host.start_call(node, call, args if isinstance(args, dict) else {}, activation)
            if node.invokes and node in config and self.sessions is not None:
                self.sessions.start(node)
        invoke.clear()

    def _unusable_arguments(self, node: Node, err: Exception) -> dict[str, Any]:
        if self.on_error is not None:
            self.on_error(f"arguments of {node.id}", err)
        return {}

    def _current_activation(self, origin: tuple[str, int]) -> bool:
        node = self.chart.nodes.get(origin[0])
        return node is not None and node in self.config and self._activation.get(node) == origin[1]

    def _configuration(self) -> Configuration:
        if self._cfg is None:
            self._cfg = self._tables.configuration(frozenset(self.config))
        return self._cfg

    def _choose(self, selection: Selection) -> tuple[Transition, ...]:
        """The enabled transitions of a selection (one with chains), before conflicts are
        removed: per atomic state in document order, the first enabled one along its chain."""
        # The step bound's restart, which the first transition considered triggers.
        if self._bounded and self.ctx.event is not self._input:
            self._restart_count(self.ctx.event)
        if selection.static is not None:
            return selection.static
        chains = selection.chains
        if len(chains) == 1:  # one atomic state reacts, along a chain without a fixed choice
            chosen = self._first_enabled(chains[0][1])
            return () if chosen is None else (chosen,)
        enabled: list[Transition] = []
        for fixed, chain in chains:
            chosen = fixed
            if chosen is None:
                chosen = self._first_enabled(chain)
                if chosen is None:
                    continue
            if chosen not in enabled:
                enabled.append(chosen)
        return tuple(enabled)

    def _first_enabled(self, chain: Chain) -> Transition | None:
        """The first candidate along the chain whose guard holds and the step bound allows."""
        ctx = self.ctx
        for owner, candidates in chain:
            for transition in candidates:
                cond = transition.cond
                if cond is not None:
                    try:
                        held = cond(ctx)
                    except Exception as err:  # a guard that cannot be evaluated is false (5.9)
                        self._error(f"guard in {owner.id}", err)
                        continue
                    if held is not True:
                        continue
                if not transition.bounded or self._step_allowed(owner):
                    return transition
        return None

    def _restart_count(self, event: Event | None) -> None:
        """The step bound's count restarts when the first transition is considered under a new
        input from outside (not an event the member raised itself), as `$sg.tick()` at
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

    def _microstep(self, enabled: tuple[Transition, ...], cfg: Configuration) -> None:
        """Take the enabled transitions from `cfg`, the engine's current configuration."""
        plan = cfg.plans.get(enabled)
        if plan is None or plan.read:  # one that depends on history: `plan` picks the one
            plan = cfg.plan(enabled, self.history)
        self._cfg = None
        exits = plan.exits
        if exits:  # history is recorded first, then the states are left in exit order
            if self._to_invoke:
                self._to_invoke.difference_update(exits)
            for node, recorded in plan.records:
                self.history[node] = recorded
            config = self.config
            cancels = plan.cancels
            if cancels is not None:  # no exit action runs: no state sees the others leave
                activations = self._activation
                for state in cancels:  # `_leave`, which has no exit action to run here
                    activation = activations.get(state) if state.call is not None else None
                    if activation is not None:
                        self.host.cancel_call(state, activation)
                        activations[state] = activation + 1  # late outcomes of it are stale
                    for event, _ in state.timers:
                        self.host.cancel_timer(state, event)
                config.difference_update(exits)
            else:
                for state in exits:
                    if state.call or state.timers or state.onexit or state.invokes:
                        self._leave(state)
                    config.discard(state)
        for action, source in plan.actions:  # `_run`'s, inlined (one per transition taken)
            try:
                action(self.ctx)
            except Exception as err:  # SCXML: the block stops and raises error.execution
                self._error(f"transition from {source.id}", err)
        entered = plan.entered
        if entered is None:
            self._enter(plan)
            return
        # nothing runs as they are entered (behaviours start after the macrostep): no order
        self.config.update(entered)
        if plan.calls:
            self._to_invoke.update(plan.calls)
        self._cfg = plan.after or self._tables.after(plan)

    def _leave(self, state: Node) -> None:
        """Cancel a state's behaviour and timers and run its exit actions."""
        activation = self._activation.get(state) if state.call is not None else None
        if activation is not None:
            self.host.cancel_call(state, activation)
            self._activation[state] = activation + 1  # late outcomes of it are stale
        for event, _ in state.timers:
            self.host.cancel_timer(state, event)
        if state.onexit is not None:
            self._run(state.onexit, "exit of", state)
        if state.invokes and self.sessions is not None:  # W3C: after the exit actions
            self.sessions.cancel(state)

    def _enter(self, plan: Plan) -> None:
        """Enter the plan's entry set in document order; the configuration is then its target."""
        self._cfg = None
        config = self.config
        if plan.entered is not None:  # nothing runs as they are entered: no order to keep
            config.update(plan.entered)
            self._to_invoke.update(plan.calls)
            self._cfg = plan.after or self._tables.after(plan)
            return
        for state, initial, default in plan.entries:
            config.add(state)
            if state.call is not None or state.invokes:  # started by `_start_calls`
                self._to_invoke.add(state)
            if state.onentry is not None:
                self._run(state.onentry, "entry of", state)
            for event, delay in state.timers:
                self.host.start_timer(state, event, delay)
            if initial is not None:
                self._run(initial, "initial transition of", state)
            if default is not None:
                self._run(default, "history default in", state)
            if state.kind == "final":
                self._reached_final(state)
        self._cfg = plan.after or self._tables.after(plan)

    def _reached_final(self, state: Node) -> None:
        parent = state.parent
        if parent is None or parent.kind == "scxml":
            done = self.parent_sessions  # an invoked session's done data is its parent's
            data = self._done_data(state) if done and state.donedata is not None else None
            self.running = False
            self.finished = True
            self._exit_everything()
            if done is not None:
                done.done(self, data)
            return
        data = self._done_data(state) if state.donedata is not None else None
        self.internal.append(self.make_event(f"done.state.{parent.id}", data, kind="platform"))
        grandparent = parent.parent
        if (
            grandparent is not None
            and grandparent.kind == "parallel"
            and all(in_final(c, self.config) for c in grandparent.children if c.kind != "history")
        ):
            self.internal.append(self.make_event(f"done.state.{grandparent.id}", kind="platform"))

    def _done_data(self, state: Node) -> Any:
        """A final state's done data; one that fails raises error.execution (before the done
        event) and the event carries none (W3C 5.5: `<donedata>`)."""
        assert state.donedata is not None
        try:
            return state.donedata(self.ctx)
        except Exception as err:
            self._error(f"done data of {state.id}", err)
            return None

    def _exit_everything(self) -> None:
        """The machine is done: behaviours are cancelled and exit actions run; the final
        configuration stays visible (as Qt SCXML reports it) for traces."""
        for state in sorted(self.config, key=document_order, reverse=True):
            self._leave(state)
        self._to_invoke.clear()
        self.internal.clear()

    # --- executable content

    def _run(self, action: Callable[[Context], None], what: str, node: Node) -> None:
        """Run executable content; `what` and the node say where, when it fails (the text is
        made only then: this runs for every action)."""
        try:
            action(self.ctx)
        except Exception as err:  # SCXML: an error stops the block and raises error.execution
            self._error(f"{what} {node.id}", err)

    def _error(self, where: str, err: BaseException) -> None:
        self.error_count += 1  # error events raised: execution and communication (as Qt)
        # no data, as in Qt SCXML: `where` and the error go to the host (`on_error`)
        name = "error.communication" if isinstance(err, CommunicationError) else "error.execution"
        error = self.make_event(name, None, kind="platform")
        error.sendid = getattr(err, "sendid", None)  # a failed send's (raise_through)
        self.internal.append(error)
        if self.on_error is not None:
            self.on_error(where, err)
