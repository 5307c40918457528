"""The SAR library's behaviours as servers: each algorithm's activity (what it does on a step and
on swarm news) and how it is served on its declared interface (action, service or topic).

Goal and request fields are read by name (`altitude`, `target_id`, `target_pose`), result and
response fields written by name (`target_id`, `target_pose`, `rover_id`, `base_position`, an
`outcome` string for an outcome beyond succeeded/aborted/preempted, `success` for services).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from rclpy.action.server import ActionServer, CancelResponse, GoalResponse

from .auction import Auctioneer, AuctionOpen, AuctionResult, Bid, Bidder, member_number
from .controllers import ABORTED, PREEMPTED, SUCCEEDED, Base, Land, MoveTo, TakeOff
from .coverage import LocalCoverage, RandomDirection
from .geometry import ZERO, Command, Pose, positive
from .members import QOS, Activity, MemberNode
from .rng import Stream, member_key
from .ros_fields import read_number, read_xy, write_fields
from .servers_config import BehaviourConfig, ConfigError, ServersConfig, import_type
from .tracking import TARGET_FOUND, TARGET_LOST, TargetEvent, TargetMonitoring, Tracking

STANDARD = (SUCCEEDED, ABORTED, PREEMPTED)
Visible = Sequence[tuple[int, float, float]]


class Rescue(Base):
    """Drive to the target, stay there `duration` seconds, then `succeeded`."""

    def __init__(
        self, x: float, y: float, max_speed: float, dt: float, tolerance: float, duration: float
    ) -> None:
        """The target at (x, y)."""
        super().__init__()
        self.drive = MoveTo(x, y, None, max_speed, dt, tolerance)
        self.duration = positive("rescue_s", duration)
        self.arrived: float | None = None

    def start(self, pose: Pose, t: float) -> None:
        """Head for the target."""
        super().start(pose, t)
        self.drive.start(pose, t)
        self.arrived = None

    def step(self, pose: Pose, t: float) -> Command:
        """Drive, then wait at the target."""
        if self._done is not None:
            return ZERO
        if self.arrived is None:
            command = self.drive.step(pose, t)
            if self.drive.done != SUCCEEDED:
                return command
            self.arrived = t
        if t - self.arrived >= self.duration:
            return self.finish(SUCCEEDED)
        return ZERO


class Coverage(Activity):
    """Random direction; with `single_target`, the member's own first find ends it."""

    def on_monitor(self, event: TargetEvent) -> None:
        """A find by this member."""
        if event.name == TARGET_FOUND and isinstance(self.controller, RandomDirection):
            self.controller.target_found(event.target_id, event.x, event.y)


class Spiral(Activity):
    """Local coverage: succeeds on seeing its target (the member's last, else any)."""

    def on_step(self, pose: Pose, t: float, visible: Visible) -> Command:
        """Look, then follow the spiral."""
        assert isinstance(self.controller, LocalCoverage)
        for target_id, x, y in visible:
            if target_id not in self.member.swarm.rescued:
                self.controller.target_found(target_id, x, y)
        return self.controller.step(pose, t)


class Follow(Activity):
    """Tracking: follows the target seen or known; succeeds on its rescue, ends `targetLost`
    when the member's monitoring loses it."""

    def __init__(self, member: MemberNode, controller: Tracking) -> None:
        """Track `controller.target_id`."""
        super().__init__(member, controller)
        self.tracking = controller

    def begin(self, pose: Pose, t: float) -> None:
        """Watch the target; an already rescued one succeeds at once."""
        super().begin(pose, t)
        target = self.tracking.target_id
        self.member.last_target = target
        if self.member.monitor is not None:
            self.member.monitor.track(target)
        if target in self.member.swarm.rescued:
            self.tracking.rescued(target)

    def on_step(self, pose: Pose, t: float, visible: Visible) -> Command:
        """Follow where the target is seen."""
        for target_id, x, y in visible:
            self.tracking.update(target_id, x, y)
        return self.tracking.step(pose, t)

    def on_monitor(self, event: TargetEvent) -> None:
        """The tracked target left the view."""
        if event.name == TARGET_LOST:
            self.tracking.lost(event.target_id)

    def on_event(self, name: str, data: dict[str, Any]) -> None:
        """`targetRescued` of the target: succeeded."""
        if name == "targetRescued" and data.get("target_id") == self.tracking.target_id:
            self.tracking.rescued(self.tracking.target_id)

    def outputs(self) -> dict[str, Any]:
        """Tracking's result carries no pose; only the outcome field (set by the server)."""
        return {}


