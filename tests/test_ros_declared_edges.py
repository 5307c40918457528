"""Declared interfaces, the rough edges (issue 12 leftovers), on real DDS and real bags.

Feedback of declared actions in traces (coalesced) and bags, a declared action's `timeout_s`,
a server that never answers a goal, a publisher behaviour that waits for its subscriber (and
one that has none), strict conversion of goal fields on the private and the declared path, and
empty enumeration fields inside messages read as the first literal. The platform
(`tests/ros_edges.py platform`) and the member driver run in two processes under time limits,
LOCALHOST discovery and a ROS_DOMAIN_ID of this test run.
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
pytest.importorskip("rosbags", reason="rosbags comes with the `ros` extra: run `make ros`")

from swarmgen.ros.interfaces import build_and_install
from swarmgen.ros_harness import ros_env
from swarmgen.trace.reader import read_run
from swarmgen.trace.recorder import BagRecorder, VirtualClock
from tests.conftest import ROOT
from tests.hostile import run_module
from tests.ros_platform.packages import build_packages

DOMAIN = 231 + os.getpid() % 2  # apart from the other ROS tests (1..230)
NAMESPACE = "/e1"
CASES = (
    "feedback", "declared_bad_value", "timeout", "no_answer", "late_subscriber",
    "no_subscriber", "private_ok", "private_bad_value",
)  # fmt: skip


# --- messages and bags, no ROS graph -----------------------------------------------------------


def test_private_fields_convert_strictly_and_enums_fill() -> None:
    from swarmgen.ros.runtime.convert import ConversionError, filled
    from swarmgen.ros.runtime.messages import encode, fits, to_ros

    assert to_ros("int64", 3.0) == 3 and to_ros("float64", 2) == 2.0
    assert to_ros("int64", None) == 0 and to_ros("enum", None) == "" and to_ros("json", None) == ""
    assert to_ros("float64[]", [1, 2.5]) == [1.0, 2.5]
    for type_, value in [("int64", 2.5), ("int64", 2**63), ("float64", "x"), ("bool", 1),
                         ("string", 5), ("enum", 3), ("float64[]", "ab"), ("int64[]", [1, 0.5])]:  # fmt: skip
        with pytest.raises(ConversionError):
            to_ros(type_, value, where="goal")
        assert encode(type_, value) in (0, 0.0, False, "", [], [1, 0])  # lenient: the zero
    assert not fits("string", 5) and fits("string", "5") and fits("json", object())
    blanks = (("mode", "search"), ("inner", (("kind", "a"),)))
    value = {"mode": "", "inner": [{"kind": ""}, {"kind": "b"}], "name": ""}
    assert filled(value, blanks) == {"mode": "search", "inner": [{"kind": "a"}, {"kind": "b"}],
                                     "name": ""}  # fmt: skip
    assert filled("", "first") == "first" and filled(["", "x"], "first") == ["first", "x"]


def test_feedback_records_in_a_bag(tmp_path: Path) -> None:
    from rosbags.highlevel import AnyReader

    from swarmgen.ros.runtime.declared import FeedbackRecord

    bag = tmp_path / "bag"
    with BagRecorder(bag, clock=VirtualClock()) as recorder:
        recorder.record_event("launch", None, "station", 0)
        record = FeedbackRecord("uav_1", "Moving", "GoTo", {"remaining": 2.5}, 7, 1.5)
        recorder.feedback(_Member("uav_1"), record)
    with AnyReader([bag]) as reader:
        found = [
            (c.topic, c.msgtype, reader.deserialize(raw, c.msgtype))
            for c, _, raw in reader.messages()
            if c.topic.endswith("/feedback")
        ]
    ((topic, msgtype, message),) = found
    assert (topic, msgtype) == ("/uav_1/feedback", "swarmgen_msgs/msg/Feedback")
    assert (message.state, message.behaviour, message.count) == ("Moving", "GoTo", 7)
    assert json.loads(message.values) == {"remaining": 2.5}
    assert (message.stamp.sec, message.stamp.nanosec) == (1, 500_000_000)
    assert [e.name for e in read_run([bag]).events] == ["launch"]  # timelines ignore feedback


class _Member:
    def __init__(self, member_id: str) -> None:
        self.member_id = member_id
        self.engine = self

    def active(self) -> list[str]:
        return []


# --- on real DDS -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """platform_msgs and this test's private package built into the venv (skipped when
    current); the environment of the ROS processes."""
    from tests.ros_edges import package_files

    work = tmp_path_factory.mktemp("edges")
    build_packages(work / "packages")
    package = work / "sgedges_interfaces"
    for path, text in package_files().items():
        (package / str(path)).parent.mkdir(parents=True, exist_ok=True)
        (package / str(path)).write_text(text, encoding="utf-8")
    build_and_install(package)
    return ros_env(work / "roslog", domain_id=DOMAIN, python_path=[ROOT])


@pytest.fixture(scope="module")
def platform(env: dict[str, str], tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The platform process (stopped at the end); yields the file its JSON lines go to."""
    log = tmp_path_factory.mktemp("edges_platform") / "platform.jsonl"
    with log.open("wb") as out:
        command = ["timeout", "-k", "5", "120", sys.executable, "-m", "tests.ros_edges"]
        process = subprocess.Popen(
            [*command, "platform", NAMESPACE], cwd=ROOT, env=env, stdout=out,
            stderr=subprocess.DEVNULL, start_new_session=True,
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


@pytest.fixture(scope="module")
def report(
    env: dict[str, str], platform: Path, tmp_path_factory: pytest.TempPathFactory
) -> dict[str, Any]:
    """Every case, in one member process; its stderr (the ROS log) under `"stderr"`."""
    bag = tmp_path_factory.mktemp("edges_bag") / "feedback"
    outcome = run_module(
        "tests.ros_edges", "drive", NAMESPACE, bag, *CASES, cwd=ROOT, env=env, timeout=120
    )
    assert outcome.exit == 0, str(outcome)
    result: dict[str, Any] = json.loads(outcome.stdout.strip().splitlines()[-1])
    print(", ".join(f"{c}: {r['seconds']} s" for c, r in result.items()))
    result["stderr"] = outcome.stderr
    result["bag"] = bag
    return result


def _platform_saw(log: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in log.read_text().splitlines() if line.strip()]


def test_feedback_is_coalesced_into_trace_records_and_the_bag(report: dict[str, Any]) -> None:
    from rosbags.highlevel import AnyReader

    case = report["feedback"]
    assert case["final"] == ["Succeeded"], case
    records = case["records"]
    print(f"{len(records)} records for 40 feedbacks: {[r['count'] for r in records]}")
    assert 1 <= len(records) <= 6  # 40 feedbacks over about 0.4 s, one record per 0.25 s
    assert {r["kind"] for r in records} == {"feedback"}
    assert {(r["state"], r["behaviour"]) for r in records} == {("Run", "Act")}
    assert records[-1]["values"] == {"remaining": 1.0}  # the last one came before the outcome
    assert 1 < sum(r["count"] for r in records) <= 40
    with AnyReader([report["bag"]]) as reader:
        bagged = [
            json.loads(reader.deserialize(raw, c.msgtype).values)
            for c, _, raw in reader.messages()
            if c.msgtype == "swarmgen_msgs/msg/Feedback"
        ]
    assert bagged == [r["values"] for r in records]


def test_empty_enumeration_fields_read_as_the_first_literal(report: dict[str, Any]) -> None:
    # declared: GoTo's empty `outcome` string is the enumeration output `mode`
    assert report["feedback"]["outputs"] == {"mode": "search"}
    # private: the result's nested Zone.mode is empty
    case = report["private_ok"]
    assert case["final"] == ["Succeeded"], case
    assert case["outputs"] == {"zone": {"mode": "search", "name": "a"}}


def test_declared_action_timeout_cancels_and_aborts(report: dict[str, Any], platform: Path) -> None:
    case = report["timeout"]
    assert case["final"] == ["Aborted"], case
    assert 0.45 <= case["seconds"] < 2.0
    assert case["errors"] == []  # a timeout is a warning, as for services
    assert "no result from 'slow_go_to' within 0.5 s" in report["stderr"]
    cancels = [e for e in _platform_saw(platform) if e["event"] == "cancel"]
    assert cancels and cancels[0]["requested"] is True


def test_goal_never_answered_aborts(report: dict[str, Any], platform: Path) -> None:
    case = report["no_answer"]
    assert case["final"] == ["Aborted"], case
    assert 0.45 <= case["seconds"] < 2.0
    assert any("not answered by 'mute_go_to' within 0.5 s" in e for e in case["errors"])
    assert any(
        e["event"] == "goal" and e["action"] == "mute_go_to" for e in _platform_saw(platform)
    )


def test_publisher_waits_for_a_subscriber(report: dict[str, Any]) -> None:
    case = report["late_subscriber"]
    assert case["final"] == ["Succeeded"], case
    subscribed, *messages = case["heard"]
    assert subscribed["subscribed"] >= 0.5
    assert messages == [{"x": 4.5}]  # published after the late match, not lost
    assert case["seconds"] >= 0.45


def test_publisher_without_subscriber_publishes_after_its_bound(report: dict[str, Any]) -> None:
    case = report["no_subscriber"]
    assert case["final"] == ["Succeeded"], case
    assert 0.25 <= case["seconds"] < 1.5
    assert "no subscriber on '/e1/nobody_pose' within 0.3 s: published anyway" in report["stderr"]


def test_values_that_do_not_convert_abort_on_both_paths(
    report: dict[str, Any], platform: Path
) -> None:
    private = report["private_bad_value"]
    assert private["final"] == ["Aborted"], private
    assert any("cannot send sgedges_interfaces/action/Survey" in e for e in private["errors"])
    assert any("expected an integer, got float 2.5" in e for e in private["errors"])
    declared = report["declared_bad_value"]
    assert declared["final"] == ["Aborted"], declared
    assert any("cannot send platform_msgs/action/GoTo" in e for e in declared["errors"])
    surveys = [e for e in _platform_saw(platform) if e.get("action") == "survey"]
    assert surveys == [  # only the good goal reached the server, with its values
        {"action": "survey", "count": 3, "event": "goal", "mode": "track", "name": "a"}
    ]
