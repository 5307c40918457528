"""How SMACH containers are built (standard library only): userdata, `with` construction,
`add` and the initial states. `smach.Container` adds execution; `smach_chart` reads the result."""

from __future__ import annotations

import threading
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, Self, Unpack

from swarmgen.runtime.chart import Action
from swarmgen.runtime.smach_states import (
    State,
    StateOptions,
    Transition,
    Transitions,
    transitions_of,
)

if TYPE_CHECKING:
    from swarmgen.runtime.engine import Event as EngineEvent
    from swarmgen.runtime.member import Member


class Hook(Protocol):
    """An observer of the top container's steps (`smach.IntrospectionHook`)."""

    def step(self, member: Member, event: EngineEvent | None) -> None:
        """See the member after a step."""


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


@dataclass(eq=False, slots=True)
class Entry:
    """A state added to a container: its label and how it is wired."""

    label: str
    state: State
    container: Composite
    transitions: list[Transition]
    remapping: dict[str, str]
    name: str


_construction = threading.local()  # the containers opened with `with`, per thread


def _stack() -> list[Composite]:
    stack: list[Composite] | None = getattr(_construction, "stack", None)
    if stack is None:
        stack = []
        _construction.stack = stack
    return stack


class Composite(State):
    """A state with children, as built: `with` construction, `add`, the initial states, the
    userdata, and the top container's execution state (which `smach.Container` drives)."""

    def __init__(
        self,
        outcomes: Sequence[str] = (),
        input_keys: Sequence[str] = (),
        output_keys: Sequence[str] = (),
        **options: Unpack[StateOptions],
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys, **options)
        self.userdata = UserData()
        # the top container's data zeros where a value's kind does not say (ChartBuilder.zeros)
        self.zeros: dict[str, Any] = {}
        self._entries: list[Entry] = []
        self._labels: dict[str, Entry] = {}
        self._initial: tuple[tuple[str, ...], Action | None] | None = None
        self._hooks: list[Hook] = []
        self._member: Member | None = None
        self._running = False
        self._preempt_requested = False

    def __enter__(self) -> Self:
        _stack().append(self)
        return self

    def __exit__(self, *exc: object) -> None:
        stack = _stack()
        if not stack or stack[-1] is not self:
            raise RuntimeError("containers must be closed in the order they were opened")
        stack.pop()

    @classmethod
    def _opened(cls) -> Composite:
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
        self._check_new(label, state)
        remap = dict(remapping or {})
        behaviour = state.behaviour
        keys = {*behaviour.input_keys, *behaviour.output_keys} if behaviour is not None else set()
        unknown = sorted(set(remap) - keys)
        if unknown:
            raise ValueError(f"{label}: remapping of keys its behaviour does not use: {unknown}")
        entry = Entry(label, state, self, transitions_of(transitions), remap, name or label)
        state._entry = entry
        self._entries.append(entry)
        self._labels[label] = entry
        return state

    def _check_new(self, label: str, state: State) -> None:
        """Refuse what cannot be added under `label`, with the reason."""
        if not isinstance(label, str) or not label or "/" in label:
            raise ValueError(f"a label is a non-empty string without '/': {label!r}")
        if not isinstance(state, State):
            raise TypeError(f"{label}: not a State: {state!r}")
        if state._entry is not None or state is self:
            raise ValueError(f"{label}: this state object was already added")
        if not isinstance(state, Composite) and hasattr(state, "execute"):
            raise TypeError(
                f"{label}: {type(state).__name__} defines execute(): states run in the chart "
                "engine here; implement the work as a library behaviour (BehaviourState)"
            )
        if label in self._labels:
            raise ValueError(f"{label}: a state with this label was already added")

    def set_initial_state(
        self, initial_states: Sequence[str] | str, *, action: Action | None = None
    ) -> None:
        """The states entered first (labels or paths in this container), after `action`.
        Without it, the first state added is the initial state (as in SMACH)."""
        targets = (initial_states,) if isinstance(initial_states, str) else tuple(initial_states)
        self._initial = (targets, action)

    def get_children(self) -> dict[str, State]:
        """The states added, by label."""
        return {entry.label: entry.state for entry in self._entries}

    def _top(self) -> Composite:
        node: Composite = self
        while node._entry is not None:
            parent = node._entry.container
            assert isinstance(parent, Composite)  # only containers hold states
            node = parent
        return node

    def _check_outcomes(self) -> None:
        """Raise ValueError when the declared outcomes are not those the chart gives."""
