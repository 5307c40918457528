"""One swarm member as an rclpy node: the statechart engine's `Host` over ROS 2.

- Swarm events travel on one topic, `/swarm/events` (the interface package's `Event`: id, stamp,
  sender, name, data = JSON object of the fields). Local-scope events never leave the node.
- After every step the node publishes its active states on `<namespace>/active_states`.
- The behaviour a state runs is a ROS 2 action at `<namespace>/<action name>`: entering the state
  sends the goal (inputs from the call's arguments), leaving it cancels the goal, and the result
  (`outcome` + outputs) becomes the event `done.invoke.<state>.<outcome>`, tagged with the
  activation so that late results of cancelled goals are dropped (as in `runtime.member`).
- Member data defaults and the hardware parameters are ROS parameters.

The goals are the part of `goals.GoalClient`, the node's base class. Everything runs in the
executor's thread: callbacks queue events, and the queue is drained with one engine macrostep
per event, exactly as the asyncio member does.
"""

from __future__ import annotations

import json
import sys
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import rclpy
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.context import Context as RosContext
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException
from rclpy.parameter import Parameter as RosParameter

from ...runtime.chart import Node as ChartNode
from ...runtime.chart import record
from ...runtime.engine import Engine
from ...runtime.engine import Event as SwarmEvent
from . import lockstep
from .bindings import BindingError
from .goals import GoalClient
from .messages import (
    EVENTS_QOS,
    LOCAL_TOPIC,
    STATES_QOS,
    STATES_TOPIC,
    SWARM_TOPIC,
    Interfaces,
    from_ros_time,
)
from .process import init_process, spin_until
from .scheduler import Handle, Scheduler
from .spec import (
    BehaviourSpec,
    Binding,
    Field,
    MemberSpec,
    Parameter,
    index_of,
    namespace_id,
)

# What generated member modules import from here (`from ._ros.node import ...`).
__all__ = [
    "BehaviourSpec",
    "Binding",
    "Field",
    "MemberNode",
    "MemberOptions",
    "MemberSpec",
    "Parameter",
    "run_member",
]


@dataclass
class MemberOptions:
    """How a member node runs. `isolated`: the member hears nothing it sends itself (replay,
    like `runtime.replay`); `timers`: model timers fire (replay freezes time)."""

    member_id: str | None = None
    member_index: int | None = None
    isolated: bool = False
    timers: bool = True
    time_scale: float | None = None
    tracer: Callable[[MemberNode, SwarmEvent | None], None] | None = None
    parameter_overrides: Sequence[RosParameter[Any]] = ()
    # a result with an undeclared outcome is a failing behaviour (`aborted`); replay turns it
    # off, since a scenario's outcome is taken as given (as `runtime.replay` does)
    check_outcomes: bool = True


