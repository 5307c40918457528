"""Swarm events between processes over UDP multicast (standard library only).

One datagram is one JSON object of the wire format (docs/network.md): an `event` (the runtime's
envelope: name, data, id, timestamp, sender), an `ack` of a station event, or an `announce`ment
(who a member is and its active states) by which members and the station discover each other;
there is no static peer list. `UdpBus` is the member side: a `Bus` whose swarm-scope events go to
the group (and to its own members at once, as `InMemoryBus` does), local-scope events stay in the
process. Every datagram that fails to parse or to validate is counted and logged, never raised.

The fault layer (`Faults`: loss, duplication, delay, seeded) acts where datagrams are received,
so each receiver loses its own copies, as on a radio. Duplicates (the station repeats its
events until they are acknowledged) are suppressed by event key in bounded memory (`Seen`).
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import random
import socket
import struct
import sys
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

from swarmgen.runtime.host import Event
from swarmgen.runtime.values import record

if TYPE_CHECKING:
    from swarmgen.runtime.member import Member

WIRE_VERSION = 1
KINDS = frozenset({"event", "ack", "announce"})
MAX_DATAGRAM = 65_507  # the largest UDP payload over IPv4
RECEIVE_BUFFER = 4 * 1024 * 1024  # bytes asked for the socket's receive buffer
SEEN_LIMIT = 4_096  # event keys remembered for duplicate suppression, per process
MAX_LOGGED = 20  # bad datagrams logged on stderr (all are counted)
DEFAULT_GROUP = "239.255.70.71"  # administratively scoped (RFC 2365): never routed off-site
DEFAULT_PORT = 5670  # the SAR model's CommunicationInterface gives `port=5670`
DEFAULT_TTL = 1  # one hop: the local network (0 would be this host only)
DEFAULT_INTERFACE = "127.0.0.1"  # loopback unless told otherwise: nothing leaves the machine
# the engine's own events (a behaviour's end, its outcome, SCXML's done.* and error.*): a
# datagram naming one would forge a behaviour's end, so none comes from the network
RESERVED = ("done.", "error.", "outcome.")
ANNOUNCE_EVERY = 0.25  # seconds between two announcements
LAST_WORDS = 3  # copies of a member's last announcement (its final states): one may be lost


class WireError(ValueError):
    """A datagram that is not a message of the wire format (the text says why)."""


@dataclass(frozen=True, slots=True)
class Options:
    """Where the swarm's datagrams go: multicast group, port, TTL, interface address."""

    group: str = DEFAULT_GROUP
    port: int = DEFAULT_PORT
    ttl: int = DEFAULT_TTL
    interface: str = DEFAULT_INTERFACE
    announce_every: float = ANNOUNCE_EVERY


def params_options(text: str, base: Options | None = None) -> Options:
    """Options from a CommunicationInterface's `communicationParams` (`group=... port=...
    ttl=...`, separated by spaces, commas or semicolons); other keys (`ifname`) are ignored,
    bad values raise ValueError."""
    values: dict[str, Any] = {}
    for item in text.replace(",", " ").replace(";", " ").split():
        key, _, value = item.partition("=")
        if key == "group":
            values["group"] = value
        elif key in ("port", "ttl"):
            values[key] = int(value)
    options = Options(**{**_fields(base or Options()), **values})
    check_options(options)
    return options


def _fields(options: Options) -> dict[str, Any]:
    return {name: getattr(options, name) for name in Options.__dataclass_fields__}


def check_options(options: Options) -> None:
    """Raise ValueError unless the group is an IPv4 multicast address, the port 1-65535, the
    TTL 0-255 and the interface an IPv4 address."""
    try:
        first = socket.inet_aton(options.group)[0]
        socket.inet_aton(options.interface)
    except OSError:
        raise ValueError(f"not IPv4 addresses: {options.group!r}, {options.interface!r}") from None
    if not 224 <= first <= 239 or options.group.count(".") != 3:
        raise ValueError(f"not a multicast group (224.0.0.0-239.255.255.255): {options.group!r}")
    if not 0 < options.port < 65_536:
        raise ValueError(f"expected a port 1-65535, got {options.port}")
    if not 0 <= options.ttl <= 255:
        raise ValueError(f"expected a TTL 0-255, got {options.ttl}")


@dataclass(slots=True)
class Faults:
    """Injected datagram faults (for tests), applied to each datagram received: dropped with
    probability `drop`, else delivered twice with probability `duplicate`, each copy delayed
    by a uniform 0-`delay` seconds (so datagrams overtake each other). Seeded: reproducible."""

    drop: float = 0.0
    duplicate: float = 0.0
    delay: float = 0.0
    seed: int = 0
    rng: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)

    @property
    def active(self) -> bool:
        """Some fault is injected."""
        return self.drop > 0 or self.duplicate > 0 or self.delay > 0

    def copies(self) -> list[float]:
        """The delays of the copies of one received datagram (none: it is lost)."""
        if self.drop > 0 and self.rng.random() < self.drop:
            return []
        count = 2 if self.duplicate > 0 and self.rng.random() < self.duplicate else 1
        return [self.rng.uniform(0.0, self.delay) if self.delay > 0 else 0.0 for _ in range(count)]


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


_STR_FIELDS: dict[str, tuple[str, ...]] = {
    "event": ("origin", "name", "sender"),
    "ack": ("origin", "sender", "of"),
    "announce": ("origin", "sender", "member_type"),
}


def decode(payload: bytes) -> dict[str, Any]:
    """A datagram as a message of the wire format; WireError says why it is not one."""
    try:
        message = json.loads(payload.decode("utf-8"), parse_constant=_no_constant)
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
        if not isinstance(message.get("timestamp"), int | float) or isinstance(
            message["timestamp"], bool
        ):
            raise WireError("event: `timestamp` is not a number")
    if kind == "announce":
        active = message.get("active")
        if not isinstance(active, list) or not all(isinstance(s, str) for s in active):
            raise WireError("announce: `active` is not a list of strings")
    return message


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


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
        loop = asyncio.get_running_loop()
        for delay in self.faults.copies():
            loop.call_later(delay, self._take, message)

    def _take(self, message: dict[str, Any]) -> None:
        if message["kind"] == "announce":
            self._heard(message)
        self.handle(message)

    def handle(self, message: dict[str, Any]) -> None:
        """A valid message from another process (what the subclass does with it)."""

    def _heard(self, message: Mapping[str, Any]) -> None:
        sender = message["sender"]
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
    are acknowledged on every copy (the station repeats them until they are), delivered once."""

    def __init__(self, options: Options, faults: Faults | None = None, name: str = "") -> None:
        super().__init__(options, faults, name)
        self.members: dict[str, Member] = {}
        self.seen = Seen()
        self.duplicates = 0
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

    def handle(self, message: dict[str, Any]) -> None:
        """Take another process's event (acknowledged when it is the station's)."""
        if message["kind"] != "event":
            return
        if message["sender"] == "station":
            for member_id in self.members:
                self.send({"kind": "ack", "sender": member_id, "of": message["origin"],
                           "id": message["id"]})  # fmt: skip
        if not self.seen.first((message["origin"], message["sender"], message["id"])):
            self.duplicates += 1
            return
        event = message_event(message)
        for member in self.members.values():
            member.deliver(event)

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


def finite_rate(text: str) -> float:
    """A probability 0-1 (argparse type helper); ValueError otherwise."""
    value = float(text)
    if not math.isfinite(value) or not 0.0 <= value <= 1.0:
        raise ValueError(f"expected a probability 0-1, got {text!r}")
    return value
