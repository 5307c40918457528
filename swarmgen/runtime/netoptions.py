"""The network transport's options: where datagrams go, what the model's CommunicationInterface
gives, and the command line of `--transport udp` and `--station-only` (standard library only).

Where an option's value comes from, in order: the defaults here; the swarm's `NETWORK` (the
package's `__init__.py`, from the model's `communicationParams`, checked at compile time by
the same functions: `param_items`, `param_value`); then the command line, which wins.
"""

from __future__ import annotations

import argparse
import json
import math
import socket
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, TextIO

from swarmgen.runtime.faults import Partition, finite_rate, parse_partition

DEFAULT_GROUP = "239.255.70.71"  # administratively scoped (RFC 2365): never routed off-site
DEFAULT_PORT = 5670
DEFAULT_TTL = 1  # one hop: the local network (0 would be this host only)
DEFAULT_INTERFACE = "127.0.0.1"  # loopback unless told otherwise: nothing leaves the machine
ANNOUNCE_EVERY = 0.25  # seconds between two announcements
REPEAT_EVERY = 0.1  # seconds between two copies of an unacknowledged station event
PEER_TIMEOUT = 1.0  # a member not heard for this long is no longer waited for
MAX_SCRIPT_BYTES = 1_000_000
# The keys of `communicationParams` the transport reads, and the one it knows and leaves to the
# command line: `ifname` names the robot's radio, but the interface stays loopback unless
# `--interface` says otherwise, so running a package on a desk never sends onto a real network.
TRANSPORT_KEYS = ("group", "port", "ttl")
KNOWN_KEYS = (*TRANSPORT_KEYS, "ifname")


@dataclass(frozen=True, slots=True)
class Options:
    """Where the swarm's datagrams go: multicast group, port, TTL, interface address."""

    group: str = DEFAULT_GROUP
    port: int = DEFAULT_PORT
    ttl: int = DEFAULT_TTL
    interface: str = DEFAULT_INTERFACE
    announce_every: float = ANNOUNCE_EVERY


class BadItem(ValueError):
    """An item of a `communicationParams` text that is not `key=value` (`item`)."""

    def __init__(self, item: str) -> None:
        super().__init__(f"'{item}' is not key=value")
        self.item = item


def param_items(text: str) -> list[tuple[str, str]]:
    """A `communicationParams` text as (key, value) items: `key=value`, separated by spaces,
    commas or semicolons. BadItem names an item that is not `key=value`."""
    items = []
    for item in text.replace(",", " ").replace(";", " ").split():
        key, separator, value = item.partition("=")
        if not separator or not key or not value:
            raise BadItem(item)
        items.append((key, value))
    return items


def param_value(key: str, value: str) -> str | int:
    """The value of a transport key (`group`, `port`, `ttl`) as the transport takes it;
    ValueError says why it cannot be."""
    if key == "group":
        check_group(value)
        return value
    low, high = (1, 65_535) if key == "port" else (0, 255)
    try:
        number = int(value, 10)
    except ValueError:
        raise ValueError(f"{key} '{value}' is not an integer") from None
    if not low <= number <= high:
        raise ValueError(f"{key} {number} is not in {low}-{high}")
    return number


def params_options(text: str, base: Options | None = None) -> Options:
    """Options from a `communicationParams` text (keys other than the transport's ignored);
    ValueError when an item or a value is bad."""
    values = {k: param_value(k, v) for k, v in param_items(text) if k in TRANSPORT_KEYS}
    return network_options(values, base)


def network_options(network: Mapping[str, Any], base: Options | None = None) -> Options:
    """`base` (else the defaults) with the transport keys of `network` (a package's NETWORK);
    ValueError when the result is not usable."""
    fields = {name: getattr(base or Options(), name) for name in Options.__dataclass_fields__}
    fields.update({k: v for k, v in network.items() if k in TRANSPORT_KEYS})
    options = Options(**fields)
    check_options(options)
    return options


def check_group(group: str) -> None:
    """Raise ValueError unless `group` is an IPv4 multicast address, dotted in full."""
    try:
        first = socket.inet_aton(group)[0]
    except (OSError, TypeError):
        raise ValueError(f"not an IPv4 address: {group!r}") from None
    if not 224 <= first <= 239 or group.count(".") != 3:
        raise ValueError(f"not a multicast group (224.0.0.0-239.255.255.255): {group!r}")


def check_options(options: Options) -> None:
    """Raise ValueError unless the group is an IPv4 multicast address, the port 1-65535, the
    TTL 0-255 and the interface an IPv4 address."""
    check_group(options.group)
    try:
        socket.inet_aton(options.interface)
    except (OSError, TypeError):
        raise ValueError(f"not an IPv4 address: {options.interface!r}") from None
    if isinstance(options.port, bool) or not 0 < options.port < 65_536:
        raise ValueError(f"expected a port 1-65535, got {options.port}")
    if isinstance(options.ttl, bool) or not 0 <= options.ttl <= 255:
        raise ValueError(f"expected a TTL 0-255, got {options.ttl}")


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
    net.add_argument(
        "--partition",
        action="append",
        type=_partition,
        default=[],
        metavar="IDS@START-END",
        help="fault: these members cut off from the others, in seconds of mission time",
    )


def resolve_options(args: Any, network: Mapping[str, Any] | None) -> Options:
    """The network options: the defaults, then the swarm's NETWORK (the model's
    `communicationParams`), then the command line. ValueError when they are not usable."""
    base = network_options(network or {}, Options(announce_every=args.announce))
    given = {k: getattr(args, k) for k in ("group", "port", "ttl", "interface")}
    fields = {k: getattr(base, k) for k in Options.__dataclass_fields__}
    options = Options(**{**fields, **{k: v for k, v in given.items() if v is not None}})
    check_options(options)
    return options


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
        if isinstance(at, bool) or not isinstance(at, int | float) or not 0 <= at < math.inf:
            raise ValueError(f"{where}: `at` is not a number of seconds >= 0")
        if data is not None and not isinstance(data, dict):
            raise ValueError(f"{where}: `data` is not an object")
        events.append((float(at), name, data))
    return sorted(events, key=lambda e: e[0])


def _refuse(name: str) -> Any:
    raise ValueError(f"non-finite number {name}")


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


def _partition(text: str) -> Partition:
    try:
        return parse_partition(text)
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
