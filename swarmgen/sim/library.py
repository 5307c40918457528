"""The simulated Abstraction Library: one implementation per behaviour name, driven by the world.

The compiled state machine of each member decides which behaviour runs when: the engine asks the
host to start a state's behaviour (with the arguments the compiled chart computed from member
data) and to cancel it when the state is left; an implementation here ends it with an outcome
and outputs, delivered as `done.invoke.<state>.<outcome>` exactly as the asyncio runtime delivers
them, and may emit swarm events through the member's bus. They are tick-driven counterparts of
the runtime's async `Behaviour`s: instead of a coroutine per activation, each kind keeps its
activations and the world advances all of them together (`World.advance`).

A behaviour whose outcome no transition of the machine waits for runs until it is preempted (as
the asyncio backend's simulated behaviours do). The implementations:

| behaviour | simulated as |
|---|---|
| TakeOff, Land | succeed after `timing.takeoff` / `timing.land` ticks |
| Coverage | random-direction coverage from where the member stands (`World`); if the machine waits for its outcome, it ends `succeeded` on the first find with outputs `target_id`, `target_pose` (the target's position in the shape of the output's model type, `swarmgen.sim.poses`) |
| TargetMonitoring | while active, finds by its member are reported as the swarm event `targetFound` (`target_id`, `pose`) |
| TaskAllocation (SelectRover) | the finder of the target auctions it: after `timing.allocation` ticks it assigns a bidding UGV (`allocation`: `paired`, the one that started where this member started; or `nearest`), emits `targetAssigned` and succeeds with `rover_id`; no bidder: `aborted` and the target can be found again. A member that did not find the target aborts at once |
| TaskBidding | bids for its target; succeeds when the auction assigns it, aborts when it assigns another or after `timing.bid_timeout` ticks |
| MoveTo | drives straight to the position in its pose argument (`poses.position_of`) at one patch per tick |
| Rescue | after `timing.rescue` ticks the target is rescued; emits `targetRescued` if the behaviour's `emits` tag names it (else the machine announces the rescue itself) |
| Tracking | hovers until its target is rescued, then succeeds |
| LocalCoverage | succeeds after `timing.local_coverage` ticks with the member's current target |
| anything else | succeeds after `timing.default` ticks with zero-valued outputs |

A find is reported once; if no behaviour of the finder takes it up (starts with that
`target_id`) in the same tick, it is forgotten and the target can be found again.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import field
from typing import Any, Protocol

from swarmgen.ir.primitives import zero_of
from swarmgen.records import dataclass
from swarmgen.runtime.member import Request
from swarmgen.sim.poses import placed, position_of
from swarmgen.sim.scenario import Scenario
from swarmgen.sim.world import FOUND, RESCUED, World


@dataclass(eq=False)
class Activation:
    """One run of a behaviour in one state of one member."""

    g: int  # the member's index in the batch
    run: int
    node_id: str
    number: int  # the engine's activation number (its outcome events carry it)
    behaviour: str
    request: Request
    waited: frozenset[str]  # outcomes some transition waits for ("*": any)
    started: int
    impl: SimBehaviour
    done: bool = False
    state: dict[str, Any] = field(default_factory=dict)

    @property
    def args(self) -> dict[str, Any]:
        """The behaviour's arguments, as the chart computed them."""
        return self.request.args


class Host(Protocol):
    """What implementations need from the simulator (`swarmgen.sim.run.Batch`)."""

    world: World
    scenario: Scenario

    def now(self, run: int) -> int:
        """The current tick of a run."""

    def after(self, act: Activation, ticks: int, then: Callable[[], None]) -> None:
        """Run `then` after `ticks`, unless the activation has ended by then."""

    def finish(self, act: Activation, outcome: str, outputs: Mapping[str, Any] | None) -> None:
        """End the activation with an outcome (and outputs) sent to its member."""

    def emit(self, act: Activation, event: str, data: Mapping[str, Any]) -> None:
        """Send an event from the activation's member, in the event's scope."""

    def outputs_of(self, behaviour: str) -> tuple[tuple[str, str | None], ...]:
        """The outputs (identifier, type) a behaviour declares."""

    def activation_of(self, g: int, impl: SimBehaviour) -> Activation | None:
        """The member's live activation of an implementation, if any."""

    def emits_of(self, behaviour: str) -> tuple[str, ...]:
        """The events a behaviour's `emits` tag names."""

    def initial_of(self, owner: str, name: str) -> Any:
        """The initial value of a behaviour's output or an event's field (None: unknown)."""


