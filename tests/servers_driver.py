"""The world's side of the lockstep, for tests/test_detailed_servers.py: a real rclpy node that
steps a `swarmgen_library.world.World` and publishes `/clock`, each robot's `camera` and `pose`
as the world node does, takes the stamped `cmd_vel` answers and the servers' step report, settles
when the report asks, and sends the goals of one scenario with real action clients.

    python -m tests.servers_driver SCENARIO    # moveto | cancel | auction | coverage | rescue
    python -m tests.servers_driver member CONFIG.json

The last stdout line is the JSON record: per step the poses and commands, the goals' statuses
and results with the step they ended at, and the swarm events heard with their step.

`member` is the other side, for tests/test_detailed_pair.py, where the real world node steps:
a node acting as the swarm's members. It sends every UAV of the config a TakeOff goal (printing
`{"event": "ready"}` once they are accepted, so the world can start), then Coverage on success;
on the first `targetFound` a MoveTo to the config's UGV, then on success a Rescue of the target.
It ends on the world's final `/world/status` (or after `limit_s`), recording its goals.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import rclpy
from builtin_interfaces.msg import Time
from cpswarm_msgs.action import Coverage, Takeoff, Target, TaskAllocation, Tracking
from cpswarm_msgs.msg import TargetPositionEvent
from geometry_msgs.msg import PoseStamped, TwistStamped
from move_base_msgs.action import MoveBase
from rclpy.action import ActionClient
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from search_and_rescue_interfaces.msg import Event
from std_msgs.msg import String
from swarmgen_library.geometry import Area
from swarmgen_library.world import RobotSpec, TargetSpec, World, WorldSpec

QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
EVENTS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
DT = 0.125  # binary-exact steps: 1 m/s moves 0.125 m per step
SETTLE_S = 0.3  # generous: the test machine may be loaded
SUCCEEDED = 4  # action_msgs/GoalStatus


def stamp(t: float) -> Time:
    """A builtin_interfaces/Time of `t` seconds."""
    sec = int(t)
    return Time(sec=sec, nanosec=round((t - sec) * 1e9))


def target_pose(x: float, y: float) -> PoseStamped:
    """A goal's PoseStamped at (x, y)."""
    pose = PoseStamped()
    pose.header.frame_id = "map"
    pose.pose.position.x, pose.pose.position.y = x, y
    pose.pose.orientation.w = 1.0
    return pose


