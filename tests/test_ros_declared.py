"""Behaviours bound to declared ROS 2 interfaces (issue 12, runtime side), on real DDS.

A hand-written platform (tests/ros_platform/platform.py: an action of a user interfaces
directory, Trigger and Empty services, PoseStamped topics) runs in one process; member nodes
with hand-written `Binding` specs (tests/ros_platform/drive.py) run against it in another, both
under a time limit, with LOCALHOST discovery and a ROS_DOMAIN_ID of this test run. The
conversion tests run in this process (message classes only, no rclpy.init).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")

from geometry_msgs.msg import Polygon, PoseStamped, PoseWithCovariance
from std_msgs.msg import Byte, Float32, UInt8

from swarmgen.ros.runtime.bindings import BindingError, assignments, outputs_of, resolve
from swarmgen.ros.runtime.convert import (
    ConversionError,
    build,
    check_path,
    get_path,
    plain,
    renamed,
    to_message,
)
from swarmgen.ros.runtime.spec import BehaviourSpec, Binding
from swarmgen.ros_harness import ros_env
from tests.conftest import ROOT
from tests.hostile import run_module
from tests.ros_platform.drive import CASES
from tests.ros_platform.packages import build_packages

DOMAIN = 201 + os.getpid() % 30  # one domain per test run (e2e: 101..200, interfaces: 1..100)
NAMESPACE = "/r1"

# --- conversion (message classes, no ROS graph) ---------------------------------------------


def test_nested_fields_by_path_and_back() -> None:
    message = build(
        PoseStamped,
        [
            ("pose.position.x", 1.5),
            ("pose.position.y", -2),
            ("header.frame_id", "map"),
            ("pose.orientation", {"z": 0.6, "w": 0.8}),
            ("pose.position.z", None),  # not given: the default stays
        ],
        "goal",
    )
    assert (message.pose.position.x, message.pose.position.y) == (1.5, -2.0)
    assert isinstance(message.pose.position.y, float)
    assert message.header.frame_id == "map"
    assert get_path(message, "pose.orientation") == {"x": 0.0, "y": 0.0, "z": 0.6, "w": 0.8}
    back = plain(message)
    assert back["header"] == {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "map"}
    assert to_message(PoseStamped, back) == message


def test_arrays_and_sequences() -> None:
    covariance = [float(i) for i in range(36)]
    message = to_message(PoseWithCovariance, {"covariance": covariance})
    assert plain(message)["covariance"] == covariance
    polygon = to_message(Polygon, {"points": [{"x": 1, "y": 2}, {"x": 3.5}]})
    assert plain(polygon) == {
        "points": [{"x": 1.0, "y": 2.0, "z": 0.0}, {"x": 3.5, "y": 0.0, "z": 0.0}]
    }
    with pytest.raises(ConversionError, match=r"covariance: expected 36 items, got 2"):
        to_message(PoseWithCovariance, {"covariance": [1.0, 2.0]})
    with pytest.raises(ConversionError, match=r"points\[0\]: expected an object"):
        to_message(Polygon, {"points": [5]})


@pytest.mark.parametrize(
    ("message_type", "value", "reason"),
    [
        (UInt8, 256, "256 is out of range for uint8"),
        (UInt8, -1, "-1 is out of range for uint8"),
        (UInt8, 2.5, "expected an integer"),
        (UInt8, True, "expected an integer"),
        (Byte, 300, "out of range for octet"),
        (Float32, 1e39, "out of range for float"),
        (Float32, "1.0", "expected a number"),
    ],
)
def test_values_out_of_range_or_of_the_wrong_type(
    message_type: Any, value: Any, reason: str
) -> None:
    with pytest.raises(ConversionError, match=reason):
        to_message(message_type, {"data": value})


def test_ranges_kept_at_their_limits() -> None:
    assert to_message(UInt8, {"data": 255}).data == 255
    assert to_message(UInt8, {"data": 3.0}).data == 3  # an integral number is an integer
    assert plain(to_message(Byte, {"data": 7})) == {"data": 7}
    assert to_message(Float32, {"data": float("inf")}).data == float("inf")


def test_unknown_fields_and_paths() -> None:
    with pytest.raises(ConversionError, match=r"PoseStamped has no field 'pose.postion.x'"):
        check_path(PoseStamped, "pose.postion.x")
    with pytest.raises(ConversionError, match=r"'frame_id' in 'header.frame_id.x' is no message"):
        check_path(PoseStamped, "header.frame_id.x")
    with pytest.raises(ConversionError, match="has no field 'nope'"):
        to_message(PoseStamped, {"nope": 1})


def test_whole_message_paths_and_key_renames() -> None:
    """The empty path (`idl_bind.WHOLE`) is the whole message both ways; data type keys the
    binding renames (`posX` -> `x`, nested under `position`) go renamed and come back."""
    spot = (("posX", "x", ()), ("posY", "y", ()))
    renames = (("input", "where", (("place", "position", spot),)), ("output", "seen", spot))
    binding = Binding(
        "topic", ("geometry_msgs", "msg", "Pose"), "pose", inputs=(("where", ""),),
        direction="publish", renames=renames,
    )  # fmt: skip
    resolved = resolve(BehaviourSpec("Put", "", "pose", "HardwareFunction", binding=binding))
    pairs = assignments(resolved, {"where": {"place": {"posX": 1.5, "posY": -2, "z": 3}}})
    assert pairs == [("", {"position": {"x": 1.5, "y": -2, "z": 3}})]
    message = build(resolved.request, [*pairs, ("orientation.w", 0.5)], "message")
    assert (message.position.x, message.position.y, message.position.z) == (1.5, -2.0, 3.0)
    assert message.orientation.w == 0.5  # a path inside is set after the whole message
    assert check_path(resolved.request, "") == []
    assert get_path(message, "")["position"] == {"x": 1.5, "y": -2.0, "z": 3.0}
    listen = Binding(
        "topic", ("geometry_msgs", "msg", "Point"), "p", outputs=(("", "seen"),),
        direction="subscribe", renames=renames,
    )  # fmt: skip
    heard = resolve(BehaviourSpec("Hear", "", "p", "HardwareFunction", binding=listen))
    point = build(heard.answer, [("", {"x": 1.0, "y": 2.0})], "message")
    assert outputs_of(heard, point) == {"seen": {"posX": 1.0, "posY": 2.0, "z": 0.0}}
    assert renamed([{"posX": 1}], spot, True) == [{"x": 1}]  # a sequence, item by item


@pytest.mark.parametrize(
    ("binding", "says"),
    [
        (Binding("topic", ("nope_msgs", "msg", "Nope"), "x", direction="publish"), "unknown ROS type nope_msgs/msg/Nope"),
        (Binding("topic", ("std_msgs", "msg", "Nope"), "x", direction="publish"), "no Nope in std_msgs.msg"),
        (Binding("topic", ("os;import", "msg", "X"), "x", direction="publish"), "invalid ROS package name"),
        (Binding("topic", ("std_msgs", "msg", "__init__"), "x", direction="publish"), "invalid ROS type name"),
        (Binding("service", ("std_msgs", "msg", "String"), "x"), "is no service type (want srv)"),
        (Binding("topic", ("std_msgs", "msg", "String"), "x"), "topic direction ''"),
        (Binding("topic", ("std_msgs", "msg", "String"), "a//b", direction="publish"), "invalid relative ROS name"),
        (Binding("service", ("std_srvs", "srv", "Trigger"), "x", outputs=(("ok", "ok"),)), "Trigger_Response has no field 'ok'"),
        (Binding("bridge", ("std_srvs", "srv", "Trigger"), "x"), "unknown ROS kind 'bridge'"),
    ],
)  # fmt: skip
def test_bad_bindings_are_one_line_errors(binding: Binding, says: str) -> None:
    behaviour = BehaviourSpec("Act", "", "x", "HardwareFunction", binding=binding)
    with pytest.raises(BindingError) as caught:
        resolve(behaviour)
    assert says in str(caught.value)
    assert "\n" not in str(caught.value)


# --- on real DDS ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """platform_msgs (from the user interfaces directory) and the swarm's interfaces built into
    this venv (skipped when current), and the environment of the ROS processes."""
    work = tmp_path_factory.mktemp("declared")
    seconds = build_packages(work / "packages")
    print(f"interface builds: {seconds}")
    return ros_env(work / "roslog", domain_id=DOMAIN, python_path=[ROOT])


@pytest.fixture(scope="module")
def platform(env: dict[str, str], tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The platform process (killed at the end); yields the file its JSON lines go to."""
    log = tmp_path_factory.mktemp("platform") / "platform.jsonl"
    with log.open("wb") as out:
        process = subprocess.Popen(
            ["timeout", "-k", "5", "120", sys.executable, "-m", "tests.ros_platform.platform", NAMESPACE],
            cwd=ROOT,
            env=env,
            stdout=out,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )  # fmt: skip
        try:
            yield log
        finally:
            os.killpg(process.pid, signal.SIGINT)
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()


