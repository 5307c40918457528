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
script; 2, in one line, when a declared interface cannot be used here (`bindings.BindingError`:
an unknown type, a field it lacks); 2, before ROS starts, for an unusable user behaviour
(`--library`, entry points: `usercode.load_library`). The last line on stdout is a JSON summary.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import rclpy
from rclpy.context import Context as RosContext
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from ...runtime.args import Parser, number
from ...runtime.engine import Event as SwarmEvent
from ...runtime.member import Library
from ...runtime.plugins import PluginError, Plugins
from . import lockstep
from .bindings import BindingError, resolve
from .declared import FeedbackRecord
from .expressions import ScriptError
from .messages import SWARM_TOPIC, Interfaces
from .node import MemberNode, MemberOptions
from .process import make_executor, spin_until
from .simulated import SimulatedBehaviours
from .spec import MemberSpec
from .station import Station, StationItem, StationProgram, check_station, station_events
from .usercode import UserBehaviours, UserLoop, add_options, load_library

MAX_MEMBERS = 1000  # per member type in one process (each member is several ROS nodes)


def _count(text: str) -> int:
    """An argparse type: a number of members, 0 to MAX_MEMBERS."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if not 0 <= value <= MAX_MEMBERS:
        raise argparse.ArgumentTypeError(f"expected 0 to {MAX_MEMBERS} members, got {value}")
    return value


# The launcher's options besides the member counts: (flag, argparse keywords).
_OPTIONS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("--script", {"help": "simulation script (JSON); see _ros/simulated.py"}),
    (
        "--time-scale",
        {
            "type": number(0.0, low_ok=False),
            "default": 1.0,
            "help": "wall seconds per simulated second",
        },
    ),
    (
        "--station",
        {
            "default": "",
            "help": "station events, in order: name@seconds (simulated) or name@state (when "
            "every member having that state is in it), comma-separated",
        },
    ),
    (
        "--duration",
        {
            "type": number(0.0, low_ok=True),
            "default": None,
            "help": "stop after this many simulated seconds",
        },
    ),
    (
        "--no-simulation",
        {
            "action": "store_true",
            "help": "start no simulated behaviours (real action servers provide them)",
        },
    ),
    ("--trace", {"action": "store_true", "help": "one JSON line per member step"}),
    ("--events", {"action": "store_true", "help": "one JSON line per swarm event"}),
    (
        "--server-timeout",
        {
            "type": number(0.0, low_ok=False),
            "default": 30.0,
            "help": "seconds to wait for action servers",
        },
    ),
    (
        "--executor",
        {
            "choices": ["events", "single"],
            "default": "events",
            "help": "rclpy's EventsExecutor (default) or SingleThreadedExecutor, in the main "
            "thread",
        },
    ),
)


def _parser(prog: str, specs: Mapping[str, MemberSpec], composition: Mapping[str, int]) -> Any:
    """The launcher's arguments: one count per member type, then `_OPTIONS`."""
    parser = Parser(
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
    for flag, options in _OPTIONS:
        parser.add_argument(flag, **options)
    add_options(parser)  # --library, --no-plugins: user behaviours (usercode.py)
    return parser


@dataclass
class _Swarm:
    """The nodes of one launch: the station, the members, their simulated behaviours."""

    station: Station
    members: list[MemberNode] = field(default_factory=list)
    nodes: list[Node] = field(default_factory=list)
    library: Library | None = None  # the user's behaviours (None: scripts only)
    loop: UserLoop | None = None  # where they run

    def trace(self, member: MemberNode, event: SwarmEvent | None) -> None:
        """`--trace`: one JSON line per member step."""
        line = {
            "t": round(self.station.scheduler.now() - self.station.started, 4),
            "member": member.member_id,
            "event": event.name if event is not None else None,
            "active": member.active(),
        }
        print(json.dumps(line), flush=True)

    def trace_feedback(self, record: FeedbackRecord) -> None:
        """`--trace`: one JSON line per (coalesced) feedback record of a declared action."""
        line = {
            "t": round(self.station.scheduler.now() - self.station.started, 4),
            **record.as_json(),
        }
        print(json.dumps(line, default=str), flush=True)


def _populate(
    swarm: _Swarm,
    specs: Mapping[str, MemberSpec],
    defaults: Mapping[str, Mapping[str, Any]],
    events: Mapping[str, tuple[str, str]],
    args: Any,
    context: RosContext,
) -> None:
    """Create every member of the composition (and its simulated behaviours) in `swarm`."""
    counts = {kind: getattr(args, f"count_{spec.node_name}") for kind, spec in specs.items()}
    per_type = {specs[kind].chart_name: count for kind, count in counts.items()}
    scheduler = swarm.station.scheduler
    for kind, spec in specs.items():
        for index in range(1, counts[kind] + 1):
            member_id = f"{spec.node_name}_{index}"
            namespace = f"/{member_id}"
            options = MemberOptions(
                member_id=member_id,
                member_index=index,
                time_scale=args.time_scale,
                tracer=swarm.trace if args.trace else None,
            )
            member = MemberNode(
                spec, namespace=namespace, options=options, scheduler=scheduler, context=context
            )
            if args.trace:
                member.on_feedback.append(swarm.trace_feedback)
            swarm.members.append(member)
            swarm.nodes.append(member)
            if args.no_simulation:
                continue
            servers: Any = SimulatedBehaviours
            if swarm.library is not None and swarm.loop is not None:
                servers = partial(UserBehaviours, swarm.library, swarm.loop)
            swarm.nodes.append(
                servers(
                    specs,
                    defaults,
                    events,
                    member_type=kind,
                    member_id=member_id,
                    member_index=index,
                    swarm=per_type,
                    script=args.script,
                    time_scale=args.time_scale,
                    namespace=namespace,
                    scheduler=scheduler,
                    context=context,
                )
            )


def _connect(executor: Executor, swarm: _Swarm, args: Any) -> bool:
    """Spin until the action servers are up and every publisher of the swarm topic reaches
    every subscription; False when servers are missing (and simulated ones were expected)."""
    for node in swarm.nodes:
        executor.add_node(node)
    members = swarm.members
    ready = spin_until(
        executor, lambda: all(m.servers_ready() for m in members), args.server_timeout, 0.02
    )
    if not ready and not args.no_simulation:
        return False
    # volatile QoS: an event published before a match is lost
    publishers = [getattr(n, "swarm_publisher", None) for n in swarm.nodes]
    subscriptions = len(swarm.station.get_subscriptions_info_by_topic(SWARM_TOPIC))
    spin_until(
        executor,
        lambda: all(
            p.get_subscription_count() >= subscriptions for p in publishers if p is not None
        ),
        args.server_timeout,
        0.02,
    )
    return True


def _run(
    executor: Executor, swarm: _Swarm, program: list[StationItem], args: Any
) -> tuple[float, float]:
    """Start the members and the station program, spin until every member finished (or the
    `--duration`, in simulated seconds); the (wall, simulated) seconds that took. Under
    `use_sim_time` simulated seconds are `/clock`'s, else wall seconds over `--time-scale`."""
    members, scheduler = swarm.members, swarm.station.scheduler
    wall_start = time.monotonic()
    started = swarm.station.started = scheduler.now()
    for member in members:
        member.start()
    StationProgram(swarm.station, program, members, args.time_scale).advance()
    lockstep.started(scheduler)
    if scheduler.simulated:
        duration = math.inf if args.duration is None else args.duration * args.time_scale
        spin_until(
            executor,
            lambda: all(m.finished for m in members) or scheduler.now() - started >= duration,
        )
    else:
        limit = None if args.duration is None else args.duration * args.time_scale
        spin_until(executor, lambda: all(m.finished for m in members), limit)
    wall, simulated = time.monotonic() - wall_start, scheduler.now() - started
    spin_until(executor, lambda: all(m.idle() for m in members), 2.0, 0.01)
    for member in members:  # the final states and events reach the subscribers
        member.flush()
    if not scheduler.simulated:
        simulated = simulated / args.time_scale if args.time_scale > 0 else math.nan
    return wall, simulated


def _summary(swarm: _Swarm, wall: float, setup: float, simulated: float) -> dict[str, Any]:
    """The launcher's last line: each member's end, the timings, the events counted."""
    members, station = swarm.members, swarm.station
    summary: dict[str, Any] = {
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
        "setup_s": round(setup, 4),
        "wall_s": round(wall, 4),
        "simulated_s": round(simulated, 4) if math.isfinite(simulated) else None,
        "events": dict(sorted(station.counts.items())),
        "first_s": {k: round(v, 4) for k, v in sorted(station.first.items())},
        "steps": sum(m.steps for m in members),
    }
    servers = [n for n in swarm.nodes if isinstance(n, SimulatedBehaviours)]
    failures = {n.member_id: n.errors for n in servers if n.errors}
    if failures:  # only then: the summary of a clean run stays as it was
        summary["server_errors"] = failures
    return summary


def _shutdown(executor: Executor, swarm: _Swarm, context: RosContext) -> None:
    for member in swarm.members:
        member.stop()
    executor.shutdown()
    for node in swarm.nodes:
        node.destroy_node()
    if swarm.loop is not None:
        swarm.loop.close()
    rclpy.try_shutdown(context=context)


def check_bindings(specs: Mapping[str, MemberSpec]) -> None:
    """Import every declared interface the members use (BindingError, one line, if one is
    unusable here: unknown type, unknown field)."""
    for spec in specs.values():
        for behaviour in spec.behaviours.values():
            if behaviour.binding is not None:
                resolve(behaviour)


def main(
    specs: Mapping[str, MemberSpec],
    composition: Mapping[str, int],
    defaults: Mapping[str, Mapping[str, Any]],
    events: Mapping[str, tuple[str, str]],
    prog: str = "launch_swarm",
    argv: Sequence[str] | None = None,
    plugins: Plugins | None = None,
) -> int:
    """Run the swarm in this process (`launch_swarm`); the exit code (module docstring).
    `plugins`: the package's typed behaviours (entry points, `--library`: usercode.py)."""
    raw = list(sys.argv[1:] if argv is None else argv)
    parser = _parser(prog, specs, composition)
    args = parser.parse_args(remove_ros_args(["x", *raw])[1:])
    try:  # before ROS starts: a bad --station is an argument error
        program = station_events(args.station)
        check_station(program, specs)
    except ScriptError as err:
        parser.error(str(err))
    try:  # before ROS starts too: a node failing half-built makes rcl print pages of errors
        check_bindings(specs)
    except BindingError as err:
        print(f"{prog}: {err}", file=sys.stderr)
        return 2
    try:  # before ROS starts too, as the asyncio package refuses them
        library = load_library(plugins, args.library, args.no_plugins, args.time_scale, prog)
    except PluginError as err:
        parser.error(f"plug-ins: {err}")
    context = rclpy.get_default_context()  # the default one: SIGINT/SIGTERM end it cleanly
    rclpy.init(args=["launch_swarm", *raw], context=context)
    executor = make_executor(args.executor, context)
    interfaces = Interfaces(next(iter(specs.values())).interfaces)
    swarm = _Swarm(Station(interfaces, context, sys.stdout if args.events else None))
    if library is not None and not args.no_simulation:
        swarm.library, swarm.loop = library, UserLoop()
    swarm.nodes.append(swarm.station)
    process_start = time.monotonic()
    try:
        _populate(swarm, specs, defaults, events, args, context)
        if not _connect(executor, swarm, args):
            print(f"{prog}: action servers not found in {args.server_timeout} s", file=sys.stderr)
            return 3
        waited = lockstep.wait_for_world(
            swarm.station.scheduler,
            lambda done: spin_until(executor, done, args.server_timeout, 0.01),
        )
        if not waited:
            print(f"{prog}: no probe from the world in {args.server_timeout} s", file=sys.stderr)
            return 3
        setup = time.monotonic() - process_start
        wall, simulated = _run(executor, swarm, program, args)
        summary = _summary(swarm, wall, setup, simulated)
        print(json.dumps(summary), flush=True)
        failed = any(m.errors for m in swarm.members) or "server_errors" in summary
        code = 1 if failed else 0
    except (ScriptError, BindingError) as err:  # BindingError: a member's declared interface
        print(f"{prog}: {err}", file=sys.stderr)
        code = 2
    except (KeyboardInterrupt, ExternalShutdownException):
        code = 0
    finally:
        _shutdown(executor, swarm, context)
    return code
