"""The generated swarm's side of an exact lockstep barrier (the detailed level's world node).

With `use_sim_time` and the ROS parameter `lockstep_topic` set (e.g. `/world/settle`), one
reporter per process counts what its nodes send and receive on the reactive channels and
answers the world's probes (`<lockstep_topic>/probe`, `{"k", "wave", "t_ns"}`) with reports
`{"k", "wave", "by", "settle", "sent", "received", "idle"}`; it reports again whenever a count
or `idle` changes while the world waits. `idle`: the process's clock has reached the probe's
time, no scheduled callback is due, and no member has an event queued. The world steps only
when every report is idle and every message sent has been received (docs/detailed.md, "The
lockstep barrier"). The process starts its members and station program only at the world's
first probe (`wait_for_world`): nothing it sends can reach a server before the world, which
starts once every reporter (the behaviour servers too) is ready, is stepping; until they have
started, the reporter is not idle. Off (the default, an empty `lockstep_topic`): nothing is created, nothing
is counted.

Channels: a topic every subscriber hears is counted by its name when sent (`/swarm/events`)
and as `<topic>@<subscriber node>` when received; `goal`, `goal_response`, `result`,
`request`, `response` are point to point; `cancel` counts a cancel request when sent and its
answer when received (the server's side of a cancel has no callback for a goal that just ended).
"""

from __future__ import annotations

import importlib
import json
from collections import Counter
from collections.abc import Callable
from typing import Any

from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from .scheduler import Scheduler

PARAMETER = "lockstep_topic"
POLL_S = 0.002  # wall seconds between checks while a probe is open (a missed hook costs this)
QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


class Lockstep:
    """One process's counts and reports (the module docstring)."""

    def __init__(self, node: Node, topic: str, scheduler: Scheduler, by: str) -> None:
        """Report on `topic` from `node`, on `scheduler`'s clock, as `by`."""
        string = importlib.import_module("std_msgs.msg").String  # only when the barrier is on
        self._string = string
        self.by = by
        self.sent: Counter[str] = Counter()
        self.received: Counter[str] = Counter()
        self.quiet: list[Callable[[], bool]] = []  # each: a member has no event queued
        self._scheduler = scheduler
        self._probe: tuple[int, int, int] | None = None  # (k, wave, t_ns)
        self._last: Any = None
        self.started = False  # the members and the station program run (`wait_for_world`)
        self._publisher = node.create_publisher(string, topic, QOS)
        node.create_subscription(string, f"{topic}/probe", self._on_probe, QOS)
        steady = Clock(clock_type=ClockType.STEADY_TIME)  # polls in wall time: /clock waits
        node.create_timer(POLL_S, self.check, clock=steady)
        scheduler.lockstep = self

    def _on_probe(self, message: Any) -> None:
        try:
            raw = json.loads(message.data)
            self._probe = (int(raw["k"]), int(raw["wave"]), int(raw["t_ns"]))
        except (ValueError, KeyError, TypeError):
            return
        self._last = None  # every wave is answered
        self.check()

    def idle(self) -> bool:
        """Nothing left to do at the probe's time (the module docstring)."""
        if not self.started or self._probe is None:
            return False
        if not self._scheduler.reached(self._probe[2]):
            return False
        return not self._scheduler.due() and all(quiet() for quiet in self.quiet)

    def check(self) -> None:
        """Report the open wave when a count or `idle` changed since the last report."""
        if self._probe is None:
            return
        idle = self.idle()
        state = (self._probe, idle, tuple(self.sent.items()), tuple(self.received.items()))
        if state == self._last:
            return
        self._last = state
        k, wave, _ = self._probe
        report = {"k": k, "wave": wave, "by": self.by, "settle": False, "idle": idle,
                  "sent": dict(self.sent), "received": dict(self.received)}  # fmt: skip
        self._publisher.publish(self._string(data=json.dumps(report, sort_keys=True)))


def wait_for_world(scheduler: Scheduler, spin: Callable[[Callable[[], bool]], bool]) -> bool:
    """With the barrier on, `spin` until the world's first probe; True when the process may
    start its members (at once when the barrier is off). `started` is set by the caller's
    `started()` afterwards."""
    lockstep = scheduler.lockstep
    if lockstep is None:
        return True
    print(json.dumps({"lockstep": "waiting", "by": lockstep.by}), flush=True)
    return spin(lambda: lockstep._probe is not None)


def started(scheduler: Scheduler) -> None:
    """The members and the station program have started: the reporter may be idle now."""
    if scheduler.lockstep is not None:
        scheduler.lockstep.started = True
        scheduler.lockstep.check()


def start(node: Node, scheduler: Scheduler, by: str) -> Lockstep | None:
    """The process's reporter if `node` runs on `use_sim_time` with `lockstep_topic` set."""
    topic = str(node.declare_parameter(PARAMETER, "").value)
    if not topic or not scheduler.simulated:
        return None
    return Lockstep(node, topic, scheduler, by)


def sent(scheduler: Scheduler, channel: str) -> None:
    """One message sent on `channel` (nothing when the barrier is off)."""
    if scheduler.lockstep is not None:
        scheduler.lockstep.sent[channel] += 1


def received(scheduler: Scheduler, channel: str) -> None:
    """One message received on `channel` (nothing when the barrier is off)."""
    if scheduler.lockstep is not None:
        scheduler.lockstep.received[channel] += 1


def listen(scheduler: Scheduler, channel: str) -> None:
    """A subscription of a broadcast channel: its count exists from 0, so the world waits for
    it too before its first message arrives."""
    if scheduler.lockstep is not None:
        scheduler.lockstep.received[channel] += 0
