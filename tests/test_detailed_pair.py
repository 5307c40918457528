"""The world node and the behaviour servers together on real rclpy, no generated nodes yet: the
world node (`swarmgen_library.world_node`), one servers process (`swarmgen_library.servers`)
and a test node acting as the members (`tests/servers_driver.py member`): TakeOff then Coverage
goals to uav_1, on `targetFound` a MoveTo to ugv_1, then a Rescue. In a 10 m x 10 m world with
one UAV, one UGV and one target, coverage finds the target, ugv_1 rescues it, and the world stops
on `all_rescued` with a complete result, at the steps the geometry gives; two runs give the same
result file except its `wall` block.

The SAR interface packages are built as tests/test_detailed_servers.py builds them. Every ROS
process runs under `timeout -k 5`, with LOCALHOST discovery, its logs in the test's tmp
directory and the ROS_DOMAIN_ID of this test run, 1 + (pid + 25) % 100 (apart from
test_ros_interfaces' 1 + pid % 100 and test_detailed_world's 1 + (pid + 50) % 100 in the same
run), and every process is ended at the end of its run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
pytest.importorskip("psutil", reason="psutil comes with the `ros` extra: run `make ros`")

from swarmgen import pipeline
from swarmgen import ros_harness as harness
from swarmgen.ros.domains import hold
from tests import rosproc
from tests.conftest import ROOT
from tests.test_detailed_servers import UAV, UGV

# lockstep runs whose step counts must agree: `make test` runs them with nothing beside them
pytestmark = pytest.mark.alone

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
LIBRARY = ROOT / "swarmgen" / "ros" / "library"
DOMAIN = hold(1, 139, start=1 + (os.getpid() + 25) % 100)  # leased: see swarmgen/ros/domains.py
DT = 0.125  # binary-exact steps: 1 m/s is 0.125 m per step
SUCCEEDED = 4  # action_msgs/GoalStatus
Run = tuple[int, str, dict[str, Any], dict[str, Any]]


@pytest.fixture(scope="module")
def prefix(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """SAR compiled as it is, its interface packages (the swarm's and the user's) built."""
    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    out = tmp_path_factory.mktemp("sar_pair")
    pipeline.write_tree(result.files, out)
    return harness.build_interfaces(out / "rclpy", model)


def files(tmp: Path) -> tuple[Path, Path, Path]:
    """The world, servers and member files of the small world: uav_1 on the ground at (2, 1),
    ugv_1 at (8, 1), target 5 at (2, 6), on uav_1's first (northward) coverage leg."""
    area = {"width": 10.0, "height": 10.0}
    world = {
        "area": area, "cell": 0.5, "dt": DT, "seed": 3,
        "robots": [
            {"name": "uav_1", "kind": "uav", "max_speed": 1.0, "fov_radius": 0.5,
             "start": [2.0, 1.0, 0.0], "pose_topics": ["pos_provider/pose"]},
            {"name": "ugv_1", "kind": "ugv", "max_speed": 1.0, "start": [8.0, 1.0]},
        ],
        "targets": [{"id": 5, "x": 2.0, "y": 6.0}],
        "stop": {"all_rescued": True, "time_s": 60.0},
        "settle_reporters": 1, "settle_s": 0.25, "step_timeout_s": 5.0,
        "status_readers": 1,  # the member: it ends on the final status, so it must be matched
        "output": "result.json",
    }  # fmt: skip
    members = [("uav_1", "uav", UAV), ("ugv_1", "ugv", UGV)]
    servers = {
        "dt": DT, "area": area, "seed": 3,
        "events": {"type": "search_and_rescue_interfaces/msg/Event", "topic": "/swarm/events",
                   "declared": ["targetFound", "targetAssigned", "targetRescued"]},
        "params": {"tolerance": 0.01},
        "members": [{"namespace": name, "kind": kind, "max_speed": 1.0, "behaviours": {
            b: {"kind": k, "rosName": n, "rosType": t} for b, (k, n, t) in behaviours.items()}}
            for name, kind, behaviours in members],
    }  # fmt: skip
    member = {"uavs": ["uav_1"], "ugv": "ugv_1", "altitude": 1.0, "limit_s": 80}
    paths = tmp / "world.json", tmp / "servers.json", tmp / "member.json"
    for path, content in zip(paths, (world, servers, member), strict=True):
        path.write_text(json.dumps(content), encoding="utf-8")
    return paths


