"""One swarm member as an rclpy node: the statechart engine's `Host` over ROS 2.

- Swarm events travel on one topic, `/swarm/events` (the interface package's `Event`: id, stamp,
  sender, name, data = JSON object of the fields). Local-scope events never leave the node.
- After every step the node publishes its active states on `<namespace>/active_states`.
- The behaviour a state runs is a ROS 2 action at `<namespace>/<action name>`: entering the state
  sends the goal (inputs from the call's arguments), leaving it cancels the goal, and the result
  (`outcome` + outputs) becomes the event `done.invoke.<state>.<outcome>`, tagged with the
  activation so that late results of cancelled goals are dropped (as in `runtime.member`).
- Member data defaults and the hardware parameters are ROS parameters.

Everything runs in the executor's thread: callbacks queue events, and the queue is drained with
one engine macrostep per event, exactly as the asyncio member does.
"""

from __future__ import annotations

import heapq
import importlib
import itertools
import json
import math
import sys
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from types import ModuleType
from typing import Any

import rclpy
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Time
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.action.client import ActionClient
from rclpy.context import Context as RosContext
from rclpy.duration import Duration
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.experimental.events_executor import EventsExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter as RosParameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from rclpy.timer import Timer

from ...runtime.chart import Call, Chart, record
from ...runtime.chart import Node as ChartNode
from ...runtime.engine import FINALIZE_PREFIX, Engine
from ...runtime.engine import Event as SwarmEvent

SWARM_TOPIC = "/swarm/events"
LOCAL_TOPIC = "local_events"  # behaviour events of local scope, inside one member's namespace
STATES_TOPIC = "active_states"
EVENTS_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
# The latest configuration is kept for late subscribers (a monitor that starts after the swarm).
STATES_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
# Result status -> outcome, when a result carries no outcome of its own.
STATUS_OUTCOMES = {
    GoalStatus.STATUS_SUCCEEDED: "succeeded",
    GoalStatus.STATUS_ABORTED: "aborted",
    GoalStatus.STATUS_CANCELED: "preempted",
}
SERVER_RETRY_S = 0.05  # how often a goal waits for its action server to appear
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1

# --- what generated member modules declare


@dataclass(frozen=True, slots=True)
class Field:
    """A behaviour input or output: its model identifier, its ROS field and how it is encoded.

    `type` is the ROS field type (`float64`, `int64`, `bool`, `string`) or `json`: a `string`
    field carrying the JSON text of a value of a model DataType (`Pose`) or of no declared type.
    """

    name: str
    field: str
    type: str


@dataclass(frozen=True, slots=True)
class BehaviourSpec:
    name: str  # the model's behaviour name (what `Call.behaviour` holds)
    action: str  # action type in the interface package
    ros_name: str  # action name, relative to the member's namespace
    kind: str  # ComplexBehavior, SwarmBehavior, SwarmFunction, HardwareFunction
    inputs: tuple[Field, ...] = ()
    outputs: tuple[Field, ...] = ()
    outcomes: tuple[str, ...] = ()
    # rosKind, rosName, rosType as the model declares them ("" when absent): metadata only
    declared: tuple[str, str, str] = ("", "", "")


@dataclass(frozen=True, slots=True)
class Parameter:
    """A ROS parameter of the member node; `data` names the member data item it initialises."""

    name: str
    type: str  # float64, int64, bool, string or json (a string parameter holding JSON)
    default: Any
    data: str | None = None
    read_only: bool = False
    description: str = ""


@dataclass(frozen=True, slots=True)
class MemberSpec:
    member_type: str  # the model's member type name
    chart_name: str  # identifier of the member type (module, script keys)
    node_name: str  # ROS node name (lower snake case)
    interfaces: str  # the interface package
    build: Callable[[], Chart]
    event_scopes: Mapping[str, str]  # event this member sends -> "swarm" or "local"
    behaviours: Mapping[str, BehaviourSpec]
    parameters: tuple[Parameter, ...] = ()


# --- values between the engine and ROS messages


