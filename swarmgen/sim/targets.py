"""The targets of a batch's runs (`World`'s part): where they are, what happened to them, and
which patches have one in view, per sight class (a `near` count per padded patch)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmgen.sim.blocks import Blocks
from swarmgen.sim.grid import I64

UNFOUND, FOUND, CLAIMED, RESCUED = 0, 1, 2, 3  # target status


class Targets:
    """Target bookkeeping, mixed into `World` (whose grid, sight classes and blocks it uses)."""

    runs: int
    W: int
    H: int
    PW: int
    PH: int
    v: int
    views: list[int]
    sight: I64
    run_of: I64
    dummy: int
    blocks: Blocks

    def _init_targets(self, targets: I64) -> None:
        """Where the targets are, their status and the ticks of what happened to them."""
        runs = self.runs
        targets = np.asarray(targets, dtype=np.int64).reshape(runs, -1, 2)
        self.tx: I64 = targets[:, :, 0].copy()
        self.ty: I64 = targets[:, :, 1].copy()
        shape = self.tx.shape
        self.status: NDArray[np.int8] = np.zeros(shape, dtype=np.int8)
        self.finder: I64 = np.full(shape, -1, dtype=np.int64)
        self.found_tick: I64 = np.full(shape, -1, dtype=np.int64)  # first find taken up
        self.reported_tick: I64 = np.full(shape, -1, dtype=np.int64)  # latest targetFound
        self.rescued_tick: I64 = np.full(shape, -1, dtype=np.int64)
        self.unfound: I64 = np.full(runs, shape[1], dtype=np.int64)
        self.fresh: list[list[int]] = [[] for _ in range(runs)]  # reported this tick
        # near[k, c] > 0: an unfound target is in the view of sight class k from patch c
        self.near: NDArray[np.int16] = np.zeros((len(self.views), self.dummy + 1), dtype=np.int16)
        for run in range(runs):
            for target in range(shape[1]):
                self._near_add(run, target, 1)

    def _near_add(self, run: int, target: int, delta: int) -> None:
        """A target enters (1) or leaves (-1) the views: every class's, and the blocks around
        it as far as the largest view sees (`Blocks` is conservative)."""
        x, y = int(self.tx[run, target]), int(self.ty[run, target])
        for k, v in enumerate(self.views):
            grid = self.near[k][: self.dummy].reshape(self.runs, self.PH, self.PW)
            rows = slice(max(0, y - v) + self.v, min(self.H, y + v + 1) + self.v)
            cols = slice(max(0, x - v) + self.v, min(self.W, x + v + 1) + self.v)
            grid[run, rows, cols] += delta
        v = self.v  # the largest view
        rows = slice(max(0, y - v), min(self.H, y + v + 1))
        cols = slice(max(0, x - v), min(self.W, x + v + 1))
        ys, xs = np.mgrid[rows, cols]
        self.blocks.change(self.blocks.block_of(run, xs.ravel(), ys.ravel()), delta)

    def targets_in_view(self, member: int, ix: int, iy: int) -> list[int]:
        """The unfound targets of the member's run within view of patch (ix, iy)."""
        run, v = int(self.run_of[member]), self.views[int(self.sight[member])]
        near = (
            (np.abs(self.tx[run] - ix) <= v)
            & (np.abs(self.ty[run] - iy) <= v)
            & (self.status[run] == UNFOUND)
        )
        return [int(t) for t in np.flatnonzero(near)]

    def report(self, run: int, target: int, member: int, tick: int) -> None:
        """A member reported a target (targetFound): nobody else will find it now."""
        if self.status[run, target] == UNFOUND:
            self._near_add(run, target, -1)
            self.unfound[run] -= 1
        self.status[run, target] = FOUND
        self.finder[run, target] = member
        self.reported_tick[run, target] = tick
        self.fresh[run].append(target)

    def claim(self, run: int, target: int) -> None:
        """The finder took the find up (a behaviour of it started on this target)."""
        if self.status[run, target] == FOUND:
            self.status[run, target] = CLAIMED
            if self.found_tick[run, target] < 0:
                self.found_tick[run, target] = self.reported_tick[run, target]

    def forget(self, run: int, target: int) -> None:
        """A find nobody took up: the target can be found again."""
        if self.status[run, target] in (FOUND, CLAIMED):
            self.status[run, target] = UNFOUND
            self.finder[run, target] = -1
            self._near_add(run, target, 1)
            self.unfound[run] += 1

    def rescue(self, run: int, target: int, tick: int) -> None:
        """A target was rescued at `tick` (found then, at the latest)."""
        if self.status[run, target] == RESCUED:
            return
        if self.status[run, target] == UNFOUND:
            self._near_add(run, target, -1)
            self.unfound[run] -= 1
        if self.found_tick[run, target] < 0:
            self.found_tick[run, target] = max(self.reported_tick[run, target], tick)
        self.status[run, target] = RESCUED
        self.rescued_tick[run, target] = tick