class Driver(Node):
    """The lockstep world node of the test."""

    def __init__(self, world: World, robots: list[str]) -> None:
        super().__init__("test_world")
        self.world, self.robots, self.k = world, robots, 0
        self.clock = self.create_publisher(Clock, "/clock", QOS)
        self.cameras = {r: self.create_publisher(String, f"/{r}/camera", QOS) for r in robots}
        self.poses = {r: self.create_publisher(PoseStamped, f"/{r}/pose", QOS) for r in robots}
        self.cmds: dict[str, TwistStamped] = {}
        for robot in robots:
            self.create_subscription(TwistStamped, f"/{robot}/cmd_vel",
                                     lambda m, r=robot: self._cmd(r, m), QOS)  # fmt: skip
        self.reports: dict[int, bool] = {}  # step -> settle
        self.create_subscription(String, "/world/settle", self._report, QOS)
        self.events: list[dict[str, Any]] = []
        self.create_subscription(Event, "/swarm/events", self._event, EVENTS_QOS)
        self.found: list[dict[str, Any]] = []
        self.create_subscription(TargetPositionEvent, "/uav_1/target_found", self._found, QOS)
        self.record: list[dict[str, Any]] = []

    def _cmd(self, robot: str, message: TwistStamped) -> None:
        stamp = message.header.stamp
        if round((stamp.sec + stamp.nanosec * 1e-9) / DT) == self.k:  # answers this step
            self.cmds[robot] = message

    def _report(self, message: String) -> None:
        report = json.loads(message.data)
        self.reports[report["k"]] = self.reports.get(report["k"], False) or report["settle"]

    def _event(self, message: Event) -> None:
        self.events.append({"k": self.k, "name": message.name, "sender": message.sender,
                            "data": json.loads(message.data or "{}"),
                            "stamp": message.stamp.sec + message.stamp.nanosec * 1e-9})  # fmt: skip

    def _found(self, message: TargetPositionEvent) -> None:
        p = message.pose.pose.position
        self.found.append({"k": self.k, "id": message.id, "xyz": [p.x, p.y, p.z]})

    def spin_until(self, done: Any, limit: float = 10.0) -> None:
        """Spin until `done()` or `limit` seconds (then AssertionError)."""
        deadline = time.monotonic() + limit
        while not done():
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out at step {self.k}")
            rclpy.spin_once(self, timeout_sec=0.02)

    def connected(self) -> None:
        """Wait until the servers subscribe to every pose and camera and publish cmd_vel."""
        self.spin_until(lambda: all(
            self.poses[r].get_subscription_count() and self.cameras[r].get_subscription_count()
            and self.count_publishers(f"/{r}/cmd_vel") for r in self.robots), 20)  # fmt: skip

    def step(self) -> None:
        """Publish step k, take one cmd_vel per robot and the step report, settle when it
        asks, apply, step the world (as the world node does)."""
        t = self.world.time
        self.clock.publish(Clock(clock=stamp(t)))
        self.cmds = {}
        for robot in self.robots:
            seen = [{"id": s.id, "x": s.x, "y": s.y} for s in self.world.visible(robot)]
            self.cameras[robot].publish(String(data=json.dumps(
                {"k": self.k, "t": t, "targets": seen})))  # fmt: skip
            pose = self.world.pose(robot)
            message = PoseStamped()
            message.header.frame_id, message.header.stamp = "map", stamp(t)
            message.pose.position.x, message.pose.position.y = pose.x, pose.y
            message.pose.position.z = pose.z
            message.pose.orientation.w = 1.0
            self.poses[robot].publish(message)
        self.spin_until(lambda: len(self.cmds) == len(self.robots) and self.k in self.reports)
        if self.reports.pop(self.k):
            start = time.monotonic()
            self.spin_until(lambda: time.monotonic() - start >= SETTLE_S, SETTLE_S + 10)
        entry: dict[str, Any] = {"k": self.k}
        for robot in self.robots:
            c = self.cmds[robot].twist.linear
            p = self.world.pose(robot)
            entry[robot] = {"pose": [p.x, p.y, p.z], "cmd": [c.x, c.y, c.z]}
            self.world.command(robot, c.x, c.y, c.z)
        self.record.append(entry)
        self.world.step()
        self.k += 1


class Goal:
    """One goal on its way: its status and result once done, and the step it ended at."""

    def __init__(self, driver: Driver, client: ActionClient, goal: Any) -> None:
        client.wait_for_server(timeout_sec=20)
        future = client.send_goal_async(goal)
        driver.spin_until(future.done)
        self.handle = future.result()
        assert self.handle.accepted
        # the goal starts in its execute callback, after the acceptance: let it start before
        # the next step, as the world's settling after a member's reaction does
        start = time.monotonic()
        driver.spin_until(lambda: time.monotonic() - start >= SETTLE_S, SETTLE_S + 10)
        self.driver, self.status, self.result, self.ended = driver, None, None, None
        self.handle.get_result_async().add_done_callback(self._done)

    def _done(self, future: Any) -> None:
        answer = future.result()
        self.status, self.ended = answer.status, self.driver.k
        self.result = answer.result

    def cancel(self) -> None:
        """Cancel, and wait until the goal has ended."""
        future = self.handle.cancel_goal_async()
        self.driver.spin_until(lambda: future.done() and self.status is not None)


def world(robots: list[RobotSpec], targets: list[TargetSpec]) -> World:
    """A 10 m x 10 m world stepped at DT."""
    return World(WorldSpec(Area(10.0, 10.0), tuple(robots), tuple(targets), cell=1.0, dt=DT))


def run_moveto(cancel: bool) -> dict[str, Any]:
    """ugv_1 from (1, 1) to (4, 1) at 1 m/s, or towards (9, 1) and cancelled after step 10."""
    driver = Driver(world([RobotSpec("ugv_1", "ugv", 1.0, None, 1.0, 1.0)], []), ["ugv_1"])
    driver.connected()
    client = ActionClient(driver, MoveBase, "/ugv_1/cmd/moveto")
    goal = Goal(driver, client, MoveBase.Goal(target_pose=target_pose(9.0 if cancel else 4.0, 1.0)))
    while driver.k < 40 and (goal.status is None or driver.k < goal.ended + 3):
        driver.step()
        if cancel and driver.k == 11:  # step 10's command is applied: cancel before step 11
            goal.cancel()
    return {"status": goal.status, "ended": goal.ended, "record": driver.record}


