"""The nodes of the behaviour servers process (`servers.py` runs them): one rclpy node per
member and the process's shared node.

Each member node serves, in the member's namespace, every behaviour the servers file names, at
its `rosName` with its `rosType` (imported by name), driving the pure controllers in lockstep
with the world node: it acts for step k once it holds the `camera` and the `pose` of step k, and
answers each pose with exactly one stamped `cmd_vel` (the active moving behaviour's command,
else zero; the pose's stamp copied in). Once every member has answered step k, the process sends
its one step report for k on `/world/settle`. The process's own node (`swarmgen_servers`)
carries what the members share: the swarm events, the auction topic, `/world/settle` and
`/world/rescue`. The algorithms are in `sar_servers`.
Exit 2 (one line on stderr) for a bad servers file, a type that does not import, or a behaviour
the library does not implement. See docs/detailed.md, "The behaviour servers".
"""

from __future__ import annotations

import itertools
import json
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from geometry_msgs.msg import PoseStamped, TwistStamped  # type: ignore[import-untyped,unused-ignore]
from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from std_msgs.msg import String  # type: ignore[import-untyped,unused-ignore]

from . import auction_bus
from .auction import AuctionOpen, AuctionResult, Bid
from .controllers import PREEMPTED, Controller
from .counting import Counters
from .geometry import ZERO, Command, Pose
from .ros_fields import pose_dict, pose_of, write_fields
from .servers_config import MemberConfig, ServersConfig, import_type
from .tracking import TARGET_FOUND, TargetEvent, TargetMonitoring

# Lockstep topics lose nothing: a lost pose or cmd_vel would stall the world for a timeout.
QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
JOIN_POLL_S = 0.02  # how often the servers look whether every client is matched
EVENTS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)  # as the members'


def sim_time() -> list[Parameter[bool]]:
    """Every node runs on the world's `/clock`."""
    return [Parameter("use_sim_time", Parameter.Type.BOOL, True)]


class Activity:
    """One running behaviour of a member: its controller, and a future done with the outcome.
    Subclasses (sar_servers) add what the behaviour does on a step and on swarm news."""

    def __init__(self, member: MemberNode, controller: Controller) -> None:
        """Not started until the member has a pose (`begin`)."""
        self.member = member
        self.controller = controller
        self.future: Future[str] = Future()
        self.started = False

    def begin(self, pose: Pose, t: float) -> None:
        """Start the controller (subclasses: open an auction, check the target, ...)."""
        self.controller.start(pose, t)
        self.started = True

    def on_step(self, pose: Pose, t: float, visible: Sequence[tuple[int, float, float]]) -> Command:
        """One control period: the controller's command."""
        return self.controller.step(pose, t)

    def on_monitor(self, event: TargetEvent) -> None:
        """The member's monitoring reported `event` (found or lost)."""

    def on_event(self, name: str, data: dict[str, Any]) -> None:
        """A swarm event was heard."""

    def on_auction(self, message: AuctionOpen | Bid | AuctionResult) -> None:
        """An auction message was heard."""

    def outputs(self) -> dict[str, Any]:
        """The result fields (the controller's, by default)."""
        return dict(self.controller.outputs)

    def ended(self, outcome: str) -> None:
        """The behaviour ended with `outcome` (subclasses: report a rescue, ...)."""


