"""A robot platform written by hand (not generated), as a platform team would have it.

`python -m tests.ros_platform.platform NAMESPACE` runs one node in NAMESPACE with:
- action `go_to` (platform_msgs/action/GoTo, from the user interfaces directory): two feedbacks,
  then the result (`reached` = the goal's position, `legs`, `outcome` = the goal's mode); mode
  `hold` runs until cancelled, mode `fail` aborts;
- services `arm` and `check` (std_srvs/srv/Trigger: success true "armed", false "battery low"),
  `reset` (std_srvs/srv/Empty, at once) and `slow_land` (Empty, answers after 5 s);
- topic `target` (geometry_msgs/msg/PoseStamped, published every 0.1 s) and a subscription on
  `goal_pose` (PoseStamped).
Everything it receives is printed as one JSON line (`{"event": ..., ...}`) on stdout.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from geometry_msgs.msg import PoseStamped
from platform_msgs.action import GoTo
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from std_srvs.srv import Empty, Trigger

QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def say(event: str, **fields: Any) -> None:
    """One JSON line on stdout, at once (the test reads it after the platform is stopped)."""
    print(json.dumps({"event": event, **fields}, sort_keys=True), flush=True)


def pose_of(message: PoseStamped) -> dict[str, Any]:
    """The fields of a PoseStamped the tests look at."""
    p, o = message.pose.position, message.pose.orientation
    return {
        "frame": message.header.frame_id,
        "position": [p.x, p.y, p.z],
        "orientation": [o.x, o.y, o.z, o.w],
    }


class Platform(Node):
    """The platform's servers and topics."""

    def __init__(self, namespace: str) -> None:
        super().__init__("platform", namespace=namespace)
        ActionServer(
            self,
            GoTo,
            "go_to",
            self._go_to,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
        )
        self.create_service(Trigger, "arm", self._arm)
        self.create_service(Trigger, "check", self._check)
        self.create_service(Empty, "reset", self._reset)
        # blocks one thread of the executor, the rest of the platform goes on
        slow = MutuallyExclusiveCallbackGroup()
        self.create_service(Empty, "slow_land", self._slow_land, callback_group=slow)
        self._target = self.create_publisher(PoseStamped, "target", QOS)
        self.create_timer(0.1, self._publish_target)
        self.create_subscription(PoseStamped, "goal_pose", self._on_goal_pose, QOS)

    def sleep(self, seconds: float) -> Future[None]:
        """A future done after `seconds` (awaited by coroutine callbacks: nothing blocks)."""
        future: Future[None] = Future()

        def fire() -> None:
            timer.cancel()
            self.destroy_timer(timer)
            future.set_result(None)

        timer = self.create_timer(seconds, fire)
        return future

    async def _go_to(self, handle: Any) -> Any:
        goal = handle.request
        say(
            "goal",
            pose=pose_of(goal.target_pose),
            speed=goal.speed,
            retries=goal.retries,
            mode=goal.mode,
        )
        for remaining in (2.0, 1.0):
            handle.publish_feedback(GoTo.Feedback(remaining=remaining))
            await self.sleep(0.05)
        result = GoTo.Result(outcome="", legs=[1.5, 2.5])
        result.reached = goal.target_pose.pose.position
        if goal.mode == "hold":
            while not handle.is_cancel_requested:
                await self.sleep(0.05)
            handle.canceled()
            say("canceled")
            return result
        if goal.mode == "fail":
            handle.abort()
            return result
        result.outcome = goal.mode
        handle.succeed()
        return result

    def _arm(self, _request: Any, response: Any) -> Any:
        say("arm")
        response.success, response.message = True, "armed"
        return response

    def _check(self, _request: Any, response: Any) -> Any:
        say("check")
        response.success, response.message = False, "battery low"
        return response

    def _reset(self, _request: Any, response: Any) -> Any:
        say("reset")
        return response

    def _slow_land(self, _request: Any, response: Any) -> Any:
        say("slow_land")
        time.sleep(5.0)
        return response

    def _publish_target(self) -> None:
        message = PoseStamped()
        message.header.frame_id = "map"
        message.pose.position.x, message.pose.position.y, message.pose.position.z = 4.0, -1.5, 2.25
        message.pose.orientation.w = 1.0
        self._target.publish(message)

    def _on_goal_pose(self, message: PoseStamped) -> None:
        say("goal_pose", pose=pose_of(message))


def main() -> int:
    """Run the platform until SIGINT/SIGTERM."""
    rclpy.init()
    node = Platform(sys.argv[1] if len(sys.argv) > 1 else "/r1")
    executor = MultiThreadedExecutor(num_threads=3)
    executor.add_node(node)
    say("ready")
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