class Rescuing(Activity):
    """Rescue: at the end, `/world/rescue` and the `targetRescued` swarm event."""

    def __init__(self, member: MemberNode, controller: Rescue, target_id: int) -> None:
        """Rescue `target_id`."""
        super().__init__(member, controller)
        self.target_id = target_id

    def begin(self, pose: Pose, t: float) -> None:
        """A target rescued already: aborted."""
        super().begin(pose, t)
        if self.target_id in self.member.swarm.rescued:
            assert isinstance(self.controller, Rescue)
            self.controller.finish(ABORTED)

    def ended(self, outcome: str) -> None:
        """Tell the world and the swarm."""
        if outcome == SUCCEEDED:
            self.member.swarm.rescue(self.member.name, self.target_id)


class Auctioning(Activity):
    """TaskAllocation: the finder of the target auctions it; anyone else aborts at once."""

    def __init__(self, member: MemberNode, controller: Auctioneer, target: int, at: Any) -> None:
        """Auction `target` at `at` ((x, y) or None: where the swarm knows it)."""
        super().__init__(member, controller)
        self.auctioneer, self.target, self.at = controller, target, at

    def begin(self, pose: Pose, t: float) -> None:
        """Open the auction (the member's own find only)."""
        super().begin(pose, t)
        swarm = self.member.swarm
        where = self.at or swarm.positions.get(self.target)
        if swarm.found_by.get(self.target) != self.member.name or where is None:
            self.auctioneer.finish(ABORTED, rover_id=0, target_id=self.target)
            return
        swarm.send_auction(self.auctioneer.open(self.target, where[0], where[1], t))

    def on_step(self, pose: Pose, t: float, visible: Visible) -> Command:
        """Close at the deadline: the result to the swarm, `targetAssigned` for a winner."""
        result = self.auctioneer.close(t)
        if result is not None:
            swarm = self.member.swarm
            swarm.send_auction(result)
            if result.winner is not None:
                rover = member_number(result.winner)
                swarm.send(self.member.name, "targetAssigned",
                           {"target_id": self.target, "rover_id": rover})  # fmt: skip
            else:
                swarm.forget(self.target)
        return ZERO

    def on_auction(self, message: AuctionOpen | Bid | AuctionResult) -> None:
        """Bids for this auction."""
        if isinstance(message, Bid):
            self.auctioneer.receive(message)


class Bidding(Activity):
    """TaskBidding: bid on the auction of the target; learn whether this member won."""

    def __init__(self, member: MemberNode, controller: Bidder, target: int, timeout: float):
        """Bid for `target`; abort when no auction opens within `timeout` seconds."""
        super().__init__(member, controller)
        self.bidder, self.target, self.timeout = controller, target, timeout
        self.since: float | None = None
        self.rover_id = 0

    def on_step(self, pose: Pose, t: float, visible: Visible) -> Command:
        """Bid once the auction is open; time out without one."""
        self.since = t if self.since is None else self.since
        auction = self.member.swarm.auctions.get(self.target)
        if self.bidder.auction is None and self.bidder.done is None:
            if auction is not None and auction.deadline >= t:
                bid = self.bidder.bid(auction, pose, t)
                if bid is not None:
                    self.member.swarm.send_auction(bid)
            elif t - self.since >= self.timeout:
                self.bidder.finish(ABORTED, target_id=self.target)
        return self.bidder.step(pose, t)

    def on_auction(self, message: AuctionOpen | Bid | AuctionResult) -> None:
        """The result of the auction bid for."""
        if isinstance(message, AuctionResult) and self.bidder.learn(message) is not None:
            self.rover_id = member_number(message.winner) if message.winner else 0

    def outputs(self) -> dict[str, Any]:
        """The bidder's fields and the winner's number."""
        return {**self.bidder.outputs, "rover_id": self.rover_id}


