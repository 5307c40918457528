"""The swarm on UDP multicast through a partition, a member killed and restarted, and the station
killed and restarted (issue 18, faults; docs/network.md "Guarantees"). Real processes, real
sockets on loopback, a group and port per test; every process killed at the end."""

from __future__ import annotations

import asyncio
import io
import signal
import socket
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from swarmgen.runtime.netoptions import Options
from swarmgen.runtime.station import Station
from swarmgen.runtime.transport import decode, encode, multicast_socket
from tests.udpkit import (
    SCALE,
    Procs,
    Steps,
    delivered,
    expected,
    final_states,
    lines,
    network,
    package,
    record_of,
    sequences,
)

__all__ = ["expected", "package"]  # fixtures

THREE = [("UAV", "uav_1"), ("UAV", "uav_2"), ("UGV", "ugv_1")]
EVERY_FINAL = {
    "uav_1": ("UAV", ["Landed"], True),
    "uav_2": ("UAV", ["Landed"], True),
    "ugv_1": ("UGV", ["Stopped"], True),
}


def member(procs: Procs, net: list[str], kind: str, member_id: str, *extra: str) -> Any:
    """One member process on the group."""
    return procs.start(
        "--member", kind, "--id", member_id, *net, "--time-scale", SCALE, "--duration", "20",
        *extra,
    )  # fmt: skip


def station_step(proc: Any, event: str) -> dict[str, Any]:
    """The mission-time of a member's step on `event` (its first)."""
    return next(step for step in lines(proc) if step.get("event") == event)


def test_a_partitioned_member_misses_the_station_and_catches_up(
    package: Path, expected: Steps
) -> None:
    """uav_1 is cut off from the others from 0.7 to 2.0 s of mission time (every process
    applies the same partition): it misses `missionStart` (sent at 1.2) while cut off; the
    others take it at once and the station delivers it without uav_1. After the heal the
    station sends it what it lacks, in order and with the script's spacing, so its trace is
    still the mission's, every step later; every member ends."""
    net = network()
    cut = ["--partition", "uav_1@0.7-2.0"]
    with Procs(package) as procs:
        members = {m: member(procs, net, k, m, *cut) for k, m in THREE}
        station = procs.start(
            "--station-only", *net, *cut, "--expect", "3", "--peer-timeout", "0.5",
            "--events", "launch@0.2,missionStart@1.2,missionAbort@2.4", "--duration", "15",
        )  # fmt: skip
        assert station.finish() == 0, station.text()
        for proc in members.values():
            assert proc.finish() == 0, proc.text()
    for kind, member_id in THREE:
        steps = sequences("".join(members[member_id].out))
        assert steps[f"{kind}/{member_id}"] == expected[f"{kind}/{member_id}"]
    isolated = members["uav_1"]
    # nothing of the station reached it while it was cut off, what it missed came after
    assert station_step(isolated, "missionStart")["mission_t"] >= 2.0
    for other in ("uav_2", "ugv_1"):
        assert station_step(members[other], "missionStart")["mission_t"] < 2.0
    assert "uav_1: partition: cut off from" in "".join(isolated.err), isolated.text()
    record = record_of(station)
    (start,) = [r for r in record if r["station"] == "delivered" and r["event"] == "missionStart"]
    assert start["members"] == ["ugv_1", "uav_2"] or start["members"] == ["uav_2", "ugv_1"]
    late = [r for r in record if r["station"] == "acked" and r["by"] == "uav_1"]
    assert [r["event"] for r in late] == ["launch", "missionStart", "missionAbort"]
    assert late[1]["t"] > start["t"]
    assert final_states(record) == EVERY_FINAL


def test_a_member_killed_and_restarted_rejoins_and_the_mission_completes(
    package: Path, expected: Steps
) -> None:
    """uav_2 is killed (SIGKILL) once it took `missionStart`, and started again with its id: a
    new incarnation, in its initial state. The station hears it rejoin and sends it the mission
    from its first event with the script's spacing, so the new incarnation runs the whole
    mission; the others are not disturbed; every member ends."""
    net = network()
    with Procs(package) as procs:
        members = {m: member(procs, net, k, m) for k, m in THREE}
        station = procs.start(
            "--station-only", *net, "--expect", "3", "--duration", "15",
            "--events", "launch@0.2,missionStart@1,missionAbort@3",
        )  # fmt: skip
        killed = members["uav_2"]
        killed.wait_for(lambda step: step.get("event") == "missionStart")
        killed.popen.send_signal(signal.SIGKILL)
        killed.finish()
        restarted = member(procs, net, "UAV", "uav_2")
        assert station.finish() == 0, station.text()
        for proc in (members["uav_1"], members["ugv_1"], restarted):
            assert proc.finish() == 0, proc.text()
    mission = expected["UAV/uav_2"]
    before = sequences("".join(killed.out))["UAV/uav_2"]
    assert before == mission[: len(before)] and before[-1][0] == "missionStart"
    assert sequences("".join(restarted.out))["UAV/uav_2"] == mission
    for kind, member_id in (("UAV", "uav_1"), ("UGV", "ugv_1")):
        steps = sequences("".join(members[member_id].out))
        assert steps[f"{kind}/{member_id}"] == expected[f"{kind}/{member_id}"]
    record = record_of(station)
    assert [r["member"] for r in record if r["station"] == "rejoined"] == ["UAV/uav_2"]
    resent = [r["event"] for r in record if r["station"] == "resent"]
    assert resent[:2] == ["launch", "missionStart"], record
    assert delivered(record) == ["launch", "missionStart", "missionAbort"]
    assert final_states(record) == EVERY_FINAL


