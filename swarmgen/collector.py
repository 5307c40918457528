"""How the batch commands (`validate`, `compile`, `graph`) treat Python's cyclic garbage collector.

A compile is a batch job over objects that live until the process ends: the XMI tree, the IR,
the charts and the rendered text. The collector finds next to no garbage in them, yet each of its
passes scans what was allocated since the last one: at 10,000 states that is about a tenth of a
compile's CPU time, and the pass that follows the restored thresholds scans the whole model once
more (docs/performance.md, "Collector, spans, templates"). Reference counting still frees
everything that is not in a cycle; the cycles left (about 250,000 objects at 10,000 states) did
not move the peak resident memory measured there.

So the console entry point (`swarmgen.cli.run`), which ends the process as soon as the command
returns, runs those commands with the collector off and leaves it off. Called in process (click's
test runner, a library user), the collector is switched back on when the command returns.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

_process_ends = False


def process_ends_after_command() -> None:
    """Declare that the process ends when the command returns (`cli.run` calls this)."""
    global _process_ends
    _process_ends = True


@contextmanager
def off_for_batch() -> Iterator[None]:
    """Run a batch command with the cyclic collector off; switched back on afterwards unless
    the process ends right after (`process_ends_after_command`) or it was off already."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled and not _process_ends:
            gc.enable()
