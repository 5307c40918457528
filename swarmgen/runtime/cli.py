"""The command line of a generated asyncio swarm package (standard library only).

    python -m <package> --member UAV --id 3 --events launch@0.1,missionStart@0.5
    python -m <package> --swarm --time-scale 0.01 --duration 5
    python -m <package> --swarm --library my_platform:library     # the platform's behaviours

Installed plug-ins (entry points of the group `<package>.behaviours`, docs/plugins.md) replace
single simulated behaviours; `--library` comes before them, and then nothing is simulated.

Prints one JSON line per processed event and member: time, member, event, active states; and one
line per behaviour fault (`"fault": ...`, docs/runtime.md). Exit status: 0 when every member ended
cleanly, 1 when a behaviour failed, was abandoned, blocked the loop or overran the hard deadline
(or the engine reported an error), 2 for bad arguments, 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import importlib
import json
import os
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from types import ModuleType
from typing import Any, NoReturn

from swarmgen.runtime.args import Parser, finite
from swarmgen.runtime.engine import Event
from swarmgen.runtime.faults import Faults
from swarmgen.runtime.member import CANCEL_GRACE, Fault, InMemoryBus, Library, Member
from swarmgen.runtime.netoptions import add_arguments, load_script, open_record, resolve_options
from swarmgen.runtime.plugins import Chain, PluginError, Plugins, load_factory
from swarmgen.runtime.station import run_station as _run_station
from swarmgen.runtime.transport import UdpBus

BEAT = 0.05  # seconds between the loop's heartbeats (what the watchdog thread watches)
BLOCK_AFTER = 0.5  # a loop that misses its heartbeat this long is blocked by a behaviour
HARD_SLACK = 1.0  # seconds past duration + grace after which the process ends regardless


class JsonTracer:
    """Writes the trace of a run as JSON lines: one per step, one per fault."""

    def __init__(
        self, out: Any = sys.stdout, clock: Callable[[], float | None] | None = None
    ) -> None:
        self.out = out
        self.start = time.monotonic()
        self.clock = clock  # the mission clock (on the network), when the process knows it
        self.lock = threading.Lock()  # the watchdog thread writes its last line too

    def step(self, member: Member, event: Event | None) -> None:
        """Write a step: the time, the member, the event and the active states (and the
        mission time, on the network once the station was heard)."""
        line = {
            "t": round(time.monotonic() - self.start, 4),
            "member": f"{member.member_type}/{member.member_id}",
            "event": event.name if event is not None else None,
            "active": member.active,
        }
        mission = self.clock() if self.clock is not None else None
        if mission is not None:
            line["mission_t"] = round(mission, 4)
        self._write(line)

    def fault(self, member: Member, fault: Fault, timeout: float = -1) -> None:
        """Write a behaviour fault (`timeout`: how long to wait for the lock)."""
        self._write(
            {
                "t": round(time.monotonic() - self.start, 4),
                "member": f"{member.member_type}/{member.member_id}",
                "fault": fault.kind,
                "behaviour": fault.behaviour,
                "state": fault.state,
                "error": fault.error,
            },
            timeout,
        )

    def _write(self, record: Mapping[str, Any], timeout: float = -1) -> None:
        if self.lock.acquire(timeout=timeout):
            try:
                print(json.dumps(record), file=self.out, flush=True)
            finally:
                self.lock.release()


def _seconds(text: str) -> float:
    return finite(text, 0.0, low_ok=True)


def _scale(text: str) -> float:
    return finite(text, 0.0, low_ok=False)


def _member_id(text: str) -> str:
    if not text or any(c.isspace() or not c.isprintable() for c in text) or len(text) > 200:
        raise argparse.ArgumentTypeError(
            f"a member id is 1-200 printable characters without spaces, got {text!r}"
        )
    return text


def _library(text: str) -> Callable[..., Library]:
    """`MODULE:FACTORY`: the platform's behaviour library (called with the time scale)."""
    try:
        return load_factory(text)
    except PluginError as err:  # argparse's usage error, exit 2
        raise argparse.ArgumentTypeError(str(err)) from None


