"""A behaviour server killed mid-mission gives `aborted`, never a hang (issue 13, faults).

The platform (`tests/ros_server_loss.py platform`) serves a declared action, a private action and
a declared service that hold; the driver runs one member per behaviour. Once every goal runs and
the request is out, the platform gets SIGKILL: each member must take `done.invoke.Run.aborted`
within `server_lost_s` + 1 s of the kill and end in `Aborted`, with a member error naming the
behaviour and its endpoint. DDS notices a dead participant only when its lease expires (Fast DDS:
20 s by default), so the platform runs with a 0.3 s lease (a Fast DDS XML profile), as a platform
whose crash must be noticed quickly would. Both processes run under time limits with LOCALHOST
discovery and the ROS_DOMAIN_ID 1 + (pid + 75) % 100 (the other tests of 1..100 use the offsets
0, 25 and 50).
"""

from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import psutil
import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")

from swarmgen.ros.domains import hold
from swarmgen.ros.interfaces import build_and_install
from swarmgen.ros_harness import ros_env
from tests import rosproc
from tests.conftest import ROOT
from tests.ros_platform.packages import build_packages

DOMAIN = hold(1, 139, start=1 + (os.getpid() + 75) % 100)  # leased: see swarmgen/ros/domains.py
NAMESPACE = "/loss"
SERVER_LOST_S = 2.0  # the member parameter's default
LEASE = """<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com"><profiles>
  <participant profile_name="short_lease" is_default_profile="true"><rtps><builtin>
    <discovery_config>
      <leaseDuration><sec>0</sec><nanosec>300000000</nanosec></leaseDuration>
      <leaseAnnouncement><sec>0</sec><nanosec>100000000</nanosec></leaseAnnouncement>
    </discovery_config>
  </builtin></rtps></participant>
</profiles></dds>
"""


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """platform_msgs and the edge tests' private package in the venv; the ROS environment."""
    from tests.ros_edges import package_files

    work = tmp_path_factory.mktemp("loss")
    build_packages(work / "packages")
    package = work / "sgedges_interfaces"
    for path, text in package_files().items():
        (package / str(path)).parent.mkdir(parents=True, exist_ok=True)
        (package / str(path)).write_text(text, encoding="utf-8")
    build_and_install(package)
    (work / "lease.xml").write_text(LEASE, encoding="utf-8")
    environment = ros_env(work / "roslog", domain_id=DOMAIN, python_path=[ROOT])
    environment["SWARMGEN_TEST_LEASE"] = str(work / "lease.xml")
    return environment


def _lines(proc: subprocess.Popen[str]) -> queue.Queue[str]:
    """The process's stdout lines, read in a thread (a readline never blocks the test)."""
    lines: queue.Queue[str] = queue.Queue()

    def read() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.put(line)

    threading.Thread(target=read, daemon=True).start()
    return lines


def _wait_for(lines: queue.Queue[str], key: str, limit: float) -> dict[str, Any]:
    """The first JSON line with `key`, within `limit` seconds (else the test fails)."""
    deadline = time.monotonic() + limit
    while (left := deadline - time.monotonic()) > 0:
        try:
            line = lines.get(timeout=left)
        except queue.Empty:
            break
        if line.startswith("{") and key in (record := json.loads(line)):
            return record
    raise AssertionError(f"no {key!r} line within {limit} s")


def _python(module: str, *args: str) -> list[str]:
    return [sys.executable, "-m", module, *args]


def test_killed_server_gives_aborted(env: dict[str, str], tmp_path: Path) -> None:
    platform_env = dict(env, FASTDDS_DEFAULT_PROFILES_FILE=env["SWARMGEN_TEST_LEASE"])
    platform = rosproc.start(
        _python("tests.ros_server_loss", "platform", NAMESPACE), platform_env, tmp_path, 60
    )
    driver = rosproc.start(_python("tests.ros_server_loss", "drive", NAMESPACE), env, tmp_path, 60)
    try:
        _wait_for(_lines(platform), "event", 20)  # ready
        out = _lines(driver)
        _wait_for(out, "running", 30)
        killed = time.monotonic()
        for child in psutil.Process(platform.pid).children(recursive=True):
            child.send_signal(signal.SIGKILL)
        report = _wait_for(out, "report", 30)["report"]
    finally:
        platform_code, _, _ = rosproc.stop(platform, 10)
        code, _, stderr = rosproc.finish(driver, 30)
    assert platform_code != 0  # killed, not stopped
    assert code == 0, stderr[-3000:]
    endpoints = {"declared_action": "action server '/loss/hold_go_to'",
                 "private_action": "action server '/loss/hold_survey'",
                 "service": "service '/loss/hold_trigger'"}  # fmt: skip
    for case, result in report.items():
        assert result["events"] == ["done.invoke.Run.aborted"], (case, result)
        assert result["final"] == ["Aborted"], (case, result)
        took = result["at"] - killed
        print(f"{case}: aborted {took:.2f} s after the kill")
        assert SERVER_LOST_S < took < SERVER_LOST_S + 1.0, (case, took)
        (error,) = result["errors"]
        assert f"behaviour Act in Run: {endpoints[case]} lost" in error, error
