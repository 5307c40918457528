"""Swarm events between processes over UDP multicast (standard library only).

One datagram is one JSON object of the wire format (docs/network.md): an `event` (the runtime's
envelope: name, data, id, timestamp, sender), an `ack` of a station event, or an `announce`ment
(who a member is and its active states) by which members and the station discover each other;
there is no static peer list. `UdpBus` is the member side: a `Bus` whose swarm-scope events go to
the group (and to its own members at once, as `InMemoryBus` does), local-scope events stay in the
process. Every datagram that fails to parse or to validate is counted and logged, never raised.

The fault layer (`faults.Faults`: loss, duplication, delay, partitions) acts where datagrams are
received, so each receiver loses its own copies, as on a radio. Copies of a member's event are
suppressed by event key in bounded memory (`Seen`); the station's events are numbered, and each
member takes them in order, once (the station repeats them until they are acknowledged).
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import socket
import struct
import sys
import time
from collections import OrderedDict
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from swarmgen.runtime.faults import Faults
from swarmgen.runtime.host import Event
from swarmgen.runtime.netoptions import Options
from swarmgen.runtime.values import record

if TYPE_CHECKING:
    from swarmgen.runtime.member import Member

WIRE_VERSION = 1
KINDS = frozenset({"event", "ack", "announce"})
MAX_DATAGRAM = 65_507  # the largest UDP payload over IPv4
RECEIVE_BUFFER = 4 * 1024 * 1024  # bytes asked for the socket's receive buffer
SEEN_LIMIT = 4_096  # event keys remembered for duplicate suppression, per process
MAX_LOGGED = 20  # bad datagrams logged on stderr (all are counted)
# the engine's own events (a behaviour's end, its outcome, SCXML's done.* and error.*): a
# datagram naming one would forge a behaviour's end, so none comes from the network
RESERVED = ("done.", "error.", "outcome.")
STATIONS_KEPT = 64  # station incarnations whose event count a member keeps (bounded memory)
LAST_WORDS = 3  # copies of a member's last announcement (its final states): one may be lost


class WireError(ValueError):
    """A datagram that is not a message of the wire format (the text says why)."""


class Seen:
    """The last SEEN_LIMIT keys seen, oldest forgotten first: duplicate suppression in bounded
    memory (a copy arriving after SEEN_LIMIT newer events would be taken again)."""

    def __init__(self, limit: int = SEEN_LIMIT) -> None:
        self.limit = limit
        self.keys: OrderedDict[tuple[str, str, int], None] = OrderedDict()

    def first(self, key: tuple[str, str, int]) -> bool:
        """Remember `key`; True the first time it is seen."""
        if key in self.keys:
            return False
        self.keys[key] = None
        if len(self.keys) > self.limit:
            self.keys.popitem(last=False)
        return True


def incarnation() -> str:
    """A token new to every process start: with the sender and the event id it keys an event
    (a restarted member counts its ids from 1 again)."""
    return os.urandom(6).hex()


def encode(message: Mapping[str, Any]) -> bytes:
    """One message as a datagram (`version` added); ValueError when it cannot be one (data
    that is not JSON, non-finite numbers, larger than a UDP payload)."""
    try:
        payload = json.dumps(
            {"version": WIRE_VERSION, **message}, allow_nan=False, separators=(",", ":")
        ).encode()
    except (TypeError, ValueError) as err:
        raise ValueError(f"not encodable as JSON: {err}") from None
    if len(payload) > MAX_DATAGRAM:
        raise ValueError(f"{len(payload)} bytes, more than a datagram holds ({MAX_DATAGRAM})")
    return payload


def event_message(event: Event, origin: str) -> dict[str, Any]:
    """The wire form of a swarm event sent by the process `origin` (its incarnation)."""
    return {
        "kind": "event",
        "origin": origin,
        "id": event.id,
        "name": event.name,
        "sender": event.sender,
        "timestamp": event.timestamp,
        "data": event.data,
    }


def _no_constant(name: str) -> Any:
    raise ValueError(f"non-finite number {name}")


def _finite(text: str) -> float:
    value = float(text)  # `1e999` is infinity, and never passes through parse_constant
    if not math.isfinite(value):
        raise ValueError(f"non-finite number {text[:20]}")
    return value


_STR_FIELDS: dict[str, tuple[str, ...]] = {
    "event": ("origin", "name", "sender"),
    "ack": ("origin", "sender", "of"),
    "announce": ("origin", "sender", "member_type"),
}


def decode(payload: bytes) -> dict[str, Any]:
    """A datagram as a message of the wire format; WireError says why it is not one."""
    try:
        message = json.loads(
            payload.decode("utf-8"), parse_constant=_no_constant, parse_float=_finite
        )
    except (UnicodeDecodeError, ValueError, RecursionError) as err:
        raise WireError(f"not JSON: {str(err)[:80]}") from None
    if not isinstance(message, dict):
        raise WireError("not a JSON object")
    if message.get("version") != WIRE_VERSION:
        raise WireError(f"wire version {_short(message.get('version'))}, not {WIRE_VERSION}")
    kind = message.get("kind")
    if kind not in KINDS:
        raise WireError(f"unknown kind {_short(kind)}")
    for key in _STR_FIELDS[kind]:
        if not isinstance(message.get(key), str) or not message[key]:
            raise WireError(f"{kind}: `{key}` is not a non-empty string")
    if kind in ("event", "ack") and not _is_int(message.get("id")):
        raise WireError(f"{kind}: `id` is not an integer")
    if kind == "event":
        if message["name"].startswith(RESERVED):
            raise WireError(f"event: the reserved name {_short(message['name'])}")
        if message.get("data") is not None and not isinstance(message["data"], dict):
            raise WireError("event: `data` is neither an object nor null")
        if not _is_number(message.get("timestamp")):
            raise WireError("event: `timestamp` is not a number")
        if "clock" in message and not _is_number(message["clock"]):
            raise WireError("event: `clock` is not a number")
        to = message.get("to")
        if to is not None and not _strings(to):
            raise WireError("event: `to` is not a list of strings")
    if kind == "announce" and not _strings(message.get("active")):
        raise WireError("announce: `active` is not a list of strings")
    return message


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _strings(value: Any) -> bool:
    return isinstance(value, list) and all(isinstance(item, str) for item in value)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def message_event(message: Mapping[str, Any]) -> Event:
    """The runtime event a decoded `event` message carries."""
    data = message.get("data")
    return Event(
        message["name"],
        record(data) if data is not None else None,
        message["id"],
        float(message["timestamp"]),
        message["sender"],
    )


def multicast_socket(options: Options) -> socket.socket:
    """A UDP socket bound to the group's port that hears the group on the interface and sends
    to it there, its own datagrams looped back (other processes of this host hear them)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # a burst of swarm events must not overflow the default buffer (the kernel caps this
        # at net.core.rmem_max)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER)
        if hasattr(socket, "SO_REUSEPORT"):  # several members of one host share the port
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
        # bound to the group, not to any address: only the group's datagrams arrive
        sock.bind((options.group, options.port))
        group, interface = socket.inet_aton(options.group), socket.inet_aton(options.interface)
        sock.setsockopt(
            socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, struct.pack("4s4s", group, interface)
        )
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, interface)
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, options.ttl)
        sock.setblocking(False)
    except BaseException:
        sock.close()
        raise
    return sock


