"""One swarm member on asyncio: an event queue, the engine, behaviours as cancellable tasks,
timers, and a swarm bus. Standard library only.

Behaviours are the platform's code, so the member holds them to the library contract
(docs/runtime.md, "Behaviours under faults"): a behaviour that raises (KeyboardInterrupt and
SystemExit included), returns something other than an `Outcome`, an undeclared outcome, unknown
outputs or outputs of the wrong type ends with the outcome `aborted`, and the member reports a
`Fault`; one that ignores its cancellation is abandoned after a grace period.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable, Collection, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from swarmgen.runtime.chart import Call, Chart, Node
from swarmgen.runtime.engine import FINALIZE_PREFIX, Engine, Event
from swarmgen.runtime.values import record

CANCEL_GRACE = 1.0  # seconds a cancelled behaviour may take to end before it is abandoned
DRAIN_BATCH = 256  # events processed between two yields to the event loop
MAX_KEPT_ERRORS = 100  # per member: a behaviour failing in a retry loop must not fill memory
# What a failing behaviour may raise: KeyboardInterrupt and SystemExit too, since raised by a
# behaviour they would otherwise leave the event loop and end every member of the process.
BEHAVIOUR_FAILURES = (Exception, KeyboardInterrupt, SystemExit)


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

    def get(self, name: str) -> Behaviour | None:
        """The behaviour implementing `name` (None: the library has none)."""


class Bus(Protocol):
    """How members exchange swarm events."""

    def attach(self, member: Member) -> None:
        """Deliver the swarm's events to `member` from now on."""

    def publish(self, event: Event, scope: str) -> None:
        """Send `event` to the members `scope` names ("swarm" or "local")."""


class Tracer(Protocol):
    """Sees every step of a member."""

    def step(self, member: Member, event: Event | None) -> None:
        """After the member started (`event` None) or processed `event`."""


@dataclass(frozen=True, slots=True)
class Fault:
    """A behaviour that broke the library contract.

    `kind`: `failed` (it ended with `aborted` instead), `abandoned` (it did not end within the
    grace period after its cancellation), `blocked` (it kept the event loop busy), `overran`
    (the process ended at its hard deadline while it still blocked the loop)."""

    kind: str
    behaviour: str
    state: str
    error: str


