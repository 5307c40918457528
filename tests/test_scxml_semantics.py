"""The emitted SCXML behaves as the model says, run in an independent engine (Qt SCXML).

Behaviour ends arrive as `done.invoke.<state>.<outcome>` events, as the swarmgen runtime sends
them; swarm and station events arrive under their own names with their data.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import pipeline
from tests.conftest import ROOT, qt_run


def _document(model: str, member: str, tmp_path: Path) -> Path:
    result = pipeline.compile_model(ROOT / model)
    path = tmp_path / f"{member}.scxml"
    path.write_text(
        result.files[pipeline.PurePosixPath("scxml", f"{member}.scxml")], encoding="utf-8"
    )
    return path


def _leaves(report: dict[str, object], leaves: set[str]) -> set[str]:
    active = report["active"]
    assert isinstance(active, list)
    return {name for name in active if name in leaves}


@pytest.fixture
def uav(tmp_path: Path, qt_available: None) -> Path:
    return _document("sample_models/sar/sar.xmi", "UAV", tmp_path)


UAV_LEAVES = {
    "Idle",
    "TakeOff",
    "Loitering",
    "Coverage",
    "SelectRover",
    "Tracking",
    "LocalCoverage",
    "Land",
    "Landed",
}


def test_sar_uav_mission(uav: Path) -> None:
    reports = qt_run(
        uav,
        [
            ("launch", None),
            ("done.invoke.TakeOff.succeeded", None),
            ("missionStart", None),
            (
                "done.invoke.Coverage.succeeded",
                None,
            ),  # Coverage leaves only on the targetFound event
            ("targetFound", {"target_id": 7, "pose": {"pose": {"position": {"x": 1.0, "y": 2.0}}}}),
            ("done.invoke.SelectRover.succeeded", {"rover_id": 3}),
            ("done.invoke.Coverage.succeeded", None),  # an outcome of another state is not ours
            ("done.invoke.Tracking.targetLost", None),
            ("done.invoke.LocalCoverage.succeeded", {"target_id": 8}),
            ("missionAbort", None),
            ("done.invoke.Land.succeeded", None),
        ],
    )
    leaves = [_leaves(r, UAV_LEAVES) for r in reports]
    assert leaves == [
        {"Idle"},
        {"TakeOff"},
        {"Loitering"},
        {"Coverage"},
        {"Coverage"},
        {"SelectRover"},
        {"Tracking"},
        {"Tracking"},
        {"LocalCoverage"},
        {"Tracking"},
        {"Land"},
        {"Landed"},
    ]
    assert {"TargetMonitoring", "Positioning"} <= set(reports[3]["active"])  # parallel regions run
    data = reports[6]["data"]
    assert isinstance(data, dict)
    assert data["target_id"] == 7 and data["rover_id"] == 3
    pose = data["target_pose"]  # the PoseStamped the event gave, filled by the value rule
    assert pose["pose"]["position"] == {"x": 1.0, "y": 2.0, "z": 0.0}
    assert pose["header"]["frame_id"] == "map" and pose["pose"]["orientation"]["w"] == 1.0
    final = reports[9]["data"]
    assert isinstance(final, dict) and final["target_id"] == 8  # output written back on the outcome


PATROL_LEAVES = {
    "Waiting", "GetZone", "GoToZone__Moving", "Sweeping", "Approach", "GoToDock__Moving",
    "Charging", "Monitoring", "Stopped",
}  # fmt: skip


def test_patrol_guards_history_submachines_and_raise(tmp_path: Path, qt_available: None) -> None:
    scout = _document("sample_models/patrol/patrol.xmi", "Scout", tmp_path)
    reports = qt_run(
        scout,
        [
            ("missionStart", None),
            ("done.invoke.GetZone.succeeded", {"zone_id": 2, "zone_pose": {"x": 5}}),
            (
                "done.invoke.GoToZone__Moving.aborted",
                None,
            ),  # choice: retries < max_retries -> retry
            (
                "done.invoke.GoToZone__Moving.succeeded",
                None,
            ),  # final state -> completion -> Sweeping
            ("intrusion", {"zone": 1, "pose": {"x": 9}}),  # guard: another zone, ignored
            ("intrusion", {"zone": 2, "pose": {"x": 9}}),
            ("batteryStatus", {"battery": 50.0}),  # guard false
            ("batteryStatus", {"battery": 10.0}),  # raise lowBattery -> GoToDock
            ("done.invoke.GoToDock__Moving.succeeded", None),
            (
                "done.invoke.Charging.succeeded",
                {"battery": 100.0},
            ),  # deep history: back to Approach
            ("recall", None),
        ],
    )
    leaves = [_leaves(r, PATROL_LEAVES) for r in reports]
    assert leaves == [
        {"Waiting"},
        {"GetZone", "Monitoring"},
        {"GoToZone__Moving", "Monitoring"},
        {"GoToZone__Moving", "Monitoring"},
        {"Sweeping", "Monitoring"},
        {"Sweeping", "Monitoring"},
        {"Approach", "Monitoring"},
        {"Approach", "Monitoring"},
        {"GoToDock__Moving", "Monitoring"},
        {"Charging", "Monitoring"},
        {"Approach", "Monitoring"},
        {"Stopped"},
    ]
    data = [r["data"] for r in reports]
    assert (
        data[2]["goal_pose"] == {"x": 5, "y": 0, "z": 0}
        and data[3]["retries"] == 1
        and data[4]["retries"] == 0
    )
    assert data[6]["alarm_raised"] is True and data[6]["intruder_pose"] == {"x": 9, "y": 0, "z": 0}
    assert data[8]["low_battery"] is True and data[8]["battery"] == 10.0
    assert data[10]["low_battery"] is False and data[10]["battery"] == 100.0