def station_events(text: str, known: Callable[[str], bool]) -> list[tuple[float, str]]:
    """`launch@0.1,missionStart@0.5` -> [(seconds, name), ...] sorted by time (no `@`: at 0).
    Raises ValueError naming the first bad item."""
    events = []
    for item in filter(None, (part.strip() for part in text.split(","))):
        name, separator, at = item.partition("@")
        if "@" in at or (separator and not at):
            raise ValueError(f"{item!r}: expected name@seconds")
        if not name:
            raise ValueError(f"{item!r}: no event name")
        if not known(name):
            raise ValueError(f"{item!r}: no member reacts to an event {name!r}")
        try:
            seconds = _seconds(at or "0")
        except argparse.ArgumentTypeError as err:
            raise ValueError(f"{item!r}: {err}") from None
        events.append((seconds, name))
    return sorted(events)


def _parser(prog: str, member_types: Mapping[str, ModuleType]) -> Parser:
    parser = Parser(prog=prog, description="Run swarm members with simulated behaviours.")
    who = parser.add_mutually_exclusive_group(required=True)
    who.add_argument("--member", choices=sorted(member_types), help="member type to run")
    who.add_argument("--swarm", action="store_true", help="run the whole swarm composition")
    parser.add_argument("--id", default="1", type=_member_id, help="member id (with --member)")
    parser.add_argument("--events", default="", help="station events: name@seconds,...")
    parser.add_argument(
        "--time-scale", type=_scale, default=1.0, help="scale of simulated durations"
    )
    parser.add_argument(
        "--duration", type=_seconds, default=10.0, help="stop after this many seconds"
    )
    parser.add_argument(
        "--library",
        type=_library,
        default=None,
        metavar="MODULE:FACTORY",
        help="the platform's behaviour library instead of the simulated one",
    )
    parser.add_argument(
        "--no-plugins",
        action="store_true",
        help="ignore the behaviours installed plug-ins provide (entry points)",
    )
    parser.add_argument(
        "--grace",
        type=_seconds,
        default=CANCEL_GRACE,
        help="seconds a cancelled behaviour may take to end before it is abandoned",
    )
    add_arguments(parser, who)
    return parser


def main(
    member_types: Mapping[str, ModuleType],
    composition: Mapping[str, int],
    library_factory: Callable[..., Library],
    prog: str = "swarm",
    argv: list[str] | None = None,
    plugins: Plugins | None = None,
    network: Mapping[str, Any] | None = None,
) -> int:
    """The generated package's command line: run members with simulated behaviours, the
    installed plug-ins of `plugins` (entry points) or the `--library` given. `network`: the
    swarm's network settings from the model (`group`, `port`, `ttl`), the defaults of the
    `--transport udp` options."""
    parser = _parser(prog, member_types)
    args = parser.parse_args(argv)
    charts = {kind: module.build() for kind, module in member_types.items()}
    try:
        args.events = station_events(args.events, lambda name: _reacts(charts.values(), name))
    except ValueError as err:
        parser.error(f"argument --events: {err}")
    _network_arguments(parser, args, network, charts)
    if args.station_only:
        return _station_only(args)
    if args.member:
        members = [(args.member, str(args.id))]
    else:
        members = [
            (kind, f"{kind.lower()}_{n}")
            for kind, count in composition.items()
            for n in range(1, count + 1)
        ]
    try:
        library = _behaviours(args, library_factory, plugins, prog)
    except PluginError as err:
        parser.error(f"plug-ins: {err}")
    outputs = _declared_outputs(member_types)
    runner = asyncio.Runner()  # its SIGINT handling cancels the run instead of raising anywhere
    try:
        code = runner.run(_run(member_types, members, library, args, outputs))
    except KeyboardInterrupt:
        code = 130
    loop = runner.get_loop()
    if any(not task.done() for task in asyncio.all_tasks(loop)):
        # abandoned behaviours ignore cancellation, so closing the loop would wait for them
        # forever (asyncio.run does): the process ends without them
        _exit(code)
    runner.close()
    return code


def _behaviours(
    args: Any, factory: Callable[..., Library], plugins: Plugins | None, prog: str
) -> Library:
    """The `--library` given (else the simulated one) and the installed plug-ins: the command
    line's library first, then the plug-ins, then the simulated behaviours (only without
    `--library`: a platform's library is never completed with simulations)."""
    base: Library = (args.library or factory)(args.time_scale)
    if plugins is None or args.no_plugins:
        return base
    found, providers = plugins.load()
    if not providers:
        return base
    print(f"{prog}: behaviours from plug-ins: {', '.join(map(str, providers))}", file=sys.stderr)
    return Chain(base, found) if args.library else Chain(found, base)