def run_auction() -> dict[str, Any]:
    """uav_1 sees target 7 at step 0 and auctions it; ugv_2 is nearer than ugv_1."""
    robots = [RobotSpec("uav_1", "uav", 1.0, 0.5, 2.0, 2.0, 1.0),
              RobotSpec("ugv_1", "ugv", 1.0, None, 8.0, 8.0),
              RobotSpec("ugv_2", "ugv", 1.0, None, 3.0, 3.0)]  # fmt: skip
    driver = Driver(world(robots, [TargetSpec(7, 2.0, 2.25)]), ["uav_1", "ugv_1", "ugv_2"])
    driver.connected()
    driver.step()
    driver.spin_until(lambda: any(e["name"] == "targetFound" for e in driver.events))
    where = target_pose(2.0, 2.25)
    goals = {"uav_1": Goal(driver, ActionClient(driver, TaskAllocation,
                                                "/uav_1/cmd/task_allocation_auction"),
                           TaskAllocation.Goal(target_id=7, target_pose=where))}  # fmt: skip
    for ugv in ("ugv_1", "ugv_2"):
        client = ActionClient(driver, TaskAllocation, f"/{ugv}/cmd/task_allocation_bid")
        goals[ugv] = Goal(driver, client, TaskAllocation.Goal(target_id=7, target_pose=where))
    while driver.k < 40 and any(g.status is None for g in goals.values()):
        driver.step()
    return {"events": driver.events, "goals": {m: {"status": g.status, "ended": g.ended,
            "rover_id": g.result.rover_id if g.result is not None else None}
            for m, g in goals.items()}}  # fmt: skip


def run_coverage() -> dict[str, Any]:
    """uav_1 covers eastwards from (1, 1); target 3 at (3, 1) enters its 0.5 m view."""
    robots = [RobotSpec("uav_1", "uav", 1.0, 0.5, 1.0, 1.0, 1.0)]
    driver = Driver(world(robots, [TargetSpec(3, 3.0, 1.0)]), ["uav_1"])
    driver.connected()
    client = ActionClient(driver, Coverage, "/uav_1/uav_coverage")
    goal = Goal(driver, client, Coverage.Goal(altitude=1.0))
    while driver.k < 20:
        driver.step()
    first = driver.world.first_detections()
    return {"events": driver.events, "found": driver.found, "first": first.get(3),
            "status": goal.status, "record": driver.record}  # fmt: skip


def run_rescue() -> dict[str, Any]:
    """uav_1 sees target 5 at step 0 and tracks it; ugv_1 drives 1 m to it and rescues it."""
    robots = [RobotSpec("uav_1", "uav", 1.0, 0.5, 2.0, 2.0, 1.0),
              RobotSpec("ugv_1", "ugv", 1.0, None, 1.0, 2.0)]  # fmt: skip
    driver = Driver(world(robots, [TargetSpec(5, 2.0, 2.0)]), ["uav_1", "ugv_1"])
    rescues: list[dict[str, Any]] = []
    driver.create_subscription(String, "/world/rescue",
                               lambda m: rescues.append({"k": driver.k, **json.loads(m.data)}),
                               QOS)  # fmt: skip
    driver.connected()
    driver.step()
    driver.spin_until(lambda: any(e["name"] == "targetFound" for e in driver.events))
    tracking = Goal(driver, ActionClient(driver, Tracking, "/uav_1/uav_tracking"),
                    Tracking.Goal(target_id=5, altitude=1.0))  # fmt: skip
    rescue = Goal(driver, ActionClient(driver, Target, "/ugv_1/ugv_rescue"),
                  Target.Goal(target_id=5, target_pose=target_pose(2.0, 2.0)))  # fmt: skip
    while driver.k < 40 and (tracking.status is None or rescue.status is None):
        driver.step()
    return {"events": driver.events, "rescues": rescues, "record": driver.record,
            "tracking": [tracking.status, tracking.ended, tracking.result.outcome],
            "rescue": [rescue.status, rescue.ended]}  # fmt: skip