class MemberNode(GoalClient):
    """A member of the swarm: its statechart, run by the engine, hosted by a ROS 2 node."""

    def __init__(
        self,
        spec: MemberSpec,
        *,
        namespace: str = "",
        options: MemberOptions | None = None,
        scheduler: Scheduler | None = None,
        context: RosContext | None = None,
    ) -> None:
        options = options or MemberOptions()
        super().__init__(
            spec.node_name,
            namespace=namespace,
            context=context,
            parameter_overrides=list(options.parameter_overrides),
        )
        self.spec = spec
        self.options = options
        self.interfaces = Interfaces(spec.interfaces)
        own = scheduler is None  # a process of its own (run_member): its own barrier reporter
        # `is None`, not `or`: an empty Scheduler is falsy (`__len__`), and a shared one must stay
        self.scheduler = scheduler if scheduler is not None else Scheduler(self)
        self._declare_parameters()
        if own:
            lockstep.start(self, self.scheduler, self.member_id)
        self.errors: list[str] = []
        self.steps = 0
        self.seen: dict[str, int] = {}  # sender -> id of the last swarm event processed
        self.finished = False
        self.on_finished: list[Callable[[MemberNode], None]] = []
        self.on_step: list[Callable[[MemberNode], None]] = []
        self._queue: deque[SwarmEvent] = deque()
        self._draining = False
        self._model_timers: dict[str, Handle] = {}
        self._delayed: dict[str, list[Handle]] = {}  # pending `raise e after ...` by send id
        if self.scheduler.lockstep is not None:
            self.scheduler.lockstep.quiet.append(lambda: not self._queue and not self._draining)
        self._create_endpoints()
        self._started = False
        self.engine = self._new_engine()

    def _create_endpoints(self) -> None:
        """The swarm and local event topics, the active-states topic, one client per action."""
        event_type = self.interfaces.Event
        self.swarm_publisher = self.create_publisher(event_type, SWARM_TOPIC, EVENTS_QOS)
        self._states = self.create_publisher(self.interfaces.ActiveStates, STATES_TOPIC, STATES_QOS)
        heard = f"{self.swarm_publisher.topic_name}@{self.get_fully_qualified_name()}"
        lockstep.listen(self.scheduler, heard)

        def on_swarm(msg: Any) -> None:
            lockstep.received(self.scheduler, heard)
            self._on_swarm_event(msg)

        self.create_subscription(event_type, SWARM_TOPIC, on_swarm, EVENTS_QOS)
        self.create_subscription(event_type, LOCAL_TOPIC, self._on_swarm_event, EVENTS_QOS)
        self._init_goals(self.spec.behaviours, self.options.check_outcomes)

    # --- parameters

    def _declare_parameters(self) -> None:
        """The member's identity, its time scale and the model's parameters, as ROS parameters."""
        options = self.options
        default_id = namespace_id(self.get_namespace(), self.spec.node_name)
        self.member_id = str(self._declare("member_id", options.member_id or default_id))
        self.member_index = int(
            self._declare("member_index", options.member_index or index_of(self.member_id))
        )
        scale = options.time_scale if options.time_scale is not None else 1.0
        self.time_scale = float(self._declare("time_scale", float(scale)))
        self._overrides: dict[str, Any] = {}
        for parameter in self.spec.parameters:
            self._declare_model_parameter(parameter)

    def _declare(
        self, name: str, default: Any, descriptor: ParameterDescriptor | None = None
    ) -> Any:
        return self.declare_parameter(name, default, descriptor or ParameterDescriptor()).value

    def _declare_model_parameter(self, parameter: Parameter) -> None:
        descriptor = ParameterDescriptor(
            description=parameter.description, read_only=parameter.read_only
        )
        default = _parameter_default(parameter)
        value = self._declare(parameter.name, default, descriptor)
        if parameter.data is None or value == default:
            return  # the model's default stays exactly as the model gives it
        if parameter.type == "json":
            try:
                value = json.loads(value)
            except ValueError:
                self.get_logger().error(f"parameter {parameter.name}: not JSON: {value!r}")
                return
        self._overrides[parameter.data] = value

    # --- lifecycle

    def _new_engine(self) -> Engine:
        engine = Engine(self.spec.build(), self, self.member_id)
        engine.on_error = lambda where, err: self.errors.append(f"{where}: {err!r}")
        for key, value in self._overrides.items():
            engine.data[key] = record(value)
        return engine

    def start(self) -> None:
        """Enter the initial configuration (behaviours start, active states are published)."""
        self._started = True
        self.engine.start()
        self._after_step(None)
        self._drain()  # the events that arrived before the start

    def reset(self) -> None:
        """Forget everything: cancel the behaviours and timers, build a fresh engine (replay)."""
        self._cancel_all()
        self._queue.clear()
        self._started = False
        self.finished = False
        self.errors.clear()
        self.engine = self._new_engine()

    def stop(self) -> None:
        """Cancel every running behaviour and timer; the machine stops where it is."""
        self.engine.running = False
        self._cancel_all()

    def _cancel_all(self) -> None:
        self._cancel_runs()
        for handle in self._model_timers.values():
            handle.cancel()
        self._model_timers.clear()
        for handles in self._delayed.values():
            for handle in handles:
                handle.cancel()
        self._delayed.clear()

    def active(self) -> list[str]:
        """The active states (the engine's configuration)."""
        return self.engine.active()

    def flush(self, timeout: float = 2.0) -> bool:
        """Wait until the subscribers acknowledged what this node published (before exiting:
        the final active states must not die with the process)."""
        limit = Duration(nanoseconds=int(timeout * 1e9))
        return all(
            publisher.wait_for_all_acked(limit)
            for publisher in (self.swarm_publisher, self._states)
        )

    def idle(self) -> bool:
        """Nothing on the way: every goal was answered, no event waits in the queue."""
        return not self._queue and not self._draining and self._goals_idle()

    # --- events

    def deliver(self, event: SwarmEvent) -> None:
        """Queue an event; the queue is drained with one macrostep per event."""
        self._queue.append(event)
        self._drain()

    def _drain(self) -> None:
        if self._draining or not self._started:
            return
        self._draining = True
        try:
            while self._queue:
                current = self._queue.popleft()
                if not self.engine.running:
                    continue
                self.engine.send(current)
                self._after_step(current)
        finally:
            self._draining = False
        if self.scheduler.lockstep is not None:
            self.scheduler.lockstep.check()  # the queue is empty: report it at once

    def _after_step(self, event: SwarmEvent | None) -> None:
        self.steps += 1
        self._states.publish(
            self.interfaces.ActiveStates(
                stamp=self.get_clock().now().to_msg(),
                member=self.member_id,
                states=self.engine.active(),
            )
        )
        if self.options.tracer is not None:
            self.options.tracer(self, event)
        for callback in list(self.on_step):
            callback(self)
        if self.engine.finished and not self.finished:
            self.finished = True
            for callback in list(self.on_finished):
                callback(self)

    def _on_swarm_event(self, msg: Any) -> None:
        if self.options.isolated and msg.sender == self.member_id:
            return  # replay: what the member sends does not come back
        try:
            data = json.loads(msg.data) if msg.data else None
        except ValueError:
            self.errors.append(f"event {msg.name} from {msg.sender}: data is not JSON")
            data = None
        event = SwarmEvent(
            msg.name,
            record(data) if isinstance(data, dict) else None,
            msg.id,
            from_ros_time(msg.stamp),
            msg.sender,
        )
        self.deliver(event)
        self.seen[msg.sender] = max(self.seen.get(msg.sender, 0), msg.id)

    def publish_event(self, event: SwarmEvent) -> None:
        """Send an event of the member on the swarm topic."""
        data = json.dumps(event.data if event.data is not None else {}, default=str)
        self.swarm_publisher.publish(
            self.interfaces.event(event.id, event.timestamp, event.sender, event.name, data)
        )
        lockstep.sent(self.scheduler, self.swarm_publisher.topic_name)

    # --- engine host

    def send_swarm(self, event: SwarmEvent) -> None:
        """Send an event the machine raised: to the swarm, or back to this member if local."""
        if self.spec.event_scopes.get(event.name, "swarm") == "local":
            if not self.options.isolated:
                self.deliver(event)
            return
        self.publish_event(event)

    def start_timer(self, node: ChartNode, event: str, delay_ms: int) -> None:
        """Start (or restart) a model timer that delivers `event` after `delay_ms` (scaled)."""
        if not self.options.timers:
            return
        previous = self._model_timers.pop(event, None)
        if previous is not None:
            previous.cancel()

        def fire() -> None:
            self._model_timers.pop(event, None)
            self.deliver(self.engine.make_event(event, None, self.member_id))

        self._model_timers[event] = self.scheduler.call_later(
            delay_ms / 1000 * self.time_scale, fire
        )

    def cancel_timer(self, node: ChartNode, event: str) -> None:
        """Stop a model timer (the state that started it was left)."""
        handle = self._model_timers.pop(event, None)
        if handle is not None:
            handle.cancel()

    def start_delayed(self, key: str, event: SwarmEvent, delay_ms: float) -> None:
        """`raise e after N ms`: deliver `event` after the delay (scaled), unless cancelled;
        like model timers, not when timers are off (an isolated replay)."""
        if not self.options.timers:
            return
        handles = self._delayed.setdefault(key, [])

        def fire() -> None:
            pending = self._delayed.get(key, [])
            if handle in pending:
                pending.remove(handle)
            if not pending:
                self._delayed.pop(key, None)
            self.deliver(event)

        handle = self.scheduler.call_later(delay_ms / 1000 * self.time_scale, fire)
        handles.append(handle)

    def cancel_delayed(self, key: str) -> None:
        """Drop the pending delayed events of `key`."""
        for handle in self._delayed.pop(key, ()):
            handle.cancel()


