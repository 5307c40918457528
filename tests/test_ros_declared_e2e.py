"""End to end on declared interfaces (issue 12): the generated SAR swarm, unmodified, runs its
mission on real DDS (loopback) against a platform written by hand (`tests/ros_platform/
sar_platform.py`) that serves every declared type the SAR sample uses: cpswarm_msgs and
move_base_msgs actions (built from the sample's `interfaces/` directory as packages of the
generated workspace), std_srvs/srv/Empty, geometry_msgs/msg/PoseStamped and
cpswarm_msgs/msg/TargetPositionEvent topics. No simulated server runs (`--no-simulation`).

The platform's bag holds every goal and result it received and sent, under the declared types'
names, decoded here with rosbags. Every ROS process runs under `timeout -k 5`, with LOCALHOST
discovery, a ROS_DOMAIN_ID of this test run and its logs in the test's tmp directory.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
pytest.importorskip("psutil", reason="psutil comes with the `ros` extra: run `make ros`")


from swarmgen import pipeline
from swarmgen import ros_harness as harness
from swarmgen.backends.rclpy_backend import nodes_package
from swarmgen.ros.domains import hold
from tests import rosproc
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
INTERFACES = SAR.parent / "interfaces"
# one domain per test run, apart from test_ros_e2e's (101 + pid % 100) in the same run
DOMAIN = hold(1, 139, start=101 + (os.getpid() + 50) % 100)  # leased: see swarmgen/ros/domains.py
TIME_SCALE = 0.25  # wall seconds per simulated second
MEMBERS = ["uav_1", "uav_2", "ugv_1", "ugv_2"]


@pytest.fixture(scope="module")
def sar(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """SAR compiled as it is, its interface packages (the swarm's and the user's) built."""
    started = time.monotonic()
    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    out = tmp_path_factory.mktemp("sar_declared")
    pipeline.write_tree(result.files, out)
    prefix = harness.build_interfaces(out / "rclpy", model)
    package = nodes_package(model)
    return {
        "package": package,
        "path": out / "rclpy" / package,
        "prefix": prefix,
        "setup_s": time.monotonic() - started,
    }


def _wait_ready(proc: subprocess.Popen[str], limit: float) -> None:
    assert proc.stdout is not None
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        if json.loads(line).get("event") == "ready":
            return
    raise AssertionError(f"the platform did not come up: {rosproc.finish(proc, 5)}")


def _bag(path: Path) -> list[tuple[str, str, dict[str, Any]]]:
    """(topic, type, message as a dict) of every message in the platform's bag."""
    from rosbags.highlevel import AnyReader

    def plain(value: Any) -> Any:
        if dataclasses.is_dataclass(value):
            fields = [f.name for f in dataclasses.fields(value) if not f.name.startswith("__")]
            return {name: plain(getattr(value, name)) for name in fields}
        return value

    with AnyReader([path]) as reader:
        return [
            (c.topic, c.msgtype, plain(reader.deserialize(raw, c.msgtype)))
            for c, _, raw in reader.messages()
        ]


