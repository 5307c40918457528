"""The generated swarm on simulated time (real rclpy, Fast DDS on loopback): launched with the
standard `--ros-args -p use_sim_time:=true`, the station program, the scripted behaviours and
the summary follow `/clock`, which a separate process publishes (as the detailed level's world
node does), not the wall clock.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")

from swarmgen import pipeline
from swarmgen import ros_harness as harness
from swarmgen.backends.rclpy_backend import interfaces_package, nodes_package
from tests import rosproc
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
DOMAIN = 201 + os.getpid() % 30  # one per test run (the other ROS tests of 201..230 run apart)
STEP_S, END_S = 0.05, 8.0  # the clock's simulated step and end

CLOCK = r'''
"""Publishes /clock from 0 in steps once the member is up (its first active_states), one step
per 2 ms of wall time: simulated time runs about 25 times faster than the wall."""
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

interfaces, step, end = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
msg = __import__(f"{interfaces}.msg", fromlist=["ActiveStates"])
rclpy.init()
node = rclpy.create_node("test_clock")
clock = node.create_publisher(Clock, "/clock", 10)
up = []
states = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.TRANSIENT_LOCAL)
node.create_subscription(msg.ActiveStates, "/uav_1/active_states", up.append, states)
deadline = time.monotonic() + 60
while not up and time.monotonic() < deadline:
    clock.publish(Clock())  # time 0 until the swarm runs
    rclpy.spin_once(node, timeout_sec=0.01)
k = 0
while k * step <= end + 1e-9 and time.monotonic() < deadline:
    message = Clock()
    nanoseconds = round(k * step * 1e9)
    message.clock.sec, message.clock.nanosec = divmod(nanoseconds, 1_000_000_000)
    clock.publish(message)
    rclpy.spin_once(node, timeout_sec=0.002)
    k += 1
print(k, flush=True)
'''


@pytest.fixture(scope="module")
def sar(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    out = tmp_path_factory.mktemp("sar_sim_time")
    pipeline.write_tree(result.files, out)
    prefix = harness.build_interfaces(out / "rclpy", model)
    package = nodes_package(model)
    return {"prefix": prefix, "package": package, "interfaces": interfaces_package(model),
            "path": out / "rclpy" / package}  # fmt: skip


def test_station_and_behaviours_follow_the_simulated_clock(
    sar: dict[str, Any], tmp_path: Path
) -> None:
    env = harness.ros_env(
        tmp_path / "roslog", domain_id=DOMAIN, python_path=[sar["path"]], prefixes=[sar["prefix"]]
    )
    (tmp_path / "clock.py").write_text(CLOCK, encoding="utf-8")
    swarm = rosproc.start(
        [
            sys.executable, "-m", f"{sar['package']}.launch_swarm", "--uav", "1", "--ugv", "0",
            "--station", "launch@1,missionStart@3", "--duration", "6", "--events",
            "--ros-args", "-p", "use_sim_time:=true",
        ],
        env, tmp_path, 60,
    )  # fmt: skip
    clock = rosproc.start(
        [sys.executable, str(tmp_path / "clock.py"), sar["interfaces"], str(STEP_S), str(END_S)],
        env, tmp_path, 60,
    )  # fmt: skip
    code, out, err = rosproc.finish(swarm, 70)
    rosproc.finish(clock, 20)
    assert code == 0, (out, err)
    lines = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    summary = lines[-1]
    events = {line["name"]: line["t"] for line in lines[:-1] if "name" in line}
    # station events at their simulated times (to the clock's step), TakeOff's scripted 1 s too
    assert abs(events["launch"] - 1.0) <= STEP_S + 1e-6, events
    assert abs(events["missionStart"] - 3.0) <= STEP_S + 1e-6, events
    assert abs(summary["simulated_s"] - 6.0) <= STEP_S + 1e-6, summary
    assert summary["wall_s"] < 6.0 / 3, summary  # far faster than the wall: it is /clock's time
    # launch -> TakeOff, its end (1 simulated s later) -> Loitering, missionStart -> Coverage
    uav = summary["members"]["uav_1"]
    assert "Coverage" in uav["active"] and uav["errors"] == [], summary
