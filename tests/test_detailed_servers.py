"""The behaviour servers of the detailed level (swarmgen_library.servers) on real rclpy, against
hand-computed cases: the servers process runs as ROS users run it (`python -m
swarmgen_library.servers FILE`, the library's folder on PYTHONPATH, the SAR interface packages
built once per session as tests/test_ros_declared_e2e.py builds them), and a driver process
(tests/servers_driver.py) plays the world node: it steps a real `World` in lockstep, publishes
its poses and camera views and sends the goals with real action clients.

Every ROS process runs under `timeout -k 5`, with LOCALHOST discovery, its logs in the test's
tmp directory and a ROS_DOMAIN_ID of this test run (201 + (pid + 15) % 30, never the other tests' in a run),
and is stopped as a tree at the end.
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

from swarmgen import pipeline
from swarmgen import ros_harness as harness
from swarmgen.ros.domains import hold
from tests import rosproc
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
LIBRARY = ROOT / "swarmgen" / "ros" / "library"
# one per test run (Fast DDS allows 0..232): never the 201 + pid % 30 of the other 201..230 tests
DOMAIN = hold(1, 139, start=201 + (os.getpid() + 15) % 30)  # leased: see swarmgen/ros/domains.py
DT = 0.125  # the driver's step (binary-exact: 1 m/s is 0.125 m per step)
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6  # action_msgs/GoalStatus
UAV = {
    "Coverage": ("action", "uav_coverage", "cpswarm_msgs/action/Coverage"),
    "TargetMonitoring": ("topic", "target_found", "cpswarm_msgs/msg/TargetPositionEvent"),
    "TaskAllocation": ("action", "cmd/task_allocation_auction",
                       "cpswarm_msgs/action/TaskAllocation"),
    "TakeOff": ("action", "cmd/takeoff", "cpswarm_msgs/action/Takeoff"),
    "Land": ("service", "cmd/land", "std_srvs/srv/Empty"),
    "Tracking": ("action", "uav_tracking", "cpswarm_msgs/action/Tracking"),
    "UwbPositioning": ("topic", "pos_provider/pose", "geometry_msgs/msg/PoseStamped"),
}  # fmt: skip
UGV = {
    "MoveTo": ("action", "cmd/moveto", "move_base_msgs/action/MoveBase"),
    "TaskBidding": ("action", "cmd/task_allocation_bid", "cpswarm_msgs/action/TaskAllocation"),
    "Rescue": ("action", "ugv_rescue", "cpswarm_msgs/action/Target"),
}


@pytest.fixture(scope="module")
def prefix(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """SAR compiled as it is, its interface packages (the swarm's and the user's) built."""
    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    out = tmp_path_factory.mktemp("sar_servers")
    pipeline.write_tree(result.files, out)
    return harness.build_interfaces(out / "rclpy", model)


def servers_file(path: Path, members: dict[str, tuple[str, dict[str, Any]]]) -> Path:
    """A servers file: members (namespace -> (kind, behaviours)) at 1 m/s, heading east."""
    config = {
        "dt": DT,
        "area": {"width": 10.0, "height": 10.0},
        "seed": 7,
        "events": {
            "type": "search_and_rescue_interfaces/msg/Event",
            "topic": "/swarm/events",
            "declared": ["targetFound", "targetAssigned", "targetRescued"],
        },
        "params": {"heading": 0.0, "tolerance": 0.01},
        "members": [
            {
                "namespace": name,
                "kind": kind,
                "max_speed": 1.0,
                "behaviours": {
                    b: {"kind": k, "rosName": n, "rosType": t}
                    for b, (k, n, t) in behaviours.items()
                },
            }
            for name, (kind, behaviours) in members.items()
        ],
    }
    path.write_text(json.dumps(config), encoding="utf-8")
    return path


def env(prefix: Path, tmp_path: Path) -> dict[str, str]:
    """The ROS environment of both processes."""
    return harness.ros_env(tmp_path / "roslog", domain_id=DOMAIN,
                           python_path=[LIBRARY, ROOT], prefixes=[prefix])  # fmt: skip


def run(
    prefix: Path, tmp_path: Path, scenario: str, members: dict[str, tuple[str, dict[str, Any]]]
) -> dict[str, Any]:
    """The servers for `members`, the driver's scenario against them: the driver's record."""
    environment = env(prefix, tmp_path)
    config = servers_file(tmp_path / "servers.json", members)
    command = [sys.executable, "-m", "swarmgen_library.servers", str(config)]
    servers = rosproc.start(command, environment, tmp_path, 90)
    try:
        driver = rosproc.start([sys.executable, "-m", "tests.servers_driver", scenario],
                               environment, tmp_path, 80)  # fmt: skip
        code, out, err = rosproc.finish(driver, 85)
    finally:
        s_code, s_out, s_err = rosproc.stop(servers, 15)
    assert code == 0, (err[-3000:], s_err[-3000:])
    assert s_code == 0, s_err[-3000:]
    assert json.loads(s_out.splitlines()[0])["event"] == "ready"
    record: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    return record


def test_move_to_ends_succeeded_at_the_step_geometry_gives(prefix: Path, tmp_path: Path) -> None:
    # (1, 1) -> (4, 1) at 0.125 m per step: 24 steps, the last one onto the goal exactly
    record = run(prefix, tmp_path, "moveto", {"ugv_1": ("ugv", UGV)})
    assert record["status"] == SUCCEEDED
    assert record["ended"] == 24  # the result came back while the world held step 24
    steps = {s["k"]: s["ugv_1"] for s in record["record"]}
    assert steps[24]["pose"] == [4.0, 1.0, 0.0]
    assert [s["cmd"] for k, s in steps.items() if k < 24] == [[1.0, 0.0, 0.0]] * 24
    assert steps[24]["cmd"] == [0.0, 0.0, 0.0]


def test_cancel_stops_motion_within_one_step(prefix: Path, tmp_path: Path) -> None:
    record = run(prefix, tmp_path, "cancel", {"ugv_1": ("ugv", UGV)})
    assert record["status"] == CANCELED
    steps = {s["k"]: s["ugv_1"] for s in record["record"]}
    assert steps[10]["cmd"] == [1.0, 0.0, 0.0]  # cancelled after step 10's command was sent
    assert steps[11]["pose"] == [1.0 + 11 * DT, 1.0, 0.0]
    for k in range(11, max(steps) + 1):
        assert steps[k]["cmd"] == [0.0, 0.0, 0.0], k
        assert steps[k]["pose"] == steps[11]["pose"], k


def test_the_auction_gives_the_target_to_the_lowest_bid(prefix: Path, tmp_path: Path) -> None:
    members = {"uav_1": ("uav", UAV), "ugv_1": ("ugv", UGV), "ugv_2": ("ugv", UGV)}
    record = run(prefix, tmp_path, "auction", members)
    goals = record["goals"]
    # ugv_2 at (3, 3) bids 1.25 m, ugv_1 at (8, 8) bids 8.32 m: ugv_2 wins
    assert goals["uav_1"] == {**goals["uav_1"], "status": SUCCEEDED, "rover_id": 2}
    assert goals["ugv_2"]["status"] == SUCCEEDED
    assert goals["ugv_1"]["status"] == ABORTED
    assigned = [e for e in record["events"] if e["name"] == "targetAssigned"]
    assert [e["data"] for e in assigned] == [{"target_id": 7, "rover_id": 2}]
    assert assigned[0]["sender"] == "uav_1"
    # opened at t = 0 (the step the servers last acted on when the goal came): the window of
    # 1 s closes at step 8, while the world holds it
    assert goals["uav_1"]["ended"] == 8


def test_coverage_first_find_sends_target_found_with_its_pose(prefix: Path, tmp_path: Path) -> None:
    record = run(prefix, tmp_path, "coverage", {"uav_1": ("uav", UAV)})
    # eastwards from (1, 1) at 0.125 m per step, the 0.5 m view reaches (3, 1) at x = 2.5
    assert record["first"] == 12 * DT
    found = [e for e in record["events"] if e["name"] == "targetFound"]
    assert len(found) == 1, found  # reported once, although in view for several steps
    assert found[0]["k"] == 12 and found[0]["sender"] == "uav_1"
    assert found[0]["data"] == {
        "target_id": 3,
        "pose": {
            "header": {"frame_id": "map"},
            "pose": {
                "position": {"x": 3.0, "y": 1.0, "z": 0.0},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
            },
        },
    }
    assert record["found"] == [{"k": 12, "id": 3, "xyz": [3.0, 1.0, 0.0]}]
    assert record["status"] is None  # coverage runs on until preempted


def test_rescue_ends_tracking_and_tells_the_world(prefix: Path, tmp_path: Path) -> None:
    record = run(prefix, tmp_path, "rescue", {"uav_1": ("uav", UAV), "ugv_1": ("ugv", UGV)})
    # goals start at t = 0 from (1, 2); 8 steps of 0.125 m reach (2, 2) at step 9 (t = 1.125),
    # then rescue_s = 1 s there: rescued at step 17 (t = 2.125)
    assert record["rescue"] == [SUCCEEDED, 17]
    assert record["rescues"] == [{"k": 17, "target": 5, "robot": "ugv_1"}]
    rescued = [e for e in record["events"] if e["name"] == "targetRescued"]
    assert [(e["sender"], e["data"]) for e in rescued] == [("ugv_1", {"target_id": 5})]
    assert record["tracking"] == [SUCCEEDED, 17, ""]  # on the rescue; no extra outcome
    steps = {s["k"]: s["ugv_1"] for s in record["record"]}
    assert steps[9]["pose"] == [2.0, 2.0, 0.0]
    assert all(steps[k]["cmd"] == [0.0, 0.0, 0.0] for k in range(9, 18))


def test_an_unimplemented_behaviour_is_refused_at_start(tmp_path: Path) -> None:
    bad = {"Dance": ("action", "dance", "cpswarm_msgs/action/Coverage")}
    config = servers_file(tmp_path / "servers.json", {"uav_1": ("uav", bad)})
    environment = harness.ros_env(tmp_path / "roslog", domain_id=DOMAIN, python_path=[LIBRARY])
    command = [sys.executable, "-m", "swarmgen_library.servers", str(config)]
    code, out, err = rosproc.finish(rosproc.start(command, environment, tmp_path, 30), 35)
    assert code == 2, (out, err)
    assert err.strip().splitlines() == [
        "servers: member uav_1, behaviour Dance: the library does not implement 'Dance' "
        "(it implements Coverage, Land, LocalCoverage, MoveTo, Rescue, TakeOff, "
        "TargetMonitoring, TaskAllocation, TaskBidding, Tracking, UwbPositioning)"
    ]
