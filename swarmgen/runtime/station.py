"""The ground station of a swarm on UDP multicast, and the command-line options of the network
transport (standard library only).

    python -m <package> --station-only --events launch@0.1,missionStart@1 --expect 6 --record run.jsonl

The station waits until it has heard `--expect` members (their announcements), then sends its
events in order, each not before its time and not before the previous one was acknowledged by
every live member it heard; it repeats an event every `--repeat` seconds until it is. Members
suppress the copies by event id, so each member takes each station event at most once, and in
the station's order. A member is live while its announcements keep coming (`--peer-timeout`)
and it has not announced that it finished. The station lists the members it hears with their
active states, and records the run as JSON lines (docs/network.md).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, TextIO

from swarmgen.runtime.transport import (
    ANNOUNCE_EVERY,
    Endpoint,
    Faults,
    Options,
    Peer,
    check_options,
    finite_rate,
    params_options,
)

REPEAT_EVERY = 0.1  # seconds between two copies of an unacknowledged station event
PEER_TIMEOUT = 1.0  # a member not heard for this long is no longer waited for
MAX_SCRIPT_BYTES = 1_000_000


@dataclass(slots=True)
class Pending:
    """A station event on its way: who acknowledged it so far."""

    name: str
    data: Mapping[str, Any] | None
    id: int
    acked: set[str] = field(default_factory=set)


class Station(Endpoint):
    """Sends the station's events to the group until every live member acknowledged them, and
    records what it sends and hears."""

    def __init__(
        self,
        options: Options,
        out: TextIO,
        faults: Faults | None = None,
        repeat: float = REPEAT_EVERY,
        peer_timeout: float = PEER_TIMEOUT,
    ) -> None:
        super().__init__(options, faults, name="station")
        self.out = out
        self.repeat = repeat
        self.peer_timeout = peer_timeout
        self.start = time.monotonic()
        self.pending: Pending | None = None
        self.next_id = 1
        self.changed = asyncio.Event()  # an ack or an announcement arrived
        # what the record last said of each member: active states, finished
        self.heard: dict[str, tuple[tuple[str, ...], bool]] = {}
        self.on_peer = self._peer

    def write(self, what: str, **fields: Any) -> None:
        """One line of the record."""
        line = {"t": round(time.monotonic() - self.start, 4), "station": what, **fields}
        print(json.dumps(line), file=self.out, flush=True)

    def _peer(self, peer: Peer) -> None:
        known = self.heard.get(peer.member_id)
        if known is None or known != (peer.active, peer.finished):
            member = f"{peer.member_type}/{peer.member_id}"
            self.write("heard", member=member, active=list(peer.active), finished=peer.finished)
        self.heard[peer.member_id] = (peer.active, peer.finished)
        self.changed.set()

    def handle(self, message: dict[str, Any]) -> None:
        """Count an acknowledgement of the event on its way."""
        pending = self.pending
        if message["kind"] != "ack" or pending is None:
            return
        if message["of"] == self.origin and message["id"] == pending.id:
            if message["sender"] not in pending.acked:
                pending.acked.add(message["sender"])
                self.write("acked", event=pending.name, id=pending.id, by=message["sender"])
            self.changed.set()

    def live(self) -> set[str]:
        """The members heard within the peer timeout that have not finished."""
        now = time.monotonic()
        return {
            p.member_id
            for p in self.peers.values()
            if not p.finished and now - p.seen <= self.peer_timeout
        }

    async def wait_for(self, count: int, until: float) -> bool:
        """Wait until `count` members were heard (False: not before `until`)."""
        while len(self.peers) < count:
            if not await self._changed(until):
                return False
        return True

    async def send_event(self, name: str, data: Mapping[str, Any] | None, until: float) -> bool:
        """Send one event until every live member acknowledged it (False: not before
        `until`)."""
        pending = self.pending = Pending(name, data, self.next_id)
        self.next_id += 1
        copies = 0
        while True:
            missing = self.live() - pending.acked
            if copies and not missing:
                self.write("delivered", event=name, id=pending.id, members=sorted(pending.acked))
                self.pending = None
                return True
            if time.monotonic() >= until:
                self.write("undelivered", event=name, id=pending.id, missing=sorted(missing))
                self.pending = None
                return False
            self.send(
                {"kind": "event", "id": pending.id, "name": name, "sender": "station",
                 "timestamp": time.time(), "data": dict(data) if data else None}
            )  # fmt: skip
            copies += 1
            if copies == 1:
                self.write("sent", event=name, id=pending.id, data=data, to=sorted(missing))
            await self._changed(min(until, time.monotonic() + self.repeat))

    async def _changed(self, until: float) -> bool:
        self.changed.clear()
        try:
            await asyncio.wait_for(self.changed.wait(), max(0.0, until - time.monotonic()))
        except TimeoutError:
            return False
        return True

    def settled(self) -> bool:
        """Every member heard has finished or gone silent."""
        return not self.live()

    def summary(self) -> dict[str, Any]:
        """The members heard, their last active states, and the datagram counts."""
        members = {
            p.member_id: {"type": p.member_type, "active": list(p.active), "finished": p.finished}
            for p in sorted(self.peers.values(), key=lambda p: p.member_id)
        }
        return {"members": members, "bad": self.bad, "unsent": self.unsent}


async def run_station(
    events: Sequence[tuple[float, str, Mapping[str, Any] | None]],
    options: Options,
    args: Any,
    out: TextIO,
) -> int:
    """Run the station for `--duration` seconds at most: 0 when every event reached every live
    member and every member heard finished, 1 otherwise."""
    station = Station(options, out, _faults(args), args.repeat, args.peer_timeout)
    deadline = time.monotonic() + args.duration
    await station.open()
    try:
        ok = await station.wait_for(args.expect, deadline)
        if not ok:
            station.write("missing", expected=args.expect, heard=sorted(station.peers))
        started = time.monotonic()
        station.write("clock", members=sorted(station.peers))
        for at, name, data in events if ok else ():
            await asyncio.sleep(max(0.0, started + at - time.monotonic()))
            ok = await station.send_event(name, data, deadline) and ok
        while not station.settled() and time.monotonic() < deadline:
            # listen on: the members' last announcements say where they ended
            await station._changed(min(deadline, time.monotonic() + station.peer_timeout))
    finally:
        station.write("summary", **station.summary())
        station.close()
    return 0 if ok and _all_finished(station) else 1


def _all_finished(station: Station) -> bool:
    return bool(station.peers) and all(p.finished for p in station.peers.values())


def _faults(args: Any) -> Faults:
    return Faults(args.drop, args.duplicate, args.delay, args.fault_seed)


def load_script(path: str, known: Callable[[str], bool]) -> list[tuple[float, str, Any]]:
    """`[{"event": "launch", "at": 0.1, "data": {...}}, ...]` from a JSON file, sorted by time;
    ValueError names the first bad item."""
    try:
        with open(path, "rb") as stream:
            raw = stream.read(MAX_SCRIPT_BYTES + 1)
    except OSError as err:
        raise ValueError(f"cannot read {path}: {err.strerror}") from None
    if len(raw) > MAX_SCRIPT_BYTES:
        raise ValueError(f"{path}: larger than {MAX_SCRIPT_BYTES} bytes")
    try:
        items = json.loads(raw, parse_constant=_refuse)
    except (ValueError, RecursionError) as err:
        raise ValueError(f"{path}: not JSON: {str(err)[:80]}") from None
    if not isinstance(items, list):
        raise ValueError(f"{path}: expected a list of events")
    events = []
    for n, item in enumerate(items):
        where = f"{path}: item {n}"
        if not isinstance(item, dict) or set(item) - {"event", "at", "data"}:
            raise ValueError(f"{where}: expected an object with event, at, data")
        name, at, data = item.get("event"), item.get("at", 0), item.get("data")
        if not isinstance(name, str) or not known(name):
            raise ValueError(f"{where}: no member reacts to an event {name!r}")
        if isinstance(at, bool) or not isinstance(at, int | float) or at < 0:
            raise ValueError(f"{where}: `at` is not a number of seconds >= 0")
        if data is not None and not isinstance(data, dict):
            raise ValueError(f"{where}: `data` is not an object")
        events.append((float(at), name, data))
    return sorted(events, key=lambda e: e[0])


def _refuse(name: str) -> Any:
    raise ValueError(f"non-finite number {name}")


def add_arguments(parser: argparse.ArgumentParser, who: Any) -> None:
    """The network options of the generated command line (`who`: its member/swarm group)."""
    who.add_argument(
        "--station-only", action="store_true", help="run the ground station on --transport udp"
    )
    net = parser.add_argument_group("network (--transport udp)")
    net.add_argument("--transport", choices=("memory", "udp"), default="memory")
    net.add_argument("--group", default=None, help="IPv4 multicast group")
    net.add_argument("--port", type=_int_type(1, 65_535), default=None, help="UDP port")
    net.add_argument("--ttl", type=_int_type(0, 255), default=None, help="multicast TTL")
    net.add_argument("--interface", default=None, help="address of the interface to use")
    net.add_argument("--announce", type=_positive, default=ANNOUNCE_EVERY, help="seconds")
    net.add_argument("--expect", type=_int_type(0, 10_000), default=0, help="station: members")
    net.add_argument("--repeat", type=_positive, default=REPEAT_EVERY, help="station: seconds")
    net.add_argument("--peer-timeout", type=_positive, default=PEER_TIMEOUT, help="seconds")
    net.add_argument("--station-script", default=None, help="station: JSON events with data")
    net.add_argument("--record", default=None, help="station: write the record to this file")
    net.add_argument("--drop", type=_rate, default=0.0, help="fault: datagram loss 0-1")
    net.add_argument("--duplicate", type=_rate, default=0.0, help="fault: duplication 0-1")
    net.add_argument("--delay", type=_non_negative, default=0.0, help="fault: max delay (s)")
    net.add_argument("--fault-seed", type=_int_type(0, 2**63), default=0, help="fault: seed")


def resolve_options(args: Any, member_types: Mapping[str, ModuleType]) -> Options:
    """The network options: the defaults, then the model's `communicationParams` (a member
    module's COMMUNICATION_PARAMS, when the package has them), then the command line.
    ValueError when they are not usable."""
    base = Options(announce_every=args.announce)
    module = member_types.get(args.member) if args.member else None
    params = getattr(module, "COMMUNICATION_PARAMS", "") if module is not None else ""
    if isinstance(params, str) and params:
        base = params_options(params, base)
    given = {k: getattr(args, k) for k in ("group", "port", "ttl", "interface")}
    options = Options(
        **{**{k: getattr(base, k) for k in Options.__dataclass_fields__}, **_set(given)}
    )
    check_options(options)
    return options


def _set(values: Mapping[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in values.items() if v is not None}


def _int_type(low: int, high: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {low}-{high}, got {value}")
        return value

    return parse


def _rate(text: str) -> float:
    try:
        return finite_rate(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _number(text: str, positive: bool) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 if positive else value >= 0) or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number {'>' if positive else '>='} 0")
    return value


def _positive(text: str) -> float:
    return _number(text, True)


def _non_negative(text: str) -> float:
    return _number(text, False)


def open_record(path: str | None) -> TextIO:
    """Where the station writes its record: the file, else stdout."""
    if path is None:
        return sys.stdout
    return open(path, "w", encoding="utf-8")  # closed by the caller
