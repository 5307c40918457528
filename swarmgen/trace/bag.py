"""Swarm traces as ROS 2 bags (rosbags), and a reader for them and for legacy CPSwarm ROS 1 bags.

Writing (`BagRecorder`), one bag per run, mcap by default or sqlite3:

- every event on `/swarm/events`, type `swarmgen_msgs/msg/Event` (id, stamp, sender, name,
  data = JSON object of the event's fields);
- every state change of a member on `/<member>/active_states`, type
  `swarmgen_msgs/msg/ActiveStates` (stamp, member, states).

Both definitions are swarmgen's own (`swarmgen.ros.interfaces.EVENT_MSG`, `ACTIVE_STATES_MSG`,
the ones the generated ROS 2 interface packages use) and are stored in the bag, so rosbags'
`AnyReader` and the ROS 2 tools read the bag without swarmgen. Bag time and message stamps are the
events' own timestamps (or a clock you pass, e.g. a `VirtualClock`), so the same events with the
same timestamps give byte-identical bags.

Recording hooks:

- as a runtime tracer: `Member(..., tracer=recorder)` (asyncio/smach members call
  `recorder.step(member, event)` after every step) or `MemberOptions(tracer=recorder)` on the
  rclpy nodes (they call `recorder(node, event)`);
- by hand, from a simulator or any host: `record_event(name, data, sender, stamp_ns)` and
  `record_states(member, states, stamp_ns)`;
- live ROS 2 topics: `write_raw(topic, msgtype, cdr_bytes, stamp_ns)` with the bytes of a raw
  subscription (see `swarmgen.trace.live`);
- a replay trace: `record_replay(path, member, steps, trace)`.

Reading (`read_events`): swarmgen bags (any message type with the Event or ActiveStates fields,
whatever its package) and legacy bags of the CPSwarm tools, whose topics are mapped to event
names as documented at `legacy_event` (and in docs/trace.md).
"""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
import sqlite3
import struct
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Protocol

from swarmgen.console import shown
from swarmgen.ros.interfaces import ACTIVE_STATES_MSG, EVENT_MSG

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag2 import Writer
    from rosbags.typesys.store import Typestore

__all__ = [
    "ACTIVE_STATES_TYPE",
    "BAG_SUFFIXES",
    "EVENTS_TOPIC",
    "EVENT_TYPE",
    "LEGACY_EVENT_TOPICS",
    "PACKAGE",
    "STORAGES",
    "BagRecorder",
    "RecordedEvent",
    "Run",
    "StateChange",
    "TraceError",
    "VirtualClock",
    "camel",
    "find_bags",
    "is_bag",
    "legacy_event",
    "read_events",
    "read_run",
    "record_replay",
    "states_topic",
]

PACKAGE = "swarmgen_msgs"
EVENT_TYPE = f"{PACKAGE}/msg/Event"
ACTIVE_STATES_TYPE = f"{PACKAGE}/msg/ActiveStates"
EVENTS_TOPIC = "/swarm/events"
STATES_TOPIC = "active_states"
STORAGES = ("mcap", "sqlite3")
BAG_SUFFIXES = (".bag", ".mcap", ".db3")  # ROS 1 bag; rosbag2 storage files without metadata

# Replay traces: step n is stamped n seconds after the start, the k-th input of a burst k ms later.
STEP_NS = 1_000_000_000
BURST_NS = 1_000_000

_EVENT_FIELDS = frozenset({"id", "stamp", "sender", "name", "data"})
_STATES_FIELDS = frozenset({"stamp", "member", "states"})
_TOKEN = re.compile(r"[^A-Za-z0-9_]+")


class TraceError(Exception):
    """A bag cannot be written or read (a user error: path exists, not a bag, corrupt)."""


# --- writing


class VirtualClock:
    """A clock for deterministic bags: `now` nanoseconds, set or advanced by the caller."""

    def __init__(self, start_ns: int = 0) -> None:
        self.now = start_ns

    def __call__(self) -> int:
        return self.now

    def set(self, stamp_ns: int) -> None:
        self.now = stamp_ns

    def advance(self, delta_ns: int) -> int:
        self.now += delta_ns
        return self.now


class _Active(Protocol):
    def active(self) -> list[str]: ...


