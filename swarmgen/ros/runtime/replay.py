"""Replay one member node against scenarios on real rclpy (`swarmgen replay --backend rclpy`).

    python -m <swarm>_nodes._ros.replay <swarm>_nodes.<member module> scenarios.json

The member runs as it does in a swarm (a `MemberNode`: events from `/swarm/events`, behaviours
as action goals), isolated: what it sends does not come back and model timers do not fire,
as in `runtime.replay`. Station events of a scenario are published on `/swarm/events`; each
behaviour is an action server whose goals end when the scenario says so (`complete`), with the
given outcome and outputs. Before the next input the harness waits until the member is idle.

The rules follow `runtime.replay` exactly, so the traces equal the other backends':
- the steps of a `burst` are resolved (which state a `complete` ends) before any of them is
  processed, then processed in order;
- a `complete` whose goal is no longer running (it already ended, or it was cancelled in the
  same burst) delivers the outcome event directly, tagged with the activation it was resolved
  against, as the asyncio replay does;
- a ROS result carries every output: outputs a `complete` step leaves out hold the field's zero
  value, which is what every backend writes for an output a behaviour does not give (the value
  rule, docs/semantics.md); JSON outputs are left empty (absent: the zero of their type).

One JSON line per scenario is printed: `{"scenario": n, "trace": [...], "stats": {...}}`; the
stats count (cumulatively) the goals the servers executed, the outcomes that came back as ROS
results, those delivered directly, and the events published.
"""

from __future__ import annotations

import importlib
import json
import sys
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import rclpy
from rclpy.action.server import CancelResponse
from rclpy.context import Context as RosContext
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from ...runtime.replay import describe, expand, outcome_event, running_state
from .messages import EVENTS_QOS, SWARM_TOPIC, Interfaces, encode
from .node import MemberNode, MemberOptions
from .process import spin_until
from .scheduler import Scheduler
from .servers import scripted_servers
from .spec import BehaviourSpec, MemberSpec

NAMESPACE = "/replay"
MEMBER_ID = "replay"
SETTLE_TIMEOUT = 20.0

Step = Mapping[str, Any]


class ReplayTimeout(RuntimeError):
    """The member did not become idle."""


class Driver(Node):
    """The station (events) and the behaviours (action servers that wait for the scenario)."""

    def __init__(self, spec: MemberSpec, context: RosContext) -> None:
        super().__init__("replay_driver", namespace=NAMESPACE, context=context)
        self.interfaces = Interfaces(spec.interfaces)
        self.scheduler = Scheduler(self)
        self.goals: dict[bytes, tuple[Any, BehaviourSpec]] = {}  # running goals (accepted)
        self.next_id = 0
        self.started = 0  # goals the servers accepted
        self._publisher = self.create_publisher(self.interfaces.Event, SWARM_TOPIC, EVENTS_QOS)
        self.servers = scripted_servers(
            self, self.interfaces, spec.behaviours, self._accepted, self._on_cancel
        )

    def publish(self, name: str, data: Any) -> int:
        """Publish a station event; its id."""
        self.next_id += 1
        stamp = self.get_clock().now().nanoseconds / 1e9
        text = json.dumps(data if data is not None else {})
        self._publisher.publish(self.interfaces.event(self.next_id, stamp, "station", name, text))
        return self.next_id

    def subscribed(self) -> bool:
        """The member hears the station."""
        return self._publisher.get_subscription_count() > 0

    def _accepted(self, behaviour: BehaviourSpec, handle: Any) -> None:
        self.started += 1
        self.goals[bytes(handle.goal_id.uuid)] = (handle, behaviour)

    def finish(self, goal: bytes, ending: tuple[str, dict[str, Any]] | None) -> None:
        """End a running goal with (outcome, result fields), or as cancelled (`None`)."""
        entry = self.goals.pop(goal, None)
        if entry is None:
            return
        handle, behaviour = entry
        action = self.interfaces.action(behaviour.action)

        def result(handle: Any) -> Any:
            if ending is None or handle.is_cancel_requested:
                handle.canceled()
                return action.Result(outcome="preempted")
            outcome, fields = ending
            if outcome == "aborted":
                handle.abort()
            else:
                handle.succeed()
            return action.Result(outcome=outcome, **fields)

        handle.execute(result)

    def _on_cancel(self, handle: Any) -> CancelResponse:
        key = bytes(handle.goal_id.uuid)
        if key in self.goals:  # after rclpy marked the goal as canceling
            self.scheduler.call_later(0.0, partial(self.finish, key, None))
        return CancelResponse.ACCEPT


