"""ROS domain leases (swarmgen/ros/domains.py): real `flock` locks in a private lock folder
(TMPDIR of this test), across real processes."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from swarmgen.ros import domains
from tests.conftest import ROOT

TRY_HOLD = "import sys; from swarmgen.ros.domains import hold; print(hold({a}, {b}))"


@pytest.fixture
def lock_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    return tmp_path


def other_process_holds(first: int, last: int) -> str:
    """What `hold(first, last)` gives in a fresh process: its domain, or its error's last line."""
    script = TRY_HOLD.format(a=first, b=last)
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    return done.stdout.strip() or done.stderr.strip().splitlines()[-1]


def test_each_hold_takes_another_domain_and_keeps_it(lock_folder: Path) -> None:
    first = domains.hold(10, 12, start=11)
    second = domains.hold(10, 12, start=11)
    assert (first, second) == (11, 12)  # searched from `start`, the held one skipped
    assert other_process_holds(11, 12).startswith("RuntimeError: every ROS domain in 11..12")
    assert other_process_holds(10, 12) == "10"
    # that process has ended, so its lock is gone with it
    assert other_process_holds(10, 10) == "10"
    assert domains.hold(10, 12) == 10


def test_a_lease_is_held_for_its_block_only(lock_folder: Path) -> None:
    with domains.lease() as domain:
        assert domains.FIRST <= domain <= domains.LAST
        assert other_process_holds(domain, domain).startswith("RuntimeError")
    assert other_process_holds(domain, domain) == str(domain)


def test_the_harness_leases_one_domain_per_process(lock_folder: Path) -> None:
    script = (
        "from pathlib import Path; from swarmgen import ros_harness as h; "
        "a = h.ros_env(Path('l'), base={})['ROS_DOMAIN_ID']; "
        "b = h.ros_env(Path('l'), base={})['ROS_DOMAIN_ID']; print(a == b, a)"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    same, domain = done.stdout.split()
    assert same == "True" and 1 <= int(domain) <= 139