def _target(request: Any) -> int:
    return int(getattr(request, "target_id", 0))


Factory = Callable[[MemberNode, BehaviourConfig, Any], Activity]


def _motion(make: Callable[[MemberNode, dict[str, float], Any], Any]) -> Factory:
    return lambda member, cfg, request: Activity(member, make(member, cfg.params, request))


def _speed(member: MemberNode) -> tuple[float, float]:
    return member.config.max_speed, member.swarm.config.dt


def _coverage(member: MemberNode, cfg: BehaviourConfig, request: Any) -> Activity:
    config = member.swarm.config
    stream = Stream(member_key(config.seed, member.index))
    controller = RandomDirection(config.area, *_speed(member), stream,
                                 cfg.params["heading"], bool(cfg.params["single_target"]))  # fmt: skip
    return Coverage(member, controller)


def _local(member: MemberNode, cfg: BehaviourConfig, request: Any) -> Activity:
    p = member.swarm.config.area, *_speed(member)
    controller = LocalCoverage(*p, cfg.params["spacing"], cfg.params["local_duration"],
                               target=member.last_target)  # fmt: skip
    return Spiral(member, controller)


def _tracking(member: MemberNode, cfg: BehaviourConfig, request: Any) -> Activity:
    target = _target(request)
    where = member.swarm.positions.get(target)
    return Follow(member, Tracking(target, *_speed(member), where))


def _rescue(member: MemberNode, cfg: BehaviourConfig, request: Any) -> Activity:
    target = _target(request)
    x, y = read_xy(request, "target_pose") or member.swarm.positions.get(target, (0.0, 0.0))
    p = cfg.params
    return Rescuing(member, Rescue(x, y, *_speed(member), p["tolerance"], p["rescue_s"]), target)


def _allocation(member: MemberNode, cfg: BehaviourConfig, request: Any) -> Activity:
    auctioneer = Auctioneer(member.name, cfg.params["auction_window"])
    return Auctioning(member, auctioneer, _target(request), read_xy(request, "target_pose"))


def _bidding(member: MemberNode, cfg: BehaviourConfig, request: Any) -> Activity:
    bidder = Bidder(member.name, cfg.params["bid_grace"])
    return Bidding(member, bidder, _target(request), cfg.params["bid_timeout"])


def _move_to(member: MemberNode, params: dict[str, float], request: Any) -> MoveTo:
    x, y = read_xy(request, "target_pose") or (0.0, 0.0)
    return MoveTo(x, y, None, *_speed(member), params["tolerance"])


def _take_off(member: MemberNode, params: dict[str, float], request: Any) -> TakeOff:
    altitude = read_number(request, "altitude", 1.0)
    return TakeOff(altitude, *_speed(member), params["tolerance"])


def _land(member: MemberNode, params: dict[str, float], request: Any) -> Land:
    return Land(*_speed(member), params["tolerance"])


# algorithm -> (the declared kinds it is served on, its activity's factory)
GOALS: dict[str, tuple[tuple[str, ...], Factory]] = {
    "TakeOff": (("action", "service"), _motion(_take_off)),
    "Land": (("action", "service"), _motion(_land)),
    "MoveTo": (("action", "service"), _motion(_move_to)),
    "Coverage": (("action",), _coverage),
    "LocalCoverage": (("action",), _local),
    "Tracking": (("action",), _tracking),
    "Rescue": (("action",), _rescue),
    "TaskAllocation": (("action",), _allocation),
    "TaskBidding": (("action",), _bidding),
}
TOPICS = ("TargetMonitoring", "UwbPositioning")  # topic behaviours: reports, or the world's pose


