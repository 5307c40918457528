"""A member type's engine as the verifier runs it: one engine and host per type, restored into
the member value at hand, given one input, captured again (`MemberKind.run`).

Each member type runs the module the asyncio backend generates for it (its chart over
`swarmgen.runtime`), so a verifier step is a macrostep of the very engine `replay` and the
generated packages run. An input is an event from the member's queue: a station or swarm event,
a fired timer or delayed raise, or a behaviour's end (`outcome`, its `done.invoke` event). After
its input a member also processes the events it queued to itself (`raise e(f = ...)`), as
`swarmgen replay` does before its next input (docs/verify.md, "The transition system").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import field
from typing import Any

from swarmgen.records import dataclass
from swarmgen.runtime.chart import Action, Chart, Context
from swarmgen.runtime.engine import FINALIZE_PREFIX, Engine, Event
from swarmgen.verify.state import (
    EngineState,
    Frozen,
    VerifyHost,
    capture,
    check_engine,
    freeze,
    restore,
    thaw,
)

MAX_OWN_EVENTS = 100_000  # events a member may queue to itself in one step (the engine's step
# bound stops a loop through them long before; this only keeps a bug from spinning)


@dataclass(frozen=True, slots=True)
class Outcome:
    """One way a behaviour can end: its outcome and the outputs it gives (frozen, or None for
    no outputs: every output is then its type's zero)."""

    name: str
    outputs: Frozen = None


@dataclass(frozen=True, slots=True)
class Ran:
    """What one input did to a member's engine: the engine after, the events it sent (name,
    data, scope), the input as a `swarmgen replay` step, the states it entered, the states
    whose behaviour it cancelled (their queued outcomes are stale) and the timers it
    cancelled."""

    after: EngineState
    sent: tuple[tuple[str, Frozen, str], ...]
    replay: Mapping[str, Any]
    entered: frozenset[str]
    left: frozenset[str] = frozenset()
    stopped: frozenset[tuple[str, str]] = frozenset()


@dataclass
class MemberKind:
    """A member type: its chart (from the generated module), one engine and host that every
    member of the type is restored into, its event scopes, its behaviours' `emits` and the
    ways each behaviour can end (outcomes with outputs from finite domains: `domains`)."""

    name: str
    chart: Chart
    scopes: Mapping[str, str]
    emits: Mapping[str, tuple[str, ...]]  # behaviour -> events it emits
    engine: Engine
    host: VerifyHost
    initial: EngineState
    entered: set[str]  # states entered since the last input (`watch_entries`)
    started: frozenset[str] = frozenset()  # states starting the machine entered
    endings: dict[str, tuple[Outcome, ...]] = field(default_factory=dict)  # state id -> ends

    def run(self, before: EngineState, kind: str, name: str, data: Frozen, state_id: str) -> Ran:
        """One input to a member in `before`: `deliver` an event (with `data`), `outcome` the
        end of the behaviour of `state_id` with the outcome `name` and outputs `data`."""
        engine, host = self.engine, self.host
        restore(engine, host, before)
        replayed: dict[str, Any]
        if kind == "outcome":
            node = self.chart.nodes[state_id]
            behaviour = node.call.behaviour if node.call is not None else ""
            host.calls.pop(state_id, None)  # the behaviour ended
            origin = (state_id, engine.activation(state_id))
            outputs = thaw(data) or {}
            event = engine.make_event(
                f"{FINALIZE_PREFIX}{state_id}.{name}", outputs, "verify", origin=origin
            )
            replayed = {"complete": behaviour, "outcome": name, "outputs": outputs}
            replayed["state"] = state_id
        else:
            value = thaw(data)
            event = Event(name, value, 0, 0.0, "verify")
            replayed = {"event": name} if value is None else {"event": name, "data": value}
        self.entered.clear()
        engine.send(event)
        own_events(engine, host)
        sent = tuple(
            (
                e.name,
                freeze(e.data) if e.data is not None else None,
                self.scopes.get(e.name, "swarm"),
            )
            for e in host.sent
        )
        after = capture(engine, host)
        left, stopped = frozenset(host.left), frozenset(host.stopped)
        return Ran(after, sent, replayed, frozenset(self.entered), left, stopped)


def make_kind(
    name: str, chart: Chart, scopes: Mapping[str, str], emits: Mapping[str, tuple[str, ...]]
) -> MemberKind:
    """A member type's engine, started once: its initial state. The chart must be the
    verifier's own (`watch_entries` changes it)."""
    entered = watch_entries(chart)
    host = VerifyHost()
    engine = Engine(chart, host, name)
    check_engine(engine)
    engine.clock = lambda: 0.0  # timestamps mean nothing to the search; keep steps alike
    engine.start()
    own_events(engine, host)
    initial = capture(engine, host)
    endings = {
        node.id: tuple(Outcome(o) for o in node.call.outcomes or ("succeeded",))
        for node in chart.nodes.values()
        if node.call is not None
    }
    return MemberKind(
        name, chart, scopes, emits, engine, host, initial, entered, frozenset(entered), endings
    )


def watch_entries(chart: Chart) -> set[str]:
    """Make every state's entry record its id in the returned set: a state entered and left
    in one macrostep (a region's final state whose completion leaves the parallel state) is
    never in a configuration between steps, yet is reached. Its entry actions run as before."""
    entered: set[str] = set()
    for node in chart.nodes.values():
        node.onentry = _recording(node.id, node.onentry, entered)
    return entered


def _recording(node_id: str, original: Action | None, entered: set[str]) -> Action:
    def entry(ctx: Context) -> None:
        entered.add(node_id)
        if original is not None:
            original(ctx)

    return entry


def own_events(engine: Engine, host: VerifyHost) -> None:
    """Process the events the member queued to itself, as its queue would before any input."""
    for _ in range(MAX_OWN_EVENTS):
        if not host.own or not engine.running:
            break
        engine.send(host.own.pop(0))
    host.own.clear()
