"""What the engine and its host exchange: the `Event`, the `Host` protocol and a `NullHost`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

from swarmgen.runtime.chart import Call, Node
from swarmgen.runtime.values import Record

__all__ = ["PROCESSOR", "Event", "Host", "NullHost", "event_fields", "system_variable"]


@dataclass(slots=True)
class Event:
    """The paper's event format: name, data, a unique id, a timestamp and the sender's id."""

    name: str
    data: Record | None = None
    id: int = 0
    timestamp: float = 0.0
    sender: str = ""
    origin: tuple[str, int] | None = None  # (state id, activation) of a behaviour's outcome
    # "external", "internal", "platform", or "raised": external, queued by this member's own
    # `raise e(f = ...)` (the step bound goes on counting through it)
    kind: str = "external"
    sendid: str | None = None  # a delayed raise's send id ("" without `as`): `_event.sendid`
    # Invoked sessions (docs/semantics.md): the invoke id of the child session that sent it
    # (`_event.invokeid`) and that session's number, and the path of invoke ids from the
    # member's own session to the session it is for (None: the member's own session).
    invokeid: str | None = None
    session: int = 0
    to: tuple[str, ...] | None = None


class Host(Protocol):
    """What the engine asks of its host: behaviours, timers, the swarm bus and its own queue."""

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """Start the behaviour of a state just entered (outcomes carry `activation`)."""

    def cancel_call(self, node: Node, activation: int) -> None:
        """Cancel the behaviour of a state being exited."""

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """Deliver `event` to the engine after `delay_ms`, unless cancelled first."""

    def cancel_timer(self, node: Node, event: str) -> None:
        """Cancel a timer of a state being exited."""

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """Deliver `event` as `deliver` does, after `delay_ms`, unless `cancel_delayed(key)`
        comes first (`raise e after N ms as key`; several may share a key)."""

    def cancel_delayed(self, key: str) -> None:
        """Drop every pending delayed event of `key` (none pending: nothing happens)."""

    def send_swarm(self, event: Event) -> None:
        """Publish an event to the swarm."""

    def deliver(self, event: Event) -> None:
        """Queue an event to this member behind the external events already waiting."""


class NullHost:
    """A host that runs nothing: outcomes and timer events are submitted by hand (tests, replay)."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, str, dict[str, Any]]] = []
        self.sent: list[Event] = []
        self.delivered: list[Event] = []  # events to itself (a `raise` with data)
        self.timers: dict[str, int] = {}
        self.delayed: list[tuple[str, Event, float]] = []  # pending (key, event, delay in ms)

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """Record the call (state id, behaviour, arguments)."""
        self.calls.append((node.id, call.behaviour, args))

    def cancel_call(self, node: Node, activation: int) -> None:
        """Nothing runs, so nothing is cancelled."""

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """Record the pending timer."""
        self.timers[event] = delay_ms

    def cancel_timer(self, node: Node, event: str) -> None:
        """Forget the pending timer."""
        self.timers.pop(event, None)

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """Record the pending delayed event (submitted by hand, as timers are)."""
        self.delayed.append((key, event, delay_ms))

    def cancel_delayed(self, key: str) -> None:
        """Forget the pending delayed events of `key`."""
        self.delayed = [pending for pending in self.delayed if pending[0] != key]

    def send_swarm(self, event: Event) -> None:
        """Record the swarm event."""
        self.sent.append(event)

    def deliver(self, event: Event) -> None:
        """Record the event to itself."""
        self.delivered.append(event)


PROCESSOR = "http://www.w3.org/TR/scxml/#SCXMLEventProcessor"  # W3C's SCXML event I/O processor
_TYPES = {"internal": "internal", "platform": "platform"}  # the rest is "external"


def event_fields(event: Event) -> Record:
    """`_event`'s W3C fields, with "" for a field W3C leaves blank and `{}` for no data: what
    the SCXML document's `$sg.meta` makes of Qt SCXML's (docs/semantics.md). An event this
    member sent itself (a raise with data, a delayed raise, a time event) has the origin
    `#_internal` and the SCXML processor's type; only delayed raises with `as` and time
    events (whose send id is their name) have a send id."""
    name = event.name
    timer = name.startswith("after.")
    sendid = name if timer else (event.sendid or "")
    sent = timer or event.sendid is not None or event.kind == "raised"
    invokeid = event.invokeid or ""
    # an event its parent session sent to an invoked session: addressed to it, sent by no one
    # in it (its own sends carry a send id, its raises are "raised")
    parent = event.to is not None and not invokeid and not sent
    data: Any = event.data  # a Record, or any value a final state's done(expr) gave
    return Record(
        name=name,
        type=_TYPES.get(event.kind, "external"),
        sendid=sendid,
        origin=f"#_{invokeid}" if invokeid else "#_parent" if parent else _origin(sent),
        origintype=PROCESSOR if sent or invokeid or parent else "",
        invokeid=invokeid,
        data=Record() if data is None or data == "" else data,  # as `$sg.meta` gives it
    )


def _origin(sent: bool) -> str:
    return "#_internal" if sent else ""


def system_variable(name: str, event: Event | None, session_id: str, chart_name: str) -> Any:
    """A system variable of the session `session_id` of the chart `chart_name` (W3C 5.10):
    `_sessionid`, `_name`, `_ioprocessors`, or `_event`'s fields (`event_fields`)."""
    if name == "_sessionid":
        return session_id
    if name == "_name":
        return chart_name
    if name == "_ioprocessors":
        where = Record(location=f"#_scxml_{session_id}")
        return Record({PROCESSOR: where, "scxml": where})
    if event is None:
        raise NameError("_event is not bound before the first event")
    return event_fields(event)
