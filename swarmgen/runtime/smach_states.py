"""The states of the SMACH construction API (standard library only): transitions with their
keys and targets, the behaviour a state runs, and the leaf states (see `smach.py`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, TypedDict, Unpack

from swarmgen.runtime.chart import Action, Call, Cond, Context, Invoke


class Placement(Protocol):
    """Where a state was added to a container (`smach_containers.Entry`, the one kind there is):
    a protocol so that states do not import the containers built from them."""

    @property
    def label(self) -> str:
        """The label the state was added under."""

    @property
    def container(self) -> State:
        """The container it was added to."""


GoalCallback = Callable[[Context], Mapping[str, Any]]


class Hooks(TypedDict, total=False):
    """The SMACH extensions every state takes: entry and exit actions and timed events."""

    onentry: Action | None
    onexit: Action | None
    timers: Sequence[tuple[str, int]]
    invokes: Sequence[Invoke]  # child SCXML sessions (W3C `<invoke>`) while it is active


class StateOptions(Hooks, total=False):
    """The keyword options of a State: its hooks and the behaviour it runs."""

    behaviour: Behaviour | None


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


def transitions_of(spec: Transitions | None) -> list[Transition]:
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
        """The chart's call of this behaviour, with userdata keys remapped to member data."""
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
        donedata: Callable[[Context], Any] | None = None,
        invokes: Sequence[Invoke] = (),
    ) -> None:
        self._outcomes = list(outcomes)
        self.invokes = tuple(invokes)
        self.donedata = donedata  # a FinalState's: the fields of its done.state event
        self._input_keys = list(input_keys)
        self._output_keys = list(output_keys)
        self.onentry = onentry
        self.onexit = onexit
        self.timers = tuple((str(event), int(delay)) for event, delay in timers)
        self.behaviour = behaviour
        self._entry: Placement | None = None

    def get_registered_outcomes(self) -> list[str]:
        """The behaviour's outcomes, then the state's own."""
        own = self.behaviour.outcomes if self.behaviour is not None else []
        return _merged(own, self._outcomes)

    def get_registered_input_keys(self) -> list[str]:
        """The behaviour's input keys, then the state's own."""
        own = self.behaviour.input_keys if self.behaviour is not None else []
        return _merged(own, self._input_keys)

    def get_registered_output_keys(self) -> list[str]:
        """The behaviour's output keys, then the state's own."""
        own = self.behaviour.output_keys if self.behaviour is not None else []
        return _merged(own, self._output_keys)

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
        **hooks: Unpack[Hooks],
    ) -> None:
        run = Behaviour(behaviour, kind, outcomes, input_keys, output_keys, goal_cb=goal_cb)
        super().__init__(behaviour=run, **hooks)


def _merged(own: list[str], extra: list[str]) -> list[str]:
    """`own`, then the items of `extra` it lacks."""
    return [*own, *(item for item in extra if item not in own)]