def test_a_restarted_station_finds_the_members_and_aborts_the_mission(
    package: Path, expected: Steps
) -> None:
    """The station is killed (SIGKILL) after `missionStart`; the members keep working. A new
    station, with no memory of the first, discovers them and their states from their
    announcements and sends `missionAbort`, which every member takes and acknowledges."""
    net = network()
    pair = [("UAV", "uav_1"), ("UGV", "ugv_1")]
    with Procs(package) as procs:
        members = {m: member(procs, net, k, m) for k, m in pair}
        first = procs.start(
            "--station-only", *net, "--expect", "2", "--duration", "15",
            "--events", "launch@0.2,missionStart@1,missionAbort@30",
        )  # fmt: skip
        first.wait_for(lambda r: r["station"] == "delivered" and r["event"] == "missionStart")
        first.popen.send_signal(signal.SIGKILL)
        first.finish()
        second = procs.start(
            "--station-only", *net, "--expect", "2", "--duration", "15",
            "--events", "missionAbort@0.3",
        )  # fmt: skip
        assert second.finish() == 0, second.text()
        for proc in members.values():
            assert proc.finish() == 0, proc.text()
    for kind, member_id in pair:
        steps = sequences("".join(members[member_id].out))
        assert steps[f"{kind}/{member_id}"] == expected[f"{kind}/{member_id}"]
    record = record_of(second)
    clock = next(n for n, r in enumerate(record) if r["station"] == "clock")
    heard = {r["member"]: r["active"] for r in record[:clock] if r["station"] == "heard"}
    assert "Coverage" in heard["UAV/uav_1"] and "Ready" in heard["UGV/ugv_1"], heard
    (abort,) = [r for r in record if r["station"] == "delivered"]
    assert abort["event"] == "missionAbort" and sorted(abort["members"]) == ["uav_1", "ugv_1"]
    assert final_states(record) == {m: EVERY_FINAL[m] for _, m in pair}


GAP = 0.3  # seconds between the two events of the script below


async def _next_event(sock: socket.socket, station: Station) -> dict[str, Any]:
    """The next station event on the group (the test's own messages skipped), the station
    pumped meanwhile as its mission loop does; bounded: 5 s."""
    loop = asyncio.get_running_loop()
    receiving = asyncio.ensure_future(loop.sock_recv(sock, 65_535))
    for _ in range(500):
        station.pump()
        done, _ = await asyncio.wait({receiving}, timeout=0.01)
        if done:
            message = decode(receiving.result())
            if message["kind"] == "event":
                return message
            receiving = asyncio.ensure_future(loop.sock_recv(sock, 65_535))
    receiving.cancel()
    raise AssertionError("no station event in 5 s")


async def _spacing(options: Options) -> tuple[list[dict[str, Any]], Station]:
    """A station and two members played by a socket on the group: `a` from the start, `c`
    heard after `launch` went out; the station's copies of `launch` and `missionStart`."""
    station = Station(options, io.StringIO(), repeat=5.0, peer_timeout=5.0)
    await station.open()
    sock = multicast_socket(options)

    def say(kind: str, sender: str, origin: str, **fields: Any) -> None:
        message = {"kind": kind, "sender": sender, "origin": origin, **fields}
        sock.sendto(encode(message), (options.group, options.port))

    def member(sender: str) -> None:
        say("announce", sender, sender, member_type="UAV", active=["Idle"], finished=False)

    async def until(done: Callable[[], bool]) -> None:
        for _ in range(500):  # bounded: 5 s
            if done():
                return
            station.pump()
            await station.wait(time.monotonic() + 0.01)
        raise AssertionError("the station did not get there in 5 s")

    try:
        member("a")
        await until(lambda: "a" in station.peers)
        station.start_clock()
        station.release("launch", None, 0.0)
        copies = [await _next_event(sock, station)]
        say("ack", "a", "a", of=station.origin, id=1)
        await until(lambda: station.followers["a"].taken == 1)
        await asyncio.sleep(GAP / 2)
        member("c")  # heard late: launch is sent to it now
        copies.append(await _next_event(sock, station))
        say("ack", "c", "c", of=station.origin, id=1)
        await until(lambda: station.followers["c"].taken == 1)
        station.release("missionStart", None, GAP)  # due at GAP for a, later for c
        copies.append(await _next_event(sock, station))
        say("ack", "a", "a", of=station.origin, id=2)
        await until(lambda: station.followers["a"].taken == 2)
        copies.append(await _next_event(sock, station))
        return copies, station
    finally:
        sock.close()
        station.close()


def test_the_station_spaces_a_late_member_and_addresses_only_then() -> None:
    """In one process with real sockets on this test's group: a copy due for every member
    whose next event it is goes without `to`; when a member heard late must wait to keep the
    script's spacing, the copy for the others names them, and the late member's copy comes no
    sooner after its previous one than the script spaces the two."""
    net = network()
    copies, station = asyncio.run(_spacing(Options(group=net[3], port=int(net[5]))))
    assert [(c["name"], c["id"]) for c in copies] == [
        ("launch", 1), ("launch", 1), ("missionStart", 2), ("missionStart", 2),
    ]  # fmt: skip
    assert [c.get("to") for c in copies] == [None, None, ["a"], None]
    assert {c["origin"] for c in copies} == {station.origin}
    assert {c["clock"] for c in copies} == {station.clock}
    late = station.followers["c"]
    assert late.sent_at is not None and late.sent_at - late.last_sent_at >= GAP - 0.001