class Traced(Protocol):
    """What a tracer needs of a member (runtime.member.Member, the rclpy MemberNode)."""

    @property
    def member_id(self) -> str: ...

    @property
    def engine(self) -> _Active: ...


class TracedEvent(Protocol):
    """The runtime's Event (runtime.engine.Event and the generated packages' vendored copy)."""

    @property
    def name(self) -> str: ...

    @property
    def data(self) -> Any: ...

    @property
    def id(self) -> int: ...

    @property
    def timestamp(self) -> float: ...

    @property
    def sender(self) -> str: ...


def states_topic(member: str) -> str:
    """`/<member>/active_states`, the member id made a valid ROS 2 name token."""
    token = re.sub(r"_+", "_", _TOKEN.sub("_", member)).strip("_") or "member"
    if token[0].isdigit():
        token = f"m{token}"
    return f"/{token}/{STATES_TOPIC}"


def _json(data: Any) -> str:
    return json.dumps(data if data is not None else {}, sort_keys=True, default=str)


@cache
def _typestore(package: str = PACKAGE) -> Typestore:
    """ROS 2 (Kilted) types plus Event and ActiveStates under `package`."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_KILTED)
    types = dict(get_types_from_msg(EVENT_MSG, f"{package}/msg/Event"))
    types.update(get_types_from_msg(ACTIVE_STATES_MSG, f"{package}/msg/ActiveStates"))
    store.register(types)
    return store


def _time(store: Typestore, stamp_ns: int) -> Any:
    sec, nanosec = divmod(stamp_ns, 1_000_000_000)
    return store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)


class BagRecorder:
    """Writes one run into a new ROS 2 bag at `path` (a directory that must not exist yet).

    `storage`: "mcap" (default) or "sqlite3". `clock`: nanoseconds for records without a stamp
    of their own (default: wall clock); pass a `VirtualClock` for deterministic bags.
    `package`: the message package name the two types are stored under (swarmgen_msgs; the rclpy
    integration may pass the model's interface package so that `ros2 bag play` feeds live nodes).
    Thread-safe; use as a context manager or call `close()`.
    """

    def __init__(
        self,
        path: Path | str,
        *,
        storage: Literal["mcap", "sqlite3"] | str = "mcap",
        clock: Callable[[], int] | None = None,
        package: str = PACKAGE,
    ) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

        if storage not in STORAGES:
            raise TraceError(f"unknown bag storage {storage!r}; choose one of {STORAGES}")
        self.path = Path(path)
        self.package = package
        self.event_type = f"{package}/msg/Event"
        self.states_type = f"{package}/msg/ActiveStates"
        self.clock: Callable[[], int] = clock if clock is not None else time.time_ns
        self._store = _typestore(package)
        self._lock = threading.RLock()
        self._connections: dict[tuple[str, str], Connection] = {}
        self._ids: dict[str, int] = {}
        self._last_states: dict[str, tuple[str, ...]] = {}
        self._seen: set[tuple[str, int, str, int]] = set()
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        try:
            self._writer: Writer | None = Writer(self.path, version=9, storage_plugin=plugin)
            self._writer.open()
        except WriterError as err:
            raise TraceError(f"cannot record into {shown(self.path)}: {err}") from None
        except OSError as err:  # a file in the way, a read-only directory, a too long name
            raise TraceError(f"cannot record into {shown(self.path)}: {err.strerror}") from None
        self._connection(EVENTS_TOPIC, self.event_type)

    # --- lifecycle

    def close(self) -> None:
        with self._lock:
            if self._writer is not None:
                self._writer.close()
                self._writer = None

    def __enter__(self) -> BagRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- hooks

    def record_event(
        self,
        name: str,
        data: Mapping[str, Any] | None = None,
        sender: str = "",
        stamp_ns: int | None = None,
        *,
        id: int | None = None,
    ) -> None:
        """One event on /swarm/events. `id` defaults to a counter per sender (1, 2, ...)."""
        stamp = self.clock() if stamp_ns is None else stamp_ns
        with self._lock:
            if id is None:
                id = self._ids.get(sender, 0) + 1
            self._ids[sender] = max(self._ids.get(sender, 0), id)
            message = self._store.types[self.event_type](
                id=id,
                stamp=_time(self._store, stamp),
                sender=sender,
                name=name,
                data=_json(data),
            )
            self._write(EVENTS_TOPIC, self.event_type, message, stamp)

    def record_states(
        self, member: str, states: Iterable[str], stamp_ns: int | None = None
    ) -> None:
        """The active states of `member` on /<member>/active_states (written unconditionally)."""
        stamp = self.clock() if stamp_ns is None else stamp_ns
        states = tuple(states)
        with self._lock:
            self._last_states[member] = states
            message = self._store.types[self.states_type](
                stamp=_time(self._store, stamp), member=member, states=list(states)
            )
            self._write(states_topic(member), self.states_type, message, stamp)

    def write_raw(self, topic: str, msgtype: str, data: bytes, stamp_ns: int | None = None) -> None:
        """CDR bytes as received by a raw subscription. `msgtype` is `<package>/msg/Event` or
        `<package>/msg/ActiveStates` of any package: their definition is swarmgen's."""
        stamp = self.clock() if stamp_ns is None else stamp_ns
        package, _, short = msgtype.partition("/msg/")
        if short not in {"Event", "ActiveStates"} or not package:
            raise TraceError(f"cannot record {msgtype}: only <package>/msg/Event or ActiveStates")
        with self._lock:
            connection = self._connection(topic, msgtype, _typestore(package))
            assert self._writer is not None
            self._writer.write(connection, stamp, data)

    def step(
        self, member: Traced, event: TracedEvent | None, *, stamp_ns: int | None = None
    ) -> None:
        """Runtime tracer: the event the member just processed, and its states if they changed.

        Stamps: `stamp_ns` if given (a host whose engine clock is not in seconds, such as a
        simulator counting ticks), else the event's own timestamp (seconds), else the clock.
        An event delivered to several members (same sender, id, name and stamp) is written once.
        """
        stamp = self.clock() if stamp_ns is None else stamp_ns
        if stamp_ns is None and event is not None and event.timestamp > 0:
            stamp = round(event.timestamp * 1e9)
        member_id = member.member_id or "member"
        states = tuple(member.engine.active())
        with self._lock:
            if event is not None:
                key = (event.sender, event.id, event.name, stamp)
                if key not in self._seen:
                    self._seen.add(key)
                    self.record_event(event.name, event.data, event.sender, stamp, id=event.id)
            if self._last_states.get(member_id) != states:
                self.record_states(member_id, states, stamp)

    def __call__(self, member: Traced, event: TracedEvent | None) -> None:
        """The rclpy nodes' tracer signature (`MemberOptions.tracer`)."""
        self.step(member, event)

    # --- internals

    def _connection(self, topic: str, msgtype: str, store: Typestore | None = None) -> Connection:
        key = (topic, msgtype)
        connection = self._connections.get(key)
        if connection is None:
            if self._writer is None:
                raise TraceError(f"{self.path}: the bag is closed")
            connection = self._writer.add_connection(topic, msgtype, typestore=store or self._store)
            self._connections[key] = connection
        return connection

    def _write(self, topic: str, msgtype: str, message: Any, stamp: int) -> None:
        if self._writer is None:
            raise TraceError(f"{self.path}: the bag is closed")
        connection = self._connection(topic, msgtype)
        self._writer.write(connection, stamp, self._store.serialize_cdr(message, msgtype))


def _expand(step: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    burst = step.get("burst")
    return list(burst) if isinstance(burst, list) else [step]


def record_replay(
    path: Path | str,
    member: str,
    steps: Sequence[Mapping[str, Any]],
    trace: Sequence[Mapping[str, Any]],
    *,
    storage: str = "mcap",
) -> Path:
    """A replay trace (`swarmgen replay`, any backend) as a bag, with virtual stamps.

    Step n (1-based) happens n seconds after the start, the k-th input of a burst k ms later:
    an `event` step is the event itself (sender `station`); a `complete` step is the event
    `<Behaviour>.<outcome>` (sender `replay`, data = outputs). The active states after step n
    (trace record n; record 0 is the initial configuration, at 0 s) follow its last input by
    1 ms. The same scenario and trace give a byte-identical bag.
    """
    path = Path(path)
    try:
        with BagRecorder(path, storage=storage, clock=VirtualClock()) as recorder:
            _write_replay(recorder, member, steps, trace)
    except OSError as err:  # e.g. the disk filled up: remove the half bag this call created
        shutil.rmtree(path, ignore_errors=True)
        raise TraceError(f"cannot record into {shown(path)}: {err.strerror or err}") from None
    return path


def _write_replay(
    recorder: BagRecorder,
    member: str,
    steps: Sequence[Mapping[str, Any]],
    trace: Sequence[Mapping[str, Any]],
) -> None:
    records = {int(r.get("step", i)): r for i, r in enumerate(trace)}
    if 0 in records:
        recorder.record_states(member, records[0].get("active", ()), 0)
    for number, step in enumerate(steps, start=1):
        base = number * STEP_NS
        items = _expand(step)
        for k, item in enumerate(items):
            stamp = base + k * BURST_NS
            if "complete" in item:
                name = f"{item['complete']}.{item.get('outcome', 'succeeded')}"
                outputs = dict(item.get("outputs") or {})
                if item.get("state") is not None:
                    outputs.setdefault("state", item["state"])
                recorder.record_event(name, outputs, "replay", stamp)
            else:
                recorder.record_event(str(item.get("event")), item.get("data"), "station", stamp)
        if number in records:
            recorder.record_states(
                member, records[number].get("active", ()), base + len(items) * BURST_NS
            )


# --- reading


@dataclass(frozen=True, slots=True)
class RecordedEvent:
    """One event of a run: its name, when (ns since the epoch, or since 0 for virtual stamps),
    who sent it, its data (a JSON object's value, or the raw text if it is not JSON), its id
    and the topic it was read from."""

    name: str
    stamp_ns: int
    sender: str = ""
    data: Any = None
    id: int = 0
    topic: str = ""


@dataclass(frozen=True, slots=True)
class StateChange:
    member: str
    states: tuple[str, ...]
    stamp_ns: int


@dataclass(frozen=True, slots=True)
class Run:
    """One run: the events (sorted by stamp, ties in bag order) and state changes of its bags."""

    source: str
    start_ns: int | None  # the earliest bag time of the run's bags (None: no messages)
    events: tuple[RecordedEvent, ...]
    states: tuple[StateChange, ...] = ()

    @property
    def launch_ns(self) -> int | None:
        """The stamp of the run's first `launch` event, else the start of the bag."""
        for event in self.events:
            if event.name == "launch":
                return event.stamp_ns
        return self.start_ns

    def first(self, name: str) -> RecordedEvent | None:
        return next((e for e in self.events if e.name == name), None)


# Topic names of the CPSwarm tools (ROS 1, relative to /cpswarm/<vehicle>_<id>) that carry
# events under their own name: what target_monitor and task_allocation publish, and the swarm
# events swarmio delivers on a topic of the same name (position and velocity are left out: they
# are periodic kinematics, not mission events).
LEGACY_EVENT_TOPICS = frozenset(
    {"target_found", "target_update", "target_lost", "target_done", "target_rescued",
     "cps_selected", "cps_selection"}
)  # fmt: skip
_BRIDGE = re.compile(r"^(?P<ns>.*?)/?bridge/events/(?P<event>[A-Za-z0-9_]+)$")
_ACTION = re.compile(r"^(?P<ns>.*?)/?cmd/(?P<behaviour>[A-Za-z0-9_]+)/(?P<part>goal|result)$")
_PLAIN = re.compile(r"^(?P<ns>.*?)/?(?P<event>[A-Za-z0-9_]+)$")
# actionlib_msgs/GoalStatus as SMACH's SimpleActionState turns it into an outcome
_GOAL_STATUS = {3: "succeeded", 2: "preempted"}


def camel(snake: str) -> str:
    """`mission_start` -> `missionStart` (names already in camelCase are kept)."""
    head, *rest = [p for p in snake.split("_") if p] or [snake]
    return head + "".join(p[:1].upper() + p[1:] for p in rest)


def legacy_event(topic: str) -> tuple[str, str, str] | None:
    """(event name, sender namespace, kind) for a CPSwarm ROS 1 topic, or None if it carries none.

    ======================================  =========================  ====================
    topic (after the namespace)             event name                 kind
    ======================================  =========================  ====================
    bridge/events/<snake_name>              camel(snake_name)          incoming
    <name> in LEGACY_EVENT_TOPICS           camel(name)                outgoing
    cmd/<behaviour>/goal                    camel(behaviour).goal      goal
    cmd/<behaviour>/result                  camel(behaviour).<outcome> result
    ======================================  =========================  ====================

    `mission_start` -> `missionStart`, `target_found` -> `targetFound`, `launch` -> `launch`,
    `cmd/takeoff/goal` -> `takeoff.goal`. A result's outcome is SMACH's reading of its actionlib
    status: 3 (SUCCEEDED) succeeded, 2 (PREEMPTED) preempted, any other aborted; `result` when
    the message has no status. The sender is the namespace, e.g. `cpswarm/uav_1`.
    """
    name = topic.strip("/")
    if match := _BRIDGE.match(name):
        return camel(match["event"]), match["ns"].strip("/"), "incoming"
    if match := _ACTION.match(name):
        return f"{camel(match['behaviour'])}.{match['part']}", match["ns"].strip("/"), "action"
    if (match := _PLAIN.match(name)) and match["event"] in LEGACY_EVENT_TOPICS:
        return camel(match["event"]), match["ns"].strip("/"), "outgoing"
    return None


def _plain(value: Any) -> Any:
    """A deserialized message as JSON-able values (dicts, lists, numbers, strings)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: _plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if not f.name.startswith("__")  # rosbags' __msgtype__
        }
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if hasattr(value, "tolist"):  # numpy arrays of primitive fields
        return value.tolist()
    if isinstance(value, bytes):
        return list(value)
    return value


def _stamp(message: Any) -> int:
    stamp = getattr(message, "stamp", None)
    if stamp is None:
        header = getattr(message, "header", None)
        stamp = getattr(header, "stamp", None)
    if stamp is None:
        return 0
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def is_bag(path: Path) -> bool:
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    return path.is_file() and path.suffix in BAG_SUFFIXES


def find_bags(path: Path | str, seen: set[tuple[int, int]] | None = None) -> list[Path]:
    """`path` itself if it is a bag (a rosbag2 directory, a .bag, .mcap or .db3 file), else every
    bag below the directory `path`, sorted by path (bag directories are not searched inside).

    Symlinks are followed, but every real directory and bag once (by device and inode, in
    `seen`): a link back up the tree or a second link to a bag cannot count a run twice."""
    path = Path(path)
    seen = set() if seen is None else seen
    try:
        if not path.exists():
            raise TraceError(f"{shown(path)}: no such file or directory")
        info = path.stat()
        if (info.st_dev, info.st_ino) in seen:
            return []
        seen.add((info.st_dev, info.st_ino))
        if is_bag(path):
            return [path]
        if not path.is_dir():
            raise TraceError(
                f"{shown(path)}: not a bag (a rosbag2 directory, .bag, .mcap or .db3 file)"
            )
        children = sorted(path.iterdir())
    except OSError as err:
        raise TraceError(f"{shown(path)}: cannot read: {err.strerror or err}") from None
    found: list[Path] = []
    for child in children:
        try:
            searched = is_bag(child) or child.is_dir()
        except OSError as err:
            raise TraceError(f"{shown(child)}: cannot read: {err.strerror or err}") from None
        if searched:
            found.extend(find_bags(child, seen))
    return found


def _field_names(store: Typestore, msgtype: str) -> frozenset[str]:
    definition = store.fielddefs.get(msgtype)
    return frozenset(name for name, _ in definition[1]) if definition else frozenset()


def _read_bag(
    path: Path, aliases: Mapping[str, str]
) -> tuple[int | None, list[tuple[int, int, RecordedEvent]], list[StateChange]]:
    from rosbags.highlevel import AnyReader

    events: list[tuple[int, int, RecordedEvent]] = []
    states: list[StateChange] = []
    try:
        with AnyReader([path]) as reader:
            kinds: dict[int, tuple[str, tuple[str, str, str] | None]] = {}
            for connection in reader.connections:
                fields = _field_names(reader.typestore, connection.msgtype)
                if fields >= _EVENT_FIELDS:
                    kinds[connection.id] = ("event", None)
                elif fields >= _STATES_FIELDS:
                    kinds[connection.id] = ("states", None)
                elif (legacy := legacy_event(connection.topic)) is not None:
                    kinds[connection.id] = ("legacy", legacy)
            start = reader.start_time if reader.message_count else None
            wanted = [c for c in reader.connections if c.id in kinds]
            for order, (connection, bag_time, raw) in enumerate(reader.messages(wanted)):
                kind, legacy = kinds[connection.id]
                message: Any = reader.deserialize(raw, connection.msgtype)
                stamp = _stamp(message) or bag_time
                if kind == "states":
                    states.append(StateChange(str(message.member), tuple(message.states), stamp))
                    continue
                event = _event(message, connection.topic, stamp, legacy)
                event = dataclasses.replace(event, name=aliases.get(event.name, event.name))
                events.append((stamp, order, event))
    except _corrupt() as err:
        lines = str(err).strip().splitlines() or [type(err).__name__]
        raise TraceError(f"{shown(path)}: cannot read the bag: {shown(lines[0])}") from None
    return start, events, states


@cache
def _corrupt() -> tuple[type[BaseException], ...]:
    """What reading a corrupt or truncated bag raises (found by truncating real mcap and sqlite3
    bags at every length and flipping random bytes): rosbags' own errors, and from below it
    struct, sqlite (apsw) and I/O errors, TypeError for a blob stored as text, and MemoryError
    or OverflowError for a length field of 2**60 in a 6 KB file. Only the reading of one bag
    is guarded by it."""
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag1 import ReaderError as Reader1Error
    from rosbags.rosbag2 import ReaderError as Reader2Error

    found: list[type[BaseException]] = [AnyReaderError, Reader1Error, Reader2Error]
    found += [ValueError, KeyError, IndexError, TypeError, EOFError, OSError, struct.error]
    found += [OverflowError, MemoryError, sqlite3.Error]
    try:
        import apsw

        found.append(apsw.Error)
    except ModuleNotFoundError:
        pass
    return tuple(found)


def _event(
    message: Any, topic: str, stamp: int, legacy: tuple[str, str, str] | None
) -> RecordedEvent:
    if legacy is None:  # a swarmgen Event
        try:
            data = json.loads(message.data) if message.data else None
        except ValueError:
            data = message.data
        return RecordedEvent(
            str(message.name), stamp, str(message.sender), data, int(message.id), topic
        )
    name, sender, kind = legacy
    fields = _plain(message)
    fields.pop("header", None)
    if kind == "action" and name.endswith(".result"):
        status = getattr(getattr(message, "status", None), "status", None)
        if status is not None:
            name = f"{name.removesuffix('.result')}.{_GOAL_STATUS.get(int(status), 'aborted')}"
    return RecordedEvent(name, stamp, sender, fields, 0, topic)


def read_run(bags: Sequence[Path | str], aliases: Mapping[str, str] | None = None) -> Run:
    """One run from one or more bags (e.g. one bag per drone of the same run), merged by stamp."""
    if not bags:
        raise TraceError("a run needs at least one bag")
    starts: list[int] = []
    events: list[tuple[int, int, int, RecordedEvent]] = []
    states: list[StateChange] = []
    for index, bag in enumerate(Path(b) for b in bags):
        if not bag.exists():
            raise TraceError(f"{bag}: no such file or directory")
        start, bag_events, bag_states = _read_bag(bag, aliases or {})
        if start is not None:
            starts.append(start)
        events.extend((stamp, index, order, e) for stamp, order, e in bag_events)
        states.extend(bag_states)
    events.sort(key=lambda item: item[:3])
    states.sort(key=lambda s: s.stamp_ns)
    source = str(bags[0]) if len(bags) == 1 else ", ".join(str(b) for b in bags)
    return Run(source, min(starts) if starts else None, tuple(e for *_, e in events), tuple(states))


def read_events(paths: Iterable[Path | str], aliases: Mapping[str, str] | None = None) -> list[Run]:
    """One `Run` per bag: each path is a bag, or a directory searched for bags (`find_bags`;
    a bag reached twice, through links or by naming it twice, is one run).

    `aliases` renames events after reading (e.g. {"targetDone": "targetRescued"} to compare
    legacy bags with the paper's names).
    """
    runs: list[Run] = []
    seen: set[tuple[int, int]] = set()
    for path in paths:
        if not str(path):
            raise TraceError("an empty path: give a bag or a directory of bags")
        known = len(seen)
        bags = find_bags(path, seen)
        if not bags and len(seen) > known:  # a new directory without bags (not one seen before)
            raise TraceError(f"no bags found in {shown(path)}")
        runs.extend(read_run([bag], aliases) for bag in bags)
    return runs
