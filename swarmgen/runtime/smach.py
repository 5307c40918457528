"""SMACH's construction API over swarmgen's statechart runtime (standard library only).

Generated smach modules build a member's behaviour the way SMACH users write it: states with
outcomes, `StateMachine` and `Concurrence` containers opened with `with`, `add(label, state,
transitions=..., remapping=...)`, userdata, `set_initial_state`, preemption and an introspection
hook. The containers do not run states themselves: `build_chart()` turns them into the same
`chart.Chart` the asyncio backend builds for the model, and execution is the shared engine
(`engine.py`, SCXML semantics) on the shared asyncio member (`member.py`). So a SMACH member and an
asyncio or Qt SCXML member of the same model produce the same traces. See docs/smach.md.

Labels are chart node ids (identifiers, unique in a member). Transition keys and targets:
    key     a behaviour outcome of the state ("succeeded")      -> event outcome.<label>.<outcome>
            an outcome of a container (its completion)          -> event done.state.<label>
            anything else, or `Event(name)`: an event descriptor (swarm event, timer, done.state.*)
    target  a sibling label ("Loitering"), a path below the current container ("Patrol/History")
            or an absolute path from the top container ("/Operating/Main/Patrol")
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from swarmgen.runtime.chart import Action, Call, Chart, ChartBuilder, Cond, Context
from swarmgen.runtime.engine import Event as EngineEvent
from swarmgen.runtime.member import Bus, InMemoryBus, Library, Member

PREEMPTED = "preempted"  # what `execute` returns when the member was preempted
GoalCallback = Callable[[Context], Mapping[str, Any]]
Publish = Callable[[list[str]], None]

# --- userdata


class UserData:
    """SMACH userdata: attribute and item access to the member data (one datamodel per member,
    shared by every container, as in SCXML). Data keys never start with `_`."""

    __slots__ = ("_data",)
    _data: dict[str, Any]

    def __init__(self, data: Mapping[str, Any] | None = None) -> None:
        object.__setattr__(self, "_data", dict(data or {}))

    def __getattr__(self, key: str) -> Any:
        try:
            return self._data[key]
        except KeyError:
            raise AttributeError(key) from None

    def __setattr__(self, key: str, value: Any) -> None:
        self._data[key] = value

    def __getitem__(self, key: str) -> Any:
        return self._data[key]

    def __setitem__(self, key: str, value: Any) -> None:
        self._data[key] = value

    def __contains__(self, key: object) -> bool:
        return key in self._data

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        return f"UserData({self._data!r})"


# --- transitions


@dataclass(frozen=True, slots=True)
class Event:
    """A transition key that always names an event, never an outcome of the state (for an event
    whose name is also one of the state's outcomes)."""

    name: str


Key = str | Event


class Transition:
    """One transition of a state, for `add(..., transitions=[...])` (SMACH extension).

    `on`: one key or several (any of them triggers it; none: an eventless transition);
    `to`: one target or several (a fork; none: a targetless transition that only runs `action`);
    `guard(ctx) -> bool` and `action(ctx)` see the member data as `ctx.data`; `internal=True` is
    SCXML's type="internal" (the source is not exited). Transitions of a state are tried in order.
    `bounded=True`: the transition lies on a potential microstep cycle and counts towards the
    step bound (docs/semantics.md; swarmgen decides it when it compiles a model).
    """

    __slots__ = ("action", "bounded", "guard", "internal", "on", "to")

    def __init__(
        self,
        on: Key | Sequence[Key] = (),
        to: str | Sequence[str] | None = (),
        *,
        guard: Cond | None = None,
        action: Action | None = None,
        internal: bool = False,
        bounded: bool = False,
    ) -> None:
        self.on: tuple[Key, ...] = (on,) if isinstance(on, str | Event) else tuple(on)
        self.to: tuple[str, ...] = () if to is None else (to,) if isinstance(to, str) else tuple(to)
        for key in self.on:
            if not isinstance(key, str | Event) or not key:
                raise TypeError(f"a transition key is a non-empty string or Event: {key!r}")
        for target in self.to:
            if not isinstance(target, str) or not target.strip("/"):
                raise TypeError(f"a transition target is a label or a label path: {target!r}")
        self.guard = guard
        self.action = action
        self.internal = internal
        self.bounded = bounded

    def __repr__(self) -> str:
        return f"Transition(on={self.on!r}, to={self.to!r})"


Transitions = Mapping[Key, str | Sequence[str] | None] | Sequence[Transition | tuple[Any, Any]]


def _transitions(spec: Transitions | None) -> list[Transition]:
    """SMACH's `{outcome: target}` dict, or a list of Transition / (key, target) pairs."""
    if spec is None:
        return []
    if isinstance(spec, Mapping):
        return [Transition(key, target) for key, target in spec.items()]
    found = []
    for item in spec:
        if isinstance(item, Transition):
            found.append(item)
        elif isinstance(item, tuple) and len(item) == 2:
            found.append(Transition(item[0], item[1]))
        else:
            raise TypeError(f"transitions: expected Transition or (key, target), got {item!r}")
    return found


# --- states


class Behaviour:
    """The library behaviour a state runs while it is active (SMACH's SimpleActionState part).

    `input_keys` are inputs read from userdata keys of the same name (`remapping` on `add` maps
    them to other member data); `goal_cb(ctx) -> {input: value}` computes the other inputs from
    expressions. `output_keys` are the outputs and, through `remapping`, the member data they go
    to; they are written when the behaviour ends, before its outcome is matched (the chart's
    finalize transition, docs/semantics.md), and not when the behaviour is preempted.
    """

    __slots__ = ("behaviour", "goal_cb", "input_keys", "kind", "outcomes", "output_keys")

    def __init__(
        self,
        behaviour: str,
        kind: str,
        outcomes: Sequence[str],
        input_keys: Sequence[str] = (),
        output_keys: Sequence[str] = (),
        *,
        goal_cb: GoalCallback | None = None,
    ) -> None:
        self.behaviour = behaviour
        self.kind = kind
        self.outcomes = list(outcomes)
        self.input_keys = list(input_keys)
        self.output_keys = list(output_keys)
        self.goal_cb = goal_cb

    def call(self, remapping: Mapping[str, str]) -> Call:
        slots = tuple((key, remapping.get(key, key)) for key in self.input_keys)
        goal_cb = self.goal_cb

        def args(ctx: Context) -> dict[str, Any]:
            data = ctx.data
            values = {key: data[source] for key, source in slots}
            if goal_cb is not None:
                values.update(goal_cb(ctx))
            return values

        results = tuple((key, remapping.get(key, key)) for key in self.output_keys)
        return Call(self.behaviour, self.kind, args, results, tuple(self.outcomes))


@dataclass(eq=False, slots=True)
class _Entry:
    """A state added to a container: its label and how it is wired."""

    label: str
    state: State
    container: Container
    transitions: list[Transition]
    remapping: dict[str, str]
    name: str


class State:
    """SMACH's State. Here states describe; the engine runs them: a plain State waits for the
    events of its transitions. `onentry`/`onexit(ctx)` and `timers` ((event, delay in ms), ...)
    are SMACH extensions for the chart's entry/exit actions and timed events."""

    kind = "state"

    def __init__(
        self,
        outcomes: Sequence[str] = (),
        input_keys: Sequence[str] = (),
        output_keys: Sequence[str] = (),
        *,
        onentry: Action | None = None,
        onexit: Action | None = None,
        timers: Sequence[tuple[str, int]] = (),
        behaviour: Behaviour | None = None,
    ) -> None:
        self._outcomes = list(outcomes)
        self._input_keys = list(input_keys)
        self._output_keys = list(output_keys)
        self.onentry = onentry
        self.onexit = onexit
        self.timers = tuple((str(event), int(delay)) for event, delay in timers)
        self.behaviour = behaviour
        self._entry: _Entry | None = None

    def get_registered_outcomes(self) -> list[str]:
        own = self.behaviour.outcomes if self.behaviour is not None else []
        return [*own, *(o for o in self._outcomes if o not in own)]

    def get_registered_input_keys(self) -> list[str]:
        own = self.behaviour.input_keys if self.behaviour is not None else []
        return [*own, *(k for k in self._input_keys if k not in own)]

    def get_registered_output_keys(self) -> list[str]:
        own = self.behaviour.output_keys if self.behaviour is not None else []
        return [*own, *(k for k in self._output_keys if k not in own)]

    @property
    def label(self) -> str | None:
        """The label this state was added under (its chart node id)."""
        return self._entry.label if self._entry is not None else None

    def _completion_outcomes(self) -> list[str]:
        return []


class EventState(State):
    """An atomic state without behaviour: it waits for the events of its transitions."""


class PseudoState(State):
    """A transient state (UML choice, junction, fork, entry or exit point): the engine leaves it
    at once through its eventless transitions (`Transition(to=..., guard=...)`)."""

    def __init__(self, pseudostate: str, **options: Any) -> None:
        super().__init__(**options)
        self.pseudostate = pseudostate


class FinalState(State):
    """A final state. Its label is an outcome of the enclosing StateMachine: entering it
    completes the container (its parent sees the container's outcome)."""

    kind = "final"


class HistoryState(State):
    """A history pseudostate of its container (shallow, or `deep=True`). `default` are the
    targets (resolved in the container) entered when there is no history yet, after `action`."""

    kind = "history"

    def __init__(
        self,
        deep: bool = False,
        default: Sequence[str] | str | None = None,
        action: Action | None = None,
    ) -> None:
        super().__init__()
        self.deep = deep
        self.default: tuple[str, ...] | None = (
            None if default is None else (default,) if isinstance(default, str) else tuple(default)
        )
        self.action = action


class BehaviourState(State):
    """A state that runs a library behaviour while active; its outcomes are the behaviour's.
    The behaviour is started when the state is entered and cancelled when it is left."""

    def __init__(
        self,
        behaviour: str,
        kind: str,
        outcomes: Sequence[str],
        input_keys: Sequence[str] = (),
        output_keys: Sequence[str] = (),
        *,
        goal_cb: GoalCallback | None = None,
        onentry: Action | None = None,
        onexit: Action | None = None,
        timers: Sequence[tuple[str, int]] = (),
    ) -> None:
        super().__init__(
            onentry=onentry,
            onexit=onexit,
            timers=timers,
            behaviour=Behaviour(
                behaviour, kind, outcomes, input_keys, output_keys, goal_cb=goal_cb
            ),
        )


# --- containers

_construction = threading.local()  # the containers opened with `with`, per thread


def _stack() -> list[Container]:
    stack: list[Container] | None = getattr(_construction, "stack", None)
    if stack is None:
        stack = []
        _construction.stack = stack
    return stack


class Container(State):
    """What StateMachine and Concurrence share: children, `with` construction, the initial
    states, userdata, and, for the top container, execution, preemption and introspection."""

    def __init__(
        self,
        outcomes: Sequence[str] = (),
        input_keys: Sequence[str] = (),
        output_keys: Sequence[str] = (),
        *,
        onentry: Action | None = None,
        onexit: Action | None = None,
        timers: Sequence[tuple[str, int]] = (),
        behaviour: Behaviour | None = None,
    ) -> None:
        super().__init__(
            outcomes,
            input_keys,
            output_keys,
            onentry=onentry,
            onexit=onexit,
            timers=timers,
            behaviour=behaviour,
        )
        self.userdata = UserData()
        self._entries: list[_Entry] = []
        self._labels: dict[str, _Entry] = {}
        self._initial: tuple[tuple[str, ...], Action | None] | None = None
        self._hooks: list[IntrospectionHook] = []
        self._member: Member | None = None
        self._running = False
        self._preempt_requested = False

    # --- construction

    def __enter__(self) -> Container:
        _stack().append(self)
        return self

    def __exit__(self, *exc: object) -> None:
        stack = _stack()
        if not stack or stack[-1] is not self:
            raise RuntimeError("containers must be closed in the order they were opened")
        stack.pop()

    @classmethod
    def _opened(cls) -> Container:
        stack = _stack()
        if not stack or not isinstance(stack[-1], cls):
            raise RuntimeError(f"{cls.__name__}.add() needs an open {cls.__name__} (`with sm:`)")
        return stack[-1]

    def _add(
        self,
        label: str,
        state: State,
        transitions: Transitions | None,
        remapping: Mapping[str, str] | None,
        name: str | None,
    ) -> State:
        if not isinstance(label, str) or not label or "/" in label:
            raise ValueError(f"a label is a non-empty string without '/': {label!r}")
        if not isinstance(state, State):
            raise TypeError(f"{label}: not a State: {state!r}")
        if state._entry is not None or state is self:
            raise ValueError(f"{label}: this state object was already added")
        if not isinstance(state, Container) and hasattr(state, "execute"):
            raise TypeError(
                f"{label}: {type(state).__name__} defines execute(): states run in the chart "
                "engine here; implement the work as a library behaviour (BehaviourState)"
            )
        if label in self._labels:
            raise ValueError(f"{label}: a state with this label was already added")
        remap = dict(remapping or {})
        behaviour = state.behaviour
        keys = {*behaviour.input_keys, *behaviour.output_keys} if behaviour is not None else set()
        unknown = sorted(set(remap) - keys)
        if unknown:
            raise ValueError(f"{label}: remapping of keys its behaviour does not use: {unknown}")
        entry = _Entry(label, state, self, _transitions(transitions), remap, name or label)
        state._entry = entry
        self._entries.append(entry)
        self._labels[label] = entry
        return state

    def set_initial_state(
        self, initial_states: Sequence[str] | str, *, action: Action | None = None
    ) -> None:
        """The states entered first (labels or paths in this container), after `action`.
        Without it, the first state added is the initial state (as in SMACH)."""
        targets = (initial_states,) if isinstance(initial_states, str) else tuple(initial_states)
        self._initial = (targets, action)

    def get_children(self) -> dict[str, State]:
        return {entry.label: entry.state for entry in self._entries}

    # --- execution (the top container)

    def build_chart(
        self, name: str, events: Mapping[str, Mapping[str, Any]] | None = None
    ) -> Chart:
        """The statechart these containers describe, as the engine runs it; `events`: each
        event's fields with the value a sender that leaves one out gives it."""
        if self._entry is not None:
            raise ValueError("build_chart() is called on the top container")
        return _Compiler(self).chart(name, events)

    async def execute_async(
        self,
        library: Library,
        *,
        member_type: str = "",
        member_id: str = "1",
        bus: Bus | None = None,
        event_scopes: Mapping[str, str] | None = None,
        chart_name: str | None = None,
        tracer: Any = None,
    ) -> str:
        """Run the member until it reaches a final state of this container (returns its label)
        or is preempted (returns "preempted"). Behaviours come from `library`; swarm events go
        through `bus`; `tracer` (a member tracer) sees every step, like the introspection hooks.
        """
        if self._entry is not None:
            raise RuntimeError("only the top container is executed")
        if self._running:
            raise RuntimeError("this container is already executing")
        if self._preempt_requested:
            self._preempt_requested = False
            return PREEMPTED
        chart = self.build_chart(chart_name or member_type or "member")
        member = Member(
            chart,
            member_type or chart.name,
            member_id,
            library,
            bus if bus is not None else InMemoryBus(),
            event_scopes=event_scopes,
            tracer=_Tracers(self, tracer),
        )
        self.userdata = UserData()
        object.__setattr__(self.userdata, "_data", member.engine.data)  # live member data
        self._member, self._running = member, True
        try:
            await member.run()
        finally:
            self._running = False
        self._preempt_requested = False
        if member.engine.finished:
            finals = [e.label for e in self._entries if e.state.kind == "final"]
            for label in finals:
                if member.engine.is_active(label):
                    return label
        return PREEMPTED

    def execute(self, library: Library, **options: Any) -> str:
        """`execute_async` in a new event loop (SMACH's blocking `execute`)."""
        return asyncio.run(self.execute_async(library, **options))

    def request_preempt(self) -> None:
        """Stop the executing member: running behaviours are cancelled (their tasks get
        CancelledError), timers are cleared, and `execute` returns "preempted". Call it from
        the event loop that executes the member (from another thread: call_soon_threadsafe)."""
        if self._entry is not None:
            raise RuntimeError("preempt the top container: a member's statechart stops as a whole")
        self._preempt_requested = True
        if self._member is not None and self._running:
            self._member.stop()

    def preempt_requested(self) -> bool:
        return self._preempt_requested

    def service_preempt(self) -> None:
        self._preempt_requested = False

    def is_running(self) -> bool:
        top = self._top()
        return top._running

    def get_active_states(self) -> list[str]:
        """Labels of this container's children that are active (empty when not executing)."""
        top = self._top()
        if top._member is None:
            return []
        engine = top._member.engine
        return [e.label for e in self._entries if engine.is_active(e.label)]

    def _top(self) -> Container:
        node: Container = self
        while node._entry is not None:
            node = node._entry.container
        return node


class StateMachine(Container):
    """SMACH's StateMachine: a compound state. `outcomes` are the labels of its FinalStates."""

    @staticmethod
    def add(
        label: str,
        state: State,
        transitions: Transitions | None = None,
        remapping: Mapping[str, str] | None = None,
        *,
        name: str | None = None,
    ) -> State:
        """Add `state` to the open StateMachine. `transitions`: `{key: target}` or a list of
        Transition; `remapping`: {state key: member data key}; `name`: the model's name."""
        return StateMachine._opened()._add(label, state, transitions, remapping, name)

    def _completion_outcomes(self) -> list[str]:
        return list(self._outcomes)


class Concurrence(Container):
    """SMACH's Concurrence: a parallel state; each child added is a region.

    The engine completes it (SCXML done.state.<label>) when every region has reached one of its
    final states, so `outcome_map` is either empty (it never completes: some region has no
    FinalState) or `{outcome: {region: final outcome(s), ...}}` naming every region with all of
    its outcomes; that outcome is then the container's only one, and `default_outcome` too.
    """

    kind = "parallel"

    def __init__(
        self,
        outcomes: Sequence[str] = (),
        default_outcome: str | None = None,
        outcome_map: Mapping[str, Mapping[str, str | Sequence[str]]] | None = None,
        input_keys: Sequence[str] = (),
        output_keys: Sequence[str] = (),
        *,
        onentry: Action | None = None,
        onexit: Action | None = None,
        timers: Sequence[tuple[str, int]] = (),
        behaviour: Behaviour | None = None,
    ) -> None:
        super().__init__(
            outcomes,
            input_keys,
            output_keys,
            onentry=onentry,
            onexit=onexit,
            timers=timers,
            behaviour=behaviour,
        )
        self.default_outcome = default_outcome
        self.outcome_map: dict[str, dict[str, tuple[str, ...]]] = {
            outcome: {
                region: (finals,) if isinstance(finals, str) else tuple(finals)
                for region, finals in condition.items()
            }
            for outcome, condition in (outcome_map or {}).items()
        }

    @staticmethod
    def add(
        label: str,
        state: State,
        transitions: Transitions | None = None,
        remapping: Mapping[str, str] | None = None,
        *,
        name: str | None = None,
    ) -> State:
        """Add a region to the open Concurrence (`transitions` are a SMACH extension)."""
        return Concurrence._opened()._add(label, state, transitions, remapping, name)

    def _completion_outcomes(self) -> list[str]:
        return list(self.outcome_map)

    def current_outcome(self) -> str | None:
        """The outcome `outcome_map` gives for the active states (None while it does not hold)."""
        regions = {e.label: e.state for e in self._entries}
        for outcome, condition in self.outcome_map.items():
            reached = True
            for region, finals in condition.items():
                state = regions.get(region)
                active = state.get_active_states() if isinstance(state, Container) else []
                reached = reached and any(final in active for final in finals)
            if reached:
                return outcome
        return None


# --- introspection


class IntrospectionHook:
    """SMACH's IntrospectionServer in process: `publish(active)` gets the labels of all active
    states (sorted, as in traces) after the member starts and after every event it processes."""

    def __init__(self, container: Container, publish: Publish) -> None:
        self.container = container._top()
        self.publish = publish
        self.last: list[str] = []
        self.container._hooks.append(self)

    def step(self, member: Member, event: EngineEvent | None) -> None:
        self.last = member.active
        self.publish(list(self.last))

    def close(self) -> None:
        if self in self.container._hooks:
            self.container._hooks.remove(self)


class _Tracers:
    """The member's tracer: the container's introspection hooks, then an optional tracer."""

    def __init__(self, container: Container, tracer: Any) -> None:
        self.container = container
        self.tracer = tracer

    def step(self, member: Member, event: EngineEvent | None) -> None:
        for hook in list(self.container._hooks):
            hook.step(member, event)
        if self.tracer is not None:
            self.tracer.step(member, event)


# --- containers -> chart


class _Compiler:
    """Emits the containers as ChartBuilder calls, in document order: a state, its initial
    transition, its children, then its transitions (the order the asyncio backend uses)."""

    def __init__(self, top: Container) -> None:
        self.top = top
        self.builder = ChartBuilder("")

    def chart(self, name: str, events: Mapping[str, Mapping[str, Any]] | None = None) -> Chart:
        top = self.top
        for container in self._containers(top):
            if container is not top and len(container.userdata):
                raise ValueError(
                    f"{container.label}: member data lives in the top container's userdata"
                )
            self._check_outcomes(container)
        self.builder = ChartBuilder(name, data=dict(top.userdata._data), events=events)
        for entry in top._entries:
            self._emit(entry, None)
        self.builder.initial(None, self._initial_targets(top))
        return self.builder.build()

    def _containers(self, top: Container) -> Iterator[Container]:
        stack = [top]
        while stack:
            container = stack.pop()
            yield container
            stack.extend(e.state for e in container._entries if isinstance(e.state, Container))

    def _emit(self, entry: _Entry, parent: str | None) -> None:
        state, label = entry.state, entry.label
        behaviour = state.behaviour
        self.builder.node(
            label,
            state.kind,
            parent,
            name=entry.name,
            onentry=state.onentry,
            onexit=state.onexit,
            call=behaviour.call(entry.remapping) if behaviour is not None else None,
            timers=state.timers,
            history=("deep" if state.deep else "shallow")
            if isinstance(state, HistoryState)
            else "",
        )
        if isinstance(state, Container) and state._initial is not None:
            targets, action = state._initial
            self.builder.initial(label, self._resolve_all(state, targets), action)
        if isinstance(state, HistoryState) and state.default is not None:
            self.builder.initial(
                label, self._resolve_all(entry.container, state.default), state.action
            )
        if isinstance(state, Container):
            for child in state._entries:
                self._emit(child, label)
        for transition in entry.transitions:
            self.builder.transition(
                label,
                self._events(entry, transition),
                self._resolve_all(entry.container, transition.to),
                cond=transition.guard,
                action=transition.action,
                internal=transition.internal,
                bounded=transition.bounded,
            )

    def _initial_targets(self, container: Container) -> tuple[str, ...]:
        if container._initial is not None:
            return self._resolve_all(container, container._initial[0])
        first = [e.label for e in container._entries if e.state.kind != "history"][:1]
        if not first:
            raise ValueError("the top container has no states")
        return tuple(first)

    # --- keys and targets

    def _events(self, entry: _Entry, transition: Transition) -> tuple[str, ...]:
        state, label = entry.state, entry.label
        outcomes = state.behaviour.outcomes if state.behaviour is not None else []
        completion = state._completion_outcomes()
        events: list[str] = []
        completed: set[str] = set()
        for key in transition.on:
            if isinstance(key, Event):
                event = key.name
            elif key in outcomes:
                event = f"outcome.{label}.{key}"
            elif key in completion:
                event = f"done.state.{label}"
                completed.add(key)
            else:
                event = key
            if event not in events:
                events.append(event)
        if completed and completed != set(completion):
            raise ValueError(
                f"{label}: a container completes with any of its outcomes "
                f"(done.state.{label}); list all of {completion} on one transition"
            )
        return tuple(events)

    def _resolve_all(self, scope: Container, targets: Sequence[str]) -> tuple[str, ...]:
        return tuple(self._resolve(scope, target) for target in targets)

    def _resolve(self, scope: Container, target: str) -> str:
        container = self.top if target.startswith("/") else scope
        parts = target.strip("/").split("/")
        entry: _Entry | None = None
        for number, part in enumerate(parts):
            entry = container._labels.get(part)
            if entry is None:
                where = f"'{scope.label}'" if scope.label is not None else "the top container"
                raise ValueError(f"unknown target {target!r} (from {where})")
            if number < len(parts) - 1:
                if not isinstance(entry.state, Container):
                    raise ValueError(f"target {target!r}: {part} is not a container")
                container = entry.state
        assert entry is not None
        return entry.label

    # --- checks

    def _check_outcomes(self, container: Container) -> None:
        where = container.label or "the top container"
        if isinstance(container, StateMachine):
            finals = [e.label for e in container._entries if e.state.kind == "final"]
            if sorted(container._outcomes) != sorted(finals):
                raise ValueError(
                    f"{where}: the outcomes of a StateMachine are the labels of its "
                    f"FinalStates {finals}, not {container._outcomes}"
                )
        elif isinstance(container, Concurrence):
            expected = _completion_map(container)
            given = [
                {region: sorted(finals) for region, finals in condition.items()}
                for condition in container.outcome_map.values()
            ]
            if given and (given != [expected] or not expected):
                raise ValueError(
                    f"{where}: outcome_map must name every region with all of its final "
                    f"outcomes, since the engine completes a Concurrence when all of its regions "
                    f"are in a final state: {{outcome: {expected}}}"
                    if expected
                    else f"{where}: outcome_map must be empty: some region has no FinalState"
                )
            if list(container.outcome_map) != container._outcomes:
                raise ValueError(
                    f"{where}: the outcomes of a Concurrence are those of its outcome_map"
                )
            if container.default_outcome not in (None, *container._outcomes):
                raise ValueError(f"{where}: default_outcome is not one of the outcomes")


def _completion_map(container: Concurrence) -> dict[str, list[str]]:
    """region -> its final outcomes (sorted), when every region is a StateMachine with
    FinalStates; else {} (the Concurrence never completes by itself)."""
    regions = [e for e in container._entries if e.state.kind != "history"]
    found: dict[str, list[str]] = {}
    for entry in regions:
        if not isinstance(entry.state, StateMachine) or not entry.state._outcomes:
            return {}
        found[entry.label] = sorted(entry.state._outcomes)
    return found


__all__ = [
    "PREEMPTED",
    "Behaviour",
    "BehaviourState",
    "Concurrence",
    "Container",
    "Event",
    "EventState",
    "FinalState",
    "HistoryState",
    "IntrospectionHook",
    "PseudoState",
    "State",
    "StateMachine",
    "Transition",
    "UserData",
]
