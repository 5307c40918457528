"""Generated ROS 2 interface packages, built with cmake from the PyPI wheels into this venv and
used by real rclpy on loopback (no mocks): events on a topic, and a behaviour action with
feedback, a result and a cancelled goal, in one process and across two processes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path, PurePosixPath
from typing import Any

import pytest

from swarmgen.ros.domains import hold
from swarmgen.ros.interfaces import (
    ACTIVE_STATES_MSG,
    BUILD_STAMP,
    EVENT_MSG,
    GENERATED_MARKER,
    InterfaceBuildError,
    behaviour_action,
    build_and_install,
    fix_wheel_cmake_files,
    interface_type,
    render_interface_package,
)
from tests.skips import need_rclpy

PACKAGE = "sgtest_interfaces"
DOMAIN = hold(1, 139, start=1 + os.getpid() % 100)  # leased: see swarmgen/ros/domains.py
COVERAGE = behaviour_action(
    [("altitude", "Real")], [("target_id", "Integer"), ("target_pose", "Pose")]
)


def _render(package: str = PACKAGE) -> dict[PurePosixPath, str]:
    return render_interface_package(
        package,
        {"Event": EVENT_MSG, "ActiveStates": ACTIVE_STATES_MSG},
        {"Coverage": COVERAGE},
        "swarmgen test interfaces",
    )


def _write(files: dict[PurePosixPath, str], root: Path) -> Path:
    for path, text in files.items():
        (root / path).parent.mkdir(parents=True, exist_ok=True)
        (root / path).write_text(text, encoding="utf-8")
    return root


# --- rendering (no ROS needed) -----------------------------------------------------------------


def test_render_interface_package_files() -> None:
    files = _render()
    assert list(files) == sorted(files)
    assert set(map(str, files)) == {
        "CMakeLists.txt",
        "package.xml",
        "msg/Event.msg",
        "msg/ActiveStates.msg",
        "action/Coverage.action",
    }
    cmake = files[PurePosixPath("CMakeLists.txt")]
    assert "DEPENDENCIES action_msgs builtin_interfaces\n" in cmake
    assert '"action/Coverage.action"\n  "msg/ActiveStates.msg"\n  "msg/Event.msg"' in cmake
    package_xml = files[PurePosixPath("package.xml")]
    assert "<member_of_group>rosidl_interface_packages</member_of_group>" in package_xml
    assert 'email="swarmgen@example.com"' in package_xml
    for path, text in files.items():
        assert GENERATED_MARKER in text.splitlines()[0 if path.suffix != ".xml" else 3]
    assert files[PurePosixPath("action/Coverage.action")] == (
        f"# {GENERATED_MARKER}\nfloat64 altitude\n---\nint64 target_id\nstring target_pose\n"
        "string outcome\n---\nstring status\n"
    )
    assert _render() == files  # deterministic


def test_render_adds_referenced_packages_and_escapes_description() -> None:
    files = render_interface_package(
        "pkg", {"Stamped": "std_msgs/Header header\nstring data\n"}, {}, "a <b> & c\x01"
    )
    assert "find_package(std_msgs REQUIRED)" in files[PurePosixPath("CMakeLists.txt")]
    assert "action_msgs" not in files[PurePosixPath("CMakeLists.txt")]
    assert "<description>a &lt;b&gt; &amp; c</description>" in files[PurePosixPath("package.xml")]


@pytest.mark.parametrize(
    ("package", "messages", "actions"),
    [
        ("good", {"Foo; message(FATAL_ERROR x)": EVENT_MSG}, {}),
        ("good", {}, {'Foo")\nmessage(FATAL_ERROR x)': COVERAGE}),
        ("../x", {"Event": EVENT_MSG}, {}),
        ("</package>", {"Event": EVENT_MSG}, {}),
        ("Bad", {"Event": EVENT_MSG}, {}),
        ("a__b", {"Event": EVENT_MSG}, {}),
        ("good", {"event": EVENT_MSG}, {}),
        ("good", {"Ev_ent": EVENT_MSG}, {}),
        ("good", {}, {}),
        ("good", {"Event": "int64 a\n---\nint64 b\n"}, {}),
        ("good", {}, {"Task": "int64 a\n"}),
    ],
)
def test_render_rejects_hostile_names(
    package: str, messages: dict[str, str], actions: dict[str, str]
) -> None:
    with pytest.raises(ValueError):
        render_interface_package(package, messages, actions, "x")


@pytest.mark.parametrize(
    ("type_name", "expected"),
    [
        ("Real", "float64"),
        ("Double", "float64"),
        ("Float", "float64"),
        ("Integer", "int64"),
        ("Int", "int64"),
        ("UnlimitedNatural", "int64"),
        ("Boolean", "bool"),
        ("String", "string"),
        (None, "string"),
        ("Pose", "string"),
        (" real ", "float64"),
    ],
)
def test_interface_type(type_name: str | None, expected: str) -> None:
    assert interface_type(type_name) == expected


@pytest.mark.parametrize(
    ("inputs", "outputs"),
    [
        ([("bad name", "Real")], []),
        ([("x}; y", "Real")], []),
        ([], [("outcome", "String")]),
        ([("a", "Real"), ("A", "Real")], []),
        ([("class", "Real")], []),
        ([("trailing_", "Real")], []),
        ([("1st", "Real")], []),
    ],
)
def test_behaviour_action_rejects_bad_fields(
    inputs: list[tuple[str, str | None]], outputs: list[tuple[str, str | None]]
) -> None:
    with pytest.raises(ValueError):
        behaviour_action(inputs, outputs)


def test_behaviour_action_lower_cases_names() -> None:
    assert behaviour_action([("Speed", None)], []) == (
        "string speed\n---\nstring outcome\n---\nstring status\n"
    )


# --- real build and real rclpy ------------------------------------------------------------------


def _mtimes(share: Path) -> dict[str, int]:
    return {str(p): p.stat().st_mtime_ns for p in sorted(share.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Build and install sgtest_interfaces into this venv; the second call must be a no-op."""
    need_rclpy()  # the build uses the ROS wheels
    root = _write(_render(), tmp_path_factory.mktemp("ros") / PACKAGE)
    share = build_and_install(root)
    first = _mtimes(share)
    assert build_and_install(root) == share
    assert share == Path(sys.prefix).resolve() / "share" / PACKAGE
    assert (share / BUILD_STAMP).is_file()
    return {"share": share, "first": first, "second": _mtimes(share)}


