"""A behaviour server that dies mid-mission, on real DDS: a platform process and a member driver.

`python -m tests.ros_server_loss platform NS` serves, in namespace NS, behaviours that hold
until cancelled (at most HOLD_S): the declared action `hold_go_to` (platform_msgs GoTo), the
private action `hold_survey` (sgedges_interfaces/Survey, the package of `tests.ros_edges`) and the
declared service `hold_trigger` (std_srvs Trigger, its response held back). One JSON line per
goal or request on stdout. The test kills it with SIGKILL while they run.

`python -m tests.ros_server_loss drive NS` runs one member per case (state `Run` runs the case's
behaviour; `aborted` leads to the final state `Aborted`), prints `{"running": t}` (monotonic
seconds) once every goal is accepted and the request sent, and, when every member ended (or
after DRIVE_S), one JSON object: case -> final state, the `done.invoke.*` events, errors and the
monotonic time the outcome arrived.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from platform_msgs.action import GoTo
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from std_srvs.srv import Trigger

from swarmgen.ros.runtime.node import MemberNode
from swarmgen.ros.runtime.process import spin_until
from swarmgen.ros.runtime.spec import BehaviourSpec, Binding, Field, MemberSpec
from swarmgen.runtime.chart import Call, Chart, ChartBuilder, Context
from swarmgen.runtime.engine import Event
from tests.ros_edges import GOTO, OUTCOMES, SWARM

HOLD_S = 30.0  # a held behaviour's limit (the platform is killed long before)
DRIVE_S = 20.0  # the driver's limit for the members to end


def _say(**line: Any) -> None:
    print(json.dumps(line, sort_keys=True), flush=True)


def _hold(handle: Any, name: str) -> None:
    _say(event="goal", action=name)
    limit = time.monotonic() + HOLD_S
    while not handle.is_cancel_requested and time.monotonic() < limit:
        time.sleep(0.02)
    handle.canceled()


def platform(namespace: str) -> int:
    """Serve the held behaviours until killed (or SIGINT/SIGTERM)."""
    from sgedges_interfaces.action import Survey

    def go_to(handle: Any) -> Any:
        _hold(handle, "hold_go_to")
        return GoTo.Result(outcome="")

    def survey(handle: Any) -> Any:
        _hold(handle, "hold_survey")
        return Survey.Result(outcome="")

    def trigger(_request: Any, response: Any) -> Any:
        _say(event="request", service="hold_trigger")
        time.sleep(HOLD_S)
        response.success = True
        return response

    rclpy.init()
    node = Node("loss_platform", namespace=namespace)
    group = ReentrantCallbackGroup()
    accept = lambda _request: CancelResponse.ACCEPT  # noqa: E731
    ActionServer(node, GoTo, "hold_go_to", go_to, callback_group=group, cancel_callback=accept)
    ActionServer(node, Survey, "hold_survey", survey, callback_group=group, cancel_callback=accept)
    node.create_service(Trigger, "hold_trigger", trigger, callback_group=group)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    _say(event="ready")
    try:
        executor.spin()
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


# --- the members -------------------------------------------------------------------------------


def _declared(binding: Binding) -> BehaviourSpec:
    return BehaviourSpec("Act", "", binding.ros_name, "HardwareFunction", outcomes=OUTCOMES,
                         binding=binding)  # fmt: skip


CASES: dict[str, BehaviourSpec] = {
    "declared_action": _declared(Binding("action", GOTO, "hold_go_to", (("x", "speed"),))),
    "service": _declared(Binding("service", ("std_srvs", "srv", "Trigger"), "hold_trigger",
                                 outcome="success", timeout_s=0.0)),
    "private_action": BehaviourSpec(
        "Act", "Survey", "hold_survey", "HardwareFunction",
        inputs=(Field("count", "count", "int64"),), outcomes=OUTCOMES,
    ),
}  # fmt: skip


def member_spec(case: str) -> MemberSpec:
    """A one-behaviour member: `Run` runs the case's behaviour, each outcome a final state."""

    def build() -> Chart:
        def call_args(_ctx: Context) -> dict[str, Any]:
            return {"x": 1.0, "count": 2}

        b = ChartBuilder(case, data={})
        b.node("Run", "state", call=Call("Act", "HardwareFunction", call_args, (), OUTCOMES))
        for outcome in OUTCOMES:
            b.node(outcome.capitalize(), "final")
            b.transition("Run", (f"outcome.Run.{outcome}",), (outcome.capitalize(),))
        b.initial(None, ("Run",))
        return b.build()

    return MemberSpec("Loss", case, f"member_{case}", SWARM, build, {}, {"Act": CASES[case]})


def _running(member: MemberNode, case: str) -> bool:
    """The case's goal is accepted, or its request sent."""
    if case == "service":
        running = member.declared_calls.running("Run")
        return running is not None and running[1] > 0
    return member.running_goal("Run") is not None


def drive(namespace: str) -> int:
    """Run the members; JSON lines on stdout."""
    rclpy.init()
    executor = SingleThreadedExecutor()
    members: dict[str, MemberNode] = {}
    seen: dict[str, list[tuple[str, float]]] = {case: [] for case in CASES}
    try:
        for case in CASES:
            member = MemberNode(member_spec(case), namespace=namespace, context=executor.context)
            members[case] = member
            deliver = member.deliver

            # the outcome events as they reach the member's queue, with their arrival time
            def record(event: Event, deliver: Any = deliver, case: str = case) -> None:
                if event.name.startswith("done.invoke."):
                    seen[case].append((event.name, time.monotonic()))
                deliver(event)

            member.deliver = record  # type: ignore[method-assign]
            executor.add_node(member)
        spin_until(executor, lambda: all(m.servers_ready() for m in members.values()), 10.0)
        for member in members.values():
            member.start()
        if spin_until(executor, lambda: all(_running(m, c) for c, m in members.items()), 10.0):
            _say(running=time.monotonic())
        spin_until(executor, lambda: all(m.finished for m in members.values()), DRIVE_S)
        report = {
            case: {
                "final": m.active() if m.finished else None,
                "events": [name for name, _ in seen[case]],
                "at": seen[case][0][1] if seen[case] else None,
                "errors": list(m.errors),
            }
            for case, m in members.items()
        }
        _say(report=report)
    finally:
        for member in members.values():
            member.stop()
            executor.remove_node(member)
            member.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    if sys.argv[1] == "platform":
        sys.exit(platform(sys.argv[2]))
    sys.exit(drive(sys.argv[2]))
