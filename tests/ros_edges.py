"""The edge cases of declared interfaces on real DDS: a platform process and a member driver.

`python -m tests.ros_edges platform NS` serves, in namespace NS: `fb_go_to` (platform_msgs GoTo:
40 feedbacks 10 ms apart, then SUCCEEDED with an empty `outcome`), `slow_go_to` (runs until
cancelled), `mute_go_to` (never answers a goal: its goal callback waits forever) and the private
action `survey` (sgedges_interfaces/Survey: the result's zone keeps the goal's name, its enum
field `mode` left empty). One JSON line per goal, cancel and result on stdout.

`python -m tests.ros_edges drive NS BAG CASE...` runs each case's one-behaviour member (state
`Run`) to its final state and prints one JSON object: case -> final state, outputs, errors,
feedback records, seconds, what a helper subscriber received. `BAG`: the bag the feedback case
records into (`MemberOptions(tracer=BagRecorder)`).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import rclpy
from geometry_msgs.msg import PoseStamped
from platform_msgs.action import GoTo
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.task import Future

from swarmgen.ros.interfaces import ACTIVE_STATES_MSG, EVENT_MSG, render_interface_package
from swarmgen.ros.runtime.node import MemberNode, MemberOptions
from swarmgen.ros.runtime.process import spin_until
from swarmgen.ros.runtime.spec import BehaviourSpec, Binding, Field, MemberSpec
from swarmgen.runtime.chart import Call, Chart, ChartBuilder, Context

SWARM = "sgedges_interfaces"
ZONE_MSG = "string mode\nstring name\n"
SURVEY_ACTION = (
    f"int64 count\n{SWARM}/Zone zone\n---\n{SWARM}/Zone zone\nstring outcome\n---\nstring status\n"
)
OUTCOMES = ("succeeded", "aborted", "preempted")
GOTO = ("platform_msgs", "action", "GoTo")
POSE = ("geometry_msgs", "msg", "PoseStamped")
FEEDBACKS = 40


def package_files() -> dict[Any, str]:
    """The private interface package of these tests (Event, ActiveStates, Zone, Survey)."""
    messages = {"Event": EVENT_MSG, "ActiveStates": ACTIVE_STATES_MSG, "Zone": ZONE_MSG}
    files = render_interface_package(SWARM, messages, {"Survey": SURVEY_ACTION}, "edge tests")
    return dict(files)


# --- the platform ------------------------------------------------------------------------------


def _say(**line: Any) -> None:
    print(json.dumps(line, sort_keys=True), flush=True)


def _fb_execute(handle: Any) -> Any:
    for i in range(FEEDBACKS):
        handle.publish_feedback(GoTo.Feedback(remaining=float(FEEDBACKS - i)))
        time.sleep(0.01)
    handle.succeed()
    _say(event="result", action="fb_go_to")
    return GoTo.Result(outcome="")


def _slow_execute(handle: Any) -> Any:
    _say(event="goal", action="slow_go_to")
    limit = time.monotonic() + 10
    while not handle.is_cancel_requested and time.monotonic() < limit:
        time.sleep(0.02)
    _say(event="cancel", action="slow_go_to", requested=bool(handle.is_cancel_requested))
    handle.canceled()
    return GoTo.Result(outcome="")


async def _never(_goal: Any) -> GoalResponse:
    _say(event="goal", action="mute_go_to")
    await Future()  # never done: the goal is never accepted nor rejected
    return GoalResponse.REJECT


def _survey_execute(handle: Any) -> Any:
    from sgedges_interfaces.action import Survey
    from sgedges_interfaces.msg import Zone

    goal = handle.request
    _say(event="goal", action="survey", count=goal.count, mode=goal.zone.mode, name=goal.zone.name)
    handle.succeed()
    return Survey.Result(zone=Zone(mode="", name=goal.zone.name), outcome="")


def platform(namespace: str) -> int:
    """Serve the actions until SIGINT/SIGTERM."""
    from sgedges_interfaces.action import Survey

    rclpy.init()
    node = Node("edges_platform", namespace=namespace)
    group = ReentrantCallbackGroup()
    accept = lambda _request: CancelResponse.ACCEPT  # noqa: E731
    servers = [
        ActionServer(node, GoTo, "fb_go_to", _fb_execute, callback_group=group),
        ActionServer(
            node, GoTo, "slow_go_to", _slow_execute, callback_group=group, cancel_callback=accept
        ),
        ActionServer(
            node, GoTo, "mute_go_to", _slow_execute, callback_group=group, goal_callback=_never
        ),
        ActionServer(node, Survey, "survey", _survey_execute, callback_group=group),
    ]
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    _say(event="ready", servers=len(servers))
    try:
        executor.spin()
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


# --- the member cases --------------------------------------------------------------------------


def _survey() -> BehaviourSpec:
    zone = Field("zone", "zone", f"{SWARM}/Zone", enums=(("mode", "search"),))
    return BehaviourSpec(
        "Act", "Survey", "survey", "HardwareFunction",
        inputs=(Field("count", "count", "int64"), zone), outputs=(zone,), outcomes=OUTCOMES,
    )  # fmt: skip


def _declared(binding: Binding) -> BehaviourSpec:
    return BehaviourSpec("Act", "", binding.ros_name, "HardwareFunction", outcomes=OUTCOMES,
                         binding=binding)  # fmt: skip


def _goto(name: str, **extra: Any) -> Binding:
    inputs = (("x", "target_pose.pose.position.x"), ("speed", "speed"))
    return Binding("action", GOTO, name, inputs, (("outcome", "mode"),), **extra)


_PUBLISH = (("x", "pose.position.x"),)
# case -> (behaviour, call arguments, outputs, node parameters)
CASES: dict[str, tuple[BehaviourSpec, dict[str, Any], tuple[str, ...], dict[str, Any]]] = {
    "feedback": (_declared(_goto("fb_go_to", enums=(("mode", "search"),))), {"x": 1.0}, ("mode",), {}),
    "declared_bad_value": (_declared(_goto("fb_go_to")), {"x": 1.0, "speed": "fast"}, ("mode",), {}),
    "timeout": (_declared(_goto("slow_go_to", timeout_s=0.5)), {"x": 1.0}, ("mode",), {}),
    "no_answer": (_declared(_goto("mute_go_to")), {"x": 1.0}, ("mode",),
                  {"goal_answer_timeout_s": 0.5}),
    "late_subscriber": (_declared(Binding("topic", POSE, "late_pose", _PUBLISH, timeout_s=5.0,
                                          direction="publish")), {"x": 4.5}, (), {}),
    "no_subscriber": (_declared(Binding("topic", POSE, "nobody_pose", _PUBLISH, timeout_s=0.3,
                                        direction="publish")), {"x": 1.0}, (), {}),
    "private_ok": (_survey(), {"count": 3, "zone": {"mode": "track", "name": "a"}}, ("zone",), {}),
    "private_bad_value": (_survey(), {"count": 2.5, "zone": {"mode": "track"}}, ("zone",), {}),
}  # fmt: skip


def member_spec(case: str) -> MemberSpec:
    """A one-behaviour member: state `Run` runs the case's behaviour."""
    behaviour, args, outputs, _ = CASES[case]

    def build() -> Chart:
        def call_args(_ctx: Context) -> dict[str, Any]:
            return dict(args)

        b = ChartBuilder(case, data=dict.fromkeys(outputs))
        results = tuple((output, output) for output in outputs)
        b.node("Run", "state", call=Call("Act", "HardwareFunction", call_args, results, OUTCOMES))
        for outcome in OUTCOMES:
            b.node(outcome.capitalize(), "final")
            b.transition("Run", (f"outcome.Run.{outcome}",), (outcome.capitalize(),))
        b.initial(None, ("Run",))
        return b.build()

    return MemberSpec("Edges", case, f"member_{case}", SWARM, build, {}, {"Act": behaviour})