class Endpoint(asyncio.DatagramProtocol):
    """The datagram plumbing both ends share: opening the group, sending messages, decoding
    what arrives through the fault layer, counting and logging what is bad. `handle(message)`
    gets each valid message (subclasses)."""

    def __init__(self, options: Options, faults: Faults | None = None, name: str = "") -> None:
        self.options = options
        self.faults = faults or Faults()
        self.name = name
        self.origin = incarnation()
        self.transport: asyncio.DatagramTransport | None = None
        self.bad = 0  # datagrams that failed to parse or validate
        self.unsent = 0  # messages that could not be encoded or sent
        self.received = 0
        self.peers: dict[str, Peer] = {}
        self.on_peer: Callable[[Peer], None] | None = None
        self.replaced: set[str] = set()  # incarnations a newer one of their member replaced
        self.clock: float | None = None  # Unix time the mission clock started (the station's)
        self.cut = 0  # datagrams a partition cut
        self._cutting = False  # the last datagram from another process was cut

    def receivers(self) -> Collection[str]:
        """The ids of who receives here (a partition's side): the process's members."""
        return ()

    def mission_time(self) -> float | None:
        """Seconds on the station's clock (None: no station heard yet)."""
        return None if self.clock is None else time.time() - self.clock

    async def open(self) -> None:
        """Join the group (OSError when the network refuses)."""
        loop = asyncio.get_running_loop()
        sock = multicast_socket(self.options)
        await loop.create_datagram_endpoint(lambda: self, sock=sock)

    def close(self) -> None:
        """Leave the group."""
        if self.transport is not None:
            self.transport.close()
            self.transport = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        """Keep the transport (asyncio calls this once the socket is ready)."""
        # a datagram endpoint's transport (3.11's selector one does not subclass the ABC)
        self.transport = cast(asyncio.DatagramTransport, transport)

    def error_received(self, exc: Exception) -> None:
        """A send failed asynchronously (ICMP): counted, the swarm goes on."""
        self.unsent += 1

    def send(self, message: Mapping[str, Any]) -> bool:
        """Send one message to the group; False (counted, logged) when it could not be."""
        try:
            payload = encode({"origin": self.origin, **message})
            if self.transport is None:
                raise OSError("not connected")
            self.transport.sendto(payload, (self.options.group, self.options.port))
        except (ValueError, OSError) as err:
            self.unsent += 1
            self._log(f"cannot send a {message.get('kind')} message: {err}", self.unsent)
            return False
        return True

    def datagram_received(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        """Decode a datagram and pass it on, through the fault layer."""
        self.received += 1
        try:
            message = decode(data)
        except WireError as err:
            self.bad += 1
            self._log(f"bad datagram {self.bad} from {addr[0]}:{addr[1]}: {err}", self.bad)
            return
        if message["origin"] == self.origin:
            return  # our own, looped back: already delivered in the process
        if not self.faults.active:
            self._take(message)
            return
        if self._partitioned(message):
            return
        loop = asyncio.get_running_loop()
        for delay in self.faults.copies():
            loop.call_later(delay, self._take, message)

    def _partitioned(self, message: Mapping[str, Any]) -> bool:
        """A partition cuts the datagram (counted; the cut's start and end logged)."""
        now = self.mission_time()
        cut = self.faults.cut(message["sender"], self.receivers(), now)
        if cut != self._cutting:
            self._cutting = cut
            what = f"cut off from {message['sender']}" if cut else "hearing the others again"
            print(f"{self.name}: partition: {what} at mission time {now:.3f}", file=sys.stderr)
        self.cut += cut
        return cut

    def _take(self, message: dict[str, Any]) -> None:
        if message["kind"] == "announce":
            self._heard(message)
        self.handle(message)

    def handle(self, message: dict[str, Any]) -> None:
        """A valid message from another process (what the subclass does with it)."""

    def _heard(self, message: Mapping[str, Any]) -> None:
        sender, origin = message["sender"], message["origin"]
        if origin in self.replaced:
            return  # a late word of an incarnation a newer one of its member replaced
        known = self.peers.get(sender)
        if known is not None and known.origin != origin:
            self.replaced.add(known.origin)
            if len(self.replaced) > SEEN_LIMIT:  # bounded: forget an arbitrary old one
                self.replaced.pop()
        peer = Peer(
            sender,
            message["member_type"],
            tuple(message["active"]),
            message["origin"],
            time.monotonic(),
            bool(message.get("finished", False)),
        )
        self.peers[sender] = peer
        if self.on_peer is not None:
            self.on_peer(peer)

    def _log(self, text: str, count: int) -> None:
        if count <= MAX_LOGGED:
            print(f"{self.name or 'udp'}: {text}", file=sys.stderr, flush=True)
        elif count == MAX_LOGGED + 1:
            print(f"{self.name or 'udp'}: (further ones counted only)", file=sys.stderr)


@dataclass(frozen=True, slots=True)
class Peer:
    """A member heard on the group: from its last announcement."""

    member_id: str
    member_type: str
    active: tuple[str, ...]
    origin: str
    seen: float  # time.monotonic() of the announcement
    finished: bool = False


class UdpBus(Endpoint):
    """A `Bus` over the group: swarm-scope events to every member of the swarm (this process's
    at once, the others by a datagram), local-scope events to the sender only. Station events
    are taken in the station's order, each once, and acknowledged on every copy (the station
    repeats them until they are)."""

    def __init__(self, options: Options, faults: Faults | None = None, name: str = "") -> None:
        super().__init__(options, faults, name)
        self.members: dict[str, Member] = {}
        self.seen = Seen()
        # (station incarnation, member id) -> how many of that station's events it took
        self.station_taken: OrderedDict[tuple[str, str], int] = OrderedDict()
        self.duplicates = 0
        self.early = 0  # station events ignored: addressed to others, or not the next one
        self._announcer: asyncio.TimerHandle | None = None

    def attach(self, member: Member) -> None:
        """Deliver the swarm's events to `member` from now on; announce it."""
        self.members[member.member_id] = member

    def publish(self, event: Event, scope: str) -> None:
        """Deliver `event` by its scope; swarm events also go to the group."""
        if scope == "local":
            target = self.members.get(event.sender)
            if target is not None:
                target.deliver(event)
            return
        self.seen.first((self.origin, event.sender, event.id))
        for member in self.members.values():
            member.deliver(event)
        self.send(event_message(event, self.origin))

    def receivers(self) -> Collection[str]:
        """The ids of this process's members."""
        return self.members.keys()

    def handle(self, message: dict[str, Any]) -> None:
        """Take another process's event: a station event in the station's order, another
        member's once."""
        if message["kind"] != "event":
            return
        if message["sender"] == "station":
            self._station_event(message)
            return
        if not self.seen.first((message["origin"], message["sender"], message["id"])):
            self.duplicates += 1
            return
        event = message_event(message)
        for member in self.members.values():
            member.deliver(event)

    def _station_event(self, message: dict[str, Any]) -> None:
        """A station numbers its events 1, 2, ... (per station incarnation): each member takes
        the next one it lacks and acknowledges it, acknowledges again the copies of those it
        took, and ignores (without acknowledging) an event addressed to others or past the
        next one, which the station sends again when it is that member's turn."""
        origin, number, to = message["origin"], message["id"], message.get("to")
        for member_id, member in self.members.items():
            key = (origin, member_id)
            taken = self.station_taken.get(key, 0)
            if number > taken + 1 or (number > taken and to is not None and member_id not in to):
                self.early += 1
                continue
            self.send({"kind": "ack", "sender": member_id, "of": origin, "id": number})
            if number <= taken:
                self.duplicates += 1
                continue
            self.station_taken[key] = number
            self.station_taken.move_to_end(key)
            if len(self.station_taken) > STATIONS_KEPT:
                self.station_taken.popitem(last=False)
            if "clock" in message:  # the mission clock of the station heard last
                self.clock = float(message["clock"])
            member.deliver(message_event(message))

    def start_announcing(self) -> None:
        """Announce every member now and every `announce_every` seconds."""
        self.announce()
        loop = asyncio.get_running_loop()
        self._announcer = loop.call_later(self.options.announce_every, self.start_announcing)

    def announce(self) -> None:
        """One announcement per member: its id, type and active states."""
        for member in self.members.values():
            self.send(
                {
                    "kind": "announce",
                    "sender": member.member_id,
                    "member_type": member.member_type,
                    "active": member.active,
                    # not running with states: in a final one (before its start it has none)
                    "finished": bool(member.active) and not member.engine.running,
                }
            )

    def close(self) -> None:
        """Announce a last time (the members' final states), stop announcing, leave."""
        if self._announcer is not None:
            self._announcer.cancel()
            self._announcer = None
        if self.transport is not None:
            for _ in range(LAST_WORDS):
                self.announce()
        super().close()
