"""Reading ROS 2 bags back into runs: swarmgen's bags and legacy CPSwarm ROS 1 bags.

`read_events` reads swarmgen bags (any message type with the Event or ActiveStates fields,
whatever its package) and legacy bags of the CPSwarm tools, whose topics are mapped to event
names as documented at `legacy_event` (and in docs/trace.md).
"""

from __future__ import annotations

import dataclasses
import json
import re
import sqlite3
import struct
from collections.abc import Iterable, Mapping, Sequence
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmgen.console import shown
from swarmgen.records import dataclass
from swarmgen.trace.bag import BAG_SUFFIXES, TraceError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = [
    "LEGACY_EVENT_TOPICS",
    "RecordedEvent",
    "Run",
    "StateChange",
    "camel",
    "find_bags",
    "is_bag",
    "legacy_event",
    "read_events",
    "read_run",
]

_EVENT_FIELDS = frozenset({"id", "stamp", "sender", "name", "data"})
_STATES_FIELDS = frozenset({"stamp", "member", "states"})


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
    """A member's active states from a stamp on."""

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
        """The first event of that name, None if there is none."""
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
    """Whether `path` is a bag: a directory with metadata.yaml or a bag file."""
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
