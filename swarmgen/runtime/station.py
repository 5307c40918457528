"""The ground station of a swarm on UDP multicast (standard library only).

    python -m <package> --station-only --events launch@0.1,missionStart@1 --expect 6 --record run.jsonl

The station waits until it has heard `--expect` members (their announcements), then starts its
clock, the mission clock. Each event of its script is released at its time into the station's
log, numbered from 1. Every member incarnation the station hears (a process of a member: a
restarted member is a new one) is brought through the log in order, each event repeated every
`--repeat` seconds until that incarnation acknowledged it, and the next one sent not before its
time nor sooner after the previous one's acknowledgement than the script spaces them: a member
heard late (started late, restarted, back from a partition) gets the events it lacks with the
mission's spacing. A member is live while its announcements keep coming (`--peer-timeout`) and
it has not announced that it finished; only live members are sent to. The station lists the
members it hears with their active states, and records the run as JSON lines (docs/network.md).
"""

from __future__ import annotations

import asyncio
import json
import math
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TextIO

from swarmgen.runtime.faults import Faults
from swarmgen.runtime.netoptions import PEER_TIMEOUT, REPEAT_EVERY, Options
from swarmgen.runtime.transport import Endpoint, Peer

# member ids in one copy's `to`: 16 of the longest ids (200 characters, JSON-escaped) fit a
# datagram with room to spare
TO_PER_COPY = 16


@dataclass(slots=True)
class Logged:
    """A station event released into the log: who acknowledged it, and its copies."""

    name: str
    data: Mapping[str, Any] | None
    id: int  # its place in the log, from 1
    at: float  # its time on the mission clock
    acked: list[str] = field(default_factory=list)  # member ids, in acknowledgement order
    addressed: set[str] = field(default_factory=set)  # the incarnations it was sent to
    last_copy: float = -math.inf  # mission time of the last copy
    last_to: frozenset[str] = frozenset()
    delivered: bool = False  # the record's `delivered` line is written


@dataclass(slots=True)
class Follower:
    """A member incarnation and how far it went through the log."""

    member_id: str
    origin: str
    taken: int = 0  # the events it acknowledged (all of the log's first `taken`)
    sent_at: float | None = None  # mission time the next event was first sent to it
    last_sent_at: float = 0.0  # mission time the last event it took was first sent to it