def _late_subscriber(executor: Any, namespace: str, heard: list[dict[str, Any]]) -> Node:
    """A node that subscribes to `late_pose` 0.5 s from now (what it hears goes to `heard`)."""
    node = Node("late_listener", namespace=namespace, context=executor.context)
    started = time.monotonic()

    def subscribe() -> None:
        timer.cancel()
        heard.append({"subscribed": round(time.monotonic() - started, 3)})
        node.create_subscription(
            PoseStamped, "late_pose", lambda m: heard.append({"x": m.pose.position.x}), 10
        )

    timer = node.create_timer(0.5, subscribe)
    executor.add_node(node)
    return node


def run_case(executor: Any, namespace: str, case: str, bag: Path) -> dict[str, Any]:
    """Run one case to its final state; what it ended with."""
    from rclpy.parameter import Parameter

    from swarmgen.trace.recorder import BagRecorder

    overrides = [Parameter(k, value=v) for k, v in CASES[case][3].items()]
    recorder = BagRecorder(bag) if case == "feedback" else None
    options = MemberOptions(parameter_overrides=overrides, tracer=recorder)
    member = MemberNode(member_spec(case), namespace=namespace, options=options,
                        context=executor.context)  # fmt: skip
    records: list[dict[str, Any]] = []
    member.on_feedback.append(lambda record: records.append(record.as_json()))
    executor.add_node(member)
    heard: list[dict[str, Any]] = []
    helper = _late_subscriber(executor, namespace, heard) if case == "late_subscriber" else None
    try:
        spin_until(executor, member.servers_ready, timeout=10.0)
        started = time.monotonic()
        member.start()
        finished = spin_until(executor, lambda: member.finished, timeout=15.0)
        seconds = time.monotonic() - started
        spin_until(executor, lambda: False, timeout=0.3)  # a cancel reaches the platform
        return {
            "final": member.active() if finished else None,
            "outputs": {o: member.engine.data.get(o) for o in CASES[case][2]},
            "errors": list(member.errors),
            "records": records,
            "heard": heard,
            "seconds": round(seconds, 3),
        }
    finally:
        if recorder is not None:
            recorder.close()
        member.stop()
        for node in (member, helper):
            if node is not None:
                executor.remove_node(node)
                node.destroy_node()


def drive(namespace: str, bag: str, cases: list[str]) -> int:
    """Run the cases; JSON on stdout."""
    rclpy.init()
    executor = SingleThreadedExecutor()
    report = {}
    try:
        for case in cases:
            report[case] = run_case(executor, namespace, case, Path(bag))
    finally:
        executor.shutdown()
        rclpy.try_shutdown()
    print(json.dumps(report, sort_keys=True))
    return 0


if __name__ == "__main__":
    if sys.argv[1] == "platform":
        sys.exit(platform(sys.argv[2]))
    sys.exit(drive(sys.argv[2], sys.argv[3], sys.argv[4:]))
