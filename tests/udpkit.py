"""What the tests of the swarm on UDP multicast share: the SAR package compiled with this
tree's runtime, a group and port per test, the in-process reference trace, and member and
station processes that are always killed at the end (`Procs`)."""

from __future__ import annotations

import json
import os
import queue
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, Any

import pytest

from swarmgen import pipeline

ROOT = Path(__file__).resolve().parent.parent
SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
PACKAGE = "search_and_rescue_swarm"
MEMBERS = [("UAV", f"uav_{n}") for n in range(1, 5)] + [("UGV", f"ugv_{n}") for n in (1, 2)]
EVENTS = "launch@0.2,missionStart@1,missionAbort@2"
SCALE = "0.1"
STATION_EVENTS = ("launch", "missionStart", "missionAbort")
FINAL = {"UAV": ["Landed"], "UGV": ["Stopped"]}
RUN_TIMEOUT = 40  # seconds any process of a test may live

Steps = dict[str, list[tuple[str | None, list[str]]]]


# made once per test session, whichever module asks first (each is seconds of work)
_made: dict[str, Any] = {}


@pytest.fixture(scope="module")
def package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The SAR sample compiled with this tree's runtime: the directory holding the package."""
    if "package" not in _made:
        out = tmp_path_factory.mktemp("sar_udp")
        compiled = pipeline.compile_model(SAR)
        assert compiled.files, "the SAR sample has errors"
        pipeline.write_tree(compiled.files, out)
        _made["package"] = out / "asyncio"
    return Path(_made["package"])


@pytest.fixture(scope="module")
def expected(package: Path) -> Steps:
    """The reference: the whole swarm in one process on the in-memory bus (once a session)."""
    if "expected" not in _made:
        _made["expected"] = _in_process(package)
    return dict(_made["expected"])


def _in_process(package: Path) -> Steps:
    command = python("--swarm", "--events", EVENTS, "--time-scale", SCALE)
    run = subprocess.run(
        [*command, "--duration", "8"],
        cwd=package,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    return sequences(run.stdout)


_counter = iter(range(1, 10_000))


def unique() -> int:
    """A number new to every call in this process (names of a test's resources)."""
    return next(_counter)


def network() -> list[str]:
    """A group and port of this test alone: a free UDP port, and a group named by it and by
    the process (parallel runs do not hear each other)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    group = f"239.255.{os.getpid() % 250 + 1}.{unique() % 250 + 1}"
    return ["--transport", "udp", "--group", group, "--port", str(port)]


def python(*args: str) -> list[str]:
    return [sys.executable, "-m", PACKAGE, *args]


def sequences(text: str) -> Steps:
    """Per member, its (event, active states) steps: what is deterministic in a trace."""
    found: Steps = {}
    for line in text.splitlines():
        step = json.loads(line)
        if "event" in step:
            found.setdefault(step["member"], []).append((step["event"], step["active"]))
    return found


class Proc:
    """A process whose output lines are read as they come (a thread per stream), so a test
    can wait for a line, with a bound."""

    def __init__(self, command: list[str], cwd: Path) -> None:
        self.popen = subprocess.Popen(
            command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        self.out: list[str] = []
        self.err: list[str] = []
        self.lines: queue.Queue[str] = queue.Queue()
        self.readers = [
            threading.Thread(target=self._read, args=(stream, into), daemon=True)
            for stream, into in ((self.popen.stdout, self.out), (self.popen.stderr, self.err))
        ]
        for reader in self.readers:
            reader.start()

    def _read(self, stream: IO[str] | None, into: list[str]) -> None:
        assert stream is not None
        for line in stream:
            into.append(line)
            if into is self.out:
                self.lines.put(line)

    def wait_for(self, found: Callable[[dict[str, Any]], bool], timeout: float = 15) -> None:
        """Wait until a JSON line of stdout satisfies `found` (fails after `timeout`)."""
        until = time.monotonic() + timeout
        while True:
            try:
                line = self.lines.get(timeout=max(0.01, until - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"not seen in {timeout} s: {self.text()}") from None
            if found(json.loads(line)):
                return

    def finish(self, timeout: float = RUN_TIMEOUT) -> int:
        """Wait for the process to end and its output to be read; its exit code."""
        code = self.popen.wait(timeout=timeout)
        for reader in self.readers:
            reader.join(timeout=10)
        return code

    def text(self) -> str:
        """What it wrote so far (stdout, then stderr)."""
        return "".join(self.out) + "".join(self.err)

    def kill(self) -> None:
        """SIGKILL, if it still runs."""
        if self.popen.poll() is None:
            self.popen.kill()
        self.popen.wait(timeout=10)


class Procs:
    """The processes of a test: started through it, every one killed when the block ends."""

    def __init__(self, package: Path) -> None:
        self.package = package
        self.all: list[Proc] = []

    def start(self, *args: str) -> Proc:
        """`python -m <package> ARGS` in the package's directory."""
        proc = Proc(python(*args), self.package)
        self.all.append(proc)
        return proc

    def __enter__(self) -> Procs:
        return self

    def __exit__(self, *exc: object) -> None:
        for proc in self.all:
            proc.kill()


def record_of(proc: Proc) -> list[dict[str, Any]]:
    """A station's record, from its stdout."""
    return [json.loads(line) for line in proc.out]


def delivered(record: list[dict[str, Any]]) -> list[str]:
    return [line["event"] for line in record if line["station"] == "delivered"]


def final_states(record: list[dict[str, Any]]) -> dict[str, tuple[str, list[str], bool]]:
    """The station's summary: where it heard each member end."""
    (last,) = [line for line in record if line["station"] == "summary"]
    return {m: (v["type"], v["active"], v["finished"]) for m, v in last["members"].items()}


def lines(proc: Proc) -> Iterator[dict[str, Any]]:
    """A member's trace lines (JSON)."""
    return (json.loads(line) for line in proc.out)