def _reacts(charts: Any, name: str) -> bool:
    return any(node.matching(name) for chart in charts for node in chart.nodes.values())


def _declared_outputs(member_types: Mapping[str, ModuleType]) -> dict[str, Sequence[str]] | None:
    """The declared outputs of each behaviour, from the package's `behaviours.SIGNATURES`
    (behaviour -> (kind, inputs, outputs, outcomes)) when the package has one."""
    for module in member_types.values():
        package = module.__name__.rpartition(".")[0]
        try:
            signatures = importlib.import_module(f"{package}.behaviours").SIGNATURES
            return {name: tuple(entry[2]) for name, entry in signatures.items()}
        except (ImportError, AttributeError, TypeError, IndexError, ValueError):
            continue
    return None


async def _run(
    member_types: Mapping[str, ModuleType],
    members: list[tuple[str, str]],
    library: Library,
    args: Any,
    outputs: Mapping[str, Sequence[str]] | None,
) -> int:
    try:
        bus = await _open_bus(args)
    except OSError as err:
        print(f"{members[0][0]}/{members[0][1]}: the network refused: {err}", file=sys.stderr)
        return 1
    tracer = JsonTracer(clock=bus.mission_time if isinstance(bus, UdpBus) else None)
    running = [
        Member(
            member_types[kind].build(),
            kind,
            member_id,
            library,
            bus,
            event_scopes=member_types[kind].EVENT_SCOPES,
            tracer=tracer,
            outputs=outputs,
            on_fault=tracer.fault,
            grace=args.grace,
        )
        for kind, member_id in members
    ]
    watchdog = Watchdog(running, tracer, args.duration + args.grace + HARD_SLACK)
    watchdog.start(asyncio.get_running_loop())
    tasks = [asyncio.create_task(m.run(), name=f"member {m.member_id}") for m in running]
    watchdog.runs = dict(zip(tasks, running, strict=True))
    if isinstance(bus, UdpBus):
        # after the members' first steps (their tasks run first): announced with their states
        asyncio.get_running_loop().call_soon(bus.start_announcing)
        station = asyncio.create_task(asyncio.sleep(0))
    else:
        station = asyncio.create_task(_station(bus, args.events))
    await asyncio.wait(tasks, timeout=args.duration)
    station.cancel()
    for member in running:
        member.stop()
    results = await asyncio.gather(*tasks, station, return_exceptions=True)
    watchdog.stop()
    if isinstance(bus, UdpBus):
        bus.close()  # after a last announcement: where each member ended
    for member, result in zip(running, results[: len(tasks)], strict=True):
        if isinstance(result, BaseException):  # the member itself broke (not a behaviour)
            member.add_error(f"the member stopped: {result!r}")
    for member in running:
        for error in member.errors:
            print(f"{member.member_type}/{member.member_id}: {error}", file=sys.stderr)
    return 0 if all(m.clean for m in running) else 1


def _network_arguments(
    parser: Parser, args: Any, network: Mapping[str, Any] | None, charts: Mapping[str, Any]
) -> None:
    """Check the network options together (argparse checked each): exit 2 when they clash."""
    if args.transport == "udp" or args.station_only:
        try:
            args.options = resolve_options(args, network)
        except ValueError as err:
            parser.error(f"network options: {err}")
    if args.station_only:
        if args.transport != "udp":
            parser.error("--station-only needs --transport udp")
        try:
            script = args.station_script and load_script(
                args.station_script, lambda name: _reacts(charts.values(), name)
            )
        except ValueError as err:
            parser.error(f"argument --station-script: {err}")
        plain = [(at, name, None) for at, name in args.events]
        args.events = sorted([*plain, *(script or [])], key=lambda e: e[0])
    elif args.transport == "udp" and (args.swarm or args.events):
        parser.error("--transport udp runs one --member per process; --station-only sends events")


