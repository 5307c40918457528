"""Shared harness of the hostile-input corpus (tests/test_hostile_*.py): run the real `swarmgen`
entry point as a process with a time limit, and say what a clean refusal looks like.

A clean refusal: exit 0, 1 or 2 (never 3, "please report a bug"), no Python traceback, no
"internal error" line, a `swarmgen:` line or a located diagnostic saying what was wrong, within the
case's time limit; and, around it, nothing written on failure and no file outside `-o` touched
(`snapshot` before and after).
"""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "sample_models" / "sar" / "sar.xmi"
CLEAN_EXITS = (0, 1, 2)


@dataclass(frozen=True)
class Outcome:
    args: tuple[str, ...]
    exit: int
    stdout: str
    stderr: str
    seconds: float

    def __str__(self) -> str:
        return (
            f"swarmgen {' '.join(self.args)} -> exit {self.exit} in {self.seconds:.2f} s\n"
            f"--- stdout\n{self.stdout[-2000:]}\n--- stderr\n{self.stderr[-4000:]}"
        )


class Hang(AssertionError):
    """The process overran its time limit (it was killed with everything under it)."""


def swarmgen(
    *args: str | os.PathLike[str],
    cwd: Path,
    timeout: float = 20.0,
    stdin: str | bytes | None = None,
    env: Mapping[str, str] | None = None,
) -> Outcome:
    """Run `python -m swarmgen ARGS` in `cwd`; a run past `timeout` seconds is a `Hang`."""
    environment = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    environment.pop("SWARMGEN_DEBUG", None)
    return run_module("swarmgen", *args, cwd=cwd, env=environment, timeout=timeout, stdin=stdin)


def run_module(
    module: str,
    *args: str | os.PathLike[str],
    cwd: Path,
    env: Mapping[str, str],
    timeout: float,
    stdin: str | bytes | None = None,
) -> Outcome:
    """`python -m MODULE ARGS` in its own session; past `timeout` it is killed with everything
    under it (killing only the child would orphan its children) and the run is a `Hang`."""
    words = tuple(os.fspath(a) for a in args)
    data = stdin.encode() if isinstance(stdin, str) else stdin
    started = time.perf_counter()
    process = subprocess.Popen(
        [sys.executable, "-m", module, *words],
        cwd=cwd,
        env=dict(env),
        stdin=subprocess.PIPE if data is not None else subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    try:
        out, err = process.communicate(data, timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        out, err = process.communicate()
        raise Hang(
            f"{module} {' '.join(words)} ran past {timeout} s\n"
            f"{err.decode(errors='replace')[-2000:]}"
        ) from None
    return Outcome(
        words,
        process.returncode,
        out.decode(errors="replace"),
        err.decode(errors="replace"),
        time.perf_counter() - started,
    )


def assert_clean(outcome: Outcome, exits: Sequence[int] = CLEAN_EXITS) -> None:
    """Exit in `exits`, no traceback, no internal error."""
    text = outcome.stdout + outcome.stderr
    assert outcome.exit in exits, f"exit {outcome.exit}, wanted one of {tuple(exits)}\n{outcome}"
    assert "Traceback (most recent call last)" not in text, str(outcome)
    assert "internal error" not in text, str(outcome)


def assert_refused(outcome: Outcome, *, exit: int | None = None, says: str | None = None) -> None:
    """A clean refusal: exit 1 or 2 (or exactly `exit`), one clear line, mentioning `says`."""
    assert_clean(outcome, (exit,) if exit is not None else (1, 2))
    assert outcome.stderr.strip() or outcome.stdout.strip(), f"refused in silence\n{outcome}"
    if says is not None:
        assert says.lower() in (outcome.stdout + outcome.stderr).lower(), (
            f"expected {says!r} in the output\n{outcome}"
        )


def snapshot(directory: Path) -> dict[str, tuple[int, str]]:
    """Every entry under `directory` (symlinks not followed): its mode and a content digest, to
    show that a command left it untouched."""
    entries: dict[str, tuple[int, str]] = {}
    for path in sorted(directory.rglob("*")):
        info = path.lstat()
        if path.is_symlink():
            digest = "->" + os.readlink(path)
        elif path.is_file():
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
        else:
            digest = ""
        entries[path.relative_to(directory).as_posix()] = (info.st_mode, digest)
    return entries