def outcome(act: Activation, wanted: str) -> str:
    """`wanted` if the machine can react to it, else an outcome it waits for."""
    if wanted in act.waited or "*" in act.waited or not act.waited:
        return wanted
    return sorted(act.waited)[0]


def target_of(host: Host, act: Activation, key: str = "target_id") -> int | None:
    """The target index (target_id - 1) an argument names, if it names one of this run."""
    value = act.args.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    index = int(value) - 1
    return index if 0 <= index < host.world.tx.shape[1] else None


def pose(host: Host, run: int, target: int, owner: str, name: str) -> Any:
    """The pose of a target of a run as the output or event field `owner.name` carries it
    (the shape of its model type, `poses.placed`)."""
    w = host.world
    template = host.initial_of(owner, name)
    return placed(template, float(w.tx[run, target]), float(w.ty[run, target]))


class SimBehaviour:
    """Base: `start` when the state is entered, `stop` when the activation ends either way."""

    name = "generic"

    def start(self, host: Host, act: Activation) -> None:
        """Succeed after `timing.default` ticks with zero-valued outputs (when waited for)."""
        if not act.waited:
            return  # nobody waits for it: it runs until preempted
        ticks = host.scenario.timing["default"]
        outputs = {n: zero_of(t) for n, t in host.outputs_of(act.behaviour)}
        host.after(act, ticks, lambda: host.finish(act, outcome(act, "succeeded"), outputs))

    def stop(self, host: Host, act: Activation) -> None:
        """The activation ended (finished or cancelled): release what it holds."""


class Timed(SimBehaviour):
    """A behaviour that succeeds after the scenario's timing of its name (TakeOff, Land)."""

    def __init__(self, name: str, timing: str) -> None:
        self.name = name
        self.timing = timing

    def start(self, host: Host, act: Activation) -> None:
        """Succeed after the behaviour's timing (when waited for)."""
        if not act.waited:
            return
        ticks = host.scenario.timing[self.timing]
        host.after(
            act, ticks, lambda: host.finish(act, outcome(act, "succeeded"), self.outputs(act))
        )

    def outputs(self, act: Activation) -> dict[str, Any]:
        """The outputs it succeeds with: none."""
        return {}


class LocalCoverage(Timed):
    """Succeeds after `timing.local_coverage` ticks with the member's current target."""

    def outputs(self, act: Activation) -> dict[str, Any]:
        """The member's current target, as it was passed in."""
        data = act.request.data
        return {"target_id": data.get("target_id"), "target_pose": data.get("target_pose")}


class Coverage(SimBehaviour):
    """Random-direction coverage in the world from where the member stands."""

    name = "Coverage"

    def start(self, host: Host, act: Activation) -> None:
        """Start covering; report the targets already in view."""
        reports = bool(act.waited)
        seen = host.world.start_covering(act.g, host.now(act.run), reports)
        if seen:
            found(host, act.run, act.g, seen)

    def stop(self, host: Host, act: Activation) -> None:
        """Stop where the member is now."""
        host.world.stop_covering(act.g, host.now(act.run))


class TargetMonitoring(SimBehaviour):
    """While active, the member's finds are reported to the swarm (`targetFound`)."""

    name = "TargetMonitoring"

    def start(self, host: Host, act: Activation) -> None:
        """The member's finds are reported from now on."""
        host.world.detecting[act.g] = True

    def stop(self, host: Host, act: Activation) -> None:
        """The member's finds are no longer reported."""
        host.world.detecting[act.g] = False


def found(host: Host, run: int, g: int, targets: list[int]) -> None:
    """Member g has unfound targets in view: its TargetMonitoring reports each as
    `targetFound`, and a Coverage that ends on a find ends with the first."""
    world = host.world
    now = host.now(run)
    monitor = host.activation_of(g, MONITOR)
    cover = host.activation_of(g, COVERAGE)
    for number, target in enumerate(targets):
        if world.status[run, target] != 0:
            continue
        world.report(run, target, g, now)
        if monitor is not None:
            where = pose(host, run, target, "targetFound", "pose")
            host.emit(monitor, "targetFound", {"target_id": target + 1, "pose": where})
        if number == 0 and cover is not None and world.reports[g]:
            where = pose(host, run, target, cover.behaviour, "target_pose")
            host.finish(
                cover,
                outcome(cover, "succeeded"),
                {"target_id": target + 1, "target_pose": where},
            )


