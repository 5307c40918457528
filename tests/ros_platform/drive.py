"""Drive member nodes with hand-written declared-interface specs against the platform.

`python -m tests.ros_platform.drive NAMESPACE CASE...` runs, for each case, a `MemberNode` whose
one state `Run` runs the case's behaviour (final states per outcome; the local event `stop`
preempts it), until the member is final; prints one JSON object: case -> final state, outputs,
errors, feedback, seconds. `python -m tests.ros_platform.drive --bad NAMESPACE` starts a member
(`run_member`) whose binding names a type this environment does not have.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor

from swarmgen.ros.runtime.node import MemberNode, run_member
from swarmgen.ros.runtime.process import spin_until
from swarmgen.ros.runtime.spec import BehaviourSpec, Binding, MemberSpec
from swarmgen.runtime.chart import Call, Chart, ChartBuilder, Context

SWARM = "sgdeclared_interfaces"
OUTCOMES = ("succeeded", "aborted", "preempted", "blocked")
GOTO = ("platform_msgs", "action", "GoTo")
POSE = ("geometry_msgs", "msg", "PoseStamped")
TRIGGER = ("std_srvs", "srv", "Trigger")
EMPTY = ("std_srvs", "srv", "Empty")
GOTO_INPUTS = (
    ("x", "target_pose.pose.position.x"),
    ("y", "target_pose.pose.position.y"),
    ("frame", "target_pose.header.frame_id"),
    ("orientation", "target_pose.pose.orientation"),
    ("speed", "speed"),
    ("retries", "retries"),
    ("mode", "mode"),
)
GOTO_OUTPUTS = (("reached", "reached"), ("reached.z", "height"), ("legs", "legs"))


def _goto(mode: str, retries: int = 3) -> tuple[Binding, dict[str, Any]]:
    binding = Binding("action", GOTO, "go_to", GOTO_INPUTS, GOTO_OUTPUTS, outcome="outcome")
    args = {"x": 1.5, "y": -2.25, "frame": "map", "orientation": {"z": 0.6, "w": 0.8}}
    args.update(speed=2.5, retries=retries, mode=mode)
    return binding, args


def _trigger(name: str) -> tuple[Binding, dict[str, Any]]:
    outputs = (("message", "message"), ("success", "ok"))
    return Binding("service", TRIGGER, name, (), outputs, outcome="success"), {}


CASES: dict[str, tuple[Binding, dict[str, Any]]] = {
    "goto": _goto(""),
    "goto_blocked": _goto("blocked"),
    "goto_failed": _goto("fail"),
    "goto_preempted": _goto("hold"),
    "goto_out_of_range": _goto("", retries=300),
    "arm": _trigger("arm"),
    "check": _trigger("check"),
    "reset": (Binding("service", EMPTY, "reset"), {}),
    "land_timeout": (Binding("service", EMPTY, "slow_land", timeout_s=0.5), {}),
    "target": (
        Binding(
            "topic",
            POSE,
            "target",
            outputs=(("pose.position.x", "tx"), ("header.frame_id", "frame"), ("pose", "pose")),
            direction="subscribe",
        ),
        {},
    ),
    "publish": (
        Binding(
            "topic",
            POSE,
            "goal_pose",
            inputs=(
                ("x", "pose.position.x"),
                ("z", "pose.position.z"),
                ("frame", "header.frame_id"),
            ),
            timeout_s=5.0,
            direction="publish",
        ),
        {"x": -3.5, "z": 12.0, "frame": "odom"},
    ),
}


def member_spec(case: str) -> MemberSpec:
    """A one-behaviour member: state `Run` runs the case's behaviour."""
    binding, args = CASES[case]
    outputs = tuple(output for _, output in binding.outputs)
    behaviour = BehaviourSpec(
        name="Act",
        action="",
        ros_name=binding.ros_name,
        kind="HardwareFunction",
        outcomes=OUTCOMES,
        binding=binding,
    )

    def build() -> Chart:
        def call_args(_ctx: Context) -> dict[str, Any]:
            return dict(args)

        b = ChartBuilder(case, data=dict.fromkeys(outputs))
        results = tuple((output, output) for output in outputs)
        b.node("Run", "state", call=Call("Act", "HardwareFunction", call_args, results, OUTCOMES))
        for outcome in OUTCOMES:
            b.node(outcome.capitalize(), "final")
            b.transition("Run", (f"outcome.Run.{outcome}",), (outcome.capitalize(),))
        b.node("Stopped", "final")
        b.transition("Run", ("stop",), ("Stopped",))
        b.initial(None, ("Run",))
        return b.build()

    return MemberSpec(
        member_type="Declared",
        chart_name=case,
        node_name=f"member_{case}",
        interfaces=SWARM,
        build=build,
        event_scopes={"stop": "local"},
        behaviours={"Act": behaviour},
    )


def run_case(executor: SingleThreadedExecutor, namespace: str, case: str) -> dict[str, Any]:
    """Run one case to its final state; what it ended with."""
    member = MemberNode(member_spec(case), namespace=namespace, context=executor.context)
    executor.add_node(member)
    try:
        spin_until(executor, member.servers_ready, timeout=10.0)
        started = time.monotonic()
        member.start()
        if case == "goto_preempted":  # preempt once the platform runs the goal
            spin_until(executor, lambda: member.running_goal("Run") is not None, timeout=10.0)
            spin_until(executor, lambda: bool(member.feedback), timeout=5.0)
            member.deliver(member.engine.make_event("stop", None, member.member_id))
        finished = spin_until(executor, lambda: member.finished, timeout=10.0)
        seconds = time.monotonic() - started
        spin_until(executor, member.idle, timeout=2.0)
        spin_until(executor, lambda: False, timeout=0.3)  # the cancel reaches the platform
        binding = CASES[case][0]
        return {
            "final": member.active() if finished else None,
            "outputs": {o: member.engine.data.get(o) for _, o in binding.outputs},
            "errors": list(member.errors),
            "feedback": [values for _, _, values in member.feedback],
            "seconds": round(seconds, 3),
        }
    finally:
        member.stop()
        executor.remove_node(member)
        member.destroy_node()


def main(argv: list[str]) -> int:
    """Run the cases named in `argv` (after the namespace); JSON on stdout."""
    if argv[0] == "--bad":
        binding = Binding("topic", ("nope_msgs", "msg", "Nope"), "nope", direction="subscribe")
        spec = member_spec("target")
        behaviour = spec.behaviours["Act"]
        bad = BehaviourSpec(behaviour.name, "", "nope", behaviour.kind, binding=binding)
        spec = dataclasses.replace(spec, behaviours={"Act": bad})
        return run_member(spec, ["--ros-args", "-r", f"__ns:={argv[1]}"])
    namespace, cases = argv[0], argv[1:]
    rclpy.init()
    executor = SingleThreadedExecutor()
    report = {}
    try:
        for case in cases:
            report[case] = run_case(executor, namespace, case)
    finally:
        executor.shutdown()
        rclpy.try_shutdown()
    print(json.dumps(report, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
