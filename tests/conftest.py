"""Shared fixtures: paths, the W3C SCXML schema, the Qt SCXML engine and the golden-file flag."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path

import pytest
import xmlschema

from tests.skips import (  # the skip policy's hooks, active in every run
    REFERENCE_REASON,
    pytest_collectreport,
    pytest_runtest_logreport,
    pytest_sessionfinish,
)

__all__ = ["pytest_collectreport", "pytest_runtest_logreport", "pytest_sessionfinish"]

ROOT = Path(__file__).resolve().parent.parent
# The external reference corpus (xmi_samples/, scxml_xsd/): CI has it in ../shared/reference,
# a user's clone does not; SWARMGEN_REFERENCE_DIR points elsewhere. Without it, the tests over it
# are reported as skipped, the only skips `make test` allows (tests/skips.py).
REFERENCE = Path(
    os.environ.get("SWARMGEN_REFERENCE_DIR") or ROOT.parent / "shared" / "reference"
).resolve()
XMI_SAMPLES = REFERENCE / "xmi_samples"
SCXML_XSD = REFERENCE / "scxml_xsd"
SAMPLE_MODELS = sorted(ROOT.glob("sample_models/*/*.xmi"))
HAS_SHARED = XMI_SAMPLES.is_dir() and SCXML_XSD.is_dir()


def reference_absent(what: Path | str = REFERENCE) -> str:
    """The skip reason for a test over the reference corpus (the one `make test` allows)."""
    return f"{REFERENCE_REASON} (set SWARMGEN_REFERENCE_DIR, or ../shared/reference): {what}"


requires_shared = pytest.mark.skipif(not HAS_SHARED, reason=reference_absent())
SYSTEM_PYTHON = "/usr/bin/python3"
QT_SCRIPT = ROOT / "swarmgen" / "scxml" / "qt_script.py"


# The test files that take longest (a clean clone's run, ROS 2 interface builds included), run
# first. `make test` hands files to two xdist workers in collection order (`--dist loadfile
# --no-loadscope-reorder`): a long file started last would keep one worker busy alone at the end.
# Order only: a file missing here runs after these, in pytest's order.
SLOW_FIRST = (
    "test_hostile_output.py",
    "test_equivalence.py",
    "test_colcon.py",
    "test_ros_declared.py",
    "test_bad_input.py",
    "test_cpswarm_dialect.py",
    "test_hostile_runtime.py",
    "test_dask_executor.py",
    "test_udp_recovery.py",
    "test_hostile_cli.py",
    "test_hostile_models_size.py",
    "test_modelio_frontend.py",
    "test_wheel.py",
    "test_optimize.py",
    "test_detailed_world.py",
    "test_udp_swarm.py",
    "test_verify.py",
    "test_ros_declared_edges.py",
    "test_ros_simulated_declared.py",
    "test_conformance_irp.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put the files of SLOW_FIRST first (a stable sort: every other order is kept)."""
    rank = {name: index for index, name in enumerate(SLOW_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(SLOW_FIRST)))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--update-golden",
        action="store_true",
        help="rewrite tests/golden/ from the current output (review the diff before committing)",
    )


@pytest.fixture(scope="session")
def update_golden(request: pytest.FixtureRequest) -> bool:
    return bool(request.config.getoption("--update-golden"))


def xmi_sample_files() -> list[Path]:
    """The reference XMI files (none without the corpus: the tests over them then run on the
    sample models only, or are skipped by `requires_shared`)."""
    if not XMI_SAMPLES.is_dir():
        return []
    return sorted(p for p in XMI_SAMPLES.iterdir() if p.suffix in {".xmi", ".uml"})


@pytest.fixture(scope="session")
def scxml_schema() -> xmlschema.XMLSchema:
    if not (SCXML_XSD / "scxml.xsd").is_file():
        pytest.skip(reference_absent(SCXML_XSD / "scxml.xsd"))
    return xmlschema.XMLSchema(
        str(SCXML_XSD / "scxml.xsd"),
        uri_mapper={"http://www.w3.org/2001/xml.xsd": str(SCXML_XSD / "xml.xsd")},
    )


def qt_load(paths: Iterable[Path]) -> list[dict[str, object]]:
    """Load SCXML files in Qt SCXML (system python3 + PySide2), start them, report errors."""
    files = [str(p) for p in paths]
    env = {k: v for k, v in os.environ.items() if not k.startswith("_ROS_WHEELS")}
    env["QT_QPA_PLATFORM"] = "offscreen"
    completed = subprocess.run(
        [SYSTEM_PYTHON, str(QT_SCRIPT), "load", *files],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    return [json.loads(line) for line in completed.stdout.splitlines() if line.strip()]


@pytest.fixture(scope="session")
def qt_available() -> None:
    probe = subprocess.run(
        [SYSTEM_PYTHON, "-c", "import PySide2.QtScxml"], capture_output=True, check=False
    )
    if probe.returncode != 0:  # a failure under `make test`, which installs it (tests/skips.py)
        pytest.skip(
            "Qt SCXML is not installed: run `make sysdeps` (Debian python3-pyside2.qtscxml)"
        )


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "swarmgen", *args],
        capture_output=True,
        text=True,
        cwd=cwd or ROOT,
        timeout=120,
        check=False,
    )


def which(name: str) -> str | None:
    return shutil.which(name)


def tool(name: str) -> str:
    """A console script of the environment running the tests: beside its interpreter (a venv's
    bin/, wherever that venv is), else on PATH."""
    beside = Path(sys.executable).parent / name
    if beside.is_file():
        return str(beside)
    found = shutil.which(name)
    assert found, f"{name} is neither beside {sys.executable} nor on PATH: pip install -e '.[dev]'"
    return found


def qt_run(
    path: Path, steps: list[tuple[str, dict[str, object] | None]]
) -> list[dict[str, object]]:
    """Run one SCXML document in Qt SCXML through `steps`; one report per step (start first)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("_ROS_WHEELS")}
    env["QT_QPA_PLATFORM"] = "offscreen"
    completed = subprocess.run(
        [SYSTEM_PYTHON, str(QT_SCRIPT), "run", str(path), json.dumps(steps)],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    reports = [json.loads(line) for line in completed.stdout.splitlines() if line.strip()]
    assert reports and "step" in reports[0], reports[:1]
    return reports