class TaskAllocation(SimBehaviour):
    """The finder auctions its target among the UGVs that bid for it."""

    name = "TaskAllocation"

    def __init__(self) -> None:
        self.bids: dict[tuple[int, int], list[Activation]] = {}

    def start(self, host: Host, act: Activation) -> None:
        """Open the auction of the member's own find (abort for anyone else's)."""
        world = host.world
        target = target_of(host, act)
        if (
            target is None
            or world.finder[act.run, target] != act.g
            or world.status[act.run, target] == RESCUED
        ):
            host.finish(act, outcome(act, "aborted"), {"rover_id": 0})
            return
        host.after(act, host.scenario.timing["allocation"], lambda: self.close(host, act, target))

    def close(self, host: Host, act: Activation, target: int) -> None:
        """Assign the target to the chosen bidder and abort the others."""
        bidders = [b for b in self.bids.get((act.run, target), []) if not b.done]
        winner = self.choose(host, act, target, bidders)
        for bid in bidders:
            if bid is not winner:
                host.finish(bid, outcome(bid, "aborted"), None)
        if winner is None:
            if host.world.status[act.run, target] != RESCUED:
                host.world.forget(act.run, target)
            host.finish(act, outcome(act, "aborted"), {"rover_id": 0})
            return
        rover = winner.request.member_id
        rover_id = int(rover.rsplit("-", 1)[-1]) if rover.rsplit("-", 1)[-1].isdigit() else 0
        host.emit(act, "targetAssigned", {"target_id": target + 1, "rover_id": rover_id})
        host.finish(winner, outcome(winner, "succeeded"), None)
        host.finish(act, outcome(act, "succeeded"), {"rover_id": rover_id})

    def choose(
        self, host: Host, act: Activation, target: int, bidders: list[Activation]
    ) -> Activation | None:
        """The winning bid by `allocation`: the paired bidder, or the nearest."""
        world = host.world
        if host.scenario.allocation == "paired":
            mine = world.start_cell[act.g]
            return next((b for b in bidders if world.start_cell[b.g] == mine), None)
        best: tuple[float, int] | None = None
        chosen = None
        for bid in bidders:
            x, y = world.where(bid.g)
            dist = math.hypot(world.tx[act.run, target] - x, world.ty[act.run, target] - y)
            if best is None or (dist, bid.g) < best:
                best, chosen = (dist, bid.g), bid
        return chosen


class TaskBidding(SimBehaviour):
    """Bids for the member's target; succeeds when the auction assigns it to this member."""

    name = "TaskBidding"

    def __init__(self, auctions: TaskAllocation) -> None:
        self.auctions = auctions

    def start(self, host: Host, act: Activation) -> None:
        """Bid for the target; abort after `timing.bid_timeout` ticks."""
        target = target_of(host, act)
        if target is None:
            host.finish(act, outcome(act, "aborted"), None)
            return
        act.state["key"] = key = (act.run, target)
        self.auctions.bids.setdefault(key, []).append(act)
        host.after(
            act,
            host.scenario.timing["bid_timeout"],
            lambda: host.finish(act, outcome(act, "aborted"), None),
        )

    def stop(self, host: Host, act: Activation) -> None:
        """Withdraw the bid."""
        key: tuple[int, int] | None = act.state.get("key")
        bids = self.auctions.bids.get(key) if key is not None else None
        if key is not None and bids is not None and act in bids:
            bids.remove(act)
            if not bids:
                del self.auctions.bids[key]


class Tracking(SimBehaviour):
    """Hovers over its target until a UGV has rescued it."""

    name = "Tracking"

    def __init__(self) -> None:
        self.trackers: dict[tuple[int, int], list[Activation]] = {}

    def start(self, host: Host, act: Activation) -> None:
        """Hover over the target until it is rescued."""
        target = target_of(host, act)
        if target is None:
            host.finish(act, outcome(act, "aborted"), None)
            return
        if host.world.status[act.run, target] == RESCUED:
            host.finish(act, outcome(act, "succeeded"), None)
            return
        act.state["key"] = key = (act.run, target)
        self.trackers.setdefault(key, []).append(act)

    def rescued(self, host: Host, run: int, target: int) -> None:
        """The target was rescued: its trackers succeed."""
        for act in list(self.trackers.get((run, target), [])):
            host.finish(act, outcome(act, "succeeded"), None)

    def stop(self, host: Host, act: Activation) -> None:
        """Stop tracking."""
        key: tuple[int, int] | None = act.state.get("key")
        acts = self.trackers.get(key) if key is not None else None
        if key is not None and acts is not None and act in acts:
            acts.remove(act)
            if not acts:
                del self.trackers[key]