def run_member(spec: MemberSpec, argv: Sequence[str] | None = None) -> int:
    """One member in this process, with ROS arguments (`--ros-args -r __ns:=/uav_1 -p ...`).

    The process ends when the member reaches its final state, or on SIGINT/SIGTERM.
    """
    context, executor = init_process(argv)
    try:
        member = MemberNode(spec, context=context)
    except BindingError as err:  # a declared interface this environment cannot provide
        print(f"{spec.node_name}: {err}", file=sys.stderr)
        executor.shutdown()
        rclpy.try_shutdown(context=context)
        return 2
    executor.add_node(member)
    try:
        if not lockstep.wait_for_world(member.scheduler, partial(spin_until, executor)):
            return 3  # not reached: no timeout given, it waits for the world or a signal
        member.start()
        lockstep.started(member.scheduler)
        spin_until(executor, lambda: member.finished)
        spin_until(executor, member.idle, timeout=2.0)
        member.flush()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        member.stop()
        executor.shutdown()
        member.destroy_node()
        rclpy.try_shutdown(context=context)
    for error in member.errors:
        print(f"{member.member_id}: {error}", file=sys.stderr)
    return 1 if member.errors else 0


def _parameter_default(parameter: Parameter) -> Any:
    """The model's default as the ROS parameter's value (JSON text for a `json` parameter)."""
    default = parameter.default
    if parameter.type == "json":
        return json.dumps(default, sort_keys=True)
    if parameter.type == "float64":
        return float(default) if isinstance(default, int | float) else 0.0
    if parameter.type == "int64":
        return int(default) if isinstance(default, int | float) else 0
    if parameter.type == "bool":
        return bool(default)
    return "" if default is None else str(default)