class InMemoryBus:
    """Delivers swarm events to every attached member, the sender included (as a ROS topic
    subscriber hears its own node's messages); local events only to the sender."""

    def __init__(self) -> None:
        self.members: dict[str, Member] = {}
        self.log: list[Event] = []

    def attach(self, member: Member) -> None:
        """Deliver the swarm's events to `member` from now on."""
        self.members[member.member_id] = member

    def publish(self, event: Event, scope: str) -> None:
        """Log `event` and deliver it by its scope."""
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
    """A member's behaviour running on an asyncio event loop.

    `outputs`: the declared outputs of each behaviour (a behaviour returning another name is
    failing; without it only the outputs written to member data are known, and other names are
    not checked). `on_fault` hears every `Fault` as it is found; `grace` is how long a cancelled
    behaviour may take to end."""

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
        outputs: Mapping[str, Collection[str]] | None = None,
        on_fault: Callable[[Member, Fault], None] | None = None,
        grace: float = CANCEL_GRACE,
    ) -> None:
        self.member_type = member_type
        self.member_id = member_id
        self.library = library
        self.bus = bus
        self.tracer = tracer
        self.event_scopes = dict(event_scopes or {})
        self.declared_outputs = {k: frozenset(v) for k, v in (outputs or {}).items()}
        self.on_fault = on_fault
        self.grace = grace
        self.engine = Engine(chart, self, member_id)
        self.queue: asyncio.Queue[Event | None] = asyncio.Queue()
        self.tasks: dict[Node, asyncio.Task[None]] = {}
        # Behaviours started in the events being drained whose task is not made yet (see
        # `_make_tasks`): state -> (call, behaviour, request, activation).
        self._starting: dict[Node, tuple[Call, Behaviour, Request, int]] = {}
        self.timers: dict[str, asyncio.TimerHandle] = {}
        # pending `raise e after ...` by send id (several may share one)
        self.delayed: dict[str, list[asyncio.TimerHandle]] = {}
        self.errors: list[str] = []
        self.faults: list[Fault] = []
        self.error_total = 0  # errors found, including those past MAX_KEPT_ERRORS
        # cancelled, not ended yet: (state, end of its grace period, when it was cancelled)
        self.cancelling: dict[asyncio.Task[None], tuple[Node, float, str]] = {}
        self.abandoned: dict[asyncio.Task[None], Node] = {}  # never awaited again
        self._sweep: asyncio.TimerHandle | None = None
        self.engine.on_error = lambda where, err: self.add_error(f"{where}: {err!r}")
        bus.attach(self)

    # --- lifecycle

    async def run(self) -> None:
        """Start the machine and process events until it finishes or `stop()` is called."""
        self.engine.start()
        self._trace(None)
        try:
            while self.engine.running:
                self._make_tasks()
                event = await self.queue.get()
                drained = 0
                while event is not None:  # drain what is queued without yielding per event
                    self.engine.send(event)
                    self._trace(event)
                    drained += 1
                    if not self.engine.running or self.queue.empty():
                        break
                    if drained % DRAIN_BATCH == 0:
                        # a queue that never empties (a member that answers its own swarm
                        # events) must not starve timers, behaviours and --duration
                        self._make_tasks()
                        await asyncio.sleep(0)
                    event = self.queue.get_nowait()
                if event is None:
                    break
        finally:
            self._make_tasks()
            await self._cancel_all()

    def stop(self) -> None:
        """End `run()` after the events already queued."""
        self.queue.put_nowait(None)

    def deliver(self, event: Event) -> None:
        """Queue an event for the engine."""
        if self._starting:  # the put may wake a waiting task: see `_make_tasks`
            self._make_tasks()
        self.queue.put_nowait(event)

    @property
    def active(self) -> list[str]:
        """Ids of the active states, sorted."""
        return self.engine.active()

    @property
    def clean(self) -> bool:
        """No engine error and no faulty behaviour so far."""
        return self.error_total == 0

    def _trace(self, event: Event | None) -> None:
        if self.tracer is not None:
            self._make_tasks()  # the tracer may look at the tasks, or schedule callbacks
            self.tracer.step(self, event)

    def add_error(self, text: str) -> None:
        """Count an error and keep its text (up to MAX_KEPT_ERRORS)."""
        self.error_total += 1
        if len(self.errors) < MAX_KEPT_ERRORS:
            self.errors.append(text)
        elif len(self.errors) == MAX_KEPT_ERRORS:
            self.errors.append("(further errors are counted, not kept)")

    def report(self, fault: Fault) -> None:
        """Record a fault and tell `on_fault` (the command line's watchdog reports too)."""
        if len(self.faults) < MAX_KEPT_ERRORS:
            self.faults.append(fault)
        self.add_error(f"behaviour {fault.behaviour} in {fault.state} {fault.kind}: {fault.error}")
        if self.on_fault is not None:
            self.on_fault(self, fault)

    def behaviour_of(self, task: asyncio.Task[Any] | None) -> Node | None:
        """The state whose behaviour `task` runs (also once cancelled or abandoned); read by
        the watchdog thread while the loop is stuck, hence the copies."""
        if task is None:
            return None
        for node, running in list(self.tasks.items()):
            if running is task:
                return node
        for cancelled, (node, _, _) in list(self.cancelling.items()):
            if cancelled is task:
                return node
        return self.abandoned.get(task)

    # --- engine host

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        """Start a state's behaviour as a task; its outcome comes back as an event."""
        try:
            behaviour = self.library.get(call.behaviour)
        except BEHAVIOUR_FAILURES as err:
            self._fail_at_start(node, call, activation, f"Library.get raised {err!r}")
            return
        if behaviour is None or not callable(behaviour):
            found = (
                "no implementation" if behaviour is None else f"not callable: {_short(behaviour)}"
            )
            self._fail_at_start(node, call, activation, found)
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
        if node in self._starting:
            self._make_tasks()
        self._starting[node] = (call, behaviour, request, activation)

    def _make_tasks(self) -> None:
        """Make the tasks of the behaviours started since the last call, in start order.

        A task made during a drain only runs once the member yields to the event loop, and a
        task cancelled before its first step runs nothing of its coroutine. So the task is
        made late, when the member is about to yield or to do anything that can put a callback
        on the loop (another task's wake-up: a cancellation, a publication, a tracer, a failed
        start), and a behaviour whose state is left before that is never made a task at all
        (most of them, when events arrive back to back). The loop then runs exactly the steps,
        in exactly the order, it would have run had every task been made at its start."""
        if not self._starting:
            return
        starting, self._starting = self._starting, {}
        loop = asyncio.get_running_loop()
        for node, (call, behaviour, request, activation) in starting.items():
            self.tasks[node] = loop.create_task(
                self._run_behaviour(node, call, behaviour, request, activation),
                name=f"{self.member_id}:{node.id}",
            )

    def _fail_at_start(self, node: Node, call: Call, activation: int, error: str) -> None:
        self._make_tasks()
        self.report(Fault("failed", call.behaviour, node.id, error))
        # on the next turn of the loop, not in this macrostep's drain: a state that re-enters
        # itself on `aborted` then cycles without keeping the loop from other work
        event = self._outcome_event(node, activation, Outcome("aborted"))
        asyncio.get_running_loop().call_soon(self.deliver, event)

    async def _run_behaviour(
        self, node: Node, call: Call, behaviour: Behaviour, request: Request, activation: int
    ) -> None:
        result: Any = None
        try:
            result = await behaviour(request)
        except asyncio.CancelledError:
            if _cancelled():
                raise
            problem: str | None = "raised CancelledError without being cancelled"
        except BEHAVIOUR_FAILURES as err:
            problem = f"raised {err!r}"
        else:
            if isinstance(result, Outcome) and result.reported:
                return
            problem = None if _cancelled() else self._violation(call, result)
        if problem is not None:
            self.report(Fault("failed", request.behaviour, node.id, problem))
            result = Outcome("aborted")
        if not _cancelled():  # after a cancellation the outcome is stale anyway
            self.deliver(self._outcome_event(node, activation, result))

    def _outcome_event(self, node: Node, activation: int, outcome: Outcome) -> Event:
        return self.engine.make_event(
            f"{FINALIZE_PREFIX}{node.id}.{outcome.name}",
            dict(outcome.outputs),
            self.member_id,
            origin=(node.id, activation),
        )

    def _violation(self, call: Call, result: Any) -> str | None:
        """What is wrong with a behaviour's result (None: it keeps the contract)."""
        if not isinstance(result, Outcome):
            return f"returned {_short(result)}, not an Outcome"
        if not isinstance(result.name, str) or not result.name:
            return f"returned the outcome name {_short(result.name)}"
        if call.outcomes and result.name not in call.outcomes:
            return f"returned the undeclared outcome {_short(result.name)}"
        outputs = result.outputs
        if not isinstance(outputs, Mapping):
            return f"returned outputs {_short(outputs)}, not a mapping"
        known = self.declared_outputs.get(call.behaviour)
        unknown = [
            k for k in outputs if not isinstance(k, str) or (known is not None and k not in known)
        ]
        if unknown:
            return f"returned unknown outputs {', '.join(map(_short, unknown))}"
        for output, key in call.results:
            value = outputs.get(output)
            if not _fits(value, self.engine.chart.data.get(key)):
                return f"returned {_short(value)} for the output {output}"
        return None

    def cancel_call(self, node: Node, activation: int) -> None:
        """Cancel a state's behaviour; it gets a grace period to end."""
        if self._starting.pop(node, None) is not None:
            return  # its task is not made: cancelled before its first step, it runs nothing
        task = self.tasks.pop(node, None)
        if task is not None and not task.done():
            self._make_tasks()  # the cancellation schedules the task's wake-up
            self._cancel(task, node, "on preemption")
            if self._sweep is None:  # one timer per member, not one per cancellation
                self._sweep = asyncio.get_running_loop().call_later(self.grace, self._sweep_now)

    def _sweep_now(self) -> None:
        """Forget the cancelled behaviours that ended; abandon those past their grace."""
        self._sweep = None
        now = time.monotonic()
        for task, (_, deadline, _) in list(self.cancelling.items()):
            if task.done():
                del self.cancelling[task]
            elif deadline <= now:
                self._check_cancelled(task)
        if self.cancelling:
            delay = min(d for _, d, _ in self.cancelling.values()) - now
            loop = asyncio.get_running_loop()
            self._sweep = loop.call_later(max(delay, 0.01), self._sweep_now)

    def _cancel(self, task: asyncio.Task[None], node: Node, when: str) -> None:
        task.cancel()  # preemption: the behaviour's own `finally` blocks do the cleanup
        self.cancelling[task] = (node, time.monotonic() + self.grace, when)

    def _check_cancelled(self, task: asyncio.Task[None]) -> None:
        """Past its grace period, a cancelled behaviour still running is abandoned: reported,
        never awaited again, and what it emits from then on is dropped."""
        node, _, when = self.cancelling.pop(task, (None, 0.0, ""))
        if node is None or task.done():
            return
        self.abandoned[task] = node
        behaviour = node.call.behaviour if node.call is not None else "?"
        error = f"still running {self.grace:g} s after its cancellation {when}"
        self.report(Fault("abandoned", behaviour, node.id, error))

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        """Deliver `event` after `delay_ms`."""
        loop = asyncio.get_running_loop()
        self.timers[event] = loop.call_later(
            delay_ms / 1000,
            lambda: self.deliver(self.engine.make_event(event, None, self.member_id)),
        )

    def cancel_timer(self, node: Node, event: str) -> None:
        """Cancel the timer of `event`."""
        handle = self.timers.pop(event, None)
        if handle is not None:
            handle.cancel()

    def start_delayed(self, key: str, event: Event, delay_ms: float) -> None:
        """Deliver `event` to this member after `delay_ms`, unless cancelled by `key`."""
        handles = self.delayed.setdefault(key, [])

        def fire() -> None:
            pending = self.delayed.get(key)
            if pending is not None and handle in pending:
                pending.remove(handle)
                if not pending:
                    del self.delayed[key]
            self.deliver(event)

        handle = asyncio.get_running_loop().call_later(delay_ms / 1000, fire)
        handles.append(handle)

    def cancel_delayed(self, key: str) -> None:
        """Cancel the pending delayed events of `key`."""
        for handle in self.delayed.pop(key, ()):
            handle.cancel()

    def send_swarm(self, event: Event) -> None:
        """Publish `event` on the bus, in its declared scope."""
        self._make_tasks()  # the bus may wake other members
        self.bus.publish(event, self.event_scopes.get(event.name, "swarm"))

    def _emit(self, name: str, data: Mapping[str, Any] | None, scope: str = "swarm") -> None:
        """Events a behaviour sends (TargetMonitoring's targetFound, ...); not those of an
        abandoned behaviour (its state was left long ago)."""
        if self.abandoned and asyncio.current_task() in self.abandoned:
            return
        self.bus.publish(self.engine.make_event(name, data, self.member_id), scope)

    async def _cancel_all(self) -> None:
        """Cancel the timers and behaviours, and wait for the cancelled behaviours until their
        grace period ends: one that ignores its cancellation is abandoned (the process ends
        without it)."""
        for handle in self.timers.values():
            handle.cancel()
        self.timers.clear()
        for handles in self.delayed.values():
            for handle in handles:
                handle.cancel()
        self.delayed.clear()
        for node, task in self.tasks.items():
            if not task.done():
                self._cancel(task, node, "when the member stopped")
        self.tasks.clear()
        if self.cancelling:
            until = max(deadline for _, deadline, _ in self.cancelling.values())
            timeout = max(0.0, until - time.monotonic())
            await asyncio.wait(list(self.cancelling), timeout=timeout)
        for task in list(self.cancelling):
            self._check_cancelled(task)
        if self._sweep is not None:
            self._sweep.cancel()
            self._sweep = None


def _cancelled() -> bool:
    """The current behaviour task was cancelled (a swallowed cancellation still counts)."""
    task = asyncio.current_task()
    return task is not None and task.cancelling() > 0


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _fits(value: Any, template: Any) -> bool:
    """An output value fits the member datum it is written to (whose initial value has the
    declared type: docs/semantics.md, the value rule). None means "not given" (the zero)."""
    if value is None or template is None:
        return True
    if isinstance(template, bool):
        return isinstance(value, bool)
    if isinstance(template, int):
        return isinstance(value, int) and not isinstance(value, bool)
    if isinstance(template, float):
        return isinstance(value, int | float) and not isinstance(value, bool)
    if isinstance(template, str):
        return isinstance(value, str)
    if isinstance(template, Mapping):
        return isinstance(value, Mapping)
    if isinstance(template, list | tuple):
        return isinstance(value, list | tuple)
    return True
