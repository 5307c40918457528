"""Behaviour plug-ins (docs/plugins.md): a user's distribution provides typed implementations of
SAR behaviours through the entry-point group `search_and_rescue_swarm.behaviours` (a real
`.dist-info` on the subprocess's path, read by the real importlib.metadata), or through
`--library`; conflicting providers are refused; real mypy checks a user's implementation against
the generated `behaviour_types` module."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from swarmgen.pipeline import compile_model, write_tree
from tests.hostile import SAMPLE, assert_clean, assert_refused, run_module

PACKAGE = "search_and_rescue_swarm"
GROUP = f"{PACKAGE}.behaviours"
EVENTS = "launch@0.05,missionStart@0.15,missionAbort@1.5"

# The user's module: Coverage reports a target (an event) and searches on until preempted;
# TaskAllocation logs the typed request it gets (the target, read from member data) and picks
# rover 2, after which the UAV is in Tracking.
PLATFORM = '''\
"""A user's platform: two SAR behaviours, typed against the generated package."""

import asyncio
import json
import os

from search_and_rescue_swarm._runtime.member import Library
from search_and_rescue_swarm.behaviour_types import (
    Context,
    CoverageBehaviour,
    CoverageRequest,
    CoverageResult,
    Header,
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    TaskAllocationBehaviour,
    TaskAllocationRequest,
    TaskAllocationResult,
    library,
)
from search_and_rescue_swarm.behaviours import simulated_library


def _log(**record: object) -> None:
    with open(os.environ["PLATFORM_LOG"], "a", encoding="utf-8") as out:
        out.write(json.dumps(record) + "\\n")


async def coverage(request: CoverageRequest, context: Context) -> CoverageResult:
    _log(behaviour="Coverage", member=context.member_id, altitude=request.altitude,
         type=type(request.altitude).__name__)
    await asyncio.sleep(0.02)
    where = {"header": {"frame_id": "map"}, "pose": {"position": {"x": 1.5, "y": -2.0, "z": 0}}}
    context.emit("targetFound", {"target_id": 7, "pose": where}, "swarm")
    await asyncio.sleep(3600)  # until preempted
    found = Pose(Point(1.5, -2.0, 0.0), Quaternion(0.0, 0.0, 0.0, 1.0))
    return CoverageResult("succeeded", target_id=7, target_pose=PoseStamped(Header("map"), found))


async def task_allocation(
    request: TaskAllocationRequest, context: Context
) -> TaskAllocationResult:
    pose = request.target_pose
    at = pose.pose.position
    _log(behaviour="TaskAllocation", target_id=request.target_id,
         pose=[type(pose).__name__, pose.header.frame_id, at.x, at.y, at.z, type(at.z).__name__,
               pose.pose.orientation.w])
    return TaskAllocationResult("succeeded", rover_id=2)


checked_coverage: CoverageBehaviour = coverage
checked_allocation: TaskAllocationBehaviour = task_allocation


def make_library(time_scale: float) -> Library:
    return library(
        {"Coverage": coverage, "TaskAllocation": task_allocation}, simulated_library(time_scale)
    )
