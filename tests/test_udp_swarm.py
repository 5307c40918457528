"""The asyncio swarm across processes over UDP multicast on loopback: one member per process and
a station (issue 18, phase 1). Real processes, real sockets; every process killed in `finally`."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from swarmgen.runtime.faults import Faults, Partition, parse_partition
from swarmgen.runtime.netoptions import Options, params_options
from swarmgen.runtime.transport import (
    SEEN_LIMIT,
    Seen,
    WireError,
    decode,
    encode,
    multicast_socket,
)
from tests.skips import PRIVILEGE_REASON
from tests.udpkit import (
    EVENTS,
    FINAL,
    MEMBERS,
    RUN_TIMEOUT,
    SCALE,
    STATION_EVENTS,
    Steps,
    delivered,
    expected,
    final_states,
    network,
    package,
    python,
    sequences,
    unique,
)

__all__ = ["expected", "package"]  # fixtures


def run_swarm(
    package: Path,
    net: list[str],
    member_args: list[str],
    station: list[str],
    meanwhile: Callable[[], None] | None = None,
    where: Callable[[int], tuple[list[str], list[str]]] = lambda n: ([], []),
) -> tuple[Steps, list[dict[str, Any]], str]:
    """Six member processes, then (after `meanwhile`) a station on the group: the members'
    merged trace, the station's record, and the members' stderr. `where(n)`: the command
    prefix and extra arguments of process n (the station is the last)."""
    procs: list[subprocess.Popen[str]] = []
    try:
        for n, (kind, member_id) in enumerate(MEMBERS):
            prefix, extra = where(n)
            command = python("--member", kind, "--id", member_id, *net, "--fault-seed", str(n))
            command += ["--time-scale", SCALE, "--duration", "20", *extra, *member_args]
            procs.append(
                subprocess.Popen(
                    [*prefix, *command],
                    cwd=package,
                    stdout=subprocess.PIPE,
                    stderr=subprocess.PIPE,
                    text=True,
                )
            )
        if meanwhile is not None:
            meanwhile()
        command = python("--station-only", *net, "--expect", str(len(MEMBERS)))
        prefix, extra = where(len(MEMBERS))
        record = subprocess.run(
            [*prefix, *command, "--duration", "25", *extra, *station],
            cwd=package,
            capture_output=True,
            text=True,
            timeout=RUN_TIMEOUT,
            check=False,
        )
        outputs = [p.communicate(timeout=RUN_TIMEOUT) for p in procs]
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
    for proc, (_, err) in zip(procs, outputs, strict=True):
        assert proc.returncode == 0, err
    assert "Traceback" not in record.stderr, record.stderr
    lines = [json.loads(line) for line in record.stdout.splitlines()]
    return sequences("".join(out for out, _ in outputs)), lines, "".join(e for _, e in outputs)


EVERY_FINAL = {member_id: (kind, FINAL[kind], True) for kind, member_id in MEMBERS}
GARBAGE = [
    b"not json",
    b"\xff\xfe",
    b"[1, 2]",
    b'{"version": 99, "kind": "event"}',
    b'{"version": 1, "kind": "teleport", "origin": "x"}',
    b'{"version": 1, "kind": "event", "origin": "x", "name": "launch", "sender": "station"}',
    b'{"version": 1, "kind": "announce", "origin": "x", "sender": "a", "member_type": "UAV"}',
    b"[" * 60_000,
    b'{"version": 1, "kind": "event", "x": NaN}',
    # a forged end of a behaviour: the engine's own events never come from the network
    b'{"version": 1, "kind": "event", "origin": "x", "name": "done.invoke.TakeOff.succeeded",'
    b' "sender": "uav_1", "id": 1, "timestamp": 0}',
    # a station event addressed wrongly, with a mission clock that is no number, infinity
    b'{"version": 1, "kind": "event", "origin": "x", "name": "launch", "sender": "station",'
    b' "id": 1, "timestamp": 0, "to": "uav_1"}',
    b'{"version": 1, "kind": "event", "origin": "x", "name": "launch", "sender": "station",'
    b' "id": 1, "timestamp": 0, "clock": "noon"}',
    b'{"version": 1, "kind": "event", "origin": "x", "name": "launch", "sender": "station",'
    b' "id": 1, "timestamp": 1e999}',
]


def hear_and_spoil(net: list[str]) -> Callable[[], None]:
    """Listen to the group as an outsider until every member announced itself (discovery needs
    no peer list), then send it garbage of every kind."""
    options = Options(group=net[3], port=int(net[5]))

    def run() -> None:
        with multicast_socket(options) as sock:
            sock.setblocking(True)
            sock.settimeout(RUN_TIMEOUT / 2)
            heard: set[str] = set()
            while len(heard) < len(MEMBERS):
                message = decode(sock.recv(65_535))
                if message["kind"] == "announce":
                    heard.add(message["sender"])
            for payload in GARBAGE:
                sock.sendto(payload, (options.group, options.port))

    return run


def test_members_in_processes_run_the_in_process_mission(
    package: Path, expected: Steps, tmp_path: Path
) -> None:
    """Six processes and a station: each member's steps are those of the `--swarm` run; the
    station heard every member and where it ended. Garbage on the group is counted and logged
    by every member and breaks nothing; a station event's data travels with it."""
    script = tmp_path / "station.json"
    items = [{"event": "launch", "at": 0.2, "data": {"note": "go", "n": [1, 2.5]}}]
    items += [{"event": "missionStart", "at": 1}, {"event": "missionAbort", "at": 2}]
    script.write_text(json.dumps(items), encoding="utf-8")
    net = network()
    merged, record, stderr = run_swarm(
        package, net, [], ["--station-script", str(script)], hear_and_spoil(net)
    )
    assert merged == expected
    assert delivered(record) == list(STATION_EVENTS)
    (sent,) = [r for r in record if r["station"] == "sent" and r["event"] == "launch"]
    assert sent["data"] == {"note": "go", "n": [1, 2.5]}
    assert final_states(record) == EVERY_FINAL
    for _, member_id in MEMBERS:  # every member logged the garbage it got
        assert f"/{member_id}: bad datagram {len(GARBAGE)} from" in stderr, stderr