def _platform_saw(log: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in log.read_text().splitlines() if line.strip()]


@pytest.fixture(scope="module")
def report(env: dict[str, str], platform: Path) -> dict[str, Any]:
    """Every case of the driver, in one member process."""
    outcome = run_module(
        "tests.ros_platform.drive", NAMESPACE, *CASES, cwd=ROOT, env=env, timeout=90
    )
    assert outcome.exit == 0, str(outcome)
    result: dict[str, Any] = json.loads(outcome.stdout.strip().splitlines()[-1])
    print(
        f"driver: {outcome.seconds:.2f} s; "
        + ", ".join(f"{c}: {r['seconds']} s" for c, r in result.items())
    )
    return result


def _goals(platform: Path) -> list[dict[str, Any]]:
    return [line for line in _platform_saw(platform) if line["event"] == "goal"]


def test_action_goal_with_nested_fields_and_result_to_outputs(
    report: dict[str, Any], platform: Path
) -> None:
    case = report["goto"]
    assert case["final"] == ["Succeeded"], case
    assert case["errors"] == []
    assert case["outputs"] == {
        "reached": {"x": 1.5, "y": -2.25, "z": 0.0},
        "height": 0.0,
        "legs": [1.5, 2.5],
    }
    assert case["feedback"] == [{"remaining": 2.0}, {"remaining": 1.0}]  # feedback in the trace
    goal = next(g for g in _goals(platform) if g["mode"] == "")
    assert goal["pose"] == {
        "frame": "map",
        "position": [1.5, -2.25, 0.0],
        "orientation": [0.0, 0.0, 0.6, 0.8],
    }
    assert goal["speed"] == 2.5 and goal["retries"] == 3


