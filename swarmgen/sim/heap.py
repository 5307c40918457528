"""Keep freed memory in the heap while a simulation runs (glibc only; elsewhere nothing).

A batch's rounds allocate and free the same large numpy temporaries (positions, gathers,
candidate patches: megabytes each) thousands of times. With glibc's defaults, a block above the
mmap threshold is mapped and unmapped each time, and a freed heap top is trimmed: the next round
faults every page back in, zero-filled by the kernel. For the paper's 200 coverage runs that was
about 190,000 page faults and 0.5 s of system time in a 2.6 s simulation
(docs/performance.md, "Simulate", fifth pass). Raising the mmap threshold (to glibc's ceiling,
32 MiB on 64-bit) and the trim threshold keeps those blocks in the heap for the next round.

The thresholds are set back to glibc's starting values (128 KiB) when the simulation ends, so a
process that goes on (a test, a notebook, an optimisation between its sweeps) gives its memory
back on its next trim; glibc's own adjusting of the mmap threshold stays off after a first
`mallopt`. Forked workers inherit the setting.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from collections.abc import Iterator

M_TRIM_THRESHOLD = -1  # glibc's mallopt parameters (malloc.h)
M_MMAP_THRESHOLD = -3
KEPT = {M_MMAP_THRESHOLD: 32 << 20, M_TRIM_THRESHOLD: 1 << 30}
DEFAULTS = {M_MMAP_THRESHOLD: 128 << 10, M_TRIM_THRESHOLD: 128 << 10}  # glibc's starting values


def _glibc() -> ctypes.CDLL | None:
    """This process's C library, if it is glibc (mallopt's parameters are glibc's)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        if not (os.confstr("CS_GNU_LIBC_VERSION") or "").startswith("glibc"):
            return None
        return ctypes.CDLL(None)
    except (OSError, ValueError):
        return None


def _set(libc: ctypes.CDLL, values: dict[int, int]) -> None:
    for parameter, value in values.items():
        libc.mallopt(ctypes.c_int(parameter), ctypes.c_int(value))


@contextlib.contextmanager
def kept_heap() -> Iterator[None]:
    """While the block runs, freed memory stays in the heap for reuse (see the module)."""
    libc = _glibc()
    if libc is None:
        yield
        return
    _set(libc, KEPT)
    try:
        yield
    finally:
        _set(libc, DEFAULTS)