'''

# The same module with two mistakes mypy must find.
WRONG = PLATFORM.replace(
    'CoverageResult("succeeded", target_id=7,', 'CoverageResult("succeeded", target_id="7",'
).replace('TaskAllocationResult("succeeded"', 'TaskAllocationResult("assigned"')


@pytest.fixture(scope="module")
def package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The SAR asyncio package, compiled for this module."""
    out = tmp_path_factory.mktemp("sar")
    compilation = compile_model(SAMPLE, ["asyncio"])
    write_tree(compilation.files, out)
    return out / "asyncio"


def install(site: Path, dist: str, version: str, module: str, points: dict[str, str]) -> None:
    """A distribution `dist` as pip leaves it: its module and a `.dist-info` with entry points."""
    site.mkdir(exist_ok=True)
    (site / f"{module}.py").write_text(PLATFORM, encoding="utf-8")
    info = site / f"{dist}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n", encoding="utf-8"
    )
    lines = "".join(f"{name} = {target}\n" for name, target in points.items())
    (info / "entry_points.txt").write_text(f"[{GROUP}]\n{lines}", encoding="utf-8")


def run_swarm(package: Path, site: Path, log: Path, *args: str) -> tuple[object, list[dict]]:
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), str(package)]),
        "PLATFORM_LOG": str(log),
    }
    outcome = run_module(
        PACKAGE,
        "--member",
        "UAV",
        "--events",
        EVENTS,
        "--time-scale",
        "0.05",
        "--duration",
        "3",
        *args,
        cwd=site,
        env=env,
        timeout=30,
    )
    records = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() else []
    return outcome, records


def assert_mission(outcome: object, records: list[dict]) -> None:
    """Coverage ran typed (a float altitude), the target it reported reached TaskAllocation's
    typed request (nested PoseStamped dataclasses, the orientation the event did not give
    filled with the model's default), whose outcome took the UAV to Tracking."""
    assert_clean(outcome, (0,))
    steps = [json.loads(line) for line in outcome.stdout.splitlines()]  # type: ignore[attr-defined]
    events = [step["event"] for step in steps]
    assert "targetFound" in events, outcome  # only the plug-in Coverage reports targets
    allocated = events.index("done.invoke.SelectRover.succeeded")
    assert "Tracking" in steps[allocated]["active"], outcome
    assert events[-1] == "done.invoke.Land.succeeded", outcome
    coverage = next(r for r in records if r["behaviour"] == "Coverage")
    assert coverage["type"] == "float" and coverage["member"] == "1"
    allocation = next(r for r in records if r["behaviour"] == "TaskAllocation")
    assert allocation["target_id"] == 7, records
    assert allocation["pose"] == ["PoseStamped", "map", 1.5, -2.0, 0.0, "float", 1.0], records


def test_entry_points_provide_behaviours(package: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    points = {"Coverage": "sar_platform:coverage", "TaskAllocation": "sar_platform:task_allocation"}
    install(site, "sar_platform", "1.0", "sar_platform", points)
    outcome, records = run_swarm(package, site, tmp_path / "log.jsonl")
    assert_mission(outcome, records)
    assert "behaviours from plug-ins: Coverage=sar_platform:coverage (sar_platform 1.0)" in (
        outcome.stderr
    )


def test_library_option_runs_the_same_module(package: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    site.mkdir()
    (site / "sar_platform.py").write_text(PLATFORM, encoding="utf-8")
    log = tmp_path / "log.jsonl"
    outcome, records = run_swarm(package, site, log, "--library", "sar_platform:make_library")
    assert_mission(outcome, records)
    assert "plug-ins" not in outcome.stderr


def test_no_plugins_runs_the_simulated_behaviours(package: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    install(site, "sar_platform", "1.0", "sar_platform", {"Coverage": "sar_platform:coverage"})
    outcome, records = run_swarm(package, site, tmp_path / "log.jsonl", "--no-plugins")
    assert_clean(outcome, (0,))
    assert records == [] and "done.invoke.Coverage.succeeded" not in outcome.stdout


def test_two_providers_of_one_behaviour_are_refused(package: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    install(site, "sar_platform", "1.0", "sar_platform", {"Tracking": "sar_platform:coverage"})
    install(
        site, "other_platform", "2.0", "other_platform", {"Tracking": "other_platform:coverage"}
    )
    outcome, records = run_swarm(package, site, tmp_path / "log.jsonl")
    assert_refused(outcome, exit=2, says="behaviour 'Tracking' has 2 providers")
    assert "sar_platform 1.0" in outcome.stderr and "other_platform 2.0" in outcome.stderr
    assert outcome.stdout == "" and records == []


@pytest.mark.parametrize(
    ("points", "says"),
    [
        ({"Tracker": "sar_platform:coverage"}, "no behaviour 'Tracker' in this package"),
        ({"Coverage": "sar_platform:missing"}, "does not load"),
        ({"Coverage": "no_such_module:coverage"}, "does not load"),
        ({"Coverage": "sar_platform:PLATFORM_NAME"}, "is not callable"),
    ],
)
def test_unusable_plugins_are_refused(
    package: Path, tmp_path: Path, points: dict[str, str], says: str
) -> None:
    site = tmp_path / "site"
    install(site, "sar_platform", "1.0", "sar_platform", points)
    with (site / "sar_platform.py").open("a", encoding="utf-8") as module:
        module.write('\nPLATFORM_NAME = "sar"\n')
    outcome, _ = run_swarm(package, site, tmp_path / "log.jsonl")
    assert_refused(outcome, exit=2, says=says)


def mypy(package: Path, module: Path) -> subprocess.CompletedProcess[str]:
    mypy_bin = Path(sys.executable).with_name("mypy")
    env = {**os.environ, "MYPYPATH": str(package)}
    cache = module.parent / ".mypy_cache"
    return subprocess.run(
        [str(mypy_bin), "--strict", "--cache-dir", str(cache), str(module)],
        capture_output=True,
        text=True,
        env=env,
        timeout=180,
        cwd=module.parent,
    )


@pytest.mark.skipif(
    shutil.which("mypy", path=str(Path(sys.executable).parent)) is None,
    reason="mypy is not installed in this interpreter's environment",
)
def test_mypy_checks_user_implementations(package: Path, tmp_path: Path) -> None:
    right = tmp_path / "right" / "sar_platform.py"
    wrong = tmp_path / "wrong" / "sar_platform.py"
    for path, text in ((right, PLATFORM), (wrong, WRONG)):
        path.parent.mkdir()
        path.write_text(text, encoding="utf-8")
    passed = mypy(package, right)
    assert passed.returncode == 0, passed.stdout + passed.stderr
    failed = mypy(package, wrong)
    assert failed.returncode == 1, failed.stdout + failed.stderr
    out = failed.stdout
    assert 'Argument "target_id" to "CoverageResult" has incompatible type "str"' in out, out
    assert (
        'Argument 1 to "TaskAllocationResult" has incompatible type "Literal[\'assigned\']"' in out
    ), out
    assert "Found 2 errors in 1 file" in out, out


def test_generated_module_text(package: Path) -> None:
    text = (package / PACKAGE / "behaviour_types.py").read_text()
    assert f'GROUP = "{GROUP}"' in text
    assert 'outcome: Literal["succeeded", "aborted", "preempted", "targetLost"]' in text
    assert "target_pose: PoseStamped | None = None" in text
    assert (
        textwrap.dedent('''\
        class Point:
            """Data type Point."""

            x: float
        ''')
        in text
    )
