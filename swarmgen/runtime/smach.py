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
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Unpack

from swarmgen.runtime.chart import Chart
from swarmgen.runtime.engine import Event as EngineEvent
from swarmgen.runtime.member import Bus, InMemoryBus, Library, Member
from swarmgen.runtime.smach_chart import compile_chart
from swarmgen.runtime.smach_containers import Composite, UserData
from swarmgen.runtime.smach_states import (
    Behaviour,
    BehaviourState,
    Event,
    EventState,
    FinalState,
    HistoryState,
    PseudoState,
    State,
    StateOptions,
    Transition,
    Transitions,
)

PREEMPTED = "preempted"  # what `execute` returns when the member was preempted
Publish = Callable[[list[str]], None]


class Container(Composite):
    """What StateMachine and Concurrence share: children, `with` construction, the initial
    states, userdata, and, for the top container, execution, preemption and introspection."""

    @classmethod
    def add(
        cls,
        label: str,
        state: State,
        transitions: Transitions | None = None,
        remapping: Mapping[str, str] | None = None,
        *,
        name: str | None = None,
    ) -> State:
        """Add `state` to the open container of this class (a region, for a Concurrence).
        `transitions`: `{key: target}` or a list of Transition (for a Concurrence's region, a
        SMACH extension); `remapping`: {state key: member data key}; `name`: the model's name."""
        return cls._opened()._add(label, state, transitions, remapping, name)

    def build_chart(
        self, name: str, events: Mapping[str, Mapping[str, Any]] | None = None
    ) -> Chart:
        """The statechart these containers describe, as the engine runs it; `events`: each
        event's fields with the value a sender that leaves one out gives it."""
        if self._entry is not None:
            raise ValueError("build_chart() is called on the top container")
        return compile_chart(self, name, events)

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
        return self._outcome(member)

    def _outcome(self, member: Member) -> str:
        """The label of the final state the member ended in, or "preempted"."""
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
        """Whether a preemption was requested and not yet serviced."""
        return self._preempt_requested

    def service_preempt(self) -> None:
        """Mark the requested preemption as serviced."""
        self._preempt_requested = False

    def is_running(self) -> bool:
        """Whether the top container is executing."""
        top = self._top()
        return top._running

    def get_active_states(self) -> list[str]:
        """Labels of this container's children that are active (empty when not executing)."""
        top = self._top()
        if top._member is None:
            return []
        engine = top._member.engine
        return [e.label for e in self._entries if engine.is_active(e.label)]


class StateMachine(Container):
    """SMACH's StateMachine: a compound state. `outcomes` are the labels of its FinalStates."""

    def _completion_outcomes(self) -> list[str]:
        return list(self._outcomes)

    def _check_outcomes(self) -> None:
        finals = [e.label for e in self._entries if e.state.kind == "final"]
        if sorted(self._outcomes) != sorted(finals):
            raise ValueError(
                f"{self.label or 'the top container'}: the outcomes of a StateMachine are the "
                f"labels of its FinalStates {finals}, not {self._outcomes}"
            )


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
        **options: Unpack[StateOptions],
    ) -> None:
        super().__init__(outcomes, input_keys, output_keys, **options)
        self.default_outcome = default_outcome
        self.outcome_map: dict[str, dict[str, tuple[str, ...]]] = {
            outcome: {
                region: (finals,) if isinstance(finals, str) else tuple(finals)
                for region, finals in condition.items()
            }
            for outcome, condition in (outcome_map or {}).items()
        }

    def _completion_outcomes(self) -> list[str]:
        return list(self.outcome_map)

    def _check_outcomes(self) -> None:
        where = self.label or "the top container"
        expected = _completion_map(self)
        given = [
            {region: sorted(finals) for region, finals in condition.items()}
            for condition in self.outcome_map.values()
        ]
        if given and (given != [expected] or not expected):
            raise ValueError(
                f"{where}: outcome_map must name every region with all of its final "
                f"outcomes, since the engine completes a Concurrence when all of its regions "
                f"are in a final state: {{outcome: {expected}}}"
                if expected
                else f"{where}: outcome_map must be empty: some region has no FinalState"
            )
        if list(self.outcome_map) != self._outcomes:
            raise ValueError(f"{where}: the outcomes of a Concurrence are those of its outcome_map")
        if self.default_outcome not in (None, *self._outcomes):
            raise ValueError(f"{where}: default_outcome is not one of the outcomes")

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
        """Publish the member's active states."""
        self.last = member.active
        self.publish(list(self.last))

    def close(self) -> None:
        """Stop publishing."""
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
