"""Behaviours bound to declared services and topics (actions run in `goals.GoalClient`).

- service: entering the state sends the request (inputs by field path) once the service is
  there; the response gives the outputs and the outcome `succeeded`, or `aborted` when its
  outcome field (`bool success`) is false, the call raised, or no response came within the
  timeout (ROS parameter `behaviours.<key>.timeout_s`, counted from the state's entry, so it
  covers a service that never appears; 0: no limit). Leaving the state drops the call.
- topic, `publish`: the inputs as one message, published as soon as the topic has a
  matched subscription (`Publisher.get_subscription_count()`, checked every RETRY_S) or,
  with a warning, once the timeout passed (default 1 s: a topic has no answer, and a message
  published before any subscriber matched is lost), then `succeeded`.
- topic, `subscribe`: the behaviour ends `succeeded` (or by its outcome field) when a message
  arrives on the topic after the state's entry, with the message's fields as outputs; with a
  timeout > 0 it ends `aborted` when none came in time.
Outcomes are delivered from the executor (scheduler), never from inside the engine's step.
Feedback of declared actions (`goals.py`) is coalesced here (`FeedbackGate`) into
`FeedbackRecord`s, the trace records of kind `feedback`.
A lost server (`ServerWatch`): a service call on its way, or a sent goal (`goals.py`), whose
server has not been matched for `server_lost_s` (a node parameter, default 2 s, wall seconds;
0: no check) ends `aborted` with a member error; a late answer is ignored.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.task import Future

from ...runtime.chart import Node as ChartNode
from . import lockstep
from .bindings import DEFAULT_TIMEOUTS, Resolved, assignments, outcome_of, outputs_of
from .convert import ConversionError, build
from .scheduler import Handle, Scheduler

RETRY_S = 0.05  # how often a call waits for its service, or a message for its subscriber
FEEDBACK_INTERVAL_S = 0.25  # at most one feedback record per goal this often (wall seconds)
TOPIC_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
SERVER_LOST_PARAMETER = "server_lost_s"
SERVER_LOST_S = 2.0
WATCH_PERIOD_S = 0.25  # wall seconds between checks for lost servers, while any is watched
# (state, activation, behaviour name, outcome, outputs)
Finish = Callable[[ChartNode, int, str, str, dict[str, Any]], None]


@dataclass(frozen=True)
class FeedbackRecord:
    """Feedback of a declared action as a trace record: the latest values (plain, the
    feedback message's fields) and how many feedback messages it stands for (`count` > 1:
    coalesced); `stamp` in seconds since the epoch (wall clock)."""

    member: str
    state: str
    behaviour: str
    values: Any
    count: int
    stamp: float

    def as_json(self) -> dict[str, Any]:
        """The record as a JSON trace line (`kind` `feedback`)."""
        return {
            "kind": "feedback",
            "member": self.member,
            "state": self.state,
            "behaviour": self.behaviour,
            "values": self.values,
            "count": self.count,
        }


class FeedbackGate:
    """The feedback of one goal, rate-limited: the first goes out at once, later ones at most
    every `FEEDBACK_INTERVAL_S`, each carrying the latest values and how many it replaces."""

    def __init__(self, scheduler: Scheduler, emit: Callable[[Any, int], None]) -> None:
        self._scheduler = scheduler
        self._emit = emit
        self._emitted = float("-inf")
        self._values: Any = None
        self._count = 0
        self._timer: Handle | None = None

    def add(self, values: Any) -> None:
        """A feedback message arrived."""
        self._values, self._count = values, self._count + 1
        if self._timer is None:
            wait = self._emitted + FEEDBACK_INTERVAL_S - time.monotonic()
            if wait <= 0:
                self.flush()
            else:
                self._timer = self._scheduler.call_later(wait, self.flush)

    def flush(self) -> None:
        """Emit what waits (the goal ended, or the interval passed)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._count:
            values, count = self._values, self._count
            self._values, self._count, self._emitted = None, 0, time.monotonic()
            self._emit(values, count)

    def drop(self) -> None:
        """Forget what waits (the goal was cancelled)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._values, self._count = None, 0


class ServerWatch:
    """One node's check for lost servers: a steady-clock timer, running only while a goal or
    a service call is on its way (`wake`). Wall time even under `use_sim_time`: a dead process
    does not come back as simulated time passes, and `/clock` may stop while the detailed
    level's world waits for an answer that will never come."""

    def __init__(self, node: Node, check: Callable[[float, float], bool]) -> None:
        """`check(now, limit)`: one round (monotonic seconds, `server_lost_s`); it returns
        whether anything is still watched (else the timer stops until the next `wake`)."""
        value: Any = node.declare_parameter(SERVER_LOST_PARAMETER, SERVER_LOST_S).value
        self.limit = max(0.0, float(value))
        self._check = check
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._timer = node.create_timer(WATCH_PERIOD_S, self._tick, clock=steady, autostart=False)
        self._on = False

    def wake(self) -> None:
        """Something was sent: watch its server (nothing when `server_lost_s` is 0)."""
        if self.limit > 0 and not self._on:
            self._on = True
            self._timer.reset()

    def _tick(self) -> None:
        if not self._check(time.monotonic(), self.limit):
            self._timer.cancel()
            self._on = False