class Swarm(Node):
    """What the members share: swarm events, the auction topic, settling and rescues."""

    def __init__(self, config: ServersConfig) -> None:
        """Publishers and subscriptions on the shared topics."""
        super().__init__("swarmgen_servers", parameter_overrides=sim_time())
        self.config = config
        self.members: dict[str, MemberNode] = {}
        self.k = 0  # the latest step any member acted on
        self._pending = False  # something a member reacts to happened since the last report
        self._acted: dict[int, set[str]] = {}  # per step, the members that have answered it
        self.positions: dict[int, tuple[float, float]] = {}  # where each known target is
        self.found_by: dict[int, str] = {}
        self.rescued: set[int] = set()
        self.auctions: dict[int, AuctionOpen] = {}  # the open auction of each target
        self.event_type = import_type(config.event_type) if config.event_type else None
        self._ids: dict[str, Iterator[int]] = {}
        self._settle = self.create_publisher(String, "/world/settle", QOS)
        self.counters = Counters(config.name, lambda text: self._settle.publish(String(data=text)))
        me = self.get_fully_qualified_name()
        self._heard = (f"{config.event_topic}@{me}", f"{config.auction_topic}@{me}")
        self.counters.listen(self._heard[1])
        self._rescue = self.create_publisher(String, "/world/rescue", QOS)
        self._auction = self.create_publisher(String, config.auction_topic, EVENTS_QOS)
        self.create_subscription(String, config.auction_topic, self._heard_auction, EVENTS_QOS)
        if self.event_type is not None:
            self._events = self.create_publisher(self.event_type, config.event_topic, EVENTS_QOS)
            self.create_subscription(
                self.event_type, config.event_topic, self._heard_event, EVENTS_QOS
            )
            self.counters.listen(self._heard[0])

    def join_barrier(self, timeout_s: float, joined: Callable[[bool], None]) -> None:
        """Subscribe to the world's probes once every service of every member has a client
        (or after `timeout_s` wall seconds; `joined(False)` then). *Why:* Fast DDS drops a
        response whose client's response reader the server has not matched yet ("client will
        not receive response"), and under load that match can lag the client's own view that
        the server is up by more than its 100 ms grace: a goal sent then is accepted, but its
        answer is lost. The world starts stepping only when every reporter has subscribed,
        and the generated swarm sends nothing before the world's first probe, so no request
        reaches a server that cannot answer it."""
        deadline = time.monotonic() + timeout_s
        steady = Clock(clock_type=ClockType.STEADY_TIME)  # wall time: /clock has not started

        def poll() -> None:
            if not self.context.ok():
                return  # shutting down (a signal): rcl calls would fail
            matched = all(
                m.count_clients(name) > 0 for m in self.members.values() for name in m.served
            )
            if matched or time.monotonic() > deadline:
                timer.cancel()
                self.create_subscription(String, "/world/settle/probe",
                                         lambda m: self.counters.probe(m.data), QOS)  # fmt: skip
                joined(matched)

        timer = self.create_timer(JOIN_POLL_S, poll, clock=steady)

    def settle(self) -> None:
        """Something a member reacts to happened: the next step report asks the world to
        settle (to give the members' reactions time before it steps on)."""
        self._pending = True

    def acted(self, member: str, k: int) -> None:
        """`member` has answered step k: once every member has, the one report of step k
        (`{"k", "by", "settle"}`), settling when anything happened since the last report."""
        done = self._acted.setdefault(k, set())
        done.add(member)
        if len(done) < len(self.members):
            return
        for old in [s for s in self._acted if s <= k]:  # an older step never completes now
            del self._acted[old]
        settle, self._pending = self._pending, False
        self.counters.step_done(k, settle)

    def send(self, sender: str, name: str, data: dict[str, Any]) -> None:
        """A swarm event from `sender`, if the model declares `name` (and there is a type)."""
        if self.event_type is None or name not in self.config.declared_events:
            return
        ids = self._ids.setdefault(sender, itertools.count(1 << 41))
        message = self.event_type()
        values = {"id": next(ids), "sender": sender, "name": name, "data": json.dumps(data)}
        for field, value in values.items():
            if hasattr(message, field):
                setattr(message, field, value)
        if hasattr(message, "stamp"):
            message.stamp = self.get_clock().now().to_msg()
        self._events.publish(message)
        self.counters.sent[self.config.event_topic] += 1
        self.settle()

    def send_auction(self, message: AuctionOpen | Bid | AuctionResult) -> None:
        """An auction message to every member (this process's included, through DDS)."""
        self._auction.publish(String(data=auction_bus.encode(message)))
        self.counters.sent[self.config.auction_topic] += 1
        self.settle()

    def found(self, member: MemberNode, event: TargetEvent) -> None:
        """`member` found a target nobody knew: every monitor knows it, the swarm hears it."""
        self.positions[event.target_id] = (event.x, event.y)
        self.found_by.setdefault(event.target_id, member.name)
        for other in self.members.values():
            if other.monitor is not None:
                other.monitor.know(event.target_id)
        member.publish_found(event)
        pose = pose_dict(event.x, event.y)
        self.send(member.name, TARGET_FOUND, {"target_id": event.target_id, "pose": pose})

    def forget(self, target_id: int) -> None:
        """The target's allocation failed: it may be found again (the abstract level's rule)."""
        if target_id in self.rescued:
            return
        self.found_by.pop(target_id, None)
        for member in self.members.values():
            if member.monitor is not None:
                member.monitor.forget(target_id)

    def rescue(self, robot: str, target_id: int) -> None:
        """`robot` rescued the target: the world and the swarm are told."""
        self.rescued.add(target_id)
        # `k`: the world counts the rescue at the step it happened in, whenever it arrives
        rescue = {"target": target_id, "robot": robot, "k": self.k}
        self._rescue.publish(String(data=json.dumps(rescue)))
        self._learn_rescued(target_id)
        self.send(robot, "targetRescued", {"target_id": target_id})

    def _learn_rescued(self, target_id: int) -> None:
        self.rescued.add(target_id)
        for member in self.members.values():
            if member.monitor is not None:
                member.monitor.know(target_id)

    def _heard_event(self, message: Any) -> None:
        self.counters.received[self._heard[0]] += 1
        try:
            data = json.loads(message.data) if message.data else {}
        except ValueError:
            data = {}
        if not isinstance(data, dict):
            data = {}
        name, target = str(message.name), data.get("target_id")
        if name == TARGET_FOUND and isinstance(target, int):
            position = data.get("pose", {}).get("pose", {}).get("position", {})
            if "x" in position and "y" in position:
                self.positions.setdefault(target, (float(position["x"]), float(position["y"])))
            for member in self.members.values():
                if member.monitor is not None:
                    member.monitor.know(target)
        elif name == "targetRescued" and isinstance(target, int):
            self._learn_rescued(target)
        for member in self.members.values():
            member.tell(lambda act: act.on_event(name, data))
        self.settle()
        self.counters.changed()

    def _heard_auction(self, message: String) -> None:
        self.counters.received[self._heard[1]] += 1
        item = auction_bus.decode(message.data)
        if item is not None:
            if isinstance(item, AuctionOpen):
                self.auctions[item.target_id] = item
            for member in self.members.values():
                member.tell(lambda act: act.on_auction(item))
            self.settle()
        self.counters.changed()