def test_second_build_is_skipped(installed: dict[str, Any]) -> None:
    """Skipped, not redone: the stamp and every installed file keep their mtimes."""
    stamp = str(installed["share"] / BUILD_STAMP)
    assert stamp in installed["first"]
    assert installed["second"] == installed["first"]


def test_wheel_cmake_files_are_fixed_once(installed: dict[str, Any]) -> None:
    assert fix_wheel_cmake_files(Path(sys.prefix)) == []
    for path in Path(sys.prefix).glob("share/*/cmake/*.cmake"):
        assert "/opt/python/cp3" not in path.read_text(encoding="utf-8"), path


def test_build_failure_reports_cmake_output(installed: dict[str, Any], tmp_path: Path) -> None:
    files = render_interface_package("sgtest_broken", {"Broken": "Float99 x\n"}, {}, "broken")
    prefix = tmp_path / "prefix"
    with pytest.raises(InterfaceBuildError, match=r"(?s)cmake build failed.*Float99"):
        build_and_install(_write(files, tmp_path / "sgtest_broken"), prefix=prefix)
    assert not (prefix / "share" / "sgtest_broken" / BUILD_STAMP).exists()


def _ros_env(tmp_path: Path) -> dict[str, str]:
    env = dict(os.environ)
    env.update(
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",  # no multicast on the real network
        ROS_DOMAIN_ID=str(DOMAIN),  # isolates concurrent test runs
        ROS_LOG_DIR=str(tmp_path / "roslog"),
        HOME=str(tmp_path),  # rclpy's logging needs one; keeps ~/.ros out of the real HOME
    )
    env.pop("ROS_LOCALHOST_ONLY", None)
    return env