def test_action_outcomes_from_the_result_field_and_the_status(report: dict[str, Any]) -> None:
    assert report["goto_blocked"]["final"] == ["Blocked"]  # result.outcome names an extra outcome
    assert report["goto_failed"]["final"] == ["Aborted"]  # status ABORTED, empty outcome field


def test_preemption_cancels_the_goal(report: dict[str, Any], platform: Path) -> None:
    assert report["goto_preempted"]["final"] == ["Stopped"]
    assert report["goto_preempted"]["errors"] == []
    assert any(line["event"] == "canceled" for line in _platform_saw(platform))


def test_out_of_range_input_aborts_before_sending(report: dict[str, Any], platform: Path) -> None:
    case = report["goto_out_of_range"]
    assert case["final"] == ["Aborted"]
    assert case["errors"] == [
        "behaviour Act in Run: cannot send platform_msgs/action/GoTo: "
        "Act.retries: 300 is out of range for uint8"
    ]
    assert all(goal["retries"] != 300 for goal in _goals(platform))


def test_services(report: dict[str, Any], platform: Path) -> None:
    assert report["arm"]["final"] == ["Succeeded"]
    assert report["arm"]["outputs"] == {"message": "armed", "ok": True}
    assert report["check"]["final"] == ["Aborted"]  # success: false
    assert report["check"]["outputs"] == {"message": "battery low", "ok": False}
    assert report["reset"]["final"] == ["Succeeded"]  # std_srvs/Empty: an empty response
    events = {line["event"] for line in _platform_saw(platform)}
    assert {"arm", "check", "reset"} <= events


def test_service_timeout_aborts(report: dict[str, Any], platform: Path) -> None:
    case = report["land_timeout"]  # the server answers after 5 s, the timeout is 0.5 s
    assert case["final"] == ["Aborted"]
    assert 0.45 <= case["seconds"] < 2.0, case
    assert any(line["event"] == "slow_land" for line in _platform_saw(platform))


def test_topic_message_ends_the_behaviour_with_its_fields(report: dict[str, Any]) -> None:
    case = report["target"]
    assert case["final"] == ["Succeeded"]
    assert case["outputs"]["tx"] == 4.0 and case["outputs"]["frame"] == "map"
    assert case["outputs"]["pose"]["position"] == {"x": 4.0, "y": -1.5, "z": 2.25}


def test_published_message_is_received(report: dict[str, Any], platform: Path) -> None:
    assert report["publish"]["final"] == ["Succeeded"]
    received = [line for line in _platform_saw(platform) if line["event"] == "goal_pose"]
    assert received == [
        {"event": "goal_pose", "pose": {"frame": "odom", "position": [-3.5, 0.0, 12.0], "orientation": [0.0, 0.0, 0.0, 1.0]}}
    ]  # fmt: skip


def test_unknown_type_is_a_one_line_error_at_node_start(env: dict[str, str]) -> None:
    outcome = run_module(
        "tests.ros_platform.drive", "--bad", NAMESPACE, cwd=ROOT, env=env, timeout=30
    )
    assert outcome.exit == 2, str(outcome)
    assert "Traceback" not in outcome.stderr
    assert outcome.stderr.strip() == (
        "member_target: behaviour 'Act': unknown ROS type nope_msgs/msg/Nope "
        "(No module named 'nope_msgs')"
    )