class Station(Endpoint):
    """Brings every live member incarnation through the log of station events, and records
    what it sends and hears."""

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
        self.started: float | None = None  # time.monotonic() the mission clock started
        self.log: list[Logged] = []
        self.followers: dict[str, Follower] = {}
        self.changed = asyncio.Event()  # an ack or an announcement arrived
        # what the record last said of each member: active states, finished
        self.heard: dict[str, tuple[tuple[str, ...], bool]] = {}
        self.on_peer = self._peer

    def receivers(self) -> Collection[str]:
        """The station is one side of a partition under the name `station`."""
        return ("station",)

    def write(self, what: str, **fields: Any) -> None:
        """One line of the record."""
        line = {"t": round(time.monotonic() - self.start, 4), "station": what, **fields}
        print(json.dumps(line), file=self.out, flush=True)

    def now(self) -> float:
        """Seconds on the mission clock (0 before it starts)."""
        return 0.0 if self.started is None else time.monotonic() - self.started

    def start_clock(self) -> None:
        """Start the mission clock; every event sent from now on carries its start."""
        self.started, self.clock = time.monotonic(), time.time()
        self.write("clock", members=sorted(self.peers), at=self.clock)

    def _peer(self, peer: Peer) -> None:
        known = self.heard.get(peer.member_id)
        if known is None or known != (peer.active, peer.finished):
            member = f"{peer.member_type}/{peer.member_id}"
            self.write("heard", member=member, active=list(peer.active), finished=peer.finished)
        self.heard[peer.member_id] = (peer.active, peer.finished)
        follower = self.followers.get(peer.member_id)
        if follower is None or follower.origin != peer.origin:
            if follower is not None:  # a restarted member: it starts the log again
                self.write("rejoined", member=f"{peer.member_type}/{peer.member_id}")
            self.followers[peer.member_id] = Follower(peer.member_id, peer.origin)
        self.changed.set()

    def handle(self, message: dict[str, Any]) -> None:
        """Count an acknowledgement: of this station, by the member's current incarnation,
        of the next event it lacked."""
        if message["kind"] != "ack" or message["of"] != self.origin:
            return
        follower = self.followers.get(message["sender"])
        if follower is None or follower.origin != message["origin"]:
            return  # an incarnation not heard yet, or a stopped one
        if message["id"] == follower.taken + 1 and follower.taken < len(self.log):
            entry = self.log[follower.taken]
            follower.taken += 1
            follower.last_sent_at = self.now() if follower.sent_at is None else follower.sent_at
            follower.sent_at = None
            entry.acked.append(follower.member_id)
            self.write("acked", event=entry.name, id=entry.id, by=follower.member_id)
            self.changed.set()

    def live(self) -> set[str]:
        """The members heard within the peer timeout that have not finished."""
        now = time.monotonic()
        return {
            p.member_id
            for p in self.peers.values()
            if not p.finished and now - p.seen <= self.peer_timeout
        }

    def release(self, name: str, data: Mapping[str, Any] | None, at: float) -> None:
        """Put the next event of the script into the log (at its time)."""
        entry = Logged(name, data, len(self.log) + 1, at)
        self.log.append(entry)
        self.write("sent", event=name, id=entry.id, data=data, to=sorted(self.live()))

    def due_at(self, follower: Follower) -> float:
        """When the next event `follower` lacks may go to it: its time, and not sooner after
        the one before was first sent to it than the script spaces the two (a member heard
        late gets the mission's events with the mission's spacing)."""
        entry = self.log[follower.taken]
        if follower.taken == 0:
            return entry.at
        before = self.log[follower.taken - 1]
        return max(entry.at, follower.last_sent_at + entry.at - before.at)

    def pump(self) -> float:
        """Send what is due (a copy per event, addressed to the members due for it; again
        after `repeat` seconds), write the `delivered` lines; the mission time to look again."""
        now, live = self.now(), self.live()
        wake = now + self.repeat
        due: dict[int, set[str]] = {}
        waiting: dict[int, set[str]] = {}  # live members whose next event it is, due or not
        for follower in self.followers.values():
            if follower.member_id not in live or follower.taken >= len(self.log):
                continue
            waiting.setdefault(follower.taken, set()).add(follower.member_id)
            at = self.due_at(follower)
            if at <= now:
                due.setdefault(follower.taken, set()).add(follower.member_id)
            else:
                wake = min(wake, at)
        for index, members in sorted(due.items()):
            # addressed only when some member whose next event it is must wait (its spacing)
            everyone = members == waiting[index]
            self._copy(self.log[index], frozenset(members), now, everyone)
        for entry in self.log:
            lacking = {f.member_id for f in self.followers.values() if f.taken < entry.id}
            if not entry.delivered and not lacking & live:
                entry.delivered = True
                self.write("delivered", event=entry.name, id=entry.id, members=entry.acked)
        return wake

    def _copy(self, entry: Logged, to: frozenset[str], now: float, everyone: bool) -> None:
        if not to - entry.last_to and now - entry.last_copy < self.repeat:
            return  # those members have a copy on its way
        for member_id in to:
            follower = self.followers[member_id]
            if follower.sent_at is None:
                follower.sent_at = now
        origins = {self.followers[m].origin: m for m in to}
        new = sorted(m for o, m in origins.items() if o not in entry.addressed)
        if new and entry.addressed:  # incarnations not there when it was first sent
            self.write("resent", event=entry.name, id=entry.id, to=new)
        entry.addressed |= origins.keys()
        entry.last_copy, entry.last_to = now, to
        message = {"kind": "event", "id": entry.id, "name": entry.name, "sender": "station",
                   "timestamp": time.time(), "data": dict(entry.data) if entry.data else None,
                   "clock": self.clock}  # fmt: skip
        if everyone:
            self.send(message)
            return
        ids = sorted(to)
        for start in range(0, len(ids), TO_PER_COPY):  # a datagram holds so many ids
            self.send({**message, "to": ids[start : start + TO_PER_COPY]})

    async def wait(self, until: float) -> bool:
        """Wait for an ack or an announcement, until the monotonic time `until` (False: none
        came)."""
        self.changed.clear()
        try:
            await asyncio.wait_for(self.changed.wait(), max(0.0, until - time.monotonic()))
        except TimeoutError:
            return False
        return True

    def settled(self) -> bool:
        """Every member heard has finished or gone silent."""
        return not self.live()

    def undelivered(self, unreleased: Sequence[tuple[float, str, Any]]) -> bool:
        """Write an `undelivered` line per event some live member lacks (True: none)."""
        live, ok = self.live(), True
        for entry in self.log:
            missing = sorted(m for m in live if self.followers[m].taken < entry.id)
            if missing:
                self.write("undelivered", event=entry.name, id=entry.id, missing=missing)
                ok = False
        for _, name, _ in unreleased:
            self.write("undelivered", event=name, id=None, missing=sorted(live))
            ok = False
        return ok

    def summary(self) -> dict[str, Any]:
        """The members heard, their last active states, and the datagram counts."""
        members = {
            p.member_id: {"type": p.member_type, "active": list(p.active), "finished": p.finished}
            for p in sorted(self.peers.values(), key=lambda p: p.member_id)
        }
        return {"members": members, "bad": self.bad, "unsent": self.unsent, "cut": self.cut}


