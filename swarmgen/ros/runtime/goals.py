"""The action-client side of a member node: the behaviour a state runs is a ROS 2 goal.

Entering the state sends the goal (waiting for its server to appear), leaving it cancels the
goal, and the result (`outcome` + outputs) becomes the event `done.invoke.<state>.<outcome>`,
tagged with the activation so that late results of cancelled goals are dropped.
"""

from __future__ import annotations

import json
import time
from collections import deque
from collections.abc import Mapping
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
from .bindings import Resolved, assignments, outcome_of, outputs_of, resolve
from .convert import ConversionError, build, plain
from .declared import DeclaredCalls
from .messages import Interfaces, decode, encode
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
        # (state, behaviour, feedback as plain values) of declared actions, for traces
        self.feedback: deque[tuple[str, str, Any]] = deque(maxlen=FEEDBACK_KEPT)
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
        if item is None:
            goal_type = self.interfaces.action(behaviour.action).Goal
            goal = goal_type(
                **{f.field: encode(f.type, args.get(f.name), f.renames) for f in behaviour.inputs}
            )
        else:
            try:
                goal = build(item.request, assignments(item, args), behaviour.name)
            except ConversionError as err:
                self._abort_later(node, activation, behaviour, f"cannot send {item.label}: {err}")
                return
        run = _Run(node, activation, behaviour, goal)
        self._runs[node.id] = run
        self._send_goal(run)

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
        future = client.send_goal_async(
            run.goal, feedback_callback=lambda feedback: self._on_feedback(run, feedback)
        )
        future.add_done_callback(lambda f: self._on_goal_response(run, f))

    def _on_feedback(self, run: _Run, feedback: Any) -> None:
        if run.behaviour.name not in self._declared:
            self.get_logger().debug(f"feedback: {feedback.feedback.status}")
            return
        values = plain(feedback.feedback)
        self.feedback.append((run.node.id, run.behaviour.name, values))
        self.get_logger().debug(f"feedback of {run.behaviour.name}: {json.dumps(values)}")

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
            present, value = decode(output.type, getattr(result, output.field), output.renames)
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
