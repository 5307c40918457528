"""ROS domains for detailed runs, leased machine-wide: two runs never share one.

A run's processes meet by ROS domain (discovery is on localhost): two runs in one domain hear
each other's swarm events and poses, which silently corrupts both. Within one command a domain
is handed to one run at a time; across commands (two sweeps, a test suite beside a benchmark)
an exclusive `flock` on `<tmp>/swarmgen-ros-domain-<n>.lock` marks a domain taken, for as long
as its run lasts; the kernel drops the lock when the process dies, so a crash leaks nothing.
`SWARMGEN_DETAILED_DOMAIN=N` makes the search start at N (a test run keeps clear of the domains
other tests use).
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


@contextlib.contextmanager
def lease(cancel: threading.Event | None = None) -> Iterator[int]:
    """A domain no other run on this machine holds, for the `with` block."""
    folder = Path(tempfile.gettempdir())
    while True:
        for domain in candidates():
            handle = (folder / f"swarmgen-ros-domain-{domain}.lock").open("a")
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.close()
                continue
            try:
                yield domain
            finally:
                fcntl.flock(handle, fcntl.LOCK_UN)
                handle.close()
            return
        if cancel is not None and cancel.is_set():
            raise RuntimeError("cancelled while waiting for a free ROS domain")
        time.sleep(WAIT_S)
