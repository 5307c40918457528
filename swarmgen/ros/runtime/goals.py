"""The action-client side of a member node: the behaviour a state runs is a ROS 2 goal.

Entering the state sends the goal (waiting for its server to appear), leaving it cancels the
goal, and the result (`outcome` + outputs) becomes the event `done.invoke.<state>.<outcome>`,
tagged with the activation so that late results of cancelled goals are dropped.

Goal fields are converted strictly on both paths (private and declared actions): a value its
field cannot hold ends the behaviour `aborted`, logged and kept as a member error, and nothing
is sent. A server that does not answer a sent goal within `goal_answer_timeout_s` (a node
parameter, default 10 s) gives `aborted`; a declared action with `behaviours.<key>.timeout_s`
> 0 is cancelled and gives `aborted` when it has not ended that long after the state's entry.
A sent goal whose action server is no longer matched for `server_lost_s` (a node parameter,
default 2 s, wall seconds: `declared.ServerWatch`) ends `aborted` with a member error, without a
cancel request (nobody would answer it); a result that still comes is ignored.
Feedback of declared actions becomes `FeedbackRecord`s for traces (`on_feedback`), at most one
per goal every `FEEDBACK_INTERVAL_S` (later ones coalesced: the latest values, with a count).
"""

from __future__ import annotations

import json
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from action_msgs.msg import GoalStatus
from rclpy.action.client import ActionClient
from rclpy.node import Node
from rclpy.task import Future

from ...runtime.chart import Call
from ...runtime.chart import Node as ChartNode
from ...runtime.engine import FINALIZE_PREFIX, Engine
from ...runtime.engine import Event as SwarmEvent
from . import lockstep
from .bindings import (
    DEFAULT_TIMEOUTS,
    Resolved,
    assignments,
    outcome_of,
    outputs_of,
    resolve,
)
from .convert import ConversionError, build, plain
from .declared import (
    DeclaredCalls,
    FeedbackGate,
    FeedbackRecord,
    ServerWatch,
    lost,
    unmatched_since,
)
from .messages import Interfaces, decode, to_ros
from .scheduler import Handle, Scheduler
from .spec import BehaviourSpec

# Result status -> outcome, when a result carries no outcome of its own.
STATUS_OUTCOMES = {
    GoalStatus.STATUS_SUCCEEDED: "succeeded",
    GoalStatus.STATUS_ABORTED: "aborted",
    GoalStatus.STATUS_CANCELED: "preempted",
}
SERVER_RETRY_S = 0.05  # how often a goal waits for its action server to appear
FEEDBACK_KEPT = 256  # feedback of declared actions kept for traces (the latest)
ANSWER_PARAMETER = "goal_answer_timeout_s"  # a sent goal's wait for accepted/rejected
ANSWER_TIMEOUT_S = 10.0


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
    answered: bool = False  # the server accepted or rejected the goal
    deadline: Handle | None = None  # `timeout_s` of a declared action
    answer_deadline: Handle | None = None  # `goal_answer_timeout_s` of a sent goal
    feedback: FeedbackGate | None = None  # declared actions: their coalesced feedback
    sent: bool = False  # the goal went out (its server is watched from then on)
    unmatched: float | None = None  # monotonic time its server was first seen unmatched


