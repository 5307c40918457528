"""`swarmgen.sim.heap.kept_heap`: freed numpy temporaries are reused without page faults."""

from __future__ import annotations

import resource
import sys

import numpy as np
import pytest

from swarmgen.sim import heap

PAGES = (8 << 20) // 4096  # one 8 MiB array


def _faults_of_cycles(cycles: int) -> int:
    """Minor page faults while an 8 MiB array is allocated, written and freed `cycles` times."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(cycles):
        block = np.ones(1 << 20)  # written: every page touched
        del block
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


@pytest.mark.skipif(heap._glibc() is None, reason="mallopt is glibc's")
def test_freed_blocks_are_reused_without_faults() -> None:
    with heap.kept_heap():
        faults = _faults_of_cycles(20)
    # at most the first allocation faults its pages in; unmapped each time it would be 20 x
    assert faults < 3 * PAGES


def test_elsewhere_it_does_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "platform", "darwin")
    assert heap._glibc() is None
    with heap.kept_heap():
        assert _faults_of_cycles(1) >= 0