def check(config: ServersConfig) -> None:
    """ConfigError for a behaviour the library does not implement, on a kind it cannot serve,
    or whose type does not import (the algorithms first: that error needs no ROS package)."""
    for member in config.members:
        for behaviour in member.behaviours.values():
            where = f"member {member.namespace}, behaviour {behaviour.name}"
            algorithm = behaviour.algorithm
            kinds = ("topic",) if algorithm in TOPICS else GOALS.get(algorithm, ((), None))[0]
            if not kinds:
                known = sorted([*GOALS, *TOPICS])
                raise ConfigError(f"{where}: the library does not implement {algorithm!r} "
                                  f"(it implements {', '.join(known)})")  # fmt: skip
            if behaviour.kind not in kinds:
                raise ConfigError(f"{where}: {algorithm} is served as {'/'.join(kinds)}, "
                                  f"not as a {behaviour.kind}")  # fmt: skip
    if config.event_type:
        import_type(config.event_type)
    for member in config.members:
        for behaviour in member.behaviours.values():
            import_type(behaviour.ros_type)


def attach(member: MemberNode) -> None:
    """Create the member's servers and topics for every behaviour of its configuration."""
    for behaviour in member.config.behaviours.values():
        kind = import_type(behaviour.ros_type)
        if behaviour.algorithm == "TargetMonitoring":
            member.monitor = TargetMonitoring()
            member.found_publisher = (member.create_publisher(kind, behaviour.ros_name, QOS), kind)
        elif behaviour.algorithm in GOALS:
            factory = GOALS[behaviour.algorithm][1]
            if behaviour.kind == "action":
                _action(member, behaviour, kind, factory)
            else:
                _service(member, behaviour, kind, factory)


def _action(member: MemberNode, cfg: BehaviourConfig, kind: Any, factory: Factory) -> None:
    running: dict[bytes, Activity] = {}

    counters = member.swarm.counters

    async def execute(handle: Any) -> Any:
        counters.busy -= 1  # accepted, now executing
        activity = factory(member, cfg, handle.request)
        counters.changed()
        key = bytes(handle.goal_id.uuid)
        running[key] = activity
        try:
            outcome = await member.run(activity)
        finally:
            running.pop(key, None)
            counters.busy -= 1  # ended (`check`); the result goes out as this returns
            counters.sent["result"] += 1
            counters.changed()
        result = kind.Result()
        write_fields(result, activity.outputs())
        if outcome == SUCCEEDED or outcome not in STANDARD:
            if outcome not in STANDARD:
                write_fields(result, {"outcome": outcome})
            handle.succeed()
        elif outcome == PREEMPTED and handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.abort()
        return result

    def cancel(handle: Any) -> CancelResponse:
        activity = running.get(bytes(handle.goal_id.uuid))
        if activity is not None:
            member.preempt(activity)
            counters.changed()
        return CancelResponse.ACCEPT

    def accept(_goal: Any) -> GoalResponse:
        counters.received["goal"] += 1
        counters.sent["goal_response"] += 1  # sent as this returns
        counters.busy += 1  # until `execute` starts, in a later executor turn
        counters.changed()
        return GoalResponse.ACCEPT

    ActionServer(member, kind, cfg.ros_name, execute,
                 goal_callback=accept, cancel_callback=cancel)  # fmt: skip
    member.served.append(f"{member.resolve_service_name(cfg.ros_name)}/_action/send_goal")


def _service(member: MemberNode, cfg: BehaviourConfig, kind: Any, factory: Factory) -> None:
    counters = member.swarm.counters

    async def call(request: Any, response: Any) -> Any:
        counters.received["request"] += 1
        counters.changed()
        activity = factory(member, cfg, request)
        outcome = await member.run(activity)  # answered when the behaviour has ended
        write_fields(response, activity.outputs())
        write_fields(response, {"success": outcome == SUCCEEDED})
        counters.busy -= 1  # ended (`check`); the response goes out as this returns
        counters.sent["response"] += 1
        counters.changed()
        return response

    member.create_service(kind, cfg.ros_name, call)
    member.served.append(member.resolve_service_name(cfg.ros_name))
