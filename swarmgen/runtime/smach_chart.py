"""SMACH containers -> chart: the `ChartBuilder` calls that give the statechart the containers
describe, with transition keys made events and target paths resolved (standard library only)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from swarmgen.runtime.chart import Chart, ChartBuilder
from swarmgen.runtime.smach_containers import Composite, Entry
from swarmgen.runtime.smach_states import Event, HistoryState, Transition


def compile_chart(
    top: Composite, name: str, events: Mapping[str, Mapping[str, Any]] | None = None
) -> Chart:
    """The statechart of the top container `top`, named `name`, with the events' defaults."""
    return _Compiler(top).chart(name, events)


class _Compiler:
    """Emits the containers as ChartBuilder calls, in document order: a state, its initial
    transition, its children, then its transitions (the order the asyncio backend uses)."""

    def __init__(self, top: Composite) -> None:
        self.top = top
        self.builder = ChartBuilder("")

    def chart(self, name: str, events: Mapping[str, Mapping[str, Any]] | None = None) -> Chart:
        top = self.top
        for container in self._containers(top):
            if container is not top and len(container.userdata):
                raise ValueError(
                    f"{container.label}: member data lives in the top container's userdata"
                )
            container._check_outcomes()
        self.builder = ChartBuilder(name, data=dict(top.userdata._data), events=events)
        self.builder.zeros(top.zeros)
        for entry in top._entries:
            self._emit(entry, None)
        self.builder.initial(None, self._initial_targets(top))
        return self.builder.build()

    def _containers(self, top: Composite) -> Iterator[Composite]:
        stack = [top]
        while stack:
            container = stack.pop()
            yield container
            stack.extend(e.state for e in container._entries if isinstance(e.state, Composite))

    def _emit(self, entry: Entry, parent: str | None) -> None:
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
            donedata=state.donedata,
            invokes=state.invokes,
            history=("deep" if state.deep else "shallow")
            if isinstance(state, HistoryState)
            else "",
        )
        if isinstance(state, Composite) and state._initial is not None:
            targets, action = state._initial
            self.builder.initial(label, self._resolve_all(state, targets), action)
        if isinstance(state, HistoryState) and state.default is not None:
            self.builder.initial(
                label, self._resolve_all(entry.container, state.default), state.action
            )
        if isinstance(state, Composite):
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

    def _initial_targets(self, container: Composite) -> tuple[str, ...]:
        if container._initial is not None:
            return self._resolve_all(container, container._initial[0])
        first = [e.label for e in container._entries if e.state.kind != "history"][:1]
        if not first:
            raise ValueError("the top container has no states")
        return tuple(first)

    # --- keys and targets

    def _events(self, entry: Entry, transition: Transition) -> tuple[str, ...]:
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

    def _resolve_all(self, scope: Composite, targets: Sequence[str]) -> tuple[str, ...]:
        return tuple(self._resolve(scope, target) for target in targets)

    def _resolve(self, scope: Composite, target: str) -> str:
        container = self.top if target.startswith("/") else scope
        parts = target.strip("/").split("/")
        entry: Entry | None = None
        for number, part in enumerate(parts):
            entry = container._labels.get(part)
            if entry is None:
                where = f"'{scope.label}'" if scope.label is not None else "the top container"
                raise ValueError(f"unknown target {target!r} (from {where})")
            if number < len(parts) - 1:
                if not isinstance(entry.state, Composite):
                    raise ValueError(f"target {target!r}: {part} is not a container")
                container = entry.state
        assert entry is not None
        return entry.label
