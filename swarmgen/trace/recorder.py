"""Writing swarm runs into ROS 2 bags (`BagRecorder`), from runtime tracers, hosts or replays.

The format is `swarmgen.trace.bag`'s. Recording hooks:

- as a runtime tracer: `Member(..., tracer=recorder)` (asyncio/smach members call
  `recorder.step(member, event)` after every step) or `MemberOptions(tracer=recorder)` on the
  rclpy nodes (they call `recorder(node, event)`, and `recorder.feedback(node, record)` with
  the coalesced feedback of declared actions);
- by hand, from a simulator or any host: `record_event(name, data, sender, stamp_ns)` and
  `record_states(member, states, stamp_ns)`;
- live ROS 2 topics: `write_raw(topic, msgtype, cdr_bytes, stamp_ns)` with the bytes of a raw
  subscription (see `swarmgen.trace.live`);
- a replay trace: `record_replay(path, member, steps, trace)`.
"""

from __future__ import annotations

import json
import shutil
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Protocol

from swarmgen.console import shown
from swarmgen.ros.interfaces import ACTIVE_STATES_MSG, EVENT_MSG
from swarmgen.trace.bag import (
    EVENTS_TOPIC,
    FEEDBACK_MSG,
    FEEDBACK_TYPE,
    PACKAGE,
    STORAGES,
    TraceError,
    feedback_topic,
    states_topic,
)

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag2 import Writer
    from rosbags.typesys.store import Typestore

__all__ = [
    "BURST_NS",
    "STEP_NS",
    "BagRecorder",
    "Traced",
    "TracedEvent",
    "TracedFeedback",
    "VirtualClock",
    "record_replay",
]

# Replay traces: step n is stamped n seconds after the start, the k-th input of a burst k ms later.
STEP_NS = 1_000_000_000
BURST_NS = 1_000_000


class VirtualClock:
    """A clock for deterministic bags: `now` nanoseconds, set or advanced by the caller."""

    def __init__(self, start_ns: int = 0) -> None:
        self.now = start_ns

    def __call__(self) -> int:
        """The clock's stamp in nanoseconds (the recorder's clock interface)."""
        return self.now

    def set(self, stamp_ns: int) -> None:
        """Set the clock to a stamp."""
        self.now = stamp_ns

    def advance(self, delta_ns: int) -> int:
        """Move the clock on; the new stamp."""
        self.now += delta_ns
        return self.now


class _Active(Protocol):
    def active(self) -> list[str]: ...


class Traced(Protocol):
    """What a tracer needs of a member (runtime.member.Member, the rclpy MemberNode)."""

    @property
    def member_id(self) -> str:
        """The member's id, as the trace names it."""

    @property
    def engine(self) -> _Active:
        """The member's engine, read for its active states."""


class TracedEvent(Protocol):
    """The runtime's Event (runtime.engine.Event and the generated packages' vendored copy)."""

    @property
    def name(self) -> str:
        """The event's name."""

    @property
    def data(self) -> Any:
        """The event's fields (None: none)."""

    @property
    def id(self) -> int:
        """The event's unique id (with the sender, what the recorder deduplicates on)."""

    @property
    def timestamp(self) -> float:
        """When the event was made, in seconds (0: not stamped)."""

    @property
    def sender(self) -> str:
        """The id of the member (or station) that sent the event."""


class TracedFeedback(Protocol):
    """A feedback record of the rclpy nodes (`_ros/declared.py`'s `FeedbackRecord`)."""

    @property
    def member(self) -> str:
        """The member's id."""

    @property
    def state(self) -> str:
        """The state running the behaviour."""

    @property
    def behaviour(self) -> str:
        """The behaviour's model name."""

    @property
    def values(self) -> Any:
        """The latest feedback message's fields, plain values."""

    @property
    def count(self) -> int:
        """How many feedback messages the record stands for."""

    @property
    def stamp(self) -> float:
        """Seconds since the epoch (0: use the recorder's clock)."""


def _json(data: Any) -> str:
    return json.dumps(data if data is not None else {}, sort_keys=True, default=str)


@cache
def _typestore(package: str = PACKAGE) -> Typestore:
    """ROS 2 (Kilted) types plus Event and ActiveStates under `package`."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_KILTED)
    types = dict(get_types_from_msg(EVENT_MSG, f"{package}/msg/Event"))
    types.update(get_types_from_msg(ACTIVE_STATES_MSG, f"{package}/msg/ActiveStates"))
    types.update(get_types_from_msg(FEEDBACK_MSG, FEEDBACK_TYPE))
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
        """Close the bag (idempotent)."""
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

    def feedback(self, member: Traced, record: TracedFeedback) -> None:
        """The rclpy nodes' feedback hook (a `MemberOptions.tracer` with this method gets the
        coalesced feedback of declared actions): one record on `/<member>/feedback`."""
        self.record_feedback(
            record.member or member.member_id or "member",
            record.state,
            record.behaviour,
            record.values,
            record.count,
            round(record.stamp * 1e9) if record.stamp > 0 else None,
        )

    def record_feedback(
        self,
        member: str,
        state: str,
        behaviour: str,
        values: Any,
        count: int = 1,
        stamp_ns: int | None = None,
    ) -> None:
        """One feedback record (`swarmgen_msgs/msg/Feedback`) on /<member>/feedback."""
        stamp = self.clock() if stamp_ns is None else stamp_ns
        with self._lock:
            message = self._store.types[FEEDBACK_TYPE](
                stamp=_time(self._store, stamp),
                member=member,
                state=state,
                behaviour=behaviour,
                values=_json(values),
                count=max(0, min(int(count), 2**32 - 1)),
            )
            self._write(feedback_topic(member), FEEDBACK_TYPE, message, stamp)

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
            elif "event" in item:  # a `wait` step is no input
                recorder.record_event(str(item.get("event")), item.get("data"), "station", stamp)
        if number in records:
            recorder.record_states(
                member, records[number].get("active", ()), base + len(items) * BURST_NS
            )
