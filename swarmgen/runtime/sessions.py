"""Invoked SCXML sessions (W3C `<invoke>`, docs/semantics.md "Invoked sessions"): the child
sessions of one engine, run by the same engine code on the member's own host.

A state's invokes start at the end of the macrostep that entered it (if it is still active),
in document order, and are cancelled when it is exited. A child is an `Engine` of its own chart
and data; everything it schedules goes through the member's host, tagged with the path of
invoke ids from the member's session to it (`Event.to`): the host delivers it to the member's
engine, which hands it down (`route`). Events from a child to its parent (`#_parent`,
`done.invoke.<id>`) carry its invoke id and its session number; once it is cancelled the parent
drops the ones still queued (W3C 6.4.1).
"""

from __future__ import annotations

import itertools
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from swarmgen.runtime.chart import Call, Chart, Context, Invoke, Node, record
from swarmgen.runtime.host import Event, Host

if TYPE_CHECKING:
    from swarmgen.runtime.engine import Engine
    from swarmgen.runtime.sends import Sends

# The values of `<invoke type>` that name an SCXML session: the W3C URI (with or without its
# last slash) and the short form
SCXML_TYPES = frozenset({"http://www.w3.org/TR/scxml/", "http://www.w3.org/TR/scxml", "scxml"})
MAX_DEPTH = 16  # sessions invoked inside each other at run time (a chart that invokes itself)
# The charts invokes built, by invoke (the invoke kept, so its id is not reused): a chart is
# built once and shared by its sessions, as a member's chart is by its engines.
_CHARTS: dict[int, tuple[Invoke, Chart]] = {}


@dataclass
class Child:
    """A running child session: the state and invoke that started it, its engine and host."""

    node: Node
    invoke: Invoke
    engine: Engine
    host: ChildHost


class ChildHost:
    """A child session's host: everything goes to the member's host, tagged for the child."""

    def __init__(self, root: Host, path: tuple[str, ...], serial: int) -> None:
        self.root, self.path, self.serial = root, path, serial
        self.prefix = "invoke." + ".".join(path) + f".{serial}."  # keys no `as` name gives
        self.keys: set[str] = set()

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """An invoked session calls no swarmgen behaviour (the reader refuses `<sg:call>`)."""

    def cancel_call(self, node: Node, activation: int) -> None:
        """Nothing was started, so nothing is cancelled."""

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """A state's time event: a delayed event of the member's host, keyed for the child."""
        timer = Event(event, None, 0, 0.0, "", None, "external", None, None, 0, self.path)
        self.start_delayed(f"timer.{node.id}.{event}", timer, delay_ms)

    def cancel_timer(self, node: Node, event: str) -> None:
        """Drop the state's pending time event."""
        self.cancel_delayed(f"timer.{node.id}.{event}")

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """The member's delayed event, under a key of this child's own."""
        if event.to is None:
            event.to = self.path
        self.keys.add(key)
        self.root.start_delayed(self.prefix + key, event, delay_ms)

    def cancel_delayed(self, key: str) -> None:
        """Drop this child's pending delayed events of `key`."""
        self.root.cancel_delayed(self.prefix + key)

    def cancel_all(self) -> None:
        """The child is cancelled: none of its delayed events arrives."""
        for key in sorted(self.keys):
            self.root.cancel_delayed(self.prefix + key)
        self.keys.clear()

    def send_swarm(self, event: Event) -> None:
        """An invoked session belongs to the member: its swarm events are the member's."""
        self.root.send_swarm(event)

    def deliver(self, event: Event) -> None:
        """The child's external queue is the member's, its events tagged with its path."""
        if event.to is None:
            event.to = self.path
        self.root.deliver(event)


