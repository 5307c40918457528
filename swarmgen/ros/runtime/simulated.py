"""Simulated behaviours as ROS 2 servers: one server per behaviour in each member's namespace,
of the behaviour's private action or of its declared interface (`servers.ScriptedServers`),
driven by a script (the ROS counterpart of `runtime.simulated`).

A script maps behaviour names to what a goal does (times are simulated seconds, multiplied by
the time scale):

    {"behaviours": {
       "TakeOff":  {"duration": 2.0},
       "Coverage": {"forever": true},
       "TargetMonitoring": {"forever": true, "every": {"period": 4.0, "emit": [
           {"event": "targetFound", "data": {"target_id": "${member.index * 100 + tick}"}}]}},
       "TaskBidding": {"duration": 5.0, "outcome": "aborted", "until": {
           "event": "targetAssigned", "when": "event.target_id == goal.target_id",
           "outcome": "${'succeeded' if event.rover_id == member.index else 'aborted'}"}}},
     "member_types": {"UGV": {"behaviours": {...}}}}

- `duration`, `outcome` (default "succeeded"), `outputs` and `emit` (events published when the
  goal ends): the goal ends after `duration` unless `forever` (then only preemption ends it).
- `every`: while the goal runs, emit events every `period` (first after `start`, default
  `period`) when `when` holds (always if absent); `tick` counts the periods.
- `until`: end early when a swarm event named `event` arrives and `when` holds; `outcome`,
  `outputs` and `emit` of the `until` block then apply.
- Strings of the form `"${expression}"` are computed; `${...}` inside a longer string is
  replaced by the value's text. Expressions are a small, safe subset of Python (literals,
  arithmetic, comparisons, `and`/`or`/`not`, `x if c else y`, attribute access and
  `min max abs round int float str len`) over the names `goal` (the goal's inputs), `member`
  (`id`, `index`, `type`), `swarm` (members per type), `count` (goals this server started),
  `tick`, and in `until` also `event` (the event's data) and `sender`.
Events are published on behalf of the member (sender = member id) with ids from 2**40 up, so
they never collide with the ids of the member's own events.

A declared interface carries the same script (docs/ros2.md, "Simulated and replayed behaviours
on declared interfaces"): the goal, request or the state's entry starts it; the outcome becomes
the goal status, the `success` field or the binding's outcome field, the outputs the fields the
binding maps; an outcome or output the interface cannot carry is a script failure.
"""

from __future__ import annotations

import itertools
import json
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import rclpy
from rclpy.context import Context as RosContext
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter as RosParameter

from ...runtime.chart import Record, record
from .expressions import ScriptError, evaluate, render
from .messages import (
    EVENTS_QOS,
    LOCAL_TOPIC,
    SWARM_TOPIC,
    Interfaces,
)
from .process import init_process, spin_until
from .scheduler import Handle, Scheduler
from .scripts import Emission, Ending, Periodic, Script, Until, load_scripts
from .served import Served
from .servers import ScriptedServers
from .spec import BehaviourSpec, MemberSpec, index_of, namespace_id

EMITTED_ID_BASE = 1 << 40


# --- the servers


@dataclass(eq=False)
class _Goal:
    served: Served
    behaviour: BehaviourSpec
    names: dict[str, Any]
    timers: list[Handle] = field(default_factory=list)
    until: Until | None = None
    done: bool = False


