"""The processes of one detailed run, started and stopped as one group (standard library only).

Each process is started in a session of its own (`start_new_session`), so that its whole tree
(rclpy spawns no children, but `timeout` wrappers and user servers may) is one process group:
stopping is `SIGTERM` to every group, a grace period, then `SIGKILL` to what is left, and
waiting for every process, so nothing outlives the run, also on Ctrl-C (`KeyboardInterrupt`
unwinds through `__exit__`) or when one of them crashes. Output goes to one log file per
process, never a pipe: a chatty node cannot block on a full pipe while nobody reads it.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import threading
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType

from swarmgen.records import dataclass

GRACE_S = 3.0  # after SIGTERM, before SIGKILL
POLL_S = 0.02


@dataclass
class Started:
    """One process of the group: its name, the process and where its output goes."""

    name: str
    process: subprocess.Popen[bytes]
    log: Path

    def tail(self, lines: int = 12) -> str:
        """The last lines of its output (stdout and stderr, interleaved)."""
        try:
            text = self.log.read_text(encoding="utf-8", errors="replace")
        except OSError:
            return ""
        return "\n".join(text.strip().splitlines()[-lines:])


class ProcessGroup:
    """Processes started together and always stopped together (module docstring)."""

    def __init__(self, logs: Path) -> None:
        self.logs = logs
        self.started: list[Started] = []

    def __enter__(self) -> ProcessGroup:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.stop()

    def start(
        self, name: str, command: Sequence[str], env: Mapping[str, str], cwd: Path
    ) -> Started:
        """Start `command` as the group's process `name`, its output in `<logs>/<name>.log`."""
        self.logs.mkdir(parents=True, exist_ok=True)
        log = self.logs / f"{name}.log"
        with log.open("wb") as out:
            process = subprocess.Popen(
                list(command),
                env=dict(env),
                cwd=cwd,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        started = Started(name, process, log)
        self.started.append(started)
        return started

    def wait(
        self,
        name: str,
        timeout: float,
        watch: Sequence[str] = (),
        cancel: threading.Event | None = None,
    ) -> int | None:
        """Wait for process `name` to exit (its exit code) for at most `timeout` seconds; None
        on time-out. Returns early, with None, when a process of `watch` exits first or
        `cancel` is set."""
        wanted = self._named(name)
        watched = [self._named(n) for n in watch]
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not (cancel is not None and cancel.is_set()):
            code = wanted.process.poll()
            if code is not None:
                return code
            if any(w.process.poll() is not None for w in watched):
                return None
            time.sleep(POLL_S)
        return None

    def exited(self) -> dict[str, int]:
        """The processes that have exited so far, with their exit codes."""
        return {s.name: code for s in self.started if (code := s.process.poll()) is not None}

    def stop(self, grace: float = GRACE_S) -> None:
        """SIGTERM every process group, SIGKILL what is left after `grace`, reap them all."""
        for started in self.started:
            _signal_group(started.process, signal.SIGTERM)
        deadline = time.monotonic() + grace
        for started in self.started:
            with contextlib.suppress(subprocess.TimeoutExpired):
                started.process.wait(max(0.0, deadline - time.monotonic()))
        for started in self.started:  # the group too: a child may outlive its parent
            _signal_group(started.process, signal.SIGKILL)
            started.process.wait()

    def _named(self, name: str) -> Started:
        for started in self.started:
            if started.name == name:
                return started
        raise KeyError(name)


def _signal_group(process: subprocess.Popen[bytes], number: signal.Signals) -> None:
    """Signal the process group the process leads (gone already: nothing to do)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, number)