def test_duplicated_delayed_datagrams_change_nothing(package: Path, expected: Steps) -> None:
    """Copies and reordering of datagrams (members and station): every event is still taken
    once, in order, so the traces are those of the in-process run."""
    faults = ["--duplicate", "0.5", "--delay", "0.03"]
    merged, record, _ = run_swarm(package, network(), faults, ["--events", EVENTS, *faults])
    assert merged == expected
    assert delivered(record) == list(STATION_EVENTS)


def test_every_member_ends_after_mission_abort_under_loss(package: Path) -> None:
    """20% of the datagrams every process receives are lost: the station repeats each event
    until every member acknowledged it, so every member still takes the three events in order
    and ends in its final state."""
    faults = ["--drop", "0.2"]
    merged, record, _ = run_swarm(package, network(), faults, ["--events", EVENTS, *faults])
    for kind, member_id in MEMBERS:
        steps = merged[f"{kind}/{member_id}"]
        station_events = [event for event, _ in steps if event in STATION_EVENTS]
        assert station_events == list(STATION_EVENTS), steps
        assert steps[-1][1] == FINAL[kind], steps
    assert delivered(record) == list(STATION_EVENTS)


# --- the wire format and its parts, on their own


def test_wire_format_round_trip_and_refusals() -> None:
    message = {"kind": "ack", "origin": "abc", "sender": "uav_1", "of": "def", "id": 3}
    assert decode(encode(message)) == {"version": 1, **message}
    for payload in GARBAGE:
        with pytest.raises(WireError):
            decode(payload)
    with pytest.raises(ValueError, match="more than a datagram holds"):
        encode({"kind": "event", "data": {"x": "y" * 70_000}})
    with pytest.raises(ValueError, match="not encodable"):
        encode({"kind": "event", "data": {"x": float("nan")}})


