"""End to end on real ROS 2 (Fast DDS on loopback, no mocks): the generated SAR swarm, 2 UAVs and
2 UGVs with simulated action servers, finds and rescues a target and stops cleanly on
`missionAbort`; and the launch file's executables (one process per member) work.

Every ROS process runs under `timeout -k 5`, with LOCALHOST discovery, a ROS_DOMAIN_ID of this
test run and its logs in the test's tmp directory. The station is a separate process that
talks to the swarm over DDS only: it publishes the station events and records everything on
`/swarm/events` and the members' `active_states`.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
pytest.importorskip("psutil", reason="psutil comes with the `ros` extra: run `make ros`")

import psutil

from swarmgen import pipeline
from swarmgen import ros_harness as harness
from swarmgen.backends.rclpy_backend import interfaces_package, nodes_package
from swarmgen.trace.reader import read_events
from tests import rosproc
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
SCRIPT = ROOT / "tests" / "fixtures" / "ros" / "sar_script.json"
DOMAIN = 101 + os.getpid() % 100  # one domain per test run (test_ros_interfaces uses 1..100)
TIME_SCALE = 0.25  # wall seconds per simulated second

STATION = r'''
"""The ground station: drives the SAR mission and records what it sees (JSON on stdout)."""
import json
import sys
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

interfaces, mode, limit = sys.argv[1], sys.argv[2], float(sys.argv[3])
members, finals = json.loads(sys.argv[4]), json.loads(sys.argv[5])
bag = sys.argv[6] if len(sys.argv) > 6 else ""
msg = __import__(f"{interfaces}.msg", fromlist=["Event", "ActiveStates"])
EVENTS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
STATES = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.TRANSIENT_LOCAL)

rclpy.init()
node = rclpy.create_node("station")
executor = SingleThreadedExecutor()
executor.add_node(node)
events, states, log, history = [], {}, [], []
started = time.monotonic()


def on_event(m):
    events.append({"t": round(time.monotonic() - started, 3), "sender": m.sender, "name": m.name,
                   "data": json.loads(m.data or "{}")})


def on_states(m):
    states[m.member] = list(m.states)
    history.append((round(time.monotonic() - started, 3), m.member, [s for s in m.states if s in
                    ("Idle", "TakeOff", "Loitering", "Land", "Landed")]))


node.create_subscription(msg.Event, "/swarm/events", on_event, EVENTS)
for member in members:
    node.create_subscription(msg.ActiveStates, f"/{member}/active_states", on_states, STATES)
publisher = node.create_publisher(msg.Event, "/swarm/events", EVENTS)
ids = iter(range(1, 1000))
recorder = None
if bag:  # the live recorder of swarmgen.trace: raw subscriptions, bytes into the bag
    from swarmgen.trace.recorder import BagRecorder
    from swarmgen.trace.live import LiveRecorder

    recorder = BagRecorder(bag, package=interfaces)
    live = LiveRecorder(node, recorder, interfaces, members, discover=False)


def publish(name):
    log.append((round(time.monotonic() - started, 3), name))
    publisher.publish(msg.Event(id=next(ids), stamp=node.get_clock().now().to_msg(),
                                sender="station", name=name, data="{}"))


def wait(condition, what):
    deadline = time.monotonic() + limit
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what}: events {[e['name'] for e in events]} states {states}")
        executor.spin_once(timeout_sec=0.05)


def seen(name):
    return any(e["name"] == name for e in events)


def final(member):
    return any(s in finals for s in states.get(member, []))


def left(member, state):  # the member was seen in `state` and has left it since
    entered = False
    for _, who, active in history:
        if who == member:
            if state in active:
                entered = True
            elif entered:
                return True
    return False


result = {"ok": False}
try:
    def listening():  # every member subscribes, and the publisher matched every subscription
        infos = node.get_subscriptions_info_by_topic("/swarm/events")
        spaces = {i.node_namespace for i in infos if i.node_name != "simulated_behaviours"}
        matched = publisher.get_subscription_count() >= len(infos)
        return matched and spaces >= {f"/{m}" for m in members}

    wait(lambda: set(states) >= set(members) and listening(), "members")
    publish("launch")
    if mode == "mission":
        wait(lambda: all("Loitering" in states[m] for m in members if m.startswith("uav")),
             "take-off")
        publish("missionStart")
        wait(lambda: seen("targetRescued"), "rescue")
    else:  # take-off only: uav_1 takes off, uav_2's TakeOff is aborted
        wait(lambda: "Loitering" in states["uav_1"] and left("uav_2", "TakeOff"), "take-off")
    publish("missionAbort")
    wait(lambda: all(final(m) for m in members), "stop")
    result["ok"] = True
except TimeoutError as err:
    result["error"] = str(err)
finally:
    result.update(events=events, states=states, published=log, history=history)
    if recorder is not None:
        executor.spin_once(timeout_sec=0.2)  # the last messages reach the raw subscriptions too
        recorder.close()
    print(json.dumps(result), flush=True)
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
'''


@pytest.fixture(scope="module")
def sar(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    out = tmp_path_factory.mktemp("sar_e2e")
    pipeline.write_tree(result.files, out)
    prefix = harness.build_interfaces(out / "rclpy", model)
    package = nodes_package(model)
    return {
        "prefix": prefix,
        "root": out,
        "package": package,
        "interfaces": interfaces_package(model),
        "path": out / "rclpy" / package,
    }


def _env(sar: dict[str, Any], tmp_path: Path) -> dict[str, str]:
    return harness.ros_env(
        tmp_path / "roslog", domain_id=DOMAIN, python_path=[sar["path"]], prefixes=[sar["prefix"]]
    )


def _leftovers(marker: str) -> list[str]:
    found = []
    for proc in psutil.process_iter(["pid", "cmdline", "environ"]):
        try:
            environ = proc.info["environ"] or {}
            if environ.get("ROS_LOG_DIR", "").startswith(marker):
                found.append(f"{proc.info['pid']}: {' '.join(proc.info['cmdline'] or [])}")
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
    return found


def _subsequence(names: list[str], wanted: list[str]) -> bool:
    position = 0
    for name in names:
        if position < len(wanted) and name == wanted[position]:
            position += 1
    return position == len(wanted)


def test_sar_swarm_rescues_and_stops_on_real_dds(sar: dict[str, Any], tmp_path: Path) -> None:
    env = _env(sar, tmp_path)
    members = ["uav_1", "uav_2", "ugv_1", "ugv_2"]
    station_py = tmp_path / "station.py"
    station_py.write_text(STATION, encoding="utf-8")
    swarm = rosproc.start(
        [
            sys.executable, "-m", f"{sar['package']}.launch_swarm", "--uav", "2", "--ugv", "2",
            "--script", str(SCRIPT), "--time-scale", str(TIME_SCALE),
        ],
        env, tmp_path, 60,
    )  # fmt: skip
    station = rosproc.start(
        [
            sys.executable, str(station_py), sar["interfaces"], "mission", "30",
            json.dumps(members), json.dumps(["Landed", "Stopped"]), str(tmp_path / "bag"),
        ],
        env, tmp_path, 60,
    )  # fmt: skip
    station_code, station_out, station_err = rosproc.finish(station, 70)
    swarm_code, swarm_out, swarm_err = rosproc.finish(swarm, 30)
    assert station_code == 0, station_err[-3000:]
    seen = json.loads(station_out.strip().splitlines()[-1])
    assert seen["ok"], seen.get("error")

    # the swarm process ended by itself: every member reached its final state
    assert swarm_code == 0, swarm_err[-3000:]
    summary = json.loads(swarm_out.strip().splitlines()[-1])
    assert sorted(summary["members"]) == members
    for member, report in summary["members"].items():
        assert report["finished"], (member, report)
        assert report["errors"] == [], (member, report)
        assert report["active"] == (["Landed"] if member.startswith("uav") else ["Stopped"])
    assert _leftovers(str(tmp_path)) == []

    # the story, as seen on /swarm/events by the station
    events = seen["events"]
    names = [e["name"] for e in events]
    assert _subsequence(
        names,
        [
            "launch",
            "missionStart",
            "targetFound",
            "targetAssigned",
            "targetRescued",
            "missionAbort",
        ],
    ), names
    rescued = next(e for e in events if e["name"] == "targetRescued")
    target = rescued["data"]["target_id"]
    found = [e for e in events if e["name"] == "targetFound" and e["data"]["target_id"] == target]
    assigned = [
        e for e in events if e["name"] == "targetAssigned" and e["data"]["target_id"] == target
    ]
    assert found and found[0]["sender"].startswith("uav_")
    assert assigned and {e["sender"] for e in assigned} <= {"uav_1", "uav_2"}
    # the rover that rescued the target is the one the auction selected
    assert rescued["sender"] == f"ugv_{assigned[0]['data']['rover_id']}"
    assert events.index(found[0]) < events.index(assigned[0]) < events.index(rescued)
    assert seen["states"]["uav_1"] == ["Landed"] and seen["states"]["ugv_2"] == ["Stopped"]
    # no wall-clock bound here: a slow or stuck run is `timeout`'s exit 124, not 0 (above)

    # the run's bag, recorded live: read with swarmgen.trace (rosbags)
    (run,) = read_events([tmp_path / "bag"])
    recorded = [e.name for e in run.events]
    story = ["launch", "missionStart", "targetFound", "targetAssigned", "targetRescued"]
    firsts = [recorded.index(name) for name in story]
    assert firsts == sorted(firsts), recorded
    assert {c.member for c in run.states} >= {"uav_1", "ugv_1"}


MEMBER_CHECK_SCRIPT = {
    "behaviours": {
        "TakeOff": {
            "duration": 0.2,
            "outcome": "${'succeeded' if goal.altitude > 5 else 'aborted'}",
        }
    }
}


def test_one_process_per_member_with_parameters(sar: dict[str, Any], tmp_path: Path) -> None:
    """What the launch file starts: a member process and its simulated behaviours, configured
    with ROS parameters. The `data.altitude` parameter reaches the TakeOff goal."""
    env = _env(sar, tmp_path)
    script = tmp_path / "takeoff.json"
    script.write_text(json.dumps(MEMBER_CHECK_SCRIPT), encoding="utf-8")
    package = sar["package"]
    members, servers = [], []
    for member, altitude in (("uav_1", "7.5"), ("uav_2", "1.5")):
        ros = ["--ros-args", "-r", f"__ns:=/{member}"]
        members.append(
            rosproc.start(
                [sys.executable, "-m", f"{package}.uav", *ros, "-p", f"data.altitude:={altitude}"],
                env,
                tmp_path,
                40,
            )
        )
        simulated = (
            f"import sys; from {package}.launch_swarm import simulated; sys.exit(simulated())"
        )
        servers.append(
            rosproc.start(
                [
                    sys.executable, "-c", simulated, *ros, "-p", "member_type:=UAV",
                    "-p", f"script:={script}", "-p", "time_scale:=1.0",
                ],
                env, tmp_path, 40,
            )
        )  # fmt: skip
    station_py = tmp_path / "station.py"
    station_py.write_text(STATION, encoding="utf-8")
    try:
        station = rosproc.start(
            [
                sys.executable, str(station_py), sar["interfaces"], "takeoff", "20",
                json.dumps(["uav_1", "uav_2"]), json.dumps(["Landed"]),
            ],
            env, tmp_path, 40,
        )  # fmt: skip
        code, out, err = rosproc.finish(station, 50)
        assert code == 0, err[-3000:]
        seen = json.loads(out.strip().splitlines()[-1])
        assert seen["ok"], seen.get("error")
        # altitude 7.5 passed the script's check, 1.5 did not: uav_2's TakeOff was aborted
        reached = {(member, state) for _, member, states in seen["history"] for state in states}
        assert ("uav_1", "Loitering") in reached, seen["history"]
        assert ("uav_2", "TakeOff") in reached and ("uav_2", "Loitering") not in reached
        assert seen["states"] == {"uav_1": ["Landed"], "uav_2": ["Landed"]}
    finally:
        # a member process ends by itself in its final state; the servers run until SIGTERM
        # (sent to the python under `timeout`: rclpy shuts down cleanly and exits 0)
        member_results = [rosproc.finish(proc, 15) for proc in members]
        for proc in servers:
            if proc.poll() is None:
                for child in psutil.Process(proc.pid).children():
                    child.terminate()
        server_results = [rosproc.finish(proc, 15) for proc in servers]
    for code, _, err in member_results + server_results:
        assert code == 0, err[-2000:]
    assert _leftovers(str(tmp_path)) == []
