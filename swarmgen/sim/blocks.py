"""Where a round's movement can still change something: a coarse index over the grid.

Late in a coverage run almost every patch a member passes has been seen, with every patch of
its view, and has no unfound target in view; passing it changes no result (a patch's seen time
is the minimum of its view's first-stood ticks, and every patch of that view was seen earlier).
`Blocks` keeps, per run and per `SIZE` x `SIZE` block of patches, how many patches are still
unseen and how many target views overlap it. A straight stretch of a member's leg whose view
touches only clean blocks is skipped whole: its positions are never computed.

The index is conservative (a dirty block may hold nothing the stretch passes), so skipping
never changes a number; it only saves the work of patches that cannot matter.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray

from swarmgen.sim.grid import I64, Geometry

SIZE = 8  # patches per block side


class Blocks:
    """Per run and block: unseen patches plus target-view overlaps (zero: nothing to do)."""

    def __init__(self, runs: int, geometry: Geometry) -> None:
        """Every patch of every run starts unseen; no target yet."""
        self.W, self.H, self.v = geometry.width, geometry.height, geometry.view
        self.runs = runs
        self.bw = -(-self.W // SIZE)
        self.bh = -(-self.H // SIZE)
        start, self.of_padded = _layout(runs, geometry)
        self.dirty: I64 = start.copy()  # (runs * bh * bw,)
        self._table: NDArray[np.int64] | None = None

    def block_of(self, run: I64 | int, x: I64, y: I64) -> I64:
        """The flat block index of patches (x, y) of runs `run`."""
        block: I64 = (run * self.bh + y // SIZE) * self.bw + x // SIZE
        return block

    def seen(self, padded: I64) -> NDArray[np.int64]:
        """Padded patches (flat, run included, each once) were seen for the first time;
        returns how many per run."""
        count = np.bincount(np.take(self.of_padded, padded), minlength=len(self.dirty))
        if padded.size:
            self.dirty -= count
            self._table = None
        per_run: NDArray[np.int64] = count.reshape(self.runs, -1).sum(axis=1)
        return per_run

    def change(self, blocks: NDArray[np.signedinteger], delta: int) -> None:
        """Add `delta` to the count of each block listed (a block may repeat)."""
        if blocks.size:
            np.add.at(self.dirty, blocks, delta)
            self._table = None

    def table(self) -> NDArray[np.int64]:
        """Summed-area table of the dirty blocks, (runs, bh + 1, bw + 1), first row and column 0."""
        if self._table is None:
            flags = (self.dirty > 0).reshape(self.runs, self.bh, self.bw)
            table = np.zeros((self.runs, self.bh + 1, self.bw + 1), dtype=np.int64)
            np.cumsum(np.cumsum(flags, axis=1), axis=2, out=table[:, 1:, 1:])
            self._table = table
        return self._table

    def touches(self, run: I64, x0: I64, x1: I64, y0: I64, y1: I64) -> NDArray[np.bool_]:
        """Whether the view from the patch rectangle [x0, x1] x [y0, y1] (in the grid) meets a
        dirty block of the run."""
        v = self.v
        bx0 = np.maximum(x0 - v, 0) // SIZE
        bx1 = np.minimum(x1 + v, self.W - 1) // SIZE + 1
        by0 = np.maximum(y0 - v, 0) // SIZE
        by1 = np.minimum(y1 + v, self.H - 1) // SIZE + 1
        t = self.table().reshape(-1)
        base = run * ((self.bh + 1) * (self.bw + 1))
        row0, row1 = base + by0 * (self.bw + 1), base + by1 * (self.bw + 1)
        total = t[row1 + bx1] - t[row0 + bx1] - t[row1 + bx0] + t[row0 + bx0]
        touched: NDArray[np.bool_] = total > 0
        return touched


@functools.lru_cache(maxsize=4)
def _layout(runs: int, geometry: Geometry) -> tuple[I64, NDArray[np.signedinteger]]:
    """The blocks' starting counts (every patch unseen), and the block of each padded patch
    (the padding takes its nearest patch's: one look-up per newly seen patch instead of two
    divisions). Shared, read-only, by the batches of one process with the same grid."""
    w, h, v = geometry.width, geometry.height, geometry.view
    bw, bh = -(-w // SIZE), -(-h // SIZE)
    xs = np.bincount(np.arange(w) // SIZE, minlength=bw)
    ys = np.bincount(np.arange(h) // SIZE, minlength=bh)
    per_run = (ys[:, None] * xs[None, :]).astype(np.int64).reshape(-1)
    ph, pw = h + 2 * v, w + 2 * v
    dtype = np.int32 if runs * ph * pw < 2**31 else np.int64
    by = np.clip(np.arange(ph) - v, 0, h - 1) // SIZE
    bx = np.clip(np.arange(pw) - v, 0, w - 1) // SIZE
    lut = ((np.arange(runs)[:, None] * bh + by[None, :]) * bw).astype(dtype)
    of_padded = np.add(lut[:, :, None], bx.astype(dtype)[None, None, :]).ravel()
    start = np.tile(per_run, runs)
    for array in (start, of_padded):
        array.setflags(write=False)
    return start, of_padded


@functools.lru_cache(maxsize=4)
def padded_index(runs: int, geometry: Geometry) -> NDArray[np.signedinteger]:
    """For each patch (flat, run included) its flat index in the grid padded by `view`
    (shared, read-only, by the batches of one process with the same grid)."""
    v, w, h = geometry.view, geometry.width, geometry.height
    ph, pw = h + 2 * v, w + 2 * v
    dtype = np.int32 if runs * ph * pw < 2**31 else np.int64
    rows = ((np.arange(runs)[:, None] * ph + np.arange(h)[None, :] + v) * pw + v).astype(dtype)
    index: NDArray[np.signedinteger] = np.add(
        rows[:, :, None], np.arange(w, dtype=dtype)[None, None, :]
    ).ravel()
    index.setflags(write=False)
    return index


def entering(
    now: NDArray[np.signedinteger],
    before: NDArray[np.signedinteger],
    full: NDArray[np.bool_],
    geometry: Geometry,
    view_offsets: NDArray[np.signedinteger],
    view: int | None = None,
) -> NDArray[np.signedinteger]:
    """The padded patches a step from `before` to `now` (padded flat indices) brings into view:
    the view around `now` less the view around `before`, whose patches are all seen already (a
    patch is stood on only with its whole view). Where `full` or the step is not to a
    neighbour, the whole view. A one-patch step adds one column and/or one row of the view, so
    this is 3 to 5 patches instead of 9, each once (a diagonal step's row leaves out the
    corner its column holds); repeats across points are the callers' to drop.
    `view`: the stepping members' view radius when it is less than the padding's
    (`geometry.view`, the largest); `view_offsets` are then that view's."""
    return np.concatenate(entering_parts(now, before, full, geometry, view_offsets, view))