class MemberNode(Node):
    """One member: its pose and camera in, its `cmd_vel` out, its running behaviours."""

    def __init__(self, swarm: Swarm, config: MemberConfig, index: int) -> None:
        """Subscriptions and the command publisher in the member's namespace."""
        super().__init__("behaviour_servers", namespace=f"/{config.namespace}",
                         parameter_overrides=sim_time())  # fmt: skip
        self.swarm, self.config, self.index = swarm, config, index
        self.name = config.namespace
        self.pose: Pose | None = None
        self.t = 0.0
        self.activities: list[Activity] = []
        self.monitor: TargetMonitoring | None = None
        self.served: list[str] = []  # its services' names (an action's: its send_goal service)
        self.found_publisher: tuple[Any, Any] | None = None  # (publisher, message type)
        self.last_target: int | None = None
        self._poses: dict[int, tuple[Pose, Any]] = {}  # per step: the pose and its stamp
        self._cameras: dict[int, list[tuple[int, float, float]]] = {}
        self._cmd = self.create_publisher(TwistStamped, "cmd_vel", QOS)
        self.create_subscription(PoseStamped, "pose", self._on_pose, QOS)
        self.create_subscription(String, "camera", self._on_camera, QOS)

    def publish_found(self, event: TargetEvent) -> None:
        """The monitoring's report on its declared topic (e.g. a TargetPositionEvent)."""
        if self.found_publisher is None:
            return
        publisher, kind = self.found_publisher
        message = kind()
        write_fields(message, {"id": event.target_id, "target_id": event.target_id})
        where = {"x": event.x, "y": event.y, "z": 0.0}
        write_fields(message, {"pose": where, "target_pose": where})
        if hasattr(message, "header"):
            message.header.frame_id = "map"
            message.header.stamp = self.get_clock().now().to_msg()
        publisher.publish(message)
        self.swarm.counters.sent[publisher.topic_name] += 1

    async def run(self, activity: Activity) -> str:
        """Run a behaviour to its end: the outcome."""
        self.activities.append(activity)
        if self.pose is not None:
            activity.begin(self.pose, self.t)
        self.swarm.settle()
        self.check(activity)
        outcome = await activity.future
        return outcome if outcome is not None else PREEMPTED

    def preempt(self, activity: Activity) -> None:
        """Cancel: the controller stops now, so the next `cmd_vel` is already zero."""
        activity.controller.stop()
        self.check(activity)

    def check(self, activity: Activity) -> None:
        """End the activity if its controller has an outcome."""
        outcome = activity.controller.done
        if outcome is None or activity not in self.activities:
            return
        self.activities.remove(activity)
        activity.ended(outcome)
        self.swarm.counters.busy += 1  # until its result is sent (a later executor turn)
        activity.future.set_result(outcome)
        self.swarm.settle()

    def tell(self, news: Any) -> None:
        """Pass swarm news to every running activity, then end those it finished."""
        for activity in list(self.activities):
            news(activity)
            self.check(activity)

    def _on_pose(self, message: PoseStamped) -> None:
        stamp = message.header.stamp
        k = round((stamp.sec + stamp.nanosec * 1e-9) / self.swarm.config.dt)
        self._poses[k] = (pose_of(message), stamp)
        self._ready(k)

    def _on_camera(self, message: String) -> None:
        try:
            raw = json.loads(message.data)
            k = int(raw["k"])
            seen = [(int(t["id"]), float(t["x"]), float(t["y"])) for t in raw.get("targets", [])]
        except (ValueError, KeyError, TypeError):
            self.get_logger().warning(f"ignored a camera message: {message.data[:200]!r}")
            return
        self._cameras[k] = seen
        self._ready(k)

    def _ready(self, k: int) -> None:
        if k in self._poses and k in self._cameras:
            for old in [s for s in self._poses if s <= k]:
                pose, stamp = self._poses.pop(old)
            visible = self._cameras.pop(k)
            for old in [s for s in self._cameras if s < k]:
                del self._cameras[old]
            self.step(k, pose, visible, stamp)

    def step(self, k: int, pose: Pose, visible: list[tuple[int, float, float]], stamp: Any) -> None:
        """Step k: monitoring, then every running behaviour; exactly one `cmd_vel`, stamped
        with the pose's `stamp` (the step it answers), then the member has acted on k."""
        self.pose, self.t = pose, k * self.swarm.config.dt
        self.swarm.k = max(self.swarm.k, k)
        if self.monitor is not None:
            for event in self.monitor.observe(visible, self.t):
                if event.name == TARGET_FOUND:
                    self.swarm.found(self, event)
                self.tell(lambda act, e=event: act.on_monitor(e))
        movers = [a for a in self.activities if a.controller.moves]
        mover = movers[-1] if movers else None  # the latest moving goal owns the body
        command = ZERO
        for activity in list(self.activities):
            if not activity.started:
                activity.begin(pose, self.t)
            own = activity.on_step(pose, self.t, visible)
            if activity is mover:
                command = own
            self.check(activity)
        if mover is not None and mover.controller.done is not None:
            command = ZERO
        answer = TwistStamped()
        answer.header.stamp = stamp
        answer.header.frame_id = "map"
        linear = answer.twist.linear
        linear.x, linear.y, linear.z = command.vx, command.vy, command.vz
        self._cmd.publish(answer)
        self.swarm.acted(self.name, k)