class Sessions:
    """The child sessions of one engine, by invoke id."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.active: dict[str, Child] = {}
        # numbers of the children it starts: made invoke ids and the tags of their events
        # (per engine, so a member's run does not depend on what else ran in the process)
        self.serials = itertools.count(1)
        # numbers of the children cancelled while they ran: what they sent is dropped (a child
        # that finished first keeps its events, done.invoke too: W3C test 236)
        self.cancelled: set[int] = set()
        # what arrived while the engine was in a macrostep (`Engine._one_at_a_time`)
        self.stepping = False
        self.waiting: deque[Event] = deque()

    def start(self, node: Node) -> None:
        """Start the invokes of a state that stayed active to the end of the macrostep."""
        for invoke in node.invokes:
            try:
                self._start(node, invoke)
            except Exception as err:  # W3C 6.4: a failed invoke is error.execution
                self.engine.execution_error(f"invoke in {node.id}", err)

    def _start(self, node: Node, invoke: Invoke) -> None:
        parent = self.engine
        ctx = parent.ctx
        serial = next(self.serials)
        invokeid = invoke.invokeid or f"{node.id}.{serial}"
        if invoke.idlocation is not None:  # written first, as W3C's idlocation
            parent.data[invoke.idlocation] = invokeid
        kind = invoke.type(ctx) if invoke.type is not None else "scxml"
        if kind not in SCXML_TYPES:
            raise ValueError(f"{kind!r} is no invoke type this member can run")
        if len(parent.path) >= MAX_DEPTH:
            raise RecursionError(f"more than {MAX_DEPTH} sessions invoked inside each other")
        args = invoke.args(ctx) if invoke.args is not None else {}
        path = (*parent.path, invokeid)
        host = ChildHost(parent.root_host, path, serial)
        child = type(parent)(
            chart_of(invoke, ctx),
            host,
            parent.member_id,
            parent.clock,
            parent.on_error,
            parent.on_log,
        )
        child.path, child.root_host, child.serial = path, parent.root_host, serial
        child.parent_sessions, child.invokeid = self, invokeid
        for key, value in args.items():  # W3C 6.4: values for the child's data of that name
            if key in child.data:
                child.data[key] = record(value)
        self.active[invokeid] = Child(node, invoke, child, host)
        child.start()

    def cancel(self, node: Node) -> None:
        """The state is exited: its sessions stop, their pending events are dropped."""
        for invokeid, child in list(self.active.items()):
            if child.node is node:
                del self.active[invokeid]
                if child.engine.running:
                    self.cancelled.add(child.engine.serial)
                halt(child)

    def route(self, event: Event, to: tuple[str, ...]) -> None:
        """An event for a session below this one: handed to the child on its path (nothing
        when that child is gone or done)."""
        child = self.active.get(to[len(self.engine.path)])
        if child is not None and child.engine.running:
            child.engine.send(event)

    def current(self, event: Event) -> Child | None:
        """The running invocation an event from a child came from (None: it is stale)."""
        child = self.active.get(event.invokeid or "")
        return child if child is not None and child.engine.serial == event.session else None

    def received(self, event: Event) -> bool:
        """Before the parent processes an external event: one from a cancelled child is
        dropped (False); one from a current child runs its `<finalize>`; every event is
        forwarded to the children that `autoforward`."""
        if event.invokeid is not None:
            if event.session in self.cancelled:
                return False
            child = self.current(event)
            # not on its done.invoke, which the platform sends, not the child (as Qt SCXML)
            if child and child.invoke.finalize and not event.name.startswith("done.invoke."):
                self.engine.run_finalize(child.invoke.finalize, child.node)
        for child in list(self.active.values()):
            if child.invoke.autoforward and child.engine.running:
                copy = Event(event.name, event.data, event.id, event.timestamp, event.sender)
                copy.kind, copy.sendid = event.kind, event.sendid
                copy.invokeid, copy.session, copy.to = event.invokeid, event.session, None
                child.host.deliver(copy)
        return True

    def to_child(self, invokeid: str, event: Event) -> bool:
        """`<send target="#_<invokeid>">`: into that child's queue (False: no such child)."""
        child = self.active.get(invokeid)
        if child is None or not child.engine.running:
            return False
        child.host.deliver(event)
        return True

    def to_parent(self, event: Event, sender: Sends) -> None:
        """`<send target="#_parent">` from the child `sender`, through the member's host."""
        event.invokeid, event.session = sender.invokeid, sender.serial
        event.to = self.engine.path or None
        sender.root_host.deliver(event)

    def done(self, sender: Engine, data: Any) -> None:
        """The child reached a top-level final state: `done.invoke.<id>` with its done data."""
        invokeid = sender.invokeid or ""
        child = self.active.get(invokeid)
        if child is not None:  # its pending delayed events die with it (W3C test 187)
            child.host.cancel_all()
        name = f"done.invoke.{invokeid}"
        done = self.engine.make_event(name, _mapping(data), sender.member_id)
        if data is not None and not isinstance(data, Mapping):
            done.data = data
        self.to_parent(done, sender)


def chart_of(invoke: Invoke, ctx: Context) -> Chart:
    """The invoke's chart, built on its first start."""
    held = _CHARTS.get(id(invoke))
    if held is not None and held[0] is invoke:
        return held[1]
    chart = invoke.chart(ctx)
    _CHARTS[id(invoke)] = (invoke, chart)
    return chart


def halt(child: Child) -> None:
    """Stop a child session and every session below it, dropping their pending events."""
    engine = child.engine
    engine.running = False
    child.host.cancel_all()
    below = engine.sessions
    if below is not None:
        for grandchild in list(below.active.values()):
            halt(grandchild)
        below.active.clear()


def _mapping(data: Any) -> Mapping[str, Any] | None:
    return data if isinstance(data, Mapping) else None