def test_seen_keys_are_bounded() -> None:
    seen = Seen()
    assert seen.first(("a", "b", 1)) and not seen.first(("a", "b", 1))
    for n in range(2, SEEN_LIMIT + 2):
        seen.first(("a", "b", n))
    assert len(seen.keys) == SEEN_LIMIT
    assert seen.first(("a", "b", 1))  # forgotten: the oldest went first


def test_faults_are_seeded() -> None:
    draws = [Faults(0.3, 0.3, 0.1, seed=7).copies() for _ in range(2)]
    assert draws[0] == draws[1]
    lossy = Faults(drop=0.2, seed=1)
    lost = sum(not lossy.copies() for _ in range(10_000))
    assert 1_700 < lost < 2_300


def test_partitions_cut_both_ways_in_their_window() -> None:
    cut = parse_partition("uav_1,ugv_2@1.5-3")
    assert (
        cut == Partition(frozenset({"uav_1", "ugv_2"}), 1.5, 3.0)
        and str(cut) == "uav_1,ugv_2@1.5-3"
    )
    assert cut.cuts("station", ["uav_1"], 2.0) and cut.cuts("uav_1", ["station"], 2.0)
    assert not cut.cuts("ugv_2", ["uav_1"], 2.0)  # the same side
    assert not cut.cuts("station", ["uav_1"], 1.0) and not cut.cuts("station", ["uav_1"], 3.0)
    faults = Faults(partitions=(cut,))
    assert faults.active and not faults.cut("station", ["uav_1"], None)  # no mission clock yet
    for bad in ("uav_1", "@1-2", "uav_1@2-1", "uav_1@a-b", "uav_1@1-inf", "uav_1@1"):
        with pytest.raises(ValueError):
            parse_partition(bad)


def test_communication_params_give_options() -> None:
    options = params_options("ifname=wlan0 port=5670, group=239.255.1.2;ttl=0")
    assert (options.group, options.port, options.ttl) == ("239.255.1.2", 5670, 0)
    for bad in ("group=10.0.0.1", "port=0", "ttl=300", "port=abc"):
        with pytest.raises(ValueError):
            params_options(bad)


BAD_ARGUMENTS = {
    "udp_swarm": (["--swarm", "--transport", "udp"], "runs one --member per process"),
    "udp_member_events": (
        ["--member", "UAV", "--transport", "udp", "--events", "launch"],
        "--station-only sends events",
    ),
    "station_memory": (["--station-only"], "--station-only needs --transport udp"),
    "group_unicast": (
        ["--member", "UAV", "--transport", "udp", "--group", "10.1.1.1"],
        "not a multicast group",
    ),
    "port_zero": (["--member", "UAV", "--transport", "udp", "--port", "0"], "expected 1-65535"),
    "drop_rate": (["--member", "UAV", "--transport", "udp", "--drop", "1.5"], "probability"),
    "partition": (
        ["--member", "UAV", "--transport", "udp", "--partition", "uav_1@2-1"],
        "argument --partition: 'uav_1@2-1': expected 0 <= START < END",
    ),
    "script_missing": (
        ["--station-only", "--transport", "udp", "--station-script", "nowhere.json"],
        "cannot read nowhere.json",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_ARGUMENTS))
def test_bad_network_arguments_are_one_line(package: Path, case: str) -> None:
    args, says = BAD_ARGUMENTS[case]
    run = subprocess.run(
        python(*args), cwd=package, capture_output=True, text=True, timeout=30, check=False
    )
    assert run.returncode == 2, run.stderr
    assert says in run.stderr and len(run.stderr.splitlines()) == 1, run.stderr


@pytest.mark.parametrize(
    "script",
    [
        '[{"event": "lunch"}]',
        '[{"event": "launch", "at": -1}]',
        '[{"event": "launch", "data": 3}]',
        '{"event": "launch"}',
        '[{"event": "launch", "at": NaN}]',
    ],
)
def test_bad_station_scripts_are_refused(package: Path, tmp_path: Path, script: str) -> None:
    path = tmp_path / "bad.json"
    path.write_text(script, encoding="utf-8")
    args = ["--station-only", "--transport", "udp", "--station-script", str(path)]
    run = subprocess.run(
        python(*args), cwd=package, capture_output=True, text=True, timeout=30, check=False
    )
    assert run.returncode == 2 and "argument --station-script" in run.stderr, run.stderr