async def run_station(
    events: Sequence[tuple[float, str, Mapping[str, Any] | None]],
    options: Options,
    args: Any,
    out: TextIO,
) -> int:
    """Run the station for `--duration` seconds at most: 0 when every event reached every live
    member and every member heard finished, 1 otherwise."""
    faults = Faults(args.drop, args.duplicate, args.delay, args.fault_seed, tuple(args.partition))
    station = Station(options, out, faults, args.repeat, args.peer_timeout)
    deadline = time.monotonic() + args.duration
    await station.open()
    schedule = list(events)
    try:
        ok = await _wait_for(station, args.expect, deadline)
        if not ok:
            station.write("missing", expected=args.expect, heard=sorted(station.peers))
        else:
            station.start_clock()
            await _mission(station, schedule, deadline)
        ok = station.undelivered(schedule) and ok
    finally:
        station.write("summary", **station.summary())
        station.close()
    return 0 if ok and _all_finished(station) else 1


async def _wait_for(station: Station, count: int, until: float) -> bool:
    """Wait until `count` members were heard (False: not before `until`)."""
    while len(station.peers) < count:
        if not await station.wait(until):
            return False
    return True


async def _mission(
    station: Station, schedule: list[tuple[float, str, Any]], deadline: float
) -> None:
    """Release the script's events at their times and bring every member through them, until
    the script is done and every member heard finished or went silent (or the deadline)."""
    while time.monotonic() < deadline:
        while schedule and schedule[0][0] <= station.now():
            at, name, data = schedule.pop(0)
            station.release(name, data, at)
        wake = station.pump()
        if not schedule and station.settled():
            return
        if schedule:
            wake = min(wake, schedule[0][0])
        # the members' announcements (their last ones say where they ended) and acks wake it
        await station.wait(min(deadline, time.monotonic() + max(0.0, wake - station.now())))


def _all_finished(station: Station) -> bool:
    return bool(station.peers) and all(p.finished for p in station.peers.values())
