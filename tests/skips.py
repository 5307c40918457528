"""The skip policy: a bare `pytest` without the extras skips, saying why; `make test` installs
every dependency, so there (SWARMGEN_STRICT_SKIPS=1) any skip but the reference corpus's fails.

tests/conftest.py re-exports the hooks below; `pytest -p tests.skips` loads them alone.
"""

from __future__ import annotations

import importlib.util
import os
from types import ModuleType

import pytest

STRICT_ENV = "SWARMGEN_STRICT_SKIPS"
# Every skip over the external reference corpus starts with this (tests/conftest.py).
REFERENCE_REASON = "reference corpus absent"
# ... or this: what a user's machine may not allow (network namespaces need root); CI runs as
# root, so there these tests run.
PRIVILEGE_REASON = "needs privileges"
ROS_EXTRA = "comes with the `ros` extra: run `make ros`"

HAS_RCLPY = importlib.util.find_spec("rclpy") is not None
RCLPY_REASON = f"rclpy {ROS_EXTRA}"
requires_rclpy = pytest.mark.skipif(not HAS_RCLPY, reason=RCLPY_REASON)

_unexpected: list[str] = []


def require(module: str, why: str = ROS_EXTRA) -> ModuleType:
    """Import an optional dependency, or skip (the whole module at import time) saying why."""
    return pytest.importorskip(module, reason=f"{module} {why}")


def need_rclpy() -> None:
    """Skip without rclpy (in a fixture: every test that uses it)."""
    if not HAS_RCLPY:
        pytest.skip(RCLPY_REASON)


def strict() -> bool:
    """Whether a skip for a missing dependency is a failure (`make test` sets it)."""
    return os.environ.get(STRICT_ENV) == "1"


def _note(report: pytest.CollectReport | pytest.TestReport) -> None:
    if not report.skipped or hasattr(report, "wasxfail") or not strict():
        return
    longrepr = report.longrepr
    reason = str(longrepr[2] if isinstance(longrepr, tuple) else longrepr)
    if not reason.removeprefix("Skipped: ").startswith((REFERENCE_REASON, PRIVILEGE_REASON)):
        _unexpected.append(f"{report.nodeid}: {reason}")


def pytest_collectreport(report: pytest.CollectReport) -> None:
    """Module-level skips (`require` at import time) are collection reports."""
    _note(report)


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Skips from marks, fixtures and `pytest.skip` inside a test."""
    _note(report)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Under SWARMGEN_STRICT_SKIPS=1, fail the run that skipped for anything but the corpus."""
    if not _unexpected:
        return
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    lines = [f"{STRICT_ENV}=1: skipped for a reason other than the reference corpus:"]
    lines += [f"  {entry}" for entry in _unexpected]
    if reporter is not None:
        reporter.write_line("")
        for line in lines:
            reporter.write_line(line, red=True)
    if session.exitstatus == pytest.ExitCode.OK:
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
