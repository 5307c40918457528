"""Processes of the ROS end-to-end tests: started under `timeout`, stopped as a tree, their
output collected with a time limit (psutil comes with the `ros` extra)."""

from __future__ import annotations

import contextlib
import subprocess
from pathlib import Path

import psutil


def start(command: list[str], env: dict[str, str], cwd: Path, limit: int) -> subprocess.Popen[str]:
    """`command` under `timeout -k 5 limit`, its output piped as text."""
    return subprocess.Popen(
        ["timeout", "-k", "5", str(limit), *command],
        env=env,
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def finish(proc: subprocess.Popen[str], limit: float) -> tuple[int, str, str]:
    """Exit code, stdout and stderr; past `limit` seconds the process tree is killed."""
    try:
        stdout, stderr = proc.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        # `timeout` itself and what it runs: killing only `timeout` would orphan the python
        # process, which keeps the pipes open and `communicate()` waiting forever
        _signal_children(proc, kill=True)
        proc.kill()
        stdout, stderr = proc.communicate()
    return proc.returncode, stdout, stderr


def stop(proc: subprocess.Popen[str], limit: float) -> tuple[int, str, str]:
    """SIGTERM to the process tree (`timeout` and what it runs), then its output."""
    _signal_children(proc, kill=False)
    return finish(proc, limit)


def _signal_children(proc: subprocess.Popen[str], *, kill: bool) -> None:
    """Terminate or kill every descendant of `proc` (those already gone are skipped)."""
    with contextlib.suppress(psutil.NoSuchProcess):
        for child in psutil.Process(proc.pid).children(recursive=True):
            with contextlib.suppress(psutil.NoSuchProcess):
                if kill:
                    child.kill()
                else:
                    child.terminate()
