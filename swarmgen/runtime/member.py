"""One swarm member on asyncio: an event queue, the engine, behaviours as cancellable tasks,
timers, and a swarm bus. Standard library only.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from swarmgen.runtime.chart import Call, Chart, Node, record
from swarmgen.runtime.engine import FINALIZE_PREFIX, Engine, Event


@dataclass(frozen=True, slots=True)
class Outcome:
    """How a behaviour ended: the outcome name and its outputs (written back as member data)."""

    name: str
    outputs: Mapping[str, Any] = field(default_factory=dict)
    reported: bool = False  # the outcome event was already delivered (replay submits it in order)


@dataclass(slots=True)
class Request:
    """Everything a behaviour implementation gets when its state is entered."""

    member_type: str
    member_id: str
    state: str
    behaviour: str
    args: dict[str, Any]
    emit: Callable[[str, Mapping[str, Any] | None, str], None]  # (event, data, scope)
    data: Mapping[str, Any]  # the member's data (read only by convention)


Behaviour = Callable[[Request], Awaitable[Outcome]]


class Library(Protocol):
    """The platform's Abstraction Library: a behaviour implementation per behaviour name."""

    def get(self, name: str) -> Behaviour | None: ...


class Bus(Protocol):
    def attach(self, member: Member) -> None: ...
    def publish(self, event: Event, scope: str) -> None: ...


class Tracer(Protocol):
    def step(self, member: Member, event: Event | None) -> None: ...


class InMemoryBus:
    """Delivers swarm events to every attached member, the sender included (as a ROS topic
    subscriber hears its own node's messages); local events only to the sender."""

    def __init__(self) -> None:
        self.members: dict[str, Member] = {}
        self.log: list[Event] = []

    def attach(self, member: Member) -> None:
        self.members[member.member_id] = member

    def publish(self, event: Event, scope: str) -> None:
        self.log.append(event)
        if scope == "local":
            target = self.members.get(event.sender)
            if target is not None:
                target.deliver(event)
            return
        for member in self.members.values():
            member.deliver(event)

    def broadcast(
        self, name: str, data: Mapping[str, Any] | None = None, sender: str = "station"
    ) -> None:
        """An event from the ground station, to every member."""
        for member in self.members.values():
            member.deliver(Event(name, record(data) if data is not None else None, sender=sender))


class Member:
    """A member's behaviour running on an asyncio event loop."""

    def __init__(
        self,
        chart: Chart,
        member_type: str,
        member_id: str,
        library: Library,
        bus: Bus,
        *,
        event_scopes: Mapping[str, str] | None = None,
        tracer: Tracer | None = None,
    ) -> None:
        self.member_type = member_type
        self.member_id = member_id
        self.library = library
        self.bus = bus
        self.tracer = tracer
        self.event_scopes = dict(event_scopes or {})
        self.engine = Engine(chart, self, member_id)
        self.queue: asyncio.Queue[Event | None] = asyncio.Queue()
        self.tasks: dict[Node, asyncio.Task[None]] = {}
        self.timers: dict[str, asyncio.TimerHandle] = {}
        self.errors: list[str] = []
        self.engine.on_error = lambda where, err: self.errors.append(f"{where}: {err!r}")
        bus.attach(self)

    # --- lifecycle

    async def run(self) -> None:
        """Start the machine and process events until it finishes or `stop()` is called."""
        self.engine.start()
        self._trace(None)
        try:
            while self.engine.running:
                event = await self.queue.get()
                while event is not None:  # drain what is queued without yielding per event
                    self.engine.send(event)
                    self._trace(event)
                    if not self.engine.running or self.queue.empty():
                        break
                    event = self.queue.get_nowait()
                if event is None:
                    break
        finally:
            await self._cancel_all()

    def stop(self) -> None:
        self.queue.put_nowait(None)

    def deliver(self, event: Event) -> None:
        self.queue.put_nowait(event)

    @property
    def active(self) -> list[str]:
        return self.engine.active()

    def _trace(self, event: Event | None) -> None:
        if self.tracer is not None:
            self.tracer.step(self, event)

    # --- engine host

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        behaviour = self.library.get(call.behaviour)
        if behaviour is None:
            self.errors.append(f"no implementation of behaviour {call.behaviour}")
            return
        request = Request(
            self.member_type,
            self.member_id,
            node.id,
            call.behaviour,
            args,
            self._emit,
            self.engine.data,
        )
        self.tasks[node] = asyncio.get_running_loop().create_task(
            self._run_behaviour(node, behaviour, request, activation),
            name=f"{self.member_id}:{node.id}",
        )

    async def _run_behaviour(
        self, node: Node, behaviour: Behaviour, request: Request, activation: int
    ) -> None:
        try:
            outcome = await behaviour(request)
        except asyncio.CancelledError:
            raise
        except Exception as err:  # a failing behaviour ends with the outcome `aborted`
            self.errors.append(f"behaviour {request.behaviour} in {node.id} failed: {err!r}")
            outcome = Outcome("aborted")
        if outcome.reported:
            return
        event = self.engine.make_event(
            f"{FINALIZE_PREFIX}{node.id}.{outcome.name}",
            dict(outcome.outputs),
            self.member_id,
            origin=(node.id, activation),
        )
        self.deliver(event)

    def cancel_call(self, node: Node, activation: int) -> None:
        task = self.tasks.pop(node, None)
        if task is not None and not task.done():
            task.cancel()  # preemption: the behaviour's own `finally` blocks do the cleanup

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        loop = asyncio.get_running_loop()
        self.timers[event] = loop.call_later(
            delay_ms / 1000,
            lambda: self.deliver(self.engine.make_event(event, None, self.member_id)),
        )

    def cancel_timer(self, node: Node, event: str) -> None:
        handle = self.timers.pop(event, None)
        if handle is not None:
            handle.cancel()

    def send_swarm(self, event: Event) -> None:
        self.bus.publish(event, self.event_scopes.get(event.name, "swarm"))

    def _emit(self, name: str, data: Mapping[str, Any] | None, scope: str = "swarm") -> None:
        """Events a behaviour sends (TargetMonitoring's targetFound, ...)."""
        self.bus.publish(self.engine.make_event(name, data, self.member_id), scope)

    async def _cancel_all(self) -> None:
        for handle in self.timers.values():
            handle.cancel()
        self.timers.clear()
        tasks = [t for t in self.tasks.values() if not t.done()]
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self.tasks.clear()