def test_sar_swarm_runs_on_the_declared_interfaces(sar: dict[str, Any], tmp_path: Path) -> None:
    started = time.monotonic()
    env = harness.ros_env(
        tmp_path / "roslog",
        domain_id=DOMAIN,
        python_path=[sar["path"], ROOT],
        prefixes=[sar["prefix"]],
    )
    bag = tmp_path / "platform_bag"
    platform = rosproc.start(
        [sys.executable, "-m", "tests.ros_platform.sar_platform", str(bag), str(INTERFACES),
         "2", "2"],
        env, tmp_path, 60,
    )  # fmt: skip
    _wait_ready(platform, 30)
    swarm = rosproc.start(
        [
            sys.executable, "-m", f"{sar['package']}.launch_swarm", "--uav", "2", "--ugv", "2",
            "--no-simulation", "--time-scale", str(TIME_SCALE), "--events",
            "--station", "launch@0.5,missionStart@Loitering,missionAbort@16",
        ],
        env, tmp_path, 45,
    )  # fmt: skip
    swarm_code, swarm_out, swarm_err = rosproc.finish(swarm, 50)
    platform_code, platform_out, platform_err = rosproc.stop(platform, 15)
    mission_s = time.monotonic() - started
    assert swarm_code == 0, swarm_err[-3000:]
    assert platform_code == 0, platform_err[-3000:]

    summary = json.loads(swarm_out.strip().splitlines()[-1])
    assert sorted(summary["members"]) == MEMBERS
    for member, report in summary["members"].items():
        assert report["finished"], (member, report)
        assert report["errors"] == [], (member, report)
        assert report["active"] == (["Landed"] if member.startswith("uav") else ["Stopped"])
    assert summary["events"].get("targetRescued", 0) >= 1, summary["events"]

    # what the platform saw: every behaviour reached it on its declared interface
    said = [json.loads(line) for line in platform_out.splitlines() if line.startswith("{")]
    goals = {(s["member"], s["name"]) for s in said if s["event"] == "goal"}
    assert {("uav_1", "cmd/takeoff"), ("uav_2", "cmd/takeoff"), ("uav_1", "uav_coverage")} <= goals
    assert ("uav_1", "cmd/task_allocation_auction") in goals
    assert {("ugv_1", "cmd/task_allocation_bid"), ("ugv_2", "cmd/task_allocation_bid")} <= goals
    rover = f"ugv_{1 + 101 % 2}"  # the auction's choice for target 101
    assert {(rover, "cmd/moveto"), (rover, "ugv_rescue")} <= goals
    assert {s["member"] for s in said if s["event"] == "land"} == {"uav_1", "uav_2"}

    # the bag: goals and results with the declared types, the fields the model's values filled
    messages = _bag(bag)
    types = {(topic, msgtype) for topic, msgtype, _ in messages}
    assert ("/uav_1/cmd/takeoff/goal", "cpswarm_msgs/action/Takeoff_Goal") in types
    assert ("/uav_1/uav_coverage/goal", "cpswarm_msgs/action/Coverage_Goal") in types
    assert ("/uav_1/target_found", "cpswarm_msgs/msg/TargetPositionEvent") in types
    by_topic = {topic: message for topic, _, message in messages}
    assert by_topic["/uav_1/cmd/takeoff/goal"]["altitude"] == 1.5  # the member's data
    auction = by_topic["/uav_1/cmd/task_allocation_auction/goal"]
    assert auction["target_id"] == 101
    _assert_found_pose(auction["target_pose"])  # the model's PoseStamped, field by field
    assert by_topic["/uav_1/cmd/task_allocation_auction/result"]["rover_id"] == 2
    move = by_topic[f"/{rover}/cmd/moveto/goal"]
    _assert_found_pose(move["target_pose"])  # move_base_msgs' own PoseStamped goal
    assert (f"/{rover}/cmd/moveto/goal", "move_base_msgs/action/MoveBase_Goal") in types
    assert (f"/{rover}/ugv_rescue/result", "cpswarm_msgs/action/Target_Result") in types
    print(f"setup {sar['setup_s']:.1f} s, mission {mission_s:.1f} s, {len(messages)} messages")


def _assert_found_pose(pose: dict[str, Any]) -> None:
    """A geometry_msgs/msg/PoseStamped as decoded from the bag, at the reported target."""
    assert pose["header"]["frame_id"] == "map"
    assert pose["pose"]["position"] == {"x": 4.0, "y": 6.0, "z": 0.0}
    assert pose["pose"]["orientation"] == {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}


def test_launcher_refuses_a_missing_declared_type_in_one_line(
    sar: dict[str, Any], tmp_path: Path
) -> None:
    # without the user interface prefix cpswarm_msgs does not import: exit 2, one line
    env = harness.ros_env(
        tmp_path / "roslog", domain_id=DOMAIN, python_path=[sar["path"]], prefixes=[]
    )
    command = [sys.executable, "-m", f"{sar['package']}.launch_swarm", "--no-simulation"]
    code, out, err = rosproc.finish(rosproc.start(command, env, tmp_path, 30), 40)
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "launch_swarm: behaviour '" in lines[0]
    assert "unknown ROS type cpswarm_msgs/action/" in lines[0], lines[0]


def test_bindings_follow_the_index_and_leave_the_runtime_its_parameters() -> None:
    from swarmgen.backends import registry

    validation = pipeline.validate(SAR)
    model, charts = validation.model, validation.charts
    assert model is not None and validation.interfaces is not None
    bound = registry(validation.interfaces)["rclpy"].render(model, charts)
    private = registry()["rclpy"].render(model, charts)  # no index: every behaviour private
    actions = "search_and_rescue_interfaces/action/"
    assert not [p for p in bound if str(p).startswith(actions)]
    assert len([p for p in private if str(p).startswith(actions)]) == 11
    assert not [p for p in private if str(p).startswith("cpswarm_msgs/")]
    uav = bound[Path("search_and_rescue_nodes/search_and_rescue_nodes/uav.py")]
    assert "binding=Binding(" in uav and "std_srvs" in uav
    assert ".timeout_s" not in uav  # the runtime declares behaviours.<key>.timeout_s itself
    # the user's definition, byte for byte; the nested standard type is a dependency
    text = (INTERFACES / "cpswarm_msgs" / "msg" / "TargetPositionEvent.msg").read_text()
    assert bound[Path("cpswarm_msgs/msg/TargetPositionEvent.msg")] == text
    cmake = bound[Path("cpswarm_msgs/CMakeLists.txt")]
    assert "find_package(geometry_msgs REQUIRED)" in cmake and "find_package(std_msgs" in cmake