SCRIPT = r'''
import json
import sys
import time

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient, ActionServer, CancelResponse, GoalResponse
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future

from sgtest_interfaces.action import Coverage
from sgtest_interfaces.msg import Event

QOS = QoSProfile(
    depth=50, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
EVENTS = [
    {"name": "target_found", "data": {"target": 7, "pose": {"x": 1.5, "y": -2.0}, "ok": True}},
    {"name": "battery_low", "data": {"level": 0.125, "note": "ünïcode \"quoted\""}},
]


def sleep(node, seconds):
    """A future done after `seconds`: awaitable inside executor tasks (no thread blocks)."""
    future = Future()

    def fire():
        timer.cancel()
        if not future.done():
            future.set_result(None)

    timer = node.create_timer(seconds, fire)
    return future


class Server:
    """Subscribes to /swarm/events and serves the Coverage behaviour."""

    def __init__(self, node):
        self.node = node
        self.events = []
        self.outcomes = []
        node.create_subscription(Event, "/swarm/events", self.on_event, QOS)
        self.action = ActionServer(
            node, Coverage, "coverage", execute_callback=self.execute,
            goal_callback=lambda goal: GoalResponse.ACCEPT,
            cancel_callback=lambda handle: CancelResponse.ACCEPT,
        )

    def on_event(self, msg):
        self.events.append({"id": msg.id, "sender": msg.sender, "name": msg.name,
                            "data": json.loads(msg.data), "sec": msg.stamp.sec})

    async def execute(self, handle):
        altitude = handle.request.altitude
        steps = 3 if altitude < 100 else 500  # the long goal is cancelled by the client
        for step in range(steps):
            if handle.is_cancel_requested:
                handle.canceled()
                self.outcomes.append("canceled")
                return Coverage.Result(outcome="canceled")
            handle.publish_feedback(Coverage.Feedback(status=f"step {step} at {altitude}"))
            await sleep(self.node, 0.02)
        handle.succeed()
        self.outcomes.append("succeeded")
        return Coverage.Result(target_id=int(altitude * 10), outcome="succeeded",
                               target_pose=json.dumps({"x": 1.0, "y": 2.0, "z": altitude}))


async def client(node, done):
    pub = node.create_publisher(Event, "/swarm/events", QOS)
    action = ActionClient(node, Coverage, "coverage")
    out = {}
    started = time.monotonic()
    while pub.get_subscription_count() < 1 or not action.server_is_ready():
        await sleep(node, 0.02)
    out["discovery_s"] = round(time.monotonic() - started, 3)
    for i, event in enumerate(EVENTS):
        pub.publish(Event(id=i + 1, stamp=node.get_clock().now().to_msg(), sender="uav1",
                          name=event["name"], data=json.dumps(event["data"])))

    feedback = []
    handle = await action.send_goal_async(
        Coverage.Goal(altitude=12.5), feedback_callback=lambda f: feedback.append(f.feedback.status))
    response = await handle.get_result_async()
    out["first"] = {"accepted": handle.accepted, "status": response.status,
                    "outcome": response.result.outcome, "target_id": response.result.target_id,
                    "target_pose": json.loads(response.result.target_pose), "feedback": feedback}

    feedback2 = []
    handle = await action.send_goal_async(
        Coverage.Goal(altitude=500.0), feedback_callback=lambda f: feedback2.append(f))
    while not feedback2:
        await sleep(node, 0.01)
    cancel = await handle.cancel_goal_async()
    response = await handle.get_result_async()
    out["second"] = {"accepted": handle.accepted, "cancel_accepted": len(cancel.goals_canceling),
                     "status": response.status, "outcome": response.result.outcome,
                     "feedback": len(feedback2)}
    out["expected"] = {"succeeded": GoalStatus.STATUS_SUCCEEDED,
                       "canceled": GoalStatus.STATUS_CANCELED}
    pub.publish(Event(id=99, stamp=node.get_clock().now().to_msg(), sender="uav1", name="done",
                      data="{}"))
    done.update(out)
    action.destroy()
    return out


def main(role):
    rclpy.init()
    executor = SingleThreadedExecutor()
    nodes = []
    result = {}
    try:
        server = None
        if role in ("both", "server"):
            node = rclpy.create_node("sg_server")
            nodes.append(node)
            executor.add_node(node)
            server = Server(node)
        if role in ("both", "client"):
            node = rclpy.create_node("sg_client")
            nodes.append(node)
            executor.add_node(node)
            task = executor.create_task(client(node, result))
            executor.spin_until_future_complete(task, timeout_sec=30)
            if task.exception() is not None:
                raise task.exception()
            if not task.done():
                raise TimeoutError("the client did not finish in 30 s")
        if server is not None:
            deadline = time.monotonic() + 30
            while not any(e["name"] == "done" for e in server.events):
                if time.monotonic() > deadline:
                    raise TimeoutError(f"the server got only {server.events}")
                executor.spin_once(timeout_sec=0.1)
            result["events"] = server.events
            result["outcomes"] = server.outcomes
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    print(json.dumps(result))


main(sys.argv[1])
'''