class Replay:
    """One member node and its driver, replaying scenario after scenario."""

    def __init__(self, spec: MemberSpec, context: RosContext) -> None:
        self.spec = spec
        self.executor = SingleThreadedExecutor(context=context)
        self.driver = Driver(spec, context)
        self.member = MemberNode(
            spec,
            namespace=NAMESPACE,
            options=MemberOptions(
                member_id=MEMBER_ID, isolated=True, timers=False, check_outcomes=False
            ),
            scheduler=self.driver.scheduler,
            context=context,
        )
        self.stats = {"goals": 0, "results": 0, "direct": 0, "events": 0}
        self.executor.add_node(self.driver)
        self.executor.add_node(self.member)
        self.settle(lambda: self.member.servers_ready() and self.driver.subscribed())

    def close(self) -> None:
        """Stop the member and destroy the nodes."""
        self.member.stop()
        self.executor.shutdown()
        self.member.destroy_node()
        self.driver.destroy_node()

    def settle(self, condition: Callable[[], bool] = lambda: True) -> None:
        """Spin until `condition` holds and the member is idle (ReplayTimeout otherwise)."""

        def quiet() -> bool:
            member = self.member
            running = member.running_goal_ids()
            return (
                condition() and member.idle() and all(goal in self.driver.goals for goal in running)
            )

        if not spin_until(self.executor, quiet, SETTLE_TIMEOUT, 0.05):
            raise ReplayTimeout(
                f"the member did not settle in {SETTLE_TIMEOUT} s (active {self.member.active()})"
            )

    def run(self, steps: Sequence[Step]) -> list[dict[str, Any]]:
        """Replay one scenario from a fresh member; its trace (one record per step)."""
        member = self.member
        member.reset()
        member.start()
        self.settle()
        trace = [self._record(0, None)]
        for number, step in enumerate(steps, start=1):
            items = expand(step)
            targets = [self._resolve(item) if "complete" in item else None for item in items]
            for item, target in zip(items, targets, strict=True):
                self._submit(item, target)
            trace.append(self._record(number, step))
        member.stop()
        self.settle()
        return trace

    def _resolve(self, step: Step) -> tuple[str, int, bytes | None] | None:
        chart = self.member.engine.chart
        node = running_state(
            chart, set(self.member.active()), str(step["complete"]), step.get("state")
        )
        if node is None:
            return None  # nothing runs that behaviour now: the step has no effect
        handle = self.member.running_goal(node.id)
        goal = bytes(handle.goal_id.uuid) if handle is not None else None
        return node.id, self.member.engine.activation(node.id), goal

    def _submit(self, step: Step, target: tuple[str, int, bytes | None] | None) -> None:
        member = self.member
        if "complete" not in step:
            sent = self.driver.publish(str(step["event"]), step.get("data"))
            self.stats["events"] += 1
            self.settle(lambda: member.seen.get("station", 0) >= sent)
            return
        if target is None:
            return
        state, activation, goal = target
        outcome = str(step.get("outcome", "succeeded"))
        outputs = dict(step.get("outputs") or {})
        handle = member.running_goal(state)
        current = bytes(handle.goal_id.uuid) if handle is not None else None
        if goal is None or current != goal or goal not in self.driver.goals:
            node = member.engine.chart.nodes[state]
            member.deliver(
                member.engine.make_event(
                    outcome_event(node, outcome), outputs, MEMBER_ID, origin=(state, activation)
                )
            )
            self.stats["direct"] += 1
            self.settle()
            return
        self.driver.finish(goal, (outcome, self._fields(state, outputs)))
        self.stats["results"] += 1
        self.settle(lambda: goal in member.results)

    def _fields(self, state: str, outputs: Mapping[str, Any]) -> dict[str, Any]:
        """The result fields for the outputs of a `complete` step (see the module docstring)."""
        node = self.member.engine.chart.nodes[state]
        assert node.call is not None
        behaviour = self.spec.behaviours[node.call.behaviour]
        return {
            output.field: encode(output.type, outputs[output.name])
            for output in behaviour.outputs
            if output.name in outputs
        }

    def _record(self, number: int, step: Step | None) -> dict[str, Any]:
        return {
            "step": number,
            "input": describe(step) if step is not None else None,
            "active": self.member.active(),
            "data": json.loads(json.dumps(self.member.engine.data, default=str)),
            "errors": self.member.engine.error_count,
        }


def main(argv: Sequence[str] | None = None) -> int:
    """`python -m <package>._ros.replay MODULE SCENARIOS`: one JSON line per scenario."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 2:
        print(
            "usage: python -m <package>._ros.replay <member module> <scenarios.json>",
            file=sys.stderr,
        )
        return 2
    module = importlib.import_module(args[0])
    spec: MemberSpec = module.SPEC
    scenarios = json.loads(Path(args[1]).read_text(encoding="utf-8"))
    context = RosContext()
    rclpy.init(args=["replay"], context=context)
    replay = Replay(spec, context)
    try:
        for number, steps in enumerate(scenarios):
            trace = replay.run(steps)
            replay.stats["goals"] = replay.driver.started
            line = {"scenario": number, "trace": trace, "stats": replay.stats}
            print(json.dumps(line), flush=True)
    except ReplayTimeout as err:
        print(f"replay: {err}", file=sys.stderr)
        return 1
    finally:
        replay.close()
        rclpy.try_shutdown(context=context)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