def encode(type_: str, value: Any) -> Any:
    """A Python value as the ROS field of `type_` holds it (lenient: unusable values give the
    field's zero value; JSON fields give `""` for a value that is absent)."""
    if type_ == "json":
        return "" if value is None else json.dumps(value, default=str, sort_keys=True)
    if type_ == "string":
        return value if isinstance(value, str) else ("" if value is None else str(value))
    if type_ == "bool":
        return bool(value) if isinstance(value, bool | int | float) else False
    if type_ == "int64":  # out of range would fail when the message is sent, in the executor
        if isinstance(value, bool | int | float) and INT64_MIN <= value <= INT64_MAX:
            return int(value)
        return 0
    if type_ == "float64":
        return float(value) if isinstance(value, bool | int | float) else 0.0
    raise ValueError(f"unknown field type {type_!r}")


def fits(type_: str, value: Any) -> bool:
    """`value` is one the ROS field of `type_` carries as it is (None: not given, the zero),
    not one `encode` would replace by the zero: what a behaviour's output must be."""
    if value is None or type_ in ("json", "string"):
        return True
    if type_ == "bool":
        return isinstance(value, bool)
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if type_ == "int64":
        return number and isinstance(value, int) and INT64_MIN <= value <= INT64_MAX
    return number and math.isfinite(float(value)) if type_ == "float64" else False


def decode(type_: str, value: Any) -> tuple[bool, Any]:
    """(present, value) of a ROS field; an empty JSON field is absent."""
    if type_ == "json":
        if value == "":
            return False, None
        try:
            return True, json.loads(value)
        except ValueError:
            return True, value
    if type_ == "float64":
        return True, float(value)
    return True, value


def ros_time(seconds: float) -> Time:
    whole = math.floor(seconds)
    return Time(sec=int(whole), nanosec=int((seconds - whole) * 1e9))


def from_ros_time(stamp: Any) -> float:
    return float(stamp.sec) + float(stamp.nanosec) / 1e9


@cache
def _module(name: str) -> ModuleType:
    return importlib.import_module(name)


class Interfaces:
    """The generated interface package's types, imported by name (the runtime is generic)."""

    def __init__(self, package: str) -> None:
        self.package = package
        msg = _module(f"{package}.msg")
        self.Event: Any = msg.Event
        self.ActiveStates: Any = msg.ActiveStates

    def action(self, name: str) -> Any:
        return getattr(_module(f"{self.package}.action"), name)


# --- one-shot callbacks on one ROS timer


class Handle:
    __slots__ = ("callback", "cancelled", "when")

    def __init__(self, when: float, callback: Callable[[], None]) -> None:
        self.when = when
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class Scheduler:
    """`call_later` on a single rclpy timer, re-armed for the earliest deadline.

    rclpy slows down (and warns) with many timers on one clock, and scripted behaviours and model
    timers need many short-lived delays; so a process shares one scheduler between its nodes.
    Callbacks run in the executor, like every other callback.
    """

    def __init__(self, node: Node) -> None:
        self._heap: list[tuple[float, int, Handle]] = []
        self._order = itertools.count()
        self._armed: float | None = None
        self._logger = node.get_logger()
        self._timer: Timer = node.create_timer(3600.0, self._fire, autostart=False)

    def call_later(self, delay: float, callback: Callable[[], None]) -> Handle:
        handle = Handle(time.monotonic() + max(0.0, delay), callback)
        heapq.heappush(self._heap, (handle.when, next(self._order), handle))
        self._arm()
        return handle

    def __len__(self) -> int:
        return sum(1 for _, _, h in self._heap if not h.cancelled)

    def _arm(self) -> None:
        while self._heap and self._heap[0][2].cancelled:
            heapq.heappop(self._heap)
        if not self._heap:
            if self._armed is not None:
                self._timer.cancel()
                self._armed = None
            return
        when = self._heap[0][0]
        if self._armed is not None and self._armed <= when:
            return  # already armed for this deadline or an earlier one
        delay = max(when - time.monotonic(), 0.0)
        self._timer.timer_period_ns = max(1000, int(delay * 1e9))
        self._timer.reset()
        self._armed = when

    def _fire(self) -> None:
        self._armed = None
        now = time.monotonic()
        while self._heap and self._heap[0][0] <= now:
            _, _, handle = heapq.heappop(self._heap)
            if handle.cancelled:
                continue
            handle.cancelled = True
            try:
                handle.callback()
            except Exception as err:  # a failing callback must not stop the others
                self._logger.error(f"scheduled callback failed: {err!r}")
        self._arm()


