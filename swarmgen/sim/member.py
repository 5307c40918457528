"""One simulated member: the runtime's `Member` with the batch's discrete-time host services."""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Mapping
from typing import Any, Protocol

from swarmgen.runtime.chart import Call, Chart, Node
from swarmgen.runtime.engine import Event
from swarmgen.runtime.member import Behaviour, InMemoryBus, Member
from swarmgen.sim.library import Activation
from swarmgen.sim.scenario import Scenario


class Host(Protocol):
    """What a member needs of its batch (`swarmgen.sim.batch.Batch`): the runs' clocks and queues,
    timed callbacks and the behaviours' start and end. A protocol, so that the batch imports the
    member and not the other way round."""

    t: list[int]
    pending: list[deque[tuple[SimMember, Event]]]
    scenario: Scenario

    def at(self, run: int, tick: int, then: Callable[[], None]) -> None:
        """Schedule `then` at a tick of a run."""

    def end(self, act: Activation) -> None:
        """End an activation (idempotent): forget it and stop its implementation."""

    def start_call(
        self, member: SimMember, node: Node, call: Call, args: dict[str, Any], activation: int
    ) -> None:
        """Start a state's behaviour in the simulated library."""


class _NoLibrary:
    def get(self, name: str) -> Behaviour | None:
        return None


class SimMember(Member):
    """A runtime `Member` whose host services are the batch's discrete-time ones."""

    def __init__(
        self,
        batch: Host,
        run: int,
        g: int,
        chart: Chart,
        member_type: str,
        index: int,
        bus: InMemoryBus,
        scopes: Mapping[str, str],
        chart_name: str,
    ) -> None:
        self.batch = batch
        self.rank = run  # the run (repetition) of the batch it belongs to
        self.g = g
        self.index = index
        self.chart_name = chart_name
        self.live: dict[str, Activation] = {}  # state id -> its running behaviour
        self.timer_tokens: dict[str, int] = {}
        self.delayed_tokens: dict[str, set[int]] = {}  # pending delayed raises by send id
        self._delayed_count = 0
        super().__init__(
            chart, member_type, f"{member_type}-{index}", _NoLibrary(), bus, event_scopes=scopes
        )
        self.engine.clock = lambda: float(batch.t[run])

    def deliver(self, event: Event) -> None:
        """Queue an event to this member for the batch's next delivery."""
        self.batch.pending[self.rank].append((self, event))

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """Start a state's behaviour through the batch."""
        self.batch.start_call(self, node, call, args, activation)

    def cancel_call(self, node: Node, activation: int) -> None:
        """End the state's behaviour if this activation still runs."""
        act = self.live.get(node.id)
        if act is not None and act.number == activation:
            self.batch.end(act)

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """Deliver `event` after `delay_ms` (in ticks, at least one) unless cancelled."""
        token = self.timer_tokens.get(event, 0) + 1
        self.timer_tokens[event] = token
        ticks = max(1, math.ceil(delay_ms / self.batch.scenario.timing["tick_ms"]))

        def fire() -> None:
            if self.timer_tokens.get(event) == token:
                del self.timer_tokens[event]
                self.deliver(self.engine.make_event(event, None, self.member_id))

        self.batch.at(self.rank, self.batch.t[self.rank] + ticks, fire)

    def cancel_timer(self, node: Node, event: str) -> None:
        """Cancel a pending timer."""
        self.timer_tokens.pop(event, None)

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """Deliver `event` after `delay_ms` (in ticks, at least one) unless cancelled by `key`."""
        self._delayed_count += 1
        token = self._delayed_count
        self.delayed_tokens.setdefault(key, set()).add(token)
        ticks = max(1, math.ceil(delay_ms / self.batch.scenario.timing["tick_ms"]))

        def fire() -> None:
            pending = self.delayed_tokens.get(key)
            if pending is not None and token in pending:
                pending.discard(token)
                if not pending:
                    del self.delayed_tokens[key]
                self.deliver(event)

        self.batch.at(self.rank, self.batch.t[self.rank] + ticks, fire)

    def cancel_delayed(self, key: str) -> None:
        """Cancel the pending delayed events of `key`."""
        self.delayed_tokens.pop(key, None)
