"""Replay one member node against scenarios on real rclpy (`swarmgen replay --backend rclpy`).

    python -m <swarm>_nodes._ros.replay <swarm>_nodes.<member module> scenarios.json

The member runs as it does in a swarm (a `MemberNode`: events from `/swarm/events`, behaviours
as action goals), isolated: what it sends does not come back and model timers do not fire,
as in `runtime.replay`. Station events of a scenario are published on `/swarm/events`; each
behaviour is a scripted server (`servers.ScriptedServers`: its private action, or its declared
action, service or topic) whose goals end when the scenario says so (`complete`), with the
given outcome and outputs. Before the next input the harness waits until the member is idle
(a service request the driver holds counts as idle, as an accepted goal does).

The rules follow `runtime.replay` exactly, so the traces equal the other backends':
- the steps of a `burst` are resolved (which state a `complete` ends) before any of them is
  processed, then processed in order;
- a `complete` whose goal is no longer running (it already ended, or it was cancelled in the
  same burst) delivers the outcome event directly, tagged with the activation it was resolved
  against, as the asyncio replay does;
- a ROS result carries every output: outputs a `complete` step leaves out hold the field's zero
  value, which is what every backend writes for an output a behaviour does not give (the value
  rule, docs/semantics.md); JSON outputs are left empty (absent: the zero of their type).
- a `complete` that a declared interface cannot carry (an outcome with no field for it, an
  output its field cannot hold), or that cannot be told apart from another (two states waiting
  on one topic), is delivered directly too: the trace stays that of every other backend.

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
from rclpy.context import Context as RosContext
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from ...runtime.chart import fill, zero_like
from ...runtime.replay import describe, expand, outcome_event, running_state
from .messages import EVENTS_QOS, SWARM_TOPIC, Interfaces
from .node import MemberNode, MemberOptions
from .process import spin_until
from .scheduler import Scheduler
from .served import Served
from .servers import ScriptedServers
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
        self.goals: dict[Any, Served] = {}  # running goals (accepted) by `Served.key`
        self.next_id = 0
        self.started = 0  # goals the servers accepted
        self._publisher = self.create_publisher(self.interfaces.Event, SWARM_TOPIC, EVENTS_QOS)
        self.servers = ScriptedServers(self, self.interfaces, spec, self._accepted, self._withdrawn)

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

    def _accepted(self, behaviour: BehaviourSpec, served: Served) -> None:
        self.started += 1
        self.goals[served.key] = served

    def finish(self, goal: Any, ending: tuple[str, Any] | None) -> None:
        """End a running goal with (outcome, its answer), or as cancelled (`None`)."""
        served = self.goals.pop(goal, None)
        if served is None:
            return

        def decide(cancel_requested: bool) -> tuple[str | None, Any]:
            if ending is None or cancel_requested:
                return None, served.cancelled()
            return ending

        served.finish(decide)

    def _withdrawn(self, key: Any) -> None:
        if key in self.goals:  # after rclpy marked the goal as canceling
            self.scheduler.call_later(0.0, partial(self.finish, key, None))


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
        self.member.declared_calls.held = lambda name, number: (name, number) in self.driver.goals
        self.stats = {"goals": 0, "results": 0, "direct": 0, "events": 0}
        self._topic_waits = sorted(
            name
            for name, b in spec.behaviours.items()
            if b.binding is not None and b.binding.direction == "subscribe"
        )
        self.executor.add_node(self.driver)
        self.executor.add_node(self.member)
        self.settle(
            lambda: (
                self.member.servers_ready()
                and self.driver.subscribed()
                and self.driver.servers.matched()
            )
        )

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
                condition()
                and member.idle()
                and all(goal in self.driver.goals for goal in running)
                and all(self.driver.servers.activation(s) is not None for s in self._waiting())
            )

        if not spin_until(self.executor, quiet, SETTLE_TIMEOUT, 0.05):
            raise ReplayTimeout(
                f"the member did not settle in {SETTLE_TIMEOUT} s (active {self.member.active()})"
            )

    def run(self, steps: Sequence[Step]) -> list[dict[str, Any]]:
        """Replay one scenario from a fresh member; its trace (one record per step)."""
        member = self.member
        member.reset()
        self.driver.servers.forget()  # the activations of the last scenario's topic waits
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
        return node.id, self.member.engine.activation(node.id), self._key(node.id)

    def _key(self, state: str) -> Any:
        """The driver's key of the goal a state runs now (None: none the driver can end)."""
        member = self.member
        handle = member.running_goal(state)
        if handle is not None:
            return bytes(handle.goal_id.uuid)
        call = member.declared_calls.running(state)
        if call is None:
            return None
        behaviour = self._behaviour(state)
        if call[1] > 0:  # a service request, numbered as the driver numbers its arrivals
            return behaviour.name, call[1]
        waiting = [s for s in self._waiting() if self._behaviour(s).name == behaviour.name]
        return self.driver.servers.activation(state) if waiting == [state] else None

    def _waiting(self) -> list[str]:
        """The states whose behaviour waits for a message of a topic the driver publishes."""
        member = self.member
        return [
            state
            for name in self._topic_waits
            for state in self.driver.servers.states_of(name)
            if member.declared_calls.running(state) is not None
        ]

    def _behaviour(self, state: str) -> BehaviourSpec:
        node = self.member.engine.chart.nodes[state]
        assert node.call is not None
        return self.spec.behaviours[node.call.behaviour]

    def _filled(self, state: str, outputs: dict[str, Any]) -> dict[str, Any]:
        """Data-type outputs filled with their zeros (the value rule) before they go into a ROS
        answer, given or not: a field the step leaves out must reach the member as the model's
        zero, not as its message's default (geometry_msgs/Quaternion's `w` is 1), and a ROS
        answer always carries the whole output."""
        engine = self.member.engine
        call = engine.chart.nodes[state].call
        for output, key in call.results if call is not None else ():
            value, zero = outputs.get(output), zero_like(engine.chart.data.get(key))
            if isinstance(zero, Mapping) and (value is None or isinstance(value, Mapping)):
                outputs[output] = fill(value, zero)
        return outputs

    def _submit(self, step: Step, target: tuple[str, int, bytes | None] | None) -> None:
        member = self.member
        if "wait" in step:  # time passes; model timers and delayed raises are off here
            return
        if "complete" not in step:
            sent = self.driver.publish(str(step["event"]), step.get("data"))
            self.stats["events"] += 1
            self.settle(lambda: member.seen.get("station", 0) >= sent)
            return
        if target is None:
            return
        state, activation, goal = target
        outcome = str(step.get("outcome", "succeeded"))
        outputs = self._filled(state, dict(step.get("outputs") or {}))
        served = self.driver.goals.get(goal) if goal is not None else None
        answer = None
        if served is not None and self._key(state) == goal:
            try:  # an output its field cannot hold: delivered directly (the given value)
                answer = served.answer(outcome, outputs)
            except ValueError:
                served = None
        else:
            served = None
        if served is None:
            node = member.engine.chart.nodes[state]
            member.deliver(
                member.engine.make_event(
                    outcome_event(node, outcome), outputs, MEMBER_ID, origin=(state, activation)
                )
            )
            self.stats["direct"] += 1
            self.settle()
            return
        before = member.declared_calls.running(state)
        self.driver.finish(goal, (outcome, answer))
        self.stats["results"] += 1
        if isinstance(goal, bytes):  # an action's result
            self.settle(lambda: goal in member.results)
        else:  # a response or message ends the member's call
            self.settle(lambda: member.declared_calls.running(state) != before)

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