# --- the member node


@dataclass(eq=False)
class _Run:
    """One activation of a state's behaviour: its goal on the way, running or finished."""

    node: ChartNode
    activation: int
    behaviour: BehaviourSpec
    goal: Any
    handle: Any = None  # ClientGoalHandle once the server answered
    retry: Handle | None = None
    waited_since: float = field(default_factory=time.monotonic)
    warned: bool = False
    cancelled: bool = False
    finished: bool = False


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


class MemberNode(Node):
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
        self.scheduler = scheduler or Scheduler(self)
        default_id = self.get_namespace().strip("/").replace("/", "_") or spec.node_name
        self.member_id = str(self._declare("member_id", options.member_id or default_id))
        self.member_index = int(
            self._declare("member_index", options.member_index or _index_of(self.member_id))
        )
        scale = options.time_scale if options.time_scale is not None else 1.0
        self.time_scale = float(self._declare("time_scale", float(scale)))
        self._overrides: dict[str, Any] = {}
        for parameter in spec.parameters:
            self._declare_model_parameter(parameter)

        self.errors: list[str] = []
        self.steps = 0
        self.seen: dict[str, int] = {}  # sender -> id of the last swarm event processed
        self.results: set[bytes] = set()  # goal ids whose result arrived
        self.pending_requests = 0  # goals sent, no answer yet
        self.pending_cancels = 0
        self.finished = False
        self.on_finished: list[Callable[[MemberNode], None]] = []
        self.on_step: list[Callable[[MemberNode], None]] = []
        self._queue: deque[SwarmEvent] = deque()
        self._draining = False
        self._runs: dict[str, _Run] = {}
        self._model_timers: dict[str, Handle] = {}

        self.swarm_publisher = self.create_publisher(self.interfaces.Event, SWARM_TOPIC, EVENTS_QOS)
        self._states = self.create_publisher(self.interfaces.ActiveStates, STATES_TOPIC, STATES_QOS)
        self.create_subscription(
            self.interfaces.Event, SWARM_TOPIC, self._on_swarm_event, EVENTS_QOS
        )
        self.create_subscription(
            self.interfaces.Event, LOCAL_TOPIC, self._on_swarm_event, EVENTS_QOS
        )
        self.action_clients: dict[str, ActionClient[Any, Any, Any]] = {
            name: ActionClient(self, self.interfaces.action(b.action), b.ros_name)
            for name, b in sorted(spec.behaviours.items())
        }
        self._started = False
        self.engine = self._new_engine()

    # --- parameters

    def _declare(
        self, name: str, default: Any, descriptor: ParameterDescriptor | None = None
    ) -> Any:
        return self.declare_parameter(name, default, descriptor or ParameterDescriptor()).value

    def _declare_model_parameter(self, parameter: Parameter) -> None:
        descriptor = ParameterDescriptor(
            description=parameter.description, read_only=parameter.read_only
        )
        default = parameter.default
        if parameter.type == "json":
            default = json.dumps(default, sort_keys=True)
        elif parameter.type == "float64":
            default = float(default) if isinstance(default, int | float) else 0.0
        elif parameter.type == "int64":
            default = int(default) if isinstance(default, int | float) else 0
        elif parameter.type == "bool":
            default = bool(default)
        else:
            default = "" if default is None else str(default)
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
        for run in list(self._runs.values()):
            self._cancel(run)
        self._runs.clear()
        for handle in self._model_timers.values():
            handle.cancel()
        self._model_timers.clear()
        self._queue.clear()
        self._started = False
        self.finished = False
        self.errors.clear()
        self.engine = self._new_engine()

    def stop(self) -> None:
        """Cancel every running behaviour and timer; the machine stops where it is."""
        self.engine.running = False
        for run in list(self._runs.values()):
            self._cancel(run)
        self._runs.clear()
        for handle in self._model_timers.values():
            handle.cancel()
        self._model_timers.clear()

    def active(self) -> list[str]:
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
        return (
            not self._queue
            and not self._draining
            and self.pending_requests == 0
            and self.pending_cancels == 0
            and all(run.handle is not None or run.finished for run in self._runs.values())
        )

    def servers_ready(self) -> bool:
        return all(client.server_is_ready() for client in self.action_clients.values())

    def running_goal(self, state: str) -> Any:
        """The goal handle of the behaviour a state runs now (None if none is running)."""
        run = self._runs.get(state)
        return run.handle if run is not None and not run.finished else None

    def running_goal_ids(self) -> set[bytes]:
        """The ids of the goals running now (accepted, no result yet)."""
        return {
            bytes(run.handle.goal_id.uuid)
            for run in self._runs.values()
            if run.handle is not None and not run.finished
        }

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
        self.swarm_publisher.publish(
            self.interfaces.Event(
                id=event.id,
                stamp=ros_time(event.timestamp),
                sender=event.sender,
                name=event.name,
                data=json.dumps(event.data if event.data is not None else {}, default=str),
            )
        )

    # --- engine host

    def send_swarm(self, event: SwarmEvent) -> None:
        if self.spec.event_scopes.get(event.name, "swarm") == "local":
            if not self.options.isolated:
                self.deliver(event)
            return
        self.publish_event(event)

    def start_timer(self, node: ChartNode, event: str, delay_ms: int) -> None:
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
        handle = self._model_timers.pop(event, None)
        if handle is not None:
            handle.cancel()

    def start_call(
        self, node: ChartNode, call: Call, args: dict[str, Any], activation: int
    ) -> None:
        behaviour = self.spec.behaviours.get(call.behaviour)
        if behaviour is None:
            self.errors.append(f"no action for behaviour {call.behaviour}")
            return
        goal_type = self.interfaces.action(behaviour.action).Goal
        goal = goal_type(**{f.field: encode(f.type, args.get(f.name)) for f in behaviour.inputs})
        run = _Run(node, activation, behaviour, goal)
        self._runs[node.id] = run
        self._send_goal(run)

    def cancel_call(self, node: ChartNode, activation: int) -> None:
        run = self._runs.pop(node.id, None)
        if run is not None:
            self._cancel(run)

    # --- goals

    def _send_goal(self, run: _Run) -> None:
        run.retry = None
        if run.cancelled:
            return
        client = self.action_clients[run.behaviour.name]
        if not client.server_is_ready():
            waited = time.monotonic() - run.waited_since
            if waited > 5.0 and not run.warned:
                run.warned = True
                self.get_logger().warning(
                    f"action server {run.behaviour.ros_name!r} not found after {waited:.0f} s"
                )
            run.retry = self.scheduler.call_later(SERVER_RETRY_S, lambda: self._send_goal(run))
            return
        self.pending_requests += 1
        future = client.send_goal_async(run.goal, feedback_callback=self._on_feedback)
        future.add_done_callback(lambda f: self._on_goal_response(run, f))

    def _on_feedback(self, feedback: Any) -> None:
        self.get_logger().debug(f"feedback: {feedback.feedback.status}")

    def _on_goal_response(self, run: _Run, future: Future[Any]) -> None:
        self.pending_requests -= 1
        error = future.exception()
        handle = future.result() if error is None else None
        if handle is None or not handle.accepted:
            run.finished = True
            if not run.cancelled:
                reason = f"failed: {error!r}" if error else "rejected"
                self.errors.append(f"goal of {run.behaviour.name} in {run.node.id} {reason}")
                self._outcome(run, "aborted", {})
            return
        run.handle = handle
        if run.cancelled:
            self._cancel_goal(run)
        handle.get_result_async().add_done_callback(lambda f: self._on_result(run, f))

    def _on_result(self, run: _Run, future: Future[Any]) -> None:
        run.finished = True
        self.results.add(bytes(run.handle.goal_id.uuid))
        if run.cancelled:
            return
        error = future.exception()
        response = future.result() if error is None else None
        if response is None:
            self.errors.append(f"no result for {run.behaviour.name} in {run.node.id}: {error!r}")
            self._outcome(run, "aborted", {})
            return
        result = response.result
        outcome = result.outcome or STATUS_OUTCOMES.get(response.status, "aborted")
        declared = run.behaviour.outcomes
        if self.options.check_outcomes and declared and outcome not in declared:
            self.errors.append(
                f"behaviour {run.behaviour.name} in {run.node.id} failed: "
                f"returned the undeclared outcome {outcome[:80]!r}"
            )
            self._outcome(run, "aborted", {})
            return
        outputs: dict[str, Any] = {}
        for output in run.behaviour.outputs:
            present, value = decode(output.type, getattr(result, output.field))
            if present:
                outputs[output.name] = value
        self._outcome(run, outcome, outputs)

    def _outcome(self, run: _Run, outcome: str, outputs: Mapping[str, Any]) -> None:
        if self._runs.get(run.node.id) is run:
            del self._runs[run.node.id]
        self.deliver(
            self.engine.make_event(
                f"{FINALIZE_PREFIX}{run.node.id}.{outcome}",
                dict(outputs),
                self.member_id,
                origin=(run.node.id, run.activation),
            )
        )

    def _cancel(self, run: _Run) -> None:
        """Preemption: the state was left, its goal is cancelled (its result will be ignored)."""
        run.cancelled = True
        if run.retry is not None:
            run.retry.cancel()
            run.retry = None
        if run.handle is not None and not run.finished:
            self._cancel_goal(run)

    def _cancel_goal(self, run: _Run) -> None:
        self.pending_cancels += 1

        def answered(_: Future[Any]) -> None:
            self.pending_cancels -= 1

        run.handle.cancel_goal_async().add_done_callback(answered)