def _start(script: Path, role: str, env: dict[str, str]) -> subprocess.Popen[str]:
    # `timeout -k` kills the process even if it is wedged (a wedged rclpy ignores SIGTERM).
    return subprocess.Popen(
        ["timeout", "-k", "5", "45", sys.executable, str(script), role],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _output(proc: subprocess.Popen[str]) -> dict[str, Any]:
    try:
        stdout, stderr = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        stdout, stderr = proc.communicate()
    assert proc.returncode == 0, f"exit {proc.returncode}\n{stderr}\n{stdout}"
    result: dict[str, Any] = json.loads(stdout.strip().splitlines()[-1])
    return result


def _check_client(result: dict[str, Any]) -> None:
    expected = result["expected"]
    first = result["first"]
    assert first["accepted"] and first["status"] == expected["succeeded"], result
    assert first["outcome"] == "succeeded" and first["target_id"] == 125
    assert first["target_pose"] == {"x": 1.0, "y": 2.0, "z": 12.5}
    assert first["feedback"] == [f"step {i} at 12.5" for i in range(3)]
    second = result["second"]
    assert second["accepted"] and second["cancel_accepted"] == 1, result
    assert second["status"] == expected["canceled"] and second["outcome"] == "canceled"
    assert 1 <= second["feedback"] < 500


def _check_server(result: dict[str, Any]) -> None:
    events = [e for e in result["events"] if e["name"] != "done"]
    assert [(e["id"], e["sender"], e["name"]) for e in events] == [
        (1, "uav1", "target_found"),
        (2, "uav1", "battery_low"),
    ]
    assert events[0]["data"] == {"target": 7, "pose": {"x": 1.5, "y": -2.0}, "ok": True}
    assert events[1]["data"] == {"level": 0.125, "note": 'ünïcode "quoted"'}
    assert all(e["sec"] > 1_600_000_000 for e in events)
    assert result["outcomes"] == ["succeeded", "canceled"]


def test_events_and_action_in_one_process(installed: dict[str, Any], tmp_path: Path) -> None:
    script = tmp_path / "ros_roundtrip.py"
    script.write_text(SCRIPT, encoding="utf-8")
    result = _output(_start(script, "both", _ros_env(tmp_path)))
    _check_client(result)
    _check_server(result)


def test_events_and_action_across_two_processes(installed: dict[str, Any], tmp_path: Path) -> None:
    script = tmp_path / "ros_roundtrip.py"
    script.write_text(SCRIPT, encoding="utf-8")
    env = _ros_env(tmp_path)
    server = _start(script, "server", env)
    try:
        client_result = _output(_start(script, "client", env))
        server_result = _output(server)
    finally:
        if server.poll() is None:
            server.kill()
            server.communicate()
    _check_client(client_result)
    _check_server(server_result)


AREA = {
    "centre": {"x": 1.5, "y": -2.0},
    "corners": [{"x": 0.0, "y": 1.0}, {"x": 2.0, "y": 3.0}],
    "mode": "track",
    "tagId": 7,
    "peak": {"x": 1.0, "y": 2.0, "z": 30.5},
    "tags": ["north", "ünïcode"],
}
DATA_SCRIPT = r"""
import json
import time

import rclpy
from rclpy.action import ActionClient, ActionServer
from rclpy.executors import SingleThreadedExecutor
from survey_interfaces.action import Scan

from swarmgen.ros.runtime.messages import decode, encode, fits
from swarmgen.ros.runtime.spec import Field

RENAMES = (("tagId", "tag_id", ()),)
AREA = Field("area", "area", "survey_interfaces/Area", RENAMES)
FOUND = Field("found", "found", "survey_interfaces/Area[]", RENAMES)
VALUE = @VALUE@


def spin_until(executor, future):
    deadline = time.monotonic() + 20
    while not future.done() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.1)
    return future.result()


def execute(handle):
    present, area = decode(AREA.type, handle.request.area, AREA.renames)
    handle.succeed()
    found = encode(FOUND.type, [area, {"tagId": 9}], FOUND.renames)
    return Scan.Result(found=found, outcome="succeeded" if present else "absent")


def main():
    rclpy.init()
    node = rclpy.create_node("k3_data")
    ActionServer(node, Scan, "scan", execute)
    client = ActionClient(node, Scan, "scan")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    deadline = time.monotonic() + 20
    while not client.server_is_ready() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.1)
    handle = spin_until(executor, client.send_goal_async(Scan.Goal(area=encode(AREA.type, VALUE, AREA.renames))))
    result = spin_until(executor, handle.get_result_async()).result
    present, found = decode(FOUND.type, result.found, FOUND.renames)
    print(json.dumps({
        "outcome": result.outcome,
        "found": found,
        "fits": fits(AREA.type, VALUE, AREA.renames),
        "partial_fits": fits(AREA.type, {"mode": "track"}, AREA.renames),
        "bad_fits": fits(AREA.type, {**VALUE, "tagId": "seven"}, AREA.renames),
        "zero_present": decode(AREA.type, encode(AREA.type, None, AREA.renames), AREA.renames)[0],
        "bad_is_zero": decode(AREA.type, encode(AREA.type, {"tagId": "x"}, AREA.renames), AREA.renames)[0],
    }))
    node.destroy_node()
    rclpy.shutdown()


main()
"""


def test_data_types_travel_as_messages(tmp_path: Path) -> None:
    """A private action of a model whose data types nest (and use a «RosMessage» type): the
    generated package builds, and a goal with nested values comes back field for field."""
    need_rclpy()
    from swarmgen import pipeline
    from tests.test_rclpy_backend import survey_model

    result = pipeline.compile_model(survey_model(tmp_path), backends=["rclpy"])
    prefix = PurePosixPath("rclpy/survey_interfaces")
    files = {p.relative_to(prefix): t for p, t in result.files.items() if p.is_relative_to(prefix)}
    build_and_install(_write(files, tmp_path / "survey_interfaces"))
    script = tmp_path / "data_roundtrip.py"
    script.write_text(DATA_SCRIPT.replace("@VALUE@", repr(AREA)), encoding="utf-8")
    env = _ros_env(tmp_path)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1])
    found = _output(_start(script, "both", env))
    zero_area = {
        "centre": {"x": 0.0, "y": 0.0}, "corners": [], "mode": "", "tagId": 9,
        "peak": {"x": 0.0, "y": 0.0, "z": 0.0}, "tags": [],
    }  # fmt: skip
    assert found["outcome"] == "succeeded"
    assert found["found"] == [AREA, zero_area]
    assert found["fits"] and not found["partial_fits"] and not found["bad_fits"]
    assert not found["zero_present"] and not found["bad_is_zero"]
