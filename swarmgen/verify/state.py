"""One member's engine between two macrosteps, as a hashable value, and back.

Between macrosteps the engine's internal queue and its set of behaviours to start are empty
(`Engine._macrostep` drains them), so a member is its configuration, data, history, whether it
runs or finished, and what its host holds: the behaviours running (with how many events each
has emitted) and the pending timers. Activation numbers and the error count are kept to restore
faithfully but are not part of the value: the verifier never delivers a stale outcome, so two
members that differ only in them behave alike (docs/verify.md).

The engine has no snapshot API of its own (its runtime is vendored into every generated
package); `restore` writes the few attributes the algorithm reads, among them the private
`_activation` and `_cfg` (the interned configuration, reset so that the next step interns the
restored one); `check_engine` fails loudly if the engine no longer has them (an assignment
to a renamed attribute would otherwise pass silently).
"""

from __future__ import annotations

import pickle
from dataclasses import field
from typing import Any

from swarmgen.records import dataclass
from swarmgen.runtime.chart import Call, Node
from swarmgen.runtime.engine import Engine, Event

Frozen = bytes | None  # a value of `freeze`


def freeze(value: Any) -> Frozen:
    """A hashable image of member or event data (None stays None): its pickle, which keeps
    the Records' key order (equal data made in another key order is merely not merged) and
    costs a fraction of a walk in Python; `thaw` inverts it."""
    return None if value is None else pickle.dumps(value, pickle.HIGHEST_PROTOCOL)


def thaw(value: Frozen) -> Any:
    """A fresh copy of the data `freeze` made `value` from."""
    return None if value is None else pickle.loads(value)


@dataclass(frozen=True, slots=True)
class EngineState:
    """A member's engine and host between macrosteps (see the module docstring)."""

    config: tuple[str, ...]
    data: Frozen
    history: tuple[tuple[str, tuple[str, ...]], ...]
    running: bool
    finished: bool
    calls: tuple[tuple[str, int], ...]  # (state id, events its behaviour emitted so far)
    timers: tuple[tuple[str, str], ...]  # (state id, timer event)
    # pending `raise e after ...`: (send id key, event, its data), in the order raised
    delayed: tuple[tuple[str, str, Frozen], ...] = ()
    activations: tuple[tuple[str, int], ...] = field(default=(), compare=False, repr=False)
    errors: int = field(default=0, compare=False, repr=False)

    def key(self) -> tuple[Any, ...]:
        """The fields that make the value (activations and errors left out)."""
        return (
            self.config, self.data, self.history, self.running, self.finished, self.calls,
            self.timers, self.delayed,
        )  # fmt: skip


class VerifyHost:
    """The engine's host during one step: records what a macrostep starts, cancels and sends
    instead of running it (the verifier decides when behaviours end and timers fire)."""

    def __init__(self) -> None:
        self.calls: dict[str, int] = {}
        self.timers: dict[str, set[str]] = {}
        self.sent: list[Event] = []
        self.own: list[Event] = []  # `raise e(f = ...)`: to this member's own queue
        self.delayed: list[tuple[str, str, Frozen]] = []  # pending delayed raises
        self.left: set[str] = set()  # states whose behaviour this step cancelled
        self.stopped: set[tuple[str, str]] = set()  # timers this step cancelled

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """A behaviour starts: it runs until the verifier ends it."""
        self.calls[node.id] = 0

    def cancel_call(self, node: Node, activation: int) -> None:
        """Its state was left: the behaviour stops (an outcome of it still queued is stale)."""
        self.calls.pop(node.id, None)
        self.left.add(node.id)

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """A pending timer: it may fire at any later step (delays are not modelled)."""
        self.timers.setdefault(node.id, set()).add(event)

    def cancel_timer(self, node: Node, event: str) -> None:
        """The timer's state was left."""
        self.stopped.add((node.id, event))
        pending = self.timers.get(node.id)
        if pending is not None:
            pending.discard(event)
            if not pending:
                del self.timers[node.id]

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """A pending delayed raise: like a timer, it may arrive at any later step."""
        self.delayed.append((key, event.name, freeze(event.data)))

    def cancel_delayed(self, key: str) -> None:
        """`cancel key`: its pending delayed raises never arrive."""
        self.delayed = [pending for pending in self.delayed if pending[0] != key]

    def send_swarm(self, event: Event) -> None:
        """An event to the swarm: the system puts it in the receivers' inboxes."""
        self.sent.append(event)

    def deliver(self, event: Event) -> None:
        """An event to this member's own queue, processed before its next input."""
        self.own.append(event)


# The engine's private attributes `restore` writes (see the module docstring).
_PRIVATE = ("_activation", "_cfg", "_to_invoke", "_steps", "_bound_hit", "_input")


def check_engine(engine: Engine) -> None:
    """The engine still has every attribute `restore` writes (a bug in swarmgen if not)."""
    missing = [name for name in _PRIVATE if not hasattr(engine, name)]
    if missing:
        raise AssertionError(f"the engine has no {', '.join(missing)}: update verify.state")


def capture(engine: Engine, host: VerifyHost) -> EngineState:
    """The engine and its host as a value."""
    activations = tuple(sorted((n.id, a) for n, a in engine._activation.items()))
    return EngineState(
        config=tuple(sorted(n.id for n in engine.config)),
        data=freeze(engine.data) or b"",
        history=tuple(
            sorted((n.id, tuple(h.id for h in nodes)) for n, nodes in engine.history.items())
        ),
        running=engine.running,
        finished=engine.finished,
        calls=tuple(sorted(host.calls.items())),
        timers=tuple(sorted((s, e) for s, events in host.timers.items() for e in events)),
        delayed=tuple(host.delayed),
        activations=activations,
        errors=engine.error_count,
    )


def restore(engine: Engine, host: VerifyHost, state: EngineState) -> None:
    """Put `state` back into the engine and host (the engine's `host` must be `host`)."""
    nodes = engine.chart.nodes
    data = thaw(state.data)
    engine.data = data
    engine.ctx.data = data
    engine.ctx.event = None
    engine.config = {nodes[i] for i in state.config}
    engine.history = {nodes[i]: tuple(nodes[h] for h in hs) for i, hs in state.history}
    engine.running = state.running
    engine.finished = state.finished
    engine.internal.clear()
    engine._to_invoke.clear()
    engine._activation = {nodes[i]: a for i, a in state.activations}
    engine._cfg = None  # the interned configuration of the engine's previous member
    # the step bound's count restarts with every input from outside, and each step is one
    engine._steps, engine._bound_hit, engine._input = 0, False, None
    engine.error_count = state.errors
    host.calls = dict(state.calls)
    host.timers = {}
    for node_id, event in state.timers:
        host.timers.setdefault(node_id, set()).add(event)
    host.delayed = list(state.delayed)
    host.sent = []
    host.own = []
    host.left = set()
    host.stopped = set()
