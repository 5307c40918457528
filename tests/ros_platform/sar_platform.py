"""The SAR robots' platform, written by hand (not generated): a server for every declared
interface the SAR sample's behaviours use, as a platform team would run them.

`python -m tests.ros_platform.sar_platform BAG INTERFACES UAVS UGVS` runs one node per member namespace
(`/uav_1` ...), one process, a SingleThreadedExecutor whose callbacks are coroutines waiting on
timers (nothing blocks). Per UAV: `cmd/takeoff` (cpswarm_msgs/action/Takeoff, a feedback, then
success), `cmd/land` (std_srvs/srv/Empty), `uav_coverage` (cpswarm_msgs/action/Coverage: runs
until cancelled; uav_1's reports one target: the swarm event `targetFound` and a
cpswarm_msgs/msg/TargetPositionEvent on `target_found`), `uav_local_coverage` (aborts),
`uav_tracking` (Tracking: succeeds when the target is rescued), `cmd/task_allocation_auction`
(TaskAllocation: rover `1 + target_id % UGVS`, announced as `targetAssigned`) and
`pos_provider/pose` (geometry_msgs/msg/PoseStamped at 5 Hz). Per UGV:
`cmd/task_allocation_bid` (TaskAllocation: succeeds on the assigned rover once `targetAssigned`
names it, aborts on the others), `cmd/moveto` (move_base_msgs/action/MoveBase) and `ugv_rescue`
(cpswarm_msgs/action/Target: success, then `targetRescued`).

Every goal, result and message it receives or sends on a declared type is written into the
rosbag2 BAG (MCAP) as the CDR bytes rclpy (de)serialised, under the type's own name
(`cpswarm_msgs/action/Coverage_Goal`, on `<namespace>/<name>/goal` and `.../result`); service
calls (std_srvs/srv/Empty has no fields) are printed only. Every event is also one JSON line on
stdout. Swarm events use the swarm's `Event` type (`search_and_rescue_interfaces`).
"""

from __future__ import annotations

import json
import re
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import rclpy
from cpswarm_msgs.action import Coverage, Takeoff, Target, TaskAllocation, Tracking
from cpswarm_msgs.msg import TargetPositionEvent
from geometry_msgs.msg import PoseStamped
from move_base_msgs.action import MoveBase
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from rclpy.task import Future
from search_and_rescue_interfaces.msg import Event
from std_srvs.srv import Empty

QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
EVENTS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
TARGET = 101  # the one target uav_1 reports
FOUND_AT = {  # where: the model's PoseStamped (a subset of geometry_msgs/msg/PoseStamped)
    "header": {"frame_id": "map"},
    "pose": {
        "position": {"x": 4.0, "y": 6.0, "z": 0.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
    },
}


def say(event: str, **fields: Any) -> None:
    """One JSON line on stdout."""
    print(json.dumps({"event": event, **fields}, sort_keys=True), flush=True)


class Bag:
    """The declared-type traffic as raw CDR in a rosbag2 bag (rosbags writes it)."""

    def __init__(self, path: Path, interfaces: Path) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        # the standard types are rosbags' own; the user's come from their definition files
        self.store = get_typestore(Stores.ROS2_KILTED)
        for path_ in sorted(interfaces.glob("*/msg/*.msg")):
            self.store.register(get_types_from_msg(path_.read_text(), _name(path_)))
        for path_ in sorted(interfaces.glob("*/action/*.action")):
            sections = re.split(r"(?m)^---[ \t]*$", path_.read_text())
            for suffix, text in zip(("_Goal", "_Result", "_Feedback"), sections, strict=True):
                self.store.register(get_types_from_msg(text, _name(path_) + suffix))
        self.writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self.writer.open()
        self.connections: dict[tuple[str, str], Any] = {}

    def write(self, topic: str, message: Any) -> None:
        """`message` (an rclpy message) under its type's name, on `topic`."""
        module = type(message).__module__.split(".")  # cpswarm_msgs.action._coverage
        msgtype = f"{module[0]}/{module[1]}/{type(message).__name__}"
        key = (topic, msgtype)
        if key not in self.connections:
            self.connections[key] = self.writer.add_connection(topic, msgtype, typestore=self.store)
        self.writer.write(self.connections[key], time.time_ns(), serialize_message(message))

    def close(self) -> None:
        """Finish the bag."""
        self.writer.close()


def _name(path: Path) -> str:
    """`<root>/cpswarm_msgs/action/Coverage.action` -> `cpswarm_msgs/action/Coverage`."""
    return f"{path.parent.parent.name}/{path.parent.name}/{path.stem}"


class Robot(Node):
    """One member's platform: its servers and topics, in the member's namespace."""

    def __init__(self, fleet: Fleet, member: str) -> None:
        super().__init__("platform", namespace=f"/{member}")
        self.fleet, self.member = fleet, member
        self.index = int(member.rsplit("_", 1)[1])
        self.events = self.create_publisher(Event, "/swarm/events", EVENTS_QOS)
        self.ids = iter(range(1 << 41, 1 << 42))

    def serve(self, kind: Any, name: str, run: Callable[[Any], Any]) -> None:
        """An action server that records every goal and result in the bag."""

        async def execute(handle: Any) -> Any:
            topic = f"/{self.member}/{name}"
            self.fleet.bag.write(f"{topic}/goal", handle.request)
            say("goal", member=self.member, name=name)
            result = await run(handle)
            self.fleet.bag.write(f"{topic}/result", result)
            return result

        ActionServer(
            self,
            kind,
            name,
            execute,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT,
        )

    def sleep(self, seconds: float) -> Future[None]:
        """A future done after `seconds`."""
        future: Future[None] = Future()

        def fire() -> None:
            timer.cancel()
            self.destroy_timer(timer)
            future.set_result(None)

        timer = self.create_timer(seconds, fire)
        return future

    def send(self, name: str, **data: Any) -> None:
        """A swarm event from this member."""
        stamp = self.get_clock().now().to_msg()
        message = Event(
            id=next(self.ids), stamp=stamp, sender=self.member, name=name, data=json.dumps(data)
        )
        self.events.publish(message)
        say("sent", member=self.member, name=name, data=data)

    async def until(self, handle: Any, done: Callable[[], bool]) -> bool:
        """Wait until `done()` (True) or a cancel request (False, goal canceled)."""
        while not done():
            if handle.is_cancel_requested:
                handle.canceled()
                return False
            await self.sleep(0.05)
        return True


class Uav(Robot):
    """A UAV's platform."""

    def __init__(self, fleet: Fleet, member: str) -> None:
        super().__init__(fleet, member)
        self.serve(Takeoff, "cmd/takeoff", self.take_off)
        self.serve(Coverage, "uav_coverage", self.coverage)
        self.serve(Coverage, "uav_local_coverage", self.local_coverage)
        self.serve(Tracking, "uav_tracking", self.tracking)
        self.serve(TaskAllocation, "cmd/task_allocation_auction", self.auction)
        self.create_service(Empty, "cmd/land", self.land)
        self.pose = self.create_publisher(PoseStamped, "pos_provider/pose", QOS)
        self.found = self.create_publisher(TargetPositionEvent, "target_found", QOS)
        self.create_timer(0.2, self.publish_pose)

    async def take_off(self, handle: Any) -> Any:
        handle.publish_feedback(Takeoff.Feedback(current_altitude=handle.request.altitude / 2))
        await self.sleep(0.2)
        handle.succeed()
        return Takeoff.Result()

    async def coverage(self, handle: Any) -> Any:
        if self.index == 1 and not self.fleet.reported:
            self.fleet.reported = True
            await self.sleep(0.5)
            message = TargetPositionEvent(id=TARGET)
            message.header.frame_id = message.pose.header.frame_id = "map"
            message.pose.pose.position.x, message.pose.pose.position.y = 4.0, 6.0
            self.found.publish(message)
            self.fleet.bag.write(f"/{self.member}/target_found", message)
            self.send("targetFound", target_id=TARGET, pose=FOUND_AT)
        await self.until(handle, lambda: False)
        return Coverage.Result()

    async def local_coverage(self, handle: Any) -> Any:
        await self.sleep(0.1)
        handle.abort()
        return Coverage.Result()

    async def tracking(self, handle: Any) -> Any:
        target = handle.request.target_id
        if await self.until(handle, lambda: target in self.fleet.rescued):
            handle.succeed()
        return Tracking.Result(outcome="")

    async def auction(self, handle: Any) -> Any:
        target = handle.request.target_id
        rover = 1 + target % self.fleet.ugvs
        await self.sleep(0.1)
        self.fleet.assigned[target] = rover
        self.send("targetAssigned", target_id=target, rover_id=rover)
        handle.succeed()
        return TaskAllocation.Result(rover_id=rover)

    def land(self, _request: Any, response: Any) -> Any:
        say("land", member=self.member)
        return response

    def publish_pose(self) -> None:
        message = PoseStamped()
        message.header.frame_id = "map"
        message.pose.position.z = 1.5
        message.pose.orientation.w = 1.0
        self.pose.publish(message)


class Ugv(Robot):
    """A UGV's platform."""

    def __init__(self, fleet: Fleet, member: str) -> None:
        super().__init__(fleet, member)
        self.serve(TaskAllocation, "cmd/task_allocation_bid", self.bid)
        self.serve(MoveBase, "cmd/moveto", self.move_to)
        self.serve(Target, "ugv_rescue", self.rescue)

    async def bid(self, handle: Any) -> Any:
        target = handle.request.target_id
        if await self.until(handle, lambda: target in self.fleet.assigned):
            if self.fleet.assigned[target] == self.index:
                handle.succeed()
            else:
                handle.abort()
        return TaskAllocation.Result(rover_id=self.fleet.assigned.get(target, 0))

    async def move_to(self, handle: Any) -> Any:
        await self.sleep(0.3)
        handle.succeed()
        return MoveBase.Result(base_position=handle.request.target_pose)

    async def rescue(self, handle: Any) -> Any:
        await self.sleep(0.3)
        target = handle.request.target_id
        self.fleet.rescued.add(target)
        self.send("targetRescued", target_id=target)
        handle.succeed()
        return Target.Result()


class Fleet:
    """What the robots share: the bag, the counts, the targets assigned and rescued."""

    def __init__(self, bag: Path, interfaces: Path, ugvs: int) -> None:
        self.bag = Bag(bag, interfaces)
        self.ugvs = ugvs
        self.reported = False
        self.assigned: dict[int, int] = {}
        self.rescued: set[int] = set()


def main() -> int:
    """Run the platform until SIGINT/SIGTERM."""
    bag, interfaces = Path(sys.argv[1]), Path(sys.argv[2])
    uavs, ugvs = int(sys.argv[3]), int(sys.argv[4])
    rclpy.init()
    fleet = Fleet(bag, interfaces, ugvs)
    robots: list[Robot] = [Uav(fleet, f"uav_{i}") for i in range(1, uavs + 1)]
    robots += [Ugv(fleet, f"ugv_{i}") for i in range(1, ugvs + 1)]
    executor = SingleThreadedExecutor()
    for robot in robots:
        executor.add_node(robot)
    say("ready")
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        # the signal shut the context down while a timer's publish ran (seen under load): the
        # shutdown, not a fault (as swarmgen_library.servers); with a valid context, a fault
        if rclpy.ok():
            raise
    finally:
        fleet.bag.close()
        executor.shutdown()
        for robot in robots:
            robot.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
