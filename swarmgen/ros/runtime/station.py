"""The ground station of the swarm launcher: it publishes the `--station` events, each at a
simulated time or when every member having a state is in it, and counts the swarm's events."""

from __future__ import annotations

import itertools
import json
import math
from collections import Counter
from collections.abc import Mapping
from typing import Any

from rclpy.context import Context as RosContext
from rclpy.node import Node

from . import lockstep
from .expressions import ScriptError
from .messages import EVENTS_QOS, SWARM_TOPIC, Interfaces
from .node import MemberNode
from .scheduler import Scheduler
from .spec import MemberSpec

StationItem = tuple[str, float | None, str | None]  # (event, seconds, state)


def station_events(text: str) -> list[StationItem]:
    """`launch@1,missionStart@Loitering,missionAbort@60` -> [(name, seconds, state), ...]:
    an event is sent at a simulated time, or as soon as every member that has the state is in
    it; in the order given (an event waits for the ones before it). A time is a finite number
    >= 0; anything else raises ScriptError."""
    events: list[StationItem] = []
    for item in filter(None, (part.strip() for part in text.split(","))):
        name, separator, at = (p.strip() for p in item.partition("@"))
        if not name:
            raise ScriptError(f"--station: {item!r}: no event name")
        if "@" in at or (separator and not at):
            raise ScriptError(f"--station: {item!r}: expected name@seconds or name@state")
        try:
            seconds = float(at or 0)
        except ValueError:
            events.append((name, None, at))
            continue
        if not math.isfinite(seconds) or seconds < 0:
            raise ScriptError(f"--station: {item!r}: a time is a finite number >= 0")
        events.append((name, seconds, None))
    return events


def check_station(items: list[StationItem], specs: Mapping[str, MemberSpec]) -> None:
    """Every station event is one some member reacts to, every state one some member has."""
    charts = [spec.build() for spec in specs.values()]
    for name, _, state in items:
        if not any(node.matching(name) for chart in charts for node in chart.nodes.values()):
            raise ScriptError(f"--station: no member reacts to an event {name!r}")
        if state is not None and not any(state in chart.nodes for chart in charts):
            raise ScriptError(f"--station: no member has a state {state!r}")


class StationProgram:
    """Sends the station events of `--station` in order (see `station_events`)."""

    def __init__(
        self,
        station: Station,
        items: list[StationItem],
        members: list[MemberNode],
        time_scale: float,
    ) -> None:
        self.station = station
        self.items = items
        self.members = members
        self.time_scale = time_scale
        self.position = 0
        self.origin = station.scheduler.now()
        self._timer: Any = None
        for _, _, state in items:
            if state is not None and not any(state in m.engine.chart.nodes for m in members):
                raise ScriptError(f"--station: no member has a state {state!r}")
        for member in members:
            member.on_step.append(lambda _member: self.advance())

    def advance(self) -> None:
        """Send the events that are due, in order, up to the first that must wait."""
        while self.position < len(self.items):
            name, at, state = self.items[self.position]
            if state is not None:
                having = [m for m in self.members if state in m.engine.chart.nodes]
                if not all(m.engine.is_active(state) for m in having):
                    return
            elif at is not None:
                wait = self.origin + at * self.time_scale - self.station.scheduler.now()
                if wait > 0:
                    if self._timer is None:
                        self._timer = self.station.scheduler.call_later(wait, self._due)
                    return
            self.position += 1
            self.station.publish(name)

    def _due(self) -> None:
        self._timer = None
        self.advance()


class Station(Node):
    """The ground station: publishes station events and counts what goes over the swarm topic."""

    def __init__(self, interfaces: Interfaces, context: RosContext, log: Any = None) -> None:
        super().__init__("swarm_launcher", context=context)
        self.interfaces = interfaces
        self.scheduler = Scheduler(self)
        self.counts: Counter[str] = Counter()
        self.first: dict[str, float] = {}
        self.log = log
        self.started = self.scheduler.now()  # the origin of trace times (simulated or not)
        self._ids = itertools.count(1)
        self.swarm_publisher = self.create_publisher(interfaces.Event, SWARM_TOPIC, EVENTS_QOS)
        self.create_subscription(interfaces.Event, SWARM_TOPIC, self._on_event, EVENTS_QOS)
        # the process's barrier reporter (detailed level: `-p lockstep_topic:=/world/settle`)
        self.lockstep = lockstep.start(self, self.scheduler, self.get_name())
        self._heard = f"{self.swarm_publisher.topic_name}@{self.get_fully_qualified_name()}"
        lockstep.listen(self.scheduler, self._heard)

    def publish(self, name: str, data: Mapping[str, Any] | None = None) -> None:
        """Send a station event on the swarm topic."""
        self.swarm_publisher.publish(
            self.interfaces.event(
                next(self._ids),
                self.get_clock().now().nanoseconds / 1e9,
                "station",
                name,
                json.dumps(dict(data or {})),
            )
        )
        lockstep.sent(self.scheduler, self.swarm_publisher.topic_name)

    def _on_event(self, msg: Any) -> None:
        lockstep.received(self.scheduler, self._heard)
        self.counts[msg.name] += 1
        self.first.setdefault(msg.name, self.scheduler.now() - self.started)
        if self.log is not None:
            line = {
                "t": round(self.scheduler.now() - self.started, 4),
                "sender": msg.sender,
                "name": msg.name,
                "data": json.loads(msg.data or "{}"),
            }
            print(json.dumps(line), file=self.log, flush=True)
