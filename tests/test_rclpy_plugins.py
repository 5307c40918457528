"""User behaviour code in the rclpy package (docs/plugins.md, "ROS 2 (rclpy)"): a user's
distribution implements SAR behaviours against the generated `behaviour_types` of the nodes
package; the swarm launcher serves them on the declared interfaces (action, service) over real
DDS on loopback, through the entry points of the model's group or `--library`; unusable
plug-ins are refused before ROS starts; real mypy checks the user's module.

No pose field is read or written here (the sample's pose type is the lead's to change): the
target's pose travels as an empty mapping, whatever its message."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
pytest.importorskip("psutil", reason="psutil comes with the `ros` extra: run `make ros`")

from swarmgen import pipeline
from swarmgen import ros_harness as harness
from tests import rosproc
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
NODES = "search_and_rescue_nodes"
GROUP = "search_and_rescue_swarm.behaviours"  # the asyncio package's group: one per model
DOMAIN = 201 + os.getpid() % 30  # one per test run, clear of test_ros_e2e's 101..200

# The user's platform: TakeOff logs its typed goal; Coverage reports target 7 and searches on
# until preempted (its cancellation is logged); TaskAllocation picks rover 2 (an output of the
# declared result) and announces it; Tracking logs the rover it got in its goal (that output,
# back through the member) and then ends the mission; Land is a service (std_srvs/Empty).
PLATFORM = '''\
"""A user's platform: SAR behaviours, typed against the generated rclpy package."""

import asyncio
import json
import os

from search_and_rescue_nodes._runtime.member import Library
from search_and_rescue_nodes.behaviour_types import (
    Context, CoverageBehaviour, CoverageRequest, CoverageResult, LandRequest, LandResult,
    TakeOffBehaviour, TakeOffRequest, TakeOffResult, TaskAllocationBehaviour,
    TaskAllocationRequest, TaskAllocationResult, TrackingRequest, TrackingResult, library,
)


def _log(**record: object) -> None:
    with open(os.environ["PLATFORM_LOG"], "a", encoding="utf-8") as out:
        out.write(json.dumps(record) + "\\n")


async def take_off(request: TakeOffRequest, context: Context) -> TakeOffResult:
    _log(behaviour="TakeOff", member=context.member_id, altitude=request.altitude,
         type=type(request.altitude).__name__)
    await asyncio.sleep(0.05)
    return TakeOffResult("succeeded")


async def coverage(request: CoverageRequest, context: Context) -> CoverageResult:
    await asyncio.sleep(0.05)
    context.emit("targetFound", {"target_id": 7, "pose": {}}, "swarm")
    try:
        await asyncio.sleep(3600)
    except asyncio.CancelledError:
        _log(behaviour="Coverage", cancelled=True)
        raise
    return CoverageResult("succeeded", target_id=7)


async def task_allocation(
    request: TaskAllocationRequest, context: Context
) -> TaskAllocationResult:
    _log(behaviour="TaskAllocation", target_id=request.target_id,
         pose=type(request.target_pose).__name__)
    context.emit("targetAssigned", {"target_id": request.target_id, "rover_id": 2}, "swarm")
    return TaskAllocationResult("succeeded", rover_id=2)


async def tracking(request: TrackingRequest, context: Context) -> TrackingResult:
    _log(behaviour="Tracking", target_id=request.target_id, rover_id=request.rover_id)
    context.emit("missionAbort", {}, "swarm")  # the platform ends the mission
    await asyncio.sleep(3600)
    return TrackingResult("targetLost")


async def land(request: LandRequest, context: Context) -> LandResult:
    _log(behaviour="Land", state=context.state)
    return LandResult("succeeded")


async def broken(request: TakeOffRequest, context: Context) -> TakeOffResult:
    raise RuntimeError("autopilot unreachable")


checked_take_off: TakeOffBehaviour = take_off
checked_coverage: CoverageBehaviour = coverage
checked_allocation: TaskAllocationBehaviour = task_allocation


def make_library(time_scale: float) -> Library:
    return library({"TakeOff": take_off, "Coverage": coverage,
                    "TaskAllocation": task_allocation, "Tracking": tracking, "Land": land})


def broken_library(time_scale: float) -> Library:
    return library({"TakeOff": broken})
