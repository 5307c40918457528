"""ROS domains for detailed runs, leased machine-wide: two runs never share one.

A run's processes meet by ROS domain (discovery is on localhost): two runs in one domain hear
each other's swarm events and poses, which silently corrupts both. Within one command a domain
is handed to one run at a time; across commands (two sweeps, a test suite beside a benchmark)
an exclusive `flock` on `<tmp>/swarmgen-ros-domain-<n>.lock` marks a domain taken, for as long
as its run lasts; the kernel drops the lock when the process dies, so a crash leaks nothing.
`SWARMGEN_DETAILED_DOMAIN=N` makes the search start at N (a test run keeps clear of the domains
other tests use). `hold` takes a domain for the rest of the process (a test module's), from the
same locks, so a test suite and a detailed run beside it never meet either.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO

FIRST, LAST = 140, 232  # Fast DDS refuses domain ids above 232
WAIT_S = 0.2  # between two searches when every domain is taken


def candidates() -> list[int]:
    """The domains to try, in order (from SWARMGEN_DETAILED_DOMAIN, else FIRST)."""
    start = os.environ.get("SWARMGEN_DETAILED_DOMAIN", "")
    first = int(start) if start.isdigit() and int(start) <= LAST else FIRST
    return (
        [*range(first, LAST + 1), *range(FIRST, first)]
        if first >= FIRST
        else list(range(first, LAST + 1))
    )


_HELD: list[IO[str]] = []  # the open lock files of `hold`: closed only when the process ends


def _try_lock(domain: int) -> IO[str] | None:
    """The open, exclusively locked lock file of a domain, or None if another holds it."""
    handle = (Path(tempfile.gettempdir()) / f"swarmgen-ros-domain-{domain}.lock").open("a")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        return None
    return handle


def hold(first: int, last: int, start: int | None = None) -> int:
    """A free domain in [first, last], searched from `start` (wrapping), held until the
    process exits; RuntimeError when every one is taken. The lock is on a close-on-exec file,
    so the processes a test starts do not keep it."""
    count = last - first + 1
    offset = (start - first) % count if start is not None else 0
    for n in range(count):
        domain = first + (offset + n) % count
        handle = _try_lock(domain)
        if handle is not None:
            _HELD.append(handle)
            return domain
    raise RuntimeError(f"every ROS domain in {first}..{last} is held by another process")


@contextlib.contextmanager
def lease(cancel: threading.Event | None = None) -> Iterator[int]:
    """A domain no other run on this machine holds, for the `with` block."""
    while True:
        for domain in candidates():
            handle = _try_lock(domain)
            if handle is None:
                continue
            try:
                yield domain
            finally:
                handle.close()  # closing the file drops its lock
            return
        if cancel is not None and cancel.is_set():
            raise RuntimeError("cancelled while waiting for a free ROS domain")
        time.sleep(WAIT_S)
