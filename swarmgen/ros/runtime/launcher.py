"""The swarm launcher: every member of the swarm composition, each in its own namespace, with its
simulated behaviours, in one process and one executor spun in the main thread.

    python -m <swarm>_nodes.launch_swarm --uav 2 --ugv 2 --script sar.json --time-scale 0.1 \
        --station launch@0.5,missionStart@2

One process keeps a large swarm cheap (one DDS participant, one scheduler timer, no per-process
interpreter), and the single-threaded executor is deterministic enough for tests; the launch
file (`launch/<swarm>.launch.py`) runs the same nodes one process each instead.

It exits when every member has reached its final state (0), after `--duration` simulated
seconds (0), on SIGINT/SIGTERM (0), or when action servers are missing (3); 1 when a member
reported errors (a goal aborted by a failing server or with an undeclared outcome among them);
2, in one line and before ROS starts, for bad arguments (a `--station` time that is not a finite
number >= 0, an event no member reacts to, a state no member has; counts, times) or a bad
script. The last line on stdout is a JSON summary.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NoReturn

import rclpy
from rclpy.context import Context as RosContext
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from ...runtime.engine import Event as SwarmEvent
from .node import (
    EVENTS_QOS,
    SWARM_TOPIC,
    Interfaces,
    MemberNode,
    MemberOptions,
    MemberSpec,
    Scheduler,
    make_executor,
    ros_time,
    spin_until,
)
from .simulated import ScriptError, SimulatedBehaviours

MAX_MEMBERS = 1000  # per member type in one process (each member is several ROS nodes)


def station_events(text: str) -> list[tuple[str, float | None, str | None]]:
    """`launch@1,missionStart@Loitering,missionAbort@60` -> [(name, seconds, state), ...]:
    an event is sent at a simulated time, or as soon as every member that has the state is in
    it; in the order given (an event waits for the ones before it). A time is a finite number
    >= 0; anything else raises ScriptError."""
    events: list[tuple[str, float | None, str | None]] = []
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


def _check_station(
    items: list[tuple[str, float | None, str | None]], specs: Mapping[str, MemberSpec]
) -> None:
    """Every station event is one some member reacts to, every state one some member has."""
    charts = [spec.build() for spec in specs.values()]
    for name, _, state in items:
        if not any(node.matching(name) for chart in charts for node in chart.nodes.values()):
            raise ScriptError(f"--station: no member reacts to an event {name!r}")
        if state is not None and not any(state in chart.nodes for chart in charts):
            raise ScriptError(f"--station: no member has a state {state!r}")


def _number(low: float, low_ok: bool) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not math.isfinite(value) or value < low or (value == low and not low_ok):
            bound = f">= {low:g}" if low_ok else f"> {low:g}"
            raise argparse.ArgumentTypeError(f"expected a finite number {bound}, got {text!r}")
        return value

    return parse


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if not 0 <= value <= MAX_MEMBERS:
        raise argparse.ArgumentTypeError(f"expected 0 to {MAX_MEMBERS} members, got {value}")
    return value


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        """One line on stderr, exit 2 (argparse would print the usage first)."""
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


class StationProgram:
    """Sends the station events of `--station` in order (see `station_events`)."""

    def __init__(
        self,
        station: Station,
        items: list[tuple[str, float | None, str | None]],
        members: list[MemberNode],
        time_scale: float,
    ) -> None:
        self.station = station
        self.items = items
        self.members = members
        self.time_scale = time_scale
        self.position = 0
        self.origin = time.monotonic()
        self._timer: Any = None
        for _, _, state in items:
            if state is not None and not any(state in m.engine.chart.nodes for m in members):
                raise ScriptError(f"--station: no member has a state {state!r}")
        for member in members:
            member.on_step.append(lambda _member: self.advance())

    def advance(self) -> None:
        while self.position < len(self.items):
            name, at, state = self.items[self.position]
            if state is not None:
                having = [m for m in self.members if state in m.engine.chart.nodes]
                if not all(m.engine.is_active(state) for m in having):
                    return
            elif at is not None:
                wait = self.origin + at * self.time_scale - time.monotonic()
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
        self.started = time.monotonic()
        self._ids = itertools.count(1)
        self.swarm_publisher = self.create_publisher(interfaces.Event, SWARM_TOPIC, EVENTS_QOS)
        self.create_subscription(interfaces.Event, SWARM_TOPIC, self._on_event, EVENTS_QOS)

    def publish(self, name: str, data: Mapping[str, Any] | None = None) -> None:
        self.swarm_publisher.publish(
            self.interfaces.Event(
                id=next(self._ids),
                stamp=ros_time(time.time()),
                sender="station",
                name=name,
                data=json.dumps(dict(data or {})),
            )
        )

    def _on_event(self, msg: Any) -> None:
        self.counts[msg.name] += 1
        self.first.setdefault(msg.name, time.monotonic() - self.started)
        if self.log is not None:
            line = {
                "t": round(time.monotonic() - self.started, 4),
                "sender": msg.sender,
                "name": msg.name,
                "data": json.loads(msg.data or "{}"),
            }
            print(json.dumps(line), file=self.log, flush=True)


def _parser(prog: str, specs: Mapping[str, MemberSpec], composition: Mapping[str, int]) -> Any:
    parser = _Parser(
        prog=prog,
        description="Run the whole swarm (members + simulated behaviours) in one process.",
    )
    for kind, spec in specs.items():
        parser.add_argument(
            f"--{spec.node_name.replace('_', '-')}",
            dest=f"count_{spec.node_name}",
            type=_count,
            default=composition.get(kind, 1),
            metavar="N",
            help=f"members of type {kind} (default {composition.get(kind, 1)})",
        )
    parser.add_argument("--script", help="simulation script (JSON); see _ros/simulated.py")
    parser.add_argument(
        "--time-scale",
        type=_number(0.0, low_ok=False),
        default=1.0,
        help="wall seconds per simulated second",
    )
    parser.add_argument(
        "--station",
        default="",
        help="station events, in order: name@seconds (simulated) or name@state (when every "
        "member having that state is in it), comma-separated",
    )
    parser.add_argument(
        "--duration",
        type=_number(0.0, low_ok=True),
        default=None,
        help="stop after this many simulated seconds",
    )
    parser.add_argument(
        "--no-simulation",
        action="store_true",
        help="start no simulated behaviours (real action servers provide them)",
    )
    parser.add_argument("--trace", action="store_true", help="one JSON line per member step")
    parser.add_argument("--events", action="store_true", help="one JSON line per swarm event")
    parser.add_argument(
        "--server-timeout",
        type=_number(0.0, low_ok=False),
        default=30.0,
        help="seconds to wait for action servers",
    )
    parser.add_argument(
        "--executor",
        choices=["events", "single"],
        default="events",
        help="rclpy's EventsExecutor (default) or SingleThreadedExecutor, in the main thread",
    )
    return parser


def main(
    specs: Mapping[str, MemberSpec],
    composition: Mapping[str, int],
    defaults: Mapping[str, Mapping[str, Any]],
    events: Mapping[str, tuple[str, str]],
    prog: str = "launch_swarm",
    argv: Sequence[str] | None = None,
) -> int:
    raw = list(sys.argv[1:] if argv is None else argv)
    parser = _parser(prog, specs, composition)
    args = parser.parse_args(remove_ros_args(["x", *raw])[1:])
    try:  # before ROS starts: a bad --station is an argument error
        program = station_events(args.station)
        _check_station(program, specs)
    except ScriptError as err:
        parser.error(str(err))
    counts = {kind: getattr(args, f"count_{spec.node_name}") for kind, spec in specs.items()}
    context = rclpy.get_default_context()  # the default one: SIGINT/SIGTERM end it cleanly
    rclpy.init(args=["launch_swarm", *raw], context=context)
    executor = make_executor(args.executor, context)
    interfaces = Interfaces(next(iter(specs.values())).interfaces)
    station = Station(interfaces, context, sys.stdout if args.events else None)
    nodes: list[Node] = [station]
    members: list[MemberNode] = []
    started = process_start = time.monotonic()

    def trace(member: MemberNode, event: SwarmEvent | None) -> None:
        line = {
            "t": round(time.monotonic() - started, 4),
            "member": member.member_id,
            "event": event.name if event is not None else None,
            "active": member.active(),
        }
        print(json.dumps(line), flush=True)

    code = 0
    try:
        swarm = {specs[kind].chart_name: count for kind, count in counts.items()}
        for kind, spec in specs.items():
            for index in range(1, counts[kind] + 1):
                member_id = f"{spec.node_name}_{index}"
                namespace = f"/{member_id}"
                member = MemberNode(
                    spec,
                    namespace=namespace,
                    options=MemberOptions(
                        member_id=member_id,
                        member_index=index,
                        time_scale=args.time_scale,
                        tracer=trace if args.trace else None,
                    ),
                    scheduler=station.scheduler,
                    context=context,
                )
                members.append(member)
                nodes.append(member)
                if not args.no_simulation:
                    nodes.append(
                        SimulatedBehaviours(
                            specs,
                            defaults,
                            events,
                            member_type=kind,
                            member_id=member_id,
                            member_index=index,
                            swarm=swarm,
                            script=args.script,
                            time_scale=args.time_scale,
                            namespace=namespace,
                            scheduler=station.scheduler,
                            context=context,
                        )
                    )
        for node in nodes:
            executor.add_node(node)
        ready = spin_until(
            executor, lambda: all(m.servers_ready() for m in members), args.server_timeout, 0.02
        )
        if not ready and not args.no_simulation:
            print(f"{prog}: action servers not found in {args.server_timeout} s", file=sys.stderr)
            return 3
        # every publisher of the swarm topic reaches every subscription before anything is sent
        # (volatile QoS: an event published before a match is lost)
        publishers = [getattr(n, "swarm_publisher", None) for n in nodes]
        subscriptions = len(station.get_subscriptions_info_by_topic(SWARM_TOPIC))
        spin_until(
            executor,
            lambda: all(
                p.get_subscription_count() >= subscriptions for p in publishers if p is not None
            ),
            args.server_timeout,
            0.02,
        )
        started = station.started = time.monotonic()
        for member in members:
            member.start()
        StationProgram(station, program, members, args.time_scale).advance()
        limit = None if args.duration is None else args.duration * args.time_scale
        spin_until(executor, lambda: all(m.finished for m in members), limit)
        finished_at = time.monotonic()
        spin_until(executor, lambda: all(m.idle() for m in members), 2.0, 0.01)
        for member in members:  # the final states and events reach the subscribers
            member.flush()
        wall = finished_at - started
        summary = {
            "members": {
                m.member_id: {
                    "type": m.spec.member_type,
                    "finished": m.finished,
                    "active": m.active(),
                    "steps": m.steps,
                    "errors": m.errors,
                }
                for m in members
            },
            "setup_s": round(station.started - process_start, 4),
            "wall_s": round(wall, 4),
            "simulated_s": round(wall / args.time_scale, 4) if args.time_scale > 0 else None,
            "events": dict(sorted(station.counts.items())),
            "first_s": {k: round(v, 4) for k, v in sorted(station.first.items())},
            "steps": sum(m.steps for m in members),
        }
        servers = [n for n in nodes if isinstance(n, SimulatedBehaviours)]
        failures = {n.member_id: n.errors for n in servers if n.errors}
        if failures:  # only then: the summary of a clean run stays as it was
            summary["server_errors"] = failures
        print(json.dumps(summary), flush=True)
        code = 1 if any(m.errors for m in members) or failures else 0
    except ScriptError as err:
        print(f"{prog}: {err}", file=sys.stderr)
        code = 2
    except (KeyboardInterrupt, ExternalShutdownException):
        code = 0
    finally:
        for member in members:
            member.stop()
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
    return code