def _station_only(args: Any) -> int:
    """The ground station of a swarm on the network (`--station-only`)."""
    try:
        out = open_record(args.record)
    except OSError as err:
        print(f"station: cannot write {args.record}: {err.strerror}", file=sys.stderr)
        return 2
    try:
        return asyncio.run(_run_station(args.events, args.options, args, out))
    except OSError as err:
        print(f"station: the network refused: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    finally:
        if out is not sys.stdout:
            out.close()


async def _open_bus(args: Any) -> InMemoryBus | UdpBus:
    """The in-process bus, or the group (`--transport udp`) joined."""
    if args.transport != "udp":
        return InMemoryBus()
    faults = Faults(args.drop, args.duplicate, args.delay, args.fault_seed, tuple(args.partition))
    bus = UdpBus(args.options, faults, name=f"{args.member}/{args.id}")
    await bus.open()
    return bus


async def _station(bus: InMemoryBus, events: list[tuple[float, str]]) -> None:
    started = time.monotonic()
    for at, name in events:
        await asyncio.sleep(max(0.0, at - (time.monotonic() - started)))
        bus.broadcast(name)


class Watchdog:
    """Watches the event loop from a thread. The loop beats every BEAT seconds; when a beat is
    late by more than BLOCK_AFTER, the behaviour task running then is noted, and the member
    reports it (`blocked`, with how long) as soon as the loop runs again. At the hard deadline
    (seconds after the start) the process ends with exit 1, whatever blocks it (`overran`)."""

    def __init__(self, members: list[Member], tracer: JsonTracer, deadline: float) -> None:
        self.members = members
        self.tracer = tracer
        self.deadline = time.monotonic() + deadline
        self.last = time.monotonic()
        self.suspect: tuple[Member, str, str] | None = None
        self.runs: dict[asyncio.Task[Any], Member] = {}  # each member's own task
        self.loop: asyncio.AbstractEventLoop | None = None
        self._stopped = threading.Event()
        self._handle: asyncio.TimerHandle | None = None

    def start(self, loop: asyncio.AbstractEventLoop) -> None:
        """Start beating on `loop` and watching it from a thread."""
        self.loop = loop
        self._beat()
        threading.Thread(target=self._watch, name="swarm watchdog", daemon=True).start()

    def stop(self) -> None:
        """Stop watching."""
        self._stopped.set()
        if self._handle is not None:
            self._handle.cancel()

    def _beat(self) -> None:
        """In the loop: the heartbeat; report a blocking that just ended."""
        now = time.monotonic()
        suspect, self.suspect = self.suspect, None
        if suspect is not None:
            member, behaviour, state = suspect
            lag = f"kept the event loop busy for {now - self.last:.2f} s"
            member.report(Fault("blocked", behaviour, state, lag))
        self.last = now
        assert self.loop is not None
        self._handle = self.loop.call_later(BEAT, self._beat)

    def _watch(self) -> None:
        while not self._stopped.wait(BEAT):
            now = time.monotonic()
            if self.suspect is None and now - self.last > BLOCK_AFTER:
                self.suspect = self._running()
            if now > self.deadline:
                self._overran()

    def _running(self) -> tuple[Member, str, str] | None:
        """The member and behaviour the blocked loop runs (read from this thread, while the
        loop is stuck); behaviour "-" when it is the member's own work (its engine)."""
        assert self.loop is not None
        task = asyncio.current_task(self.loop)
        for member in self.members:
            try:
                node = member.behaviour_of(task)
            except RuntimeError:  # changed while read: the loop is not stuck after all
                continue
            if node is not None and node.call is not None:
                return member, node.call.behaviour, node.id
        own = self.runs.get(task) if task is not None else None
        return (own, "-", "-") if own is not None else None

    def _overran(self) -> NoReturn:
        error = f"still blocking the event loop {HARD_SLACK:g} s past --duration + --grace"
        blocker = self.suspect or self._running()
        if blocker is None:
            print(f"swarm: the event loop {error}", file=sys.stderr)
            _exit(1)
        member, behaviour, state = blocker
        # written from this thread: the loop, which would otherwise write it, is stuck
        self.tracer.fault(member, Fault("overran", behaviour, state, error), timeout=0.5)
        name = f"{member.member_type}/{member.member_id}"
        print(f"{name}: behaviour {behaviour} in {state} overran: {error}", file=sys.stderr)
        _exit(1)


def _exit(code: int) -> NoReturn:
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # a closed stream: nothing to flush
            stream.flush()
    os._exit(code)