def run_pair(prefix: Path, tmp: Path) -> Run:
    """One run: the world's exit code and stderr, the result file, the member's record."""
    env = harness.ros_env(tmp / "roslog", domain_id=DOMAIN, python_path=[LIBRARY, ROOT],
                          prefixes=[prefix])  # fmt: skip
    world, servers, member = files(tmp)
    procs: list[subprocess.Popen[str]] = []
    try:
        procs.append(rosproc.start([sys.executable, "-m", "swarmgen_library.servers",
                                    str(servers)], env, tmp, 150))  # fmt: skip
        procs.append(rosproc.start([sys.executable, "-m", "tests.servers_driver", "member",
                                    str(member)], env, ROOT, 140))  # fmt: skip
        assert procs[1].stdout is not None
        ready = procs[1].stdout.readline()  # its TakeOff goals are accepted: the world may start
        assert json.loads(ready or "{}").get("event") == "ready", procs[1].communicate()[1][-3000:]
        procs.append(rosproc.start([sys.executable, "-m", "swarmgen_library.world_node",
                                    str(world)], env, tmp, 100))  # fmt: skip
        code, _, err = rosproc.finish(procs[2], 110)
        m_code, m_out, m_err = rosproc.finish(procs[1], 30)  # it ends on the world's final status
        assert m_code == 0, m_err[-3000:]
    finally:
        for proc in procs:
            if proc.poll() is None:
                rosproc.stop(proc, 15)
    result_path = tmp / "result.json"
    result = json.loads(result_path.read_text()) if result_path.exists() else {}
    return code, err, result, json.loads(m_out.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def runs(prefix: Path, tmp_path_factory: pytest.TempPathFactory) -> list[Run]:
    """The small world run twice."""
    return [run_pair(prefix, tmp_path_factory.mktemp("pair")) for _ in range(2)]


def test_coverage_finds_the_target_and_the_ugv_rescues_it(runs: list[Run]) -> None:
    code, err, result, member = runs[0]
    assert code == 0, err[-3000:]
    assert result["complete"] and result["reason"] == "all_rescued"
    faults = ("timeouts", "report_timeouts", "stale", "bad_messages", "status_unmatched")
    assert {f: result[f] for f in faults} == dict.fromkeys(faults, 0)
    assert result["unserved"] == []
    # TakeOff from step 0 at 1 m/s: z = 0.125 k, blind below 0.5 m (a camera on the ground
    # sees nothing), 1 m up at step 8, where it succeeds. Coverage starts from step 8's pose and
    # heads north from step 9: the 0.5 m view reaches (2, 6) at y = 5.5, step 9 + 36 = 45.
    # ugv_1 drives from (8, 1) from step 46: 7.81 m, 63 steps, on the target at step 109;
    # the Rescue starts from there and waits rescue_s (1 s, 8 steps): rescued at step 118.
    assert result["targets"] == {
        "5": {"first_detection": 45 * DT, "rescued": 118 * DT, "robot": "ugv_1"}
    }
    assert result["steps"] == 119 and result["sim_s"] == 119 * DT  # stopped at the next step
    goals = [(g["goal"], g.get("status")) for g in member["goals"]]
    assert goals == [
        ("/uav_1/cmd/takeoff", SUCCEEDED),
        ("/uav_1/uav_coverage", None),  # it runs on until the world ends
        ("/ugv_1/cmd/moveto", SUCCEEDED),
        ("/ugv_1/ugv_rescue", SUCCEEDED),
    ]
    names = [(e["name"], e["sender"]) for e in member["events"]]
    assert names == [("targetFound", "uav_1"), ("targetRescued", "ugv_1")]
    assert member["final"]["final"] is True


def test_the_run_is_reproducible_to_the_step(runs: list[Run]) -> None:
    (_, _, first, _), (code, err, second, _) = runs
    assert code == 0, err[-3000:]
    first, second = dict(first), dict(second)
    first.pop("wall")
    second.pop("wall")
    assert first == second
    assert first["samples"][0] == [0, 0.0]  # nothing covered while on the ground