def entering_parts(
    now: NDArray[np.signedinteger],
    before: NDArray[np.signedinteger],
    full: NDArray[np.bool_],
    geometry: Geometry,
    view_offsets: NDArray[np.signedinteger],
    view: int | None = None,
) -> list[NDArray[np.signedinteger]]:
    """`entering` in four parts, whose concatenation it is (whole views, columns, rows,
    diagonal steps' rows): a caller that filters them can concatenate only what it keeps."""
    pw = geometry.width + 2 * geometry.view
    v = geometry.view if view is None else view
    if v == 0:
        return [now]
    delta = now - before
    dy = (delta + pw + 1) // pw - 1  # exact for steps to a neighbour (pw >= 3)
    dx = delta - dy * pw
    full = full | (np.abs(dx) > 1) | (np.abs(dy) > 1)
    step, across = ~full, dx != 0
    cols = step & across
    rows = step & (dy != 0)
    corner = rows & across
    straight = rows ^ corner  # rows & (dx == 0)
    span = np.arange(-v, v + 1, dtype=now.dtype)
    # `np.compress`: picking by these scattered masks is several times faster than boolean
    # indexing (the same values, in the same order)
    at_cols, at_straight, at_corner = (np.compress(m, now) for m in (cols, straight, corner))
    # a diagonal step's row: the span less the corner at dx * v (-v .. v-1, or -v+1 .. v)
    shifted = at_corner + np.compress(corner, dy) * (v * pw) + (np.compress(corner, dx) < 0)
    column = at_cols + np.compress(cols, dx) * v  # the column's middle patch
    row = at_straight + np.compress(straight, dy) * (v * pw)  # the row's middle patch
    return [
        (np.compress(full, now)[:, None] + view_offsets[None, :]).reshape(-1),
        (column[:, None] + (span * pw)[None, :]).reshape(-1),
        (row[:, None] + span[None, :]).reshape(-1),
        (shifted[:, None] + span[None, :-1]).reshape(-1),
    ]