def _index_of(member_id: str) -> int:
    """`uav_3` -> 3 (members are numbered from 1 within their type); 1 when there is no number."""
    tail = member_id.rsplit("_", 1)[-1]
    return int(tail) if tail.isdigit() else 1


# --- running one member per process (the launch file's executables)


def ros_args(argv: Sequence[str] | None) -> list[str]:
    return list(sys.argv if argv is None else ["member", *argv])


def make_executor(kind: str, context: RosContext | None = None) -> Executor:
    """`events`: rclpy's EventsExecutor (no wait set rebuilt per callback: much faster with many
    entities); `single`: the SingleThreadedExecutor. Either is spun in the calling thread only
    (an EventsExecutor spun in another thread hangs on shutdown)."""
    if kind == "events":
        return EventsExecutor(context=context)
    return SingleThreadedExecutor(context=context)


def spin_until(
    executor: Executor,
    done: Callable[[], bool],
    timeout: float | None = None,
    step: float = 0.1,
) -> bool:
    """Spin in this thread until `done()` or the timeout; False on timeout.

    A SIGINT/SIGTERM shuts the context down from rclpy's signal handler, possibly between two
    `spin_once` calls: the next one then fails inside rcl ("context is not valid") instead of
    raising ExternalShutdownException. Both are the same clean shutdown to every caller."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while not done():
        if deadline is not None and time.monotonic() > deadline:
            return False
        try:
            executor.spin_once(timeout_sec=step)
        except Exception:
            if executor.context.ok():
                raise
            raise ExternalShutdownException() from None
    return True


def run_member(spec: MemberSpec, argv: Sequence[str] | None = None) -> int:
    """One member in this process, with ROS arguments (`--ros-args -r __ns:=/uav_1 -p ...`).

    The process ends when the member reaches its final state, or on SIGINT/SIGTERM.
    """
    context = rclpy.get_default_context()  # the default one: SIGINT/SIGTERM end it cleanly
    rclpy.init(args=ros_args(argv), context=context)
    executor = SingleThreadedExecutor(context=context)
    member = MemberNode(spec, context=context)
    executor.add_node(member)
    try:
        member.start()
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