class SimulatedBehaviours(Node):
    """The scripted action servers of one member (node `simulated_behaviours` in its namespace).

    Parameters: `member_type`, `member_id`, `member_index`, `script` (a JSON file, optional),
    `time_scale` and `swarm` (JSON object: members per type), when not given to the constructor.
    """

    def __init__(
        self,
        specs: Mapping[str, MemberSpec],
        defaults: Mapping[str, Mapping[str, Any]],
        events: Mapping[str, tuple[str, str]],
        *,
        member_type: str | None = None,
        member_id: str | None = None,
        member_index: int | None = None,
        swarm: Mapping[str, int] | None = None,
        script: Mapping[str, Any] | str | None = None,
        time_scale: float = 1.0,
        namespace: str = "",
        scheduler: Scheduler | None = None,
        context: RosContext | None = None,
        parameter_overrides: Sequence[RosParameter[Any]] = (),
    ) -> None:
        super().__init__(
            "simulated_behaviours",
            namespace=namespace,
            context=context,
            parameter_overrides=list(parameter_overrides),
        )
        self._declare_member(specs, member_type, member_id, member_index)
        self.time_scale = float(self.declare_parameter("time_scale", float(time_scale)).value)
        counts = json.dumps(dict(swarm or {}))
        self.swarm = Record(json.loads(str(self.declare_parameter("swarm", counts).value)))
        script_param = str(self.declare_parameter("script", "").value)
        source = script if script is not None else (script_param or None)
        self.scripts = load_scripts(defaults, self.spec.chart_name, source)
        self.events = dict(events)
        self.interfaces = Interfaces(self.spec.interfaces)
        self.scheduler = scheduler if scheduler is not None else Scheduler(self)
        self.started: list[tuple[str, str]] = []  # (behaviour, "started" | outcome)
        self.errors: list[str] = []  # script failures (each aborted a goal or an emission)
        self._ids = itertools.count(EMITTED_ID_BASE)
        self._counts: dict[str, int] = {}
        self._goals: dict[Any, _Goal] = {}  # by `Served.key`
        self._create_endpoints()

    def _declare_member(
        self,
        specs: Mapping[str, MemberSpec],
        member_type: str | None,
        member_id: str | None,
        member_index: int | None,
    ) -> None:
        """Which member this node simulates (type, id, index), as ROS parameters."""
        default_type = member_type or next(iter(specs))
        self.member_type = str(self.declare_parameter("member_type", default_type).value)
        if self.member_type not in specs:
            raise ScriptError(f"unknown member type {self.member_type!r}: {sorted(specs)}")
        self.spec = specs[self.member_type]
        default_id = namespace_id(self.get_namespace(), self.spec.node_name)
        self.member_id = str(self.declare_parameter("member_id", member_id or default_id).value)
        index = member_index or index_of(self.member_id)
        self.member_index = int(self.declare_parameter("member_index", index).value)

    def _create_endpoints(self) -> None:
        """The event publishers, the swarm subscription (for `until`), one server per behaviour."""
        event_type = self.interfaces.Event
        self.swarm_publisher = self.create_publisher(event_type, SWARM_TOPIC, EVENTS_QOS)
        self._local = self.create_publisher(event_type, LOCAL_TOPIC, EVENTS_QOS)
        if any(s.until is not None for s in self.scripts.values()):
            self.create_subscription(event_type, SWARM_TOPIC, self._on_event, EVENTS_QOS)
        self.servers = ScriptedServers(
            self, self.interfaces, self.spec, self._accepted, self._withdrawn
        )

    def _accepted(self, behaviour: BehaviourSpec, served: Served) -> None:
        """A goal starts; if starting it fails, it is aborted (an exception here would leave
        rclpy's executor, and stop every node of the process)."""
        try:
            self._start(behaviour, served)
        except Exception as err:
            self._failed(f"{behaviour.name}: the goal could not start: {err!r}")
            goal = self._goals.get(served.key) or _Goal(served, behaviour, {})
            self._finish(goal, Ending(outcome="aborted"))

    def _start(self, behaviour: BehaviourSpec, served: Served) -> None:
        """A goal starts: its end is scheduled (duration, `until`), its emissions too."""
        script = self.scripts.get(behaviour.name) or Script(forever=True)
        count = self._counts[behaviour.name] = self._counts.get(behaviour.name, 0) + 1
        inputs = served.inputs()
        names: dict[str, Any] = {
            "goal": record(inputs),
            "member": Record(id=self.member_id, index=self.member_index, type=self.member_type),
            "swarm": self.swarm,
            "count": count,
            "tick": 0,
        }
        goal = _Goal(served, behaviour, names, until=script.until)
        self._goals[served.key] = goal
        self.started.append((behaviour.name, "started"))
        served.running()
        if not script.forever:
            goal.timers.append(
                self.scheduler.call_later(
                    script.duration * self.time_scale, partial(self._finish, goal, script.ending)
                )
            )
        if script.every is not None:
            self._periodic(goal, script.every, script.every.start)

    def _finish(self, goal: _Goal, ending: Ending | None) -> None:
        """The goal ends (`None`: it was cancelled): its final state and result are set."""
        if goal.done:
            return
        goal.done = True
        for timer in goal.timers:
            timer.cancel()
        self._goals.pop(goal.served.key, None)
        goal.served.finish(partial(self._decide, goal, ending))

    def _decide(
        self, goal: _Goal, ending: Ending | None, cancel_requested: bool
    ) -> tuple[str | None, Any]:
        """(outcome, answer) when the goal ends (outcome None: it is cancelled)."""
        behaviour, served = goal.behaviour, goal.served
        if ending is None or cancel_requested:
            self.started.append((behaviour.name, "preempted"))
            return None, served.cancelled()
        try:
            outcome = str(render(ending.outcome, goal.names))
            outputs = render(dict(ending.outputs), goal.names)
            answer = served.answer(outcome, outputs)  # the wrong type: a failing behaviour
            for emission in ending.emit:
                self.emit(emission, goal.names)
        except Exception as err:  # a failing script aborts the goal, not the server's node
            self._failed(f"{behaviour.name}: script failed: {err!r}")
            self.started.append((behaviour.name, "aborted"))
            return "aborted", served.failure()
        self.started.append((behaviour.name, outcome))
        return outcome, answer

    def _periodic(self, goal: _Goal, every: Periodic, delay: float) -> None:
        def tick() -> None:
            if goal.done:
                return
            goal.names["tick"] += 1
            try:
                if every.when is None or evaluate(every.when, goal.names):
                    for emission in every.emit:
                        self.emit(emission, goal.names)
            except Exception as err:
                self._failed(f"{goal.behaviour.name}: emission failed: {err!r}")
            self._periodic(goal, every, every.period)

        goal.timers.append(self.scheduler.call_later(delay * self.time_scale, tick))

    def _withdrawn(self, key: Any) -> None:
        """A cancel request (or the state of a topic activation was left)."""
        goal = self._goals.get(key)
        if goal is not None:  # after rclpy marked the goal as canceling
            self.scheduler.call_later(0.0, partial(self._finish, goal, None))

    def _on_event(self, msg: Any) -> None:
        for goal in list(self._goals.values()):
            until = goal.until
            if until is None or goal.done:
                continue
            if self.events.get(until.event, (until.event, ""))[0] != msg.name:
                continue
            try:
                data = json.loads(msg.data) if msg.data else {}
                names = {
                    **goal.names,
                    "event": record(data if isinstance(data, dict) else {}),
                    "sender": msg.sender,
                }
                if until.when is None or evaluate(until.when, names):
                    goal.names = names
                    self._finish(goal, until.ending)
            except Exception as err:
                self._failed(f"{goal.behaviour.name}: `until` failed: {err!r}")

    def _failed(self, error: str) -> None:
        self.get_logger().error(error)
        if len(self.errors) < 100:  # a script failing on every tick must not fill memory
            self.errors.append(error)

    def emit(self, emission: Emission, names: Mapping[str, Any]) -> None:
        """Publish an event on behalf of the member (its data rendered over `names`)."""
        self.publish_event(emission.event, render(dict(emission.data), names), emission.scope)

    def publish_event(self, event: str, data: Any, scope: str | None = None) -> None:
        """Publish `event` with `data` as it is (JSON) on behalf of the member; `scope` None
        or empty: the event's declared one."""
        ident, declared_scope = self.events.get(event, (event, "swarm"))
        msg = self.interfaces.event(
            next(self._ids),
            self.get_clock().now().nanoseconds / 1e9,
            self.member_id,
            ident,
            json.dumps(data, default=str, sort_keys=True),
        )
        scope = scope or declared_scope or "swarm"
        (self._local if scope == "local" else self.swarm_publisher).publish(msg)


def run_simulated(
    specs: Mapping[str, MemberSpec],
    defaults: Mapping[str, Mapping[str, Any]],
    events: Mapping[str, tuple[str, str]],
    argv: Sequence[str] | None = None,
    make: Callable[..., SimulatedBehaviours] | None = None,
) -> int:
    """The simulated behaviours of one member in this process (the launch file's executable),
    configured with ROS parameters; runs until SIGINT/SIGTERM. `make`: the node's class (or a
    factory taking its arguments; None: `SimulatedBehaviours`)."""
    context, executor = init_process(argv)
    try:
        node = (make or SimulatedBehaviours)(specs, defaults, events, context=context)
    except ScriptError as err:
        print(f"simulated_behaviours: {err}", file=sys.stderr)
        rclpy.try_shutdown(context=context)
        return 2
    executor.add_node(node)
    try:
        spin_until(executor, lambda: False)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return 0