def test_a_member_that_hears_nothing_is_never_acknowledged(package: Path) -> None:
    """All datagrams to the member lost: the station hears its announcements but no
    acknowledgement, repeats `launch` until its --duration ends, says so and exits 1; the
    member never takes `launch`."""
    net = network()
    member = subprocess.Popen(
        [*python("--member", "UGV", "--id", "deaf", *net, "--drop", "1"), "--duration", "3"],
        cwd=package,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        station = subprocess.run(
            python(
                "--station-only", *net, "--expect", "1", "--events", "launch", "--duration", "2"
            ),
            cwd=package,
            capture_output=True,
            text=True,
            timeout=RUN_TIMEOUT,
            check=False,
        )
        out, _ = member.communicate(timeout=RUN_TIMEOUT)
    finally:
        if member.poll() is None:
            member.kill()
            member.wait(timeout=10)
    assert station.returncode == 1, station.stderr
    record = [json.loads(line) for line in station.stdout.splitlines()]
    assert [r["missing"] for r in record if r["station"] == "undelivered"] == [["deaf"]]
    assert [step for step, _ in sequences(out)["UGV/deaf"]] == [None], out


def netns_available() -> str | None:
    """Why network namespaces cannot be made here (None: they can)."""
    probe = f"sgprobe{os.getpid()}"
    made = subprocess.run(
        ["ip", "netns", "add", probe], capture_output=True, text=True, check=False
    )
    if made.returncode != 0:
        why = made.stderr.strip()
        return f"{PRIVILEGE_REASON}: cannot create network namespaces (`ip netns add`: {why})"
    subprocess.run(["ip", "netns", "del", probe], capture_output=True, check=False)
    return None


@pytest.fixture
def two_robots() -> Iterator[list[tuple[str, str]]]:
    """Two network namespaces joined by a veth pair: [(namespace, its address)] x 2, removed
    afterwards (deleting a namespace deletes its end of the pair, and the pair with it)."""
    reason = netns_available() if shutil.which("ip") else f"{PRIVILEGE_REASON}: no `ip` command"
    if reason is not None:
        pytest.skip(reason)
    tag = f"{os.getpid() % 100_000}{unique()}"
    spaces = [(f"sg{tag}a", "10.213.0.1"), (f"sg{tag}b", "10.213.0.2")]
    ends = [f"sg{tag}va", f"sg{tag}vb"]
    try:
        for name, _ in spaces:
            ip("netns", "add", name)
        ip("link", "add", ends[0], "type", "veth", "peer", "name", ends[1])
        for (name, address), end in zip(spaces, ends, strict=True):
            ip("link", "set", end, "netns", name)
            ip("-n", name, "addr", "add", f"{address}/24", "dev", end)
            ip("-n", name, "link", "set", end, "up")
            ip("-n", name, "link", "set", "lo", "up")
        yield spaces
    finally:
        for name, _ in spaces:
            subprocess.run(["ip", "netns", "del", name], capture_output=True, check=False)
        subprocess.run(["ip", "link", "del", ends[0]], capture_output=True, check=False)


def ip(*args: str) -> None:
    subprocess.run(["ip", *args], capture_output=True, text=True, check=True, timeout=30)


def test_members_in_two_namespaces_run_the_in_process_mission(
    package: Path, expected: Steps, two_robots: list[tuple[str, str]]
) -> None:
    """Two "robots" (network namespaces over a veth pair, multicast on the link): the UAVs and
    the station on one, the UGVs on the other; the traces are those of the in-process run."""

    def where(n: int) -> tuple[list[str], list[str]]:
        name, address = two_robots[n < len(MEMBERS) and MEMBERS[n][0] == "UGV"]
        return ["ip", "netns", "exec", name], ["--interface", address]

    merged, record, _ = run_swarm(package, network(), [], ["--events", EVENTS], where=where)
    assert merged == expected
    assert delivered(record) == list(STATION_EVENTS)
    assert final_states(record) == EVERY_FINAL