class GoalClient(Node):
    """The behaviours of a member as action goals; the member node (`MemberNode`) provides
    the engine, the interface types, the event queue (`deliver`), the scheduler and the
    error list."""

    engine: Engine
    interfaces: Interfaces
    member_id: str
    scheduler: Scheduler
    errors: list[str]

    def _init_goals(self, behaviours: Mapping[str, BehaviourSpec], check_outcomes: bool) -> None:
        """One action client per behaviour; `check_outcomes`: an undeclared outcome fails."""
        interfaces = self.interfaces
        self._behaviours = behaviours
        self._check_outcomes = check_outcomes
        self.results: set[bytes] = set()  # goal ids whose result arrived
        self.pending_requests = 0  # goals sent, no answer yet
        self.pending_cancels = 0
        self._runs: dict[str, _Run] = {}
        # declared interfaces: checked and imported now (BindingError: the node cannot start)
        self._declared: dict[str, Resolved] = {
            name: resolve(b) for name, b in sorted(behaviours.items()) if b.binding is not None
        }
        # (state, behaviour, feedback as plain values) of declared actions, the latest
        self.feedback: deque[tuple[str, str, Any]] = deque(maxlen=FEEDBACK_KEPT)
        # the coalesced feedback records go to these (the launcher's --trace, a bag recorder)
        self.on_feedback: list[Callable[[FeedbackRecord], None]] = []
        self._hook_tracer()
        self.action_timeouts = {
            name: self._declare_timeout(item)
            for name, item in self._declared.items()
            if item.binding.kind == "action"
        }
        answer: Any = self.declare_parameter(ANSWER_PARAMETER, ANSWER_TIMEOUT_S).value
        self.answer_timeout = max(0.0, float(answer))
        self.action_clients: dict[str, ActionClient[Any, Any, Any]] = {}
        for name, b in sorted(behaviours.items()):
            item = self._declared.get(name)
            if item is None:
                self.action_clients[name] = ActionClient(
                    self, interfaces.action(b.action), b.ros_name
                )
            elif item.binding.kind == "action":
                self.action_clients[name] = ActionClient(self, item.type, item.binding.ros_name)
        others = {n: r for n, r in self._declared.items() if r.binding.kind != "action"}
        self.declared_calls = DeclaredCalls(
            self, self.scheduler, others, self._finish_declared, self.errors
        )
        self.server_watch = ServerWatch(self, self._watch_servers)
        self.declared_calls.on_sent = self.server_watch.wake

    def _hook_tracer(self) -> None:
        """A tracer (`MemberOptions.tracer`) with a `feedback(member, record)` method (the bag
        recorder) also gets the feedback records."""
        tracer = getattr(getattr(self, "options", None), "tracer", None)
        hook = getattr(tracer, "feedback", None)
        if callable(hook):
            self.on_feedback.append(lambda record: hook(self, record))

    def _declare_timeout(self, item: Resolved) -> float:
        """`behaviours.<key>.timeout_s` of a declared action (default: none, 0)."""
        default = item.binding.timeout_s
        if default is None:
            default = DEFAULT_TIMEOUTS["action"]
        value: Any = self.declare_parameter(item.parameter, float(default)).value
        return max(0.0, float(value))

    def deliver(self, event: SwarmEvent) -> None:
        """Queue an event for the engine (the member node's)."""
        raise NotImplementedError

    def servers_ready(self) -> bool:
        """Every behaviour's action server is up."""
        clients = self.action_clients.values()
        return all(c.server_is_ready() for c in clients) and self.declared_calls.ready()

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

    def _goals_idle(self) -> bool:
        """Every goal was answered (accepted or finished), every cancel request too."""
        return (
            self.pending_requests == 0
            and self.pending_cancels == 0
            and all(run.handle is not None or run.finished for run in self._runs.values())
            and self.declared_calls.idle()
        )

    def _cancel_runs(self) -> None:
        for run in list(self._runs.values()):
            self._cancel(run)
        self._runs.clear()
        self.declared_calls.cancel_all()

    def start_call(
        self, node: ChartNode, call: Call, args: dict[str, Any], activation: int
    ) -> None:
        """Send the goal of the behaviour a state runs (the engine's host interface)."""
        behaviour = self._behaviours.get(call.behaviour)
        if behaviour is None:
            self.errors.append(f"no action for behaviour {call.behaviour}")
            return
        if self.declared_calls.handles(behaviour.name):
            self.declared_calls.start(node, behaviour.name, args, activation)
            return
        item = self._declared.get(behaviour.name)
        try:
            goal = self._goal(behaviour, item, args)
        except ConversionError as err:
            label = item.label if item is not None else f"{self.interfaces.package}/action/"
            label += "" if item is not None else behaviour.action
            self._abort_later(node, activation, behaviour, f"cannot send {label}: {err}")
            return
        run = _Run(node, activation, behaviour, goal)
        self._runs[node.id] = run
        timeout = self.action_timeouts.get(behaviour.name, 0.0)
        if timeout > 0:
            run.deadline = self.scheduler.call_later(timeout, lambda: self._timed_out(run))
        self._send_goal(run)

    def _goal(
        self, behaviour: BehaviourSpec, item: Resolved | None, args: Mapping[str, Any]
    ) -> Any:
        """The goal message, converted strictly (ConversionError: a value does not fit)."""
        if item is not None:
            return build(item.request, assignments(item, args), behaviour.name)
        goal_type = self.interfaces.action(behaviour.action).Goal
        return goal_type(
            **{
                f.field: to_ros(f.type, args.get(f.name), f.renames, f"{behaviour.name}.{f.name}")
                for f in behaviour.inputs
            }
        )

    def _timed_out(self, run: _Run) -> None:
        """`timeout_s` passed: the goal is cancelled and the behaviour ends `aborted`."""
        run.deadline = None
        if run.cancelled or run.finished or self._runs.get(run.node.id) is not run:
            return
        limit = self.action_timeouts.get(run.behaviour.name, 0.0)
        self.get_logger().warning(
            f"behaviour {run.behaviour.name} in {run.node.id}: no result from "
            f"{run.behaviour.ros_name!r} within {limit:g} s: goal cancelled"
        )
        self._cancel(run)
        self._outcome(run, "aborted", {})

    def _no_answer(self, run: _Run) -> None:
        """The server did not accept or reject the goal in time: `aborted` (a member error)."""
        run.answer_deadline = None
        if run.answered:
            return
        run.answered = True  # a late answer is ignored (an accepted goal is cancelled then)
        self.pending_requests -= 1
        if run.cancelled or self._runs.get(run.node.id) is not run:
            return
        text = (
            f"goal of {run.behaviour.name} in {run.node.id} not answered by "
            f"{run.behaviour.ros_name!r} within {self.answer_timeout:g} s"
        )
        self.errors.append(text)
        self.get_logger().error(text)
        self._cancel(run)
        self._outcome(run, "aborted", {})

    def _abort_later(
        self, node: ChartNode, activation: int, behaviour: BehaviourSpec, reason: str
    ) -> None:
        """The behaviour cannot start: it ends `aborted` from the executor (not inside the
        engine's step), with the reason logged and kept as a member error."""
        text = f"behaviour {behaviour.name} in {node.id}: {reason}"
        self.errors.append(text)
        self.get_logger().error(text)
        self.scheduler.call_later(
            0.0, lambda: self._finish_declared(node, activation, behaviour.name, "aborted", {})
        )

    def _finish_declared(
        self,
        node: ChartNode,
        activation: int,
        behaviour: str,
        outcome: str,
        outputs: dict[str, Any],
    ) -> None:
        run = _Run(node, activation, self._behaviours[behaviour], None)
        if self._undeclared(run, outcome):
            outcome, outputs = "aborted", {}
        self._outcome(run, outcome, outputs)

    def cancel_call(self, node: ChartNode, activation: int) -> None:
        """The state was left: cancel its goal (the engine's host interface)."""
        run = self._runs.pop(node.id, None)
        if run is not None:
            self._cancel(run)
        self.declared_calls.cancel(node.id)

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
        lockstep.sent(self.scheduler, "goal")
        future = client.send_goal_async(
            run.goal, feedback_callback=lambda feedback: self._on_feedback(run, feedback)
        )
        if self.answer_timeout > 0:
            run.answer_deadline = self.scheduler.call_later(
                self.answer_timeout, lambda: self._no_answer(run)
            )
        future.add_done_callback(lambda f: self._on_goal_response(run, f))
        run.sent = True
        self.server_watch.wake()

    def _watch_servers(self, now: float, limit: float) -> bool:
        """A `ServerWatch` round over the sent goals and the service calls; True while any
        is still on its way."""
        busy = False
        for run in list(self._runs.values()):
            if not run.sent or run.finished or run.cancelled:
                continue
            ready = self.action_clients[run.behaviour.name].server_is_ready()
            run.unmatched = unmatched_since(run.unmatched, ready, now)
            if not lost(run.unmatched, now, limit):
                busy = True
            else:
                self._server_lost(run, limit)
        return self.declared_calls.watch(now, limit) or busy

    def _server_lost(self, run: _Run, limit: float) -> None:
        """The goal's server is gone: `aborted` and a member error, as a server-side abort."""
        item = self._declared.get(run.behaviour.name)
        ros_name = item.binding.ros_name if item is not None else run.behaviour.ros_name
        name = self.resolve_service_name(ros_name)  # actions expand as services do
        text = (
            f"behaviour {run.behaviour.name} in {run.node.id}: action server {name!r} lost "
            f"(not matched for {limit:g} s): aborted"
        )
        self.errors.append(text)
        self.get_logger().error(text)
        if not run.answered:  # a late answer is ignored (an accepted goal is cancelled then)
            run.answered = True
            self.pending_requests -= 1
        run.cancelled = run.finished = True  # a server that comes back does not resume it
        self._outcome(run, "aborted", {})

    def _on_feedback(self, run: _Run, feedback: Any) -> None:
        if run.behaviour.name not in self._declared:
            self.get_logger().debug(f"feedback: {feedback.feedback.status}")
            return
        values = plain(feedback.feedback)
        self.feedback.append((run.node.id, run.behaviour.name, values))
        self.get_logger().debug(f"feedback of {run.behaviour.name}: {json.dumps(values)}")
        if run.feedback is None:
            emit = lambda values, count: self._emit_feedback(run, values, count)  # noqa: E731
            run.feedback = FeedbackGate(self.scheduler, emit)
        if not (run.cancelled or run.finished):
            run.feedback.add(values)

    def _emit_feedback(self, run: _Run, values: Any, count: int) -> None:
        """One coalesced feedback record to the `on_feedback` hooks."""
        record = FeedbackRecord(
            self.member_id, run.node.id, run.behaviour.name, values, count, time.time()
        )
        for hook in list(self.on_feedback):
            hook(record)

    def _on_goal_response(self, run: _Run, future: Future[Any]) -> None:
        lockstep.received(self.scheduler, "goal_response")
        if run.answered:  # too late: the behaviour ended already
            handle = future.result() if future.exception() is None else None
            if handle is not None and handle.accepted:
                run.handle = handle
                self._cancel_goal(run)
            return
        run.answered = True
        if run.answer_deadline is not None:
            run.answer_deadline.cancel()
            run.answer_deadline = None
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
        lockstep.received(self.scheduler, "result")
        if run.feedback is not None and not run.cancelled:
            run.feedback.flush()  # the last feedback comes before the outcome
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
        status = STATUS_OUTCOMES.get(response.status, "aborted")
        item = self._declared.get(run.behaviour.name)
        outcome = outcome_of(item, result, status) if item else (result.outcome or status)
        if self._undeclared(run, outcome):
            self._outcome(run, "aborted", {})
            return
        if item is not None:
            self._outcome(run, outcome, outputs_of(item, result))
            return
        outputs: dict[str, Any] = {}
        for output in run.behaviour.outputs:
            present, value = decode(
                output.type, getattr(result, output.field), output.renames, output.enums
            )
            if present:
                outputs[output.name] = value
        self._outcome(run, outcome, outputs)

    def _undeclared(self, run: _Run, outcome: str) -> bool:
        """The behaviour does not declare `outcome` (a member error: it ends `aborted`)."""
        declared = run.behaviour.outcomes
        if self._check_outcomes and declared and outcome not in declared:
            self.errors.append(
                f"behaviour {run.behaviour.name} in {run.node.id} failed: "
                f"returned the undeclared outcome {outcome[:80]!r}"
            )
            return True
        return False

    def _outcome(self, run: _Run, outcome: str, outputs: Mapping[str, Any]) -> None:
        _stop_timers(run)
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
        _stop_timers(run, answer=False)  # a goal on its way is still bounded by its answer
        if run.handle is not None and not run.finished:
            self._cancel_goal(run)

    def _cancel_goal(self, run: _Run) -> None:
        self.pending_cancels += 1
        lockstep.sent(self.scheduler, "cancel")

        def answered(_: Future[Any]) -> None:
            self.pending_cancels -= 1
            lockstep.received(self.scheduler, "cancel")

        run.handle.cancel_goal_async().add_done_callback(answered)


def _stop_timers(run: _Run, *, answer: bool = True) -> None:
    """Cancel a run's retry, its deadlines (`answer`: also the goal answer's) and feedback."""
    for handle in (run.retry, run.deadline, run.answer_deadline if answer else None):
        if handle is not None:
            handle.cancel()
    run.retry = run.deadline = None
    if answer:
        run.answer_deadline = None
    if run.feedback is not None:
        run.feedback.drop()