'''

WRONG = PLATFORM.replace(
    'TaskAllocationResult("succeeded", rover_id=2)',
    'TaskAllocationResult("assigned", rover_id="2")',
)
POINTS = {
    "TakeOff": "sar_platform:take_off",
    "Coverage": "sar_platform:coverage",
    "TaskAllocation": "sar_platform:task_allocation",
    "Tracking": "sar_platform:tracking",
    "Land": "sar_platform:land",
}


@pytest.fixture(scope="module")
def nodes(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The SAR rclpy package compiled for this module, and the prefix of its user interface
    packages (all built)."""
    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    out = tmp_path_factory.mktemp("sar_plugins")
    pipeline.write_tree(result.files, out)
    prefix = harness.build_interfaces(out / "rclpy", model)
    return out / "rclpy" / NODES, prefix


def ros_env(nodes: tuple[Path, Path], site: Path, tmp: Path) -> dict[str, str]:
    """A ROS subprocess's environment: the user's site and the nodes package on its path."""
    path, prefix = nodes
    return harness.ros_env(
        tmp / "roslog", domain_id=DOMAIN, python_path=[site, path], prefixes=[prefix]
    )


def install(site: Path, dist: str, module: str, points: dict[str, str]) -> None:
    """A distribution `dist` 1.0 as pip leaves it: its module and a `.dist-info`."""
    site.mkdir(exist_ok=True)
    (site / f"{module}.py").write_text(PLATFORM + '\nNOT_CALLABLE = "sar"\n', encoding="utf-8")
    info = site / f"{dist}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n", encoding="utf-8"
    )
    lines = "".join(f"{name} = {target}\n" for name, target in points.items())
    (info / "entry_points.txt").write_text(f"[{GROUP}]\n{lines}", encoding="utf-8")


def launch(
    nodes: tuple[Path, Path], site: Path, tmp: Path, *args: str
) -> tuple[int, str, str, list[Any]]:
    """The UAV alone (no UGV) through launch: exit code, stdout, stderr, the platform's log."""
    env = ros_env(nodes, site, tmp)
    log = tmp / "platform.jsonl"
    env["PLATFORM_LOG"] = str(log)
    command = [
        sys.executable, "-m", f"{NODES}.launch_swarm", "--uav", "1", "--ugv", "0",
        "--time-scale", "0.05", "--events", *args,
    ]  # fmt: skip
    code, out, err = rosproc.finish(rosproc.start(command, env, tmp, 40), 50)
    records = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []
    return code, out, err, records


def test_entry_points_serve_the_mission_on_declared_interfaces(
    nodes: tuple[Path, Path], tmp_path: Path
) -> None:
    site = tmp_path / "site"
    install(site, "sar_platform", "sar_platform", POINTS)
    code, out, err, records = launch(
        nodes, site, tmp_path, "--station", "launch@0.5,missionStart@Loitering", "--duration", "200"
    )
    assert code == 0, err[-3000:]
    assert "behaviours from plug-ins: Coverage=sar_platform:coverage (sar_platform 1.0)" in err
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["members"]["uav_1"]["active"] == ["Landed"], summary
    assert "server_errors" not in summary
    by = {r["behaviour"]: r for r in records}
    assert by["TakeOff"]["type"] == "float" and by["TakeOff"]["member"] == "uav_1", records
    assert by["Coverage"] == {"behaviour": "Coverage", "cancelled": True}, records
    assert by["TaskAllocation"]["target_id"] == 7, records
    assert by["Tracking"] == {"behaviour": "Tracking", "target_id": 7, "rover_id": 2}, records
    assert by["Land"]["state"] == "Land", records
    # the trace (`--events`): what the user's code emitted, on /swarm/events
    events = [json.loads(line) for line in out.splitlines() if line.startswith("{")][:-1]
    assigned = [e for e in events if e.get("name") == "targetAssigned"]
    assert assigned and assigned[0]["data"] == {"target_id": 7, "rover_id": 2}, events


def test_library_option_and_a_failing_implementation(
    nodes: tuple[Path, Path], tmp_path: Path
) -> None:
    """--library's TakeOff raises: the goal is aborted (the member back in Idle), a log line
    names it, the node lives on; --no-plugins: the installed entry points are not used."""
    site = tmp_path / "site"
    install(site, "sar_platform", "sar_platform", POINTS)
    code, out, err, records = launch(
        nodes, site, tmp_path, "--library", "sar_platform:broken_library", "--no-plugins",
        "--station", "launch@0.5", "--duration", "40",
    )  # fmt: skip
    assert code == 1, err[-3000:]  # a server error, as a failing script
    summary = json.loads(out.strip().splitlines()[-1])
    active = summary["members"]["uav_1"]["active"]
    assert "Idle" in active and "TakeOff" not in active, summary
    (error,) = summary["server_errors"]["uav_1"]
    assert "TakeOff: user implementation failed: RuntimeError('autopilot unreachable')" in error
    assert "user implementation failed" in err and "plug-ins" not in err
    assert records == []


@pytest.mark.parametrize(
    ("points", "says"),
    [
        ({"Tracker": "sar_platform:coverage"}, "no behaviour 'Tracker' in this package"),
        ({"Coverage": "sar_platform:missing"}, "does not load"),
        ({"Coverage": "no_such_module:coverage"}, "does not load"),
        ({"Coverage": "sar_platform:NOT_CALLABLE"}, "is not callable"),
    ],
)
def test_unusable_plugins_are_refused(
    nodes: tuple[Path, Path], tmp_path: Path, points: dict[str, str], says: str
) -> None:
    site = tmp_path / "site"
    install(site, "sar_platform", "sar_platform", points)
    code, out, err, _ = launch(nodes, site, tmp_path, "--station", "launch@0.5")
    assert code == 2 and says in err and out == "", err[-2000:]
    assert "Traceback" not in err


def test_two_providers_are_refused_by_both_executables(
    nodes: tuple[Path, Path], tmp_path: Path
) -> None:
    site = tmp_path / "site"
    install(site, "sar_platform", "sar_platform", {"Land": "sar_platform:land"})
    install(site, "other_platform", "other_platform", {"Land": "other_platform:land"})
    code, _, err, _ = launch(nodes, site, tmp_path)
    assert code == 2 and "behaviour 'Land' has 2 providers" in err, err[-2000:]
    assert "sar_platform 1.0" in err and "other_platform 1.0" in err
    env = ros_env(nodes, site, tmp_path)
    served = f"import sys; from {NODES}.launch_swarm import simulated; sys.exit(simulated())"
    code, _, err = rosproc.finish(
        rosproc.start([sys.executable, "-c", served], env, tmp_path, 30), 40
    )
    assert code == 2 and "behaviour 'Land' has 2 providers" in err, err[-2000:]


def mypy(nodes: tuple[Path, Path], module: Path) -> subprocess.CompletedProcess[str]:
    """Real `mypy --strict` on the user's module, the nodes package on MYPYPATH."""
    mypy_bin = Path(sys.executable).with_name("mypy")
    return subprocess.run(
        [
            str(mypy_bin),
            "--strict",
            "--cache-dir",
            str(module.parent.parent / ".mypy"),
            str(module),
        ],
        capture_output=True,
        text=True,
        env={**os.environ, "MYPYPATH": str(nodes[0])},
        timeout=180,
        cwd=module.parent,
    )


@pytest.mark.skipif(
    shutil.which("mypy", path=str(Path(sys.executable).parent)) is None,
    reason="mypy is not installed in this interpreter's environment",
)
def test_mypy_checks_user_implementations(nodes: tuple[Path, Path], tmp_path: Path) -> None:
    right = tmp_path / "right" / "sar_platform.py"
    wrong = tmp_path / "wrong" / "sar_platform.py"
    for path, text in ((right, PLATFORM), (wrong, WRONG)):
        path.parent.mkdir()
        path.write_text(text, encoding="utf-8")
    passed = mypy(nodes, right)
    assert passed.returncode == 0, passed.stdout + passed.stderr
    failed = mypy(nodes, wrong)
    out = failed.stdout
    assert failed.returncode == 1, out + failed.stderr
    assert 'Argument 1 to "TaskAllocationResult" has incompatible type' in out, out
    assert 'Argument "rover_id" to "TaskAllocationResult" has incompatible type "str"' in out, out
    assert "Found 2 errors in 1 file" in out, out