class Member(Node):
    """The members' side of a run against the world node (the `member` mode)."""

    def __init__(self, config: dict[str, Any]) -> None:
        super().__init__("test_member")
        self.config, self.t = config, 0.0
        self.log: list[dict[str, Any]] = []
        self.events: list[dict[str, Any]] = []
        self.final: dict[str, Any] | None = None
        self.found = False
        self.actions: dict[str, ActionClient] = {}
        self.create_subscription(Clock, "/clock", self._on_clock, QOS)
        self.create_subscription(Event, "/swarm/events", self._on_event, EVENTS_QOS)
        self.create_subscription(String, "/world/status", self._on_status, QOS)

    def _on_clock(self, message: Clock) -> None:
        self.t = message.clock.sec + message.clock.nanosec * 1e-9

    def _on_status(self, message: String) -> None:
        status = json.loads(message.data)
        self.final = status if status.get("final") else self.final

    def client(self, kind: Any, name: str) -> ActionClient:
        """The action client of `name` (made once, and waited for)."""
        if name not in self.actions:
            self.actions[name] = ActionClient(self, kind, name)
            assert self.actions[name].wait_for_server(timeout_sec=20), name
        return self.actions[name]

    def send(self, kind: Any, name: str, goal: Any, then: Any = None) -> None:
        """Send a goal; log its acceptance and its end; on success call `then(result)`."""
        entry: dict[str, Any] = {"goal": name, "sent": self.t}
        self.log.append(entry)

        def ended(future: Any) -> None:
            answer = future.result()
            entry.update(status=answer.status, ended=self.t)
            if then is not None and answer.status == SUCCEEDED:
                then(answer.result)

        def accepted(future: Any) -> None:
            handle = future.result()
            entry["accepted"] = handle.accepted
            handle.get_result_async().add_done_callback(ended)

        self.client(kind, name).send_goal_async(goal).add_done_callback(accepted)

    def take_off(self, uav: str) -> None:
        """TakeOff, then Coverage."""
        altitude = self.config.get("altitude", 1.0)
        cover = Coverage.Goal(altitude=altitude)
        self.send(Takeoff, f"/{uav}/cmd/takeoff", Takeoff.Goal(altitude=altitude),
                  lambda _: self.send(Coverage, f"/{uav}/uav_coverage", cover))  # fmt: skip

    def _on_event(self, message: Event) -> None:
        data = json.loads(message.data or "{}")
        self.events.append({"t": self.t, "name": message.name, "sender": message.sender,
                            "data": data})  # fmt: skip
        ugv = self.config.get("ugv")
        if message.name != "targetFound" or self.found or ugv is None:
            return
        self.found = True  # the first find: the UGV drives there and rescues it
        position = data["pose"]["pose"]["position"]
        where = target_pose(position["x"], position["y"])
        rescue = Target.Goal(target_id=data["target_id"], target_pose=where)
        self.send(MoveBase, f"/{ugv}/cmd/moveto", MoveBase.Goal(target_pose=where),
                  lambda _: self.send(Target, f"/{ugv}/ugv_rescue", rescue))  # fmt: skip


def run_member(path: str) -> dict[str, Any]:
    """The `member` mode: TakeOff goals accepted, "ready", then on until the world ends."""
    with open(path, encoding="utf-8") as handle:
        config = json.load(handle)
    member = Member(config)
    if config.get("ugv"):  # discovered before the world starts: no wait inside the run
        member.client(MoveBase, f"/{config['ugv']}/cmd/moveto")
        member.client(Target, f"/{config['ugv']}/ugv_rescue")
    for uav in config["uavs"]:
        member.client(Coverage, f"/{uav}/uav_coverage")
        member.take_off(uav)
    deadline = time.monotonic() + 20
    while not all("accepted" in e for e in member.log) and time.monotonic() < deadline:
        rclpy.spin_once(member, timeout_sec=0.05)
    print(json.dumps({"event": "ready"}), flush=True)
    deadline = time.monotonic() + config.get("limit_s", 60)
    while member.final is None and time.monotonic() < deadline:
        rclpy.spin_once(member, timeout_sec=0.05)
    return {"goals": member.log, "events": member.events, "final": member.final}


def main() -> int:
    """Run one scenario; its record as the last stdout line."""
    scenario = sys.argv[1]
    rclpy.init()
    try:
        if scenario == "member":
            print(json.dumps(run_member(sys.argv[2])), flush=True)
            return 0
        runs = {"moveto": lambda: run_moveto(False), "cancel": lambda: run_moveto(True),
                "auction": run_auction, "coverage": run_coverage, "rescue": run_rescue}  # fmt: skip
        print(json.dumps(runs[scenario]()), flush=True)
    finally:
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