def unmatched_since(since: float | None, ready: bool, now: float) -> float | None:
    """When the server was first seen unmatched in the current stretch (None: matched)."""
    if ready:
        return None
    return now if since is None else since


def lost(since: float | None, now: float, limit: float) -> bool:
    """Unmatched for `limit` seconds: the ticks are WATCH_PERIOD_S apart, so the tick that
    completes the limit may read a hair below it (a strict `>` would wait one more tick)."""
    return since is not None and now - since >= limit - 1e-3


@dataclass(eq=False)
class _Call:
    """One activation of a declared service or topic behaviour."""

    node: ChartNode
    activation: int
    resolved: Resolved
    message: Any = None  # the request, or the message to publish
    future: Future[Any] | None = None
    retry: Handle | None = None
    deadline: Handle | None = None
    done: bool = False
    number: int = 0  # the node's calls, from 1 (replay tells activations apart by it)
    request: int = 0  # the behaviour's service requests, from 1 in the order sent
    unmatched: float | None = None  # monotonic time its service was first seen unmatched


class DeclaredCalls:
    """The service and topic behaviours of one member node."""

    def __init__(
        self,
        node: Node,
        scheduler: Scheduler,
        resolved: Mapping[str, Resolved],
        finish: Finish,
        errors: list[str],
    ) -> None:
        self._node = node
        self._scheduler = scheduler
        self._finish = finish
        self._errors = errors
        self._resolved = dict(resolved)
        self._calls: dict[str, _Call] = {}  # state id -> call
        self._endpoints: dict[str, Any] = {}
        self.timeouts: dict[str, float] = {}
        self._numbers = itertools.count(1)
        self._requests: dict[str, int] = {}
        # (behaviour, request) -> its server holds the request: the call counts as idle (replay)
        self.held: Callable[[str, int], bool] = lambda _behaviour, _request: False
        self.on_sent: Callable[[], None] = lambda: None  # a request went out (`ServerWatch`)
        for name, item in sorted(self._resolved.items()):
            self._endpoints[name] = self._endpoint(name, item)
            default = item.binding.timeout_s
            if default is None:
                default = DEFAULT_TIMEOUTS[_mode(item)]
            declared: Any = node.declare_parameter(item.parameter, float(default)).value
            self.timeouts[name] = max(0.0, float(declared))

    def _endpoint(self, name: str, item: Resolved) -> Any:
        ros_name = item.binding.ros_name
        mode = _mode(item)
        if mode == "service":
            return self._node.create_client(item.type, ros_name)
        if mode == "publish":
            return self._node.create_publisher(item.type, ros_name, TOPIC_QOS)
        heard: list[str] = []  # `<topic>@<node>`, once the subscription knows its topic

        def on_message(message: Any) -> None:
            lockstep.received(self._scheduler, heard[0])
            self._on_message(name, message)

        subscription = self._node.create_subscription(item.type, ros_name, on_message, TOPIC_QOS)
        heard.append(f"{subscription.topic_name}@{self._node.get_fully_qualified_name()}")
        lockstep.listen(self._scheduler, heard[0])
        return subscription

    def handles(self, behaviour: str) -> bool:
        """The behaviour is a declared service or topic."""
        return behaviour in self._resolved

    def ready(self) -> bool:
        """Every declared service is up (topics need nothing)."""
        return all(
            self._endpoints[name].service_is_ready()
            for name, item in self._resolved.items()
            if _mode(item) == "service"
        )

    def idle(self) -> bool:
        """No call is on its way (a subscriber waiting for its message is idle, and so is a
        request its server holds by `held`: the replay driver's)."""
        return all(
            c.done
            or _mode(c.resolved) == "subscribe"
            or (c.request > 0 and self.held(c.resolved.behaviour.name, c.request))
            for c in self._calls.values()
        )

    def running(self, state: str) -> tuple[int, int] | None:
        """(number, request) of the call a state has on its way (request 0: none sent)."""
        call = self._calls.get(state)
        return (call.number, call.request) if call is not None and not call.done else None

    def start(
        self, node: ChartNode, behaviour: str, args: Mapping[str, Any], activation: int
    ) -> None:
        """A state running the behaviour was entered."""
        item = self._resolved[behaviour]
        call = _Call(node, activation, item, number=next(self._numbers))
        self.cancel(node.id)
        self._calls[node.id] = call
        mode = _mode(item)
        if mode != "subscribe":
            try:
                call.message = build(item.request, assignments(item, args), behaviour)
            except ConversionError as err:
                self._fail(call, f"cannot send {item.label}: {err}", error=True)
                return
        timeout = self.timeouts[behaviour]
        if timeout > 0 and mode != "publish":
            call.deadline = self._scheduler.call_later(timeout, lambda: self._timed_out(call))
        if mode == "service":
            self._call_service(call)
        elif mode == "publish":
            self._publish(call, timeout)

    def cancel(self, state: str) -> None:
        """The state was left: its call is dropped (a late answer is ignored)."""
        call = self._calls.pop(state, None)
        if call is not None:
            self._close(call)

    def cancel_all(self) -> None:
        """Drop every call."""
        for state in list(self._calls):
            self.cancel(state)

    def _close(self, call: _Call) -> None:
        call.done = True
        for handle in (call.retry, call.deadline):
            if handle is not None:
                handle.cancel()
        # with the barrier on, the late response is still taken (and counted), then ignored
        pending = call.future is not None and not call.future.done()
        if pending and self._scheduler.lockstep is None:
            self._endpoints[call.resolved.behaviour.name].remove_pending_request(call.future)

    def _end(self, call: _Call, outcome: str, outputs: dict[str, Any]) -> None:
        if call.done:
            return
        self._close(call)
        if self._calls.get(call.node.id) is call:
            del self._calls[call.node.id]
        self._finish(call.node, call.activation, call.resolved.behaviour.name, outcome, outputs)

    def _fail(self, call: _Call, reason: str, *, error: bool) -> None:
        """End `aborted` from the executor, logging why (`error`: also a member error)."""
        text = f"behaviour {call.resolved.behaviour.name} in {call.node.id}: {reason}"
        if error:
            self._errors.append(text)
            self._node.get_logger().error(text)
        else:
            self._node.get_logger().warning(text)
        self._scheduler.call_later(0.0, lambda: self._end(call, "aborted", {}))

    def _call_service(self, call: _Call) -> None:
        call.retry = None
        if call.done:
            return
        client = self._endpoints[call.resolved.behaviour.name]
        if not client.service_is_ready():
            call.retry = self._scheduler.call_later(RETRY_S, lambda: self._call_service(call))
            return
        call.future = client.call_async(call.message)
        lockstep.sent(self._scheduler, "request")
        name = call.resolved.behaviour.name
        call.request = self._requests[name] = self._requests.get(name, 0) + 1
        call.future.add_done_callback(lambda future: self._on_response(call, future))
        self.on_sent()

    def watch(self, now: float, limit: float) -> bool:
        """A `ServerWatch` round: a request on its way whose service has not been matched
        for `limit` seconds ends `aborted` (a member error); True while any is still out."""
        busy = False
        for call in list(self._calls.values()):
            if call.done or call.future is None or call.future.done():
                continue
            client = self._endpoints[call.resolved.behaviour.name]
            call.unmatched = unmatched_since(call.unmatched, client.service_is_ready(), now)
            if not lost(call.unmatched, now, limit):
                busy = True
                continue
            text = (
                f"behaviour {call.resolved.behaviour.name} in {call.node.id}: service "
                f"{self._node.resolve_service_name(client.srv_name)!r} lost (not matched for {limit:g} s): aborted"
            )
            self._errors.append(text)
            self._node.get_logger().error(text)
            self._end(call, "aborted", {})  # in a timer callback: not inside the engine's step
        return busy

    def _on_response(self, call: _Call, future: Future[Any]) -> None:
        lockstep.received(self._scheduler, "response")
        if call.done:
            return
        error = future.exception()
        if error is not None or future.result() is None:
            self._fail(call, f"service call failed: {error!r}", error=True)
            return
        response = future.result()
        outcome = outcome_of(call.resolved, response, "succeeded")
        self._end(call, outcome, outputs_of(call.resolved, response))

    def _timed_out(self, call: _Call) -> None:
        if call.done:
            return
        limit = self.timeouts[call.resolved.behaviour.name]
        what = "no message" if _mode(call.resolved) == "subscribe" else "no response"
        self._fail(call, f"{what} from {call.resolved.binding.ros_name!r} within {limit:g} s",
                   error=False)  # fmt: skip

    def _publish(self, call: _Call, timeout: float, waited: float = 0.0) -> None:
        call.retry = None
        if call.done:
            return
        publisher = self._endpoints[call.resolved.behaviour.name]
        if publisher.get_subscription_count() == 0:
            if waited < timeout:
                call.retry = self._scheduler.call_later(
                    RETRY_S, lambda: self._publish(call, timeout, waited + RETRY_S)
                )
                return
            # published anyway (a topic may have no listener by design), but it may be lost
            self._node.get_logger().warning(
                f"behaviour {call.resolved.behaviour.name} in {call.node.id}: no subscriber "
                f"on {publisher.topic_name!r} within {timeout:g} s: published anyway"
            )
        publisher.publish(call.message)
        lockstep.sent(self._scheduler, publisher.topic_name)
        self._scheduler.call_later(0.0, lambda: self._end(call, "succeeded", {}))

    def _on_message(self, behaviour: str, message: Any) -> None:
        waiting = [c for c in self._calls.values() if c.resolved.behaviour.name == behaviour]
        for call in waiting:
            outcome = outcome_of(call.resolved, message, "succeeded")
            self._end(call, outcome, outputs_of(call.resolved, message))


def _mode(item: Resolved) -> str:
    """`service`, `publish` or `subscribe` (actions do not come here)."""
    return item.binding.kind if item.binding.kind == "service" else item.binding.direction