class MoveTo(SimBehaviour):
    """Straight to the pose at one patch per tick."""

    name = "MoveTo"

    def start(self, host: Host, act: Activation) -> None:
        """Drive straight to the goal pose, one patch per tick."""
        goal = next((p for p in map(position_of, act.args.values()) if p is not None), None)
        if goal is None:
            host.finish(act, outcome(act, "aborted"), None)
            return
        world = host.world
        x0, y0 = world.where(act.g)
        x1, y1 = goal
        distance = math.hypot(x1 - x0, y1 - y0)
        act.state.update(x0=x0, y0=y0, x1=x1, y1=y1, distance=distance)

        def arrive() -> None:
            world.place(act.g, x1, y1)
            act.state["arrived"] = True
            host.finish(act, outcome(act, "succeeded"), None)

        host.after(act, math.ceil(distance - 1e-9), arrive)

    def stop(self, host: Host, act: Activation) -> None:
        """Stopped on the way: stand where the drive has got to."""
        s = act.state
        if not s or s.get("arrived"):
            return
        travelled = host.now(act.run) - act.started
        share = min(1.0, travelled / s["distance"]) if s["distance"] > 0 else 1.0
        host.world.place(
            act.g, s["x0"] + share * (s["x1"] - s["x0"]), s["y0"] + share * (s["y1"] - s["y0"])
        )


class Rescue(SimBehaviour):
    """Rescues the member's target after `timing.rescue` ticks (and emits `targetRescued` if the
    behaviour declares it)."""

    name = "Rescue"

    def __init__(self, tracking: Tracking) -> None:
        self.tracking = tracking

    def start(self, host: Host, act: Activation) -> None:
        """Rescue the target after `timing.rescue` ticks."""

        def done() -> None:
            target = target_of(host, act)
            if target is None or host.world.status[act.run, target] == RESCUED:
                host.finish(act, outcome(act, "aborted"), None)
                return
            host.world.rescue(act.run, target, host.now(act.run))
            if "targetRescued" in host.emits_of(act.behaviour):  # else the machine announces it
                host.emit(act, "targetRescued", {"target_id": target + 1})
            self.tracking.rescued(host, act.run, target)
            host.finish(act, outcome(act, "succeeded"), None)

        host.after(act, host.scenario.timing["rescue"], done)


COVERAGE = Coverage()
MONITOR = TargetMonitoring()


class Library:
    """The implementations of one batch, by simulated behaviour name."""

    def __init__(self, aliases: Mapping[str, str]) -> None:
        allocation = TaskAllocation()
        tracking = Tracking()
        self.tracking = tracking
        self.impls: dict[str, SimBehaviour] = {
            "TakeOff": Timed("TakeOff", "takeoff"),
            "Land": Timed("Land", "land"),
            "Coverage": COVERAGE,
            "LocalCoverage": LocalCoverage("LocalCoverage", "local_coverage"),
            "TargetMonitoring": MONITOR,
            "TaskAllocation": allocation,
            "TaskBidding": TaskBidding(allocation),
            "Tracking": tracking,
            "MoveTo": MoveTo(),
            "Rescue": Rescue(tracking),
            "generic": SimBehaviour(),
        }
        self.aliases = {"SelectRover": "TaskAllocation", "Bidding": "TaskBidding", **aliases}

    def get(self, behaviour: str) -> SimBehaviour:
        """The implementation of a behaviour (or of its alias), else the generic one."""
        name = self.aliases.get(behaviour, behaviour)
        return self.impls.get(name) or self.impls["generic"]

    def known(self) -> list[str]:
        """Every behaviour name with an implementation or an alias."""
        return sorted(set(self.impls) | set(self.aliases))


def claims(world: World, run: int, g: int, args: Mapping[str, Any]) -> None:
    """A behaviour of member g starts on a target it reported: the find is taken up."""
    value = args.get("target_id")
    if isinstance(value, bool) or not isinstance(value, int | float):
        return
    target = int(value) - 1
    if (
        0 <= target < world.tx.shape[1]
        and world.finder[run, target] == g
        and world.status[run, target] == FOUND
    ):
        world.claim(run, target)
