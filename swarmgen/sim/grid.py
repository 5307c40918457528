"""The world's building blocks: grid geometry, start placements, the counter-based random mixer
and the patches passed in one round (`Points`); see `world` for the model they serve."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from swarmgen.records import dataclass

INF = int(np.iinfo(np.int32).max)  # "never": a patch not (yet) seen
I64 = NDArray[np.int64]
F64 = NDArray[np.float64]
U64 = NDArray[np.uint64]
Bool = NDArray[np.bool_]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
MEMBER_KEY = np.uint64(0xD1B54A32D192ED03)
BLOCK = 8  # turn directions drawn at once
SHIFT = 4
STRETCH = 1 << SHIFT  # steps of a leg computed, and tested against the blocks, together
GAMMAS = np.arange(BLOCK + 1, dtype=np.uint64) * _GOLDEN  # k * gamma, wrapping


def mix64(z: U64) -> U64:
    """splitmix64's finaliser: a bijection on 64-bit words with good avalanche."""
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@dataclass(frozen=True)
class Geometry:
    """The grid's size in patches and how far a member sees."""

    width: int = 201
    height: int = 201
    view: int = 1  # Chebyshev radius of what a member sees (1: Moore neighbourhood)

    @property
    def cells(self) -> int:
        """The number of patches of one run's grid."""
        return self.width * self.height


def south_line(count: int, geometry: Geometry, spacing: float) -> tuple[F64, F64]:
    """`count` start points on the south side, centred, `spacing` patches apart (closer when
    they would not fit), west to east."""
    centre = (geometry.width - 1) / 2
    if count > 1:
        spacing = min(spacing, (geometry.width - 1) / (count - 1))
    offsets = (np.arange(count, dtype=np.float64) - (count - 1) / 2) * spacing
    return centre + offsets, np.zeros(count, dtype=np.float64)


def fan_headings(count: int) -> F64:
    """Directions (radians, counter-clockwise from east) dividing the northern half-plane
    regularly, one per member west to east: each member takes the bisector of its sector, so
    one member flies north, two fly north-west and north-east, and so on."""
    return math.pi - math.pi * (np.arange(count, dtype=np.float64) + 0.5) / max(count, 1)


def distinct(index: I64, stamp: NDArray[np.int32]) -> I64:
    """The distinct values of `index`, in O(n) with a scratch array as large as the index
    space: every position writes its number, the positions whose number survived are one per
    value."""
    # numpy scatters and gathers fastest with native (intp) indices, and `np.compress` picks
    # by a scattered mask several times faster than boolean indexing (same values, same order)
    at = index.astype(np.intp, copy=False)
    order = np.arange(len(index), dtype=np.int32)
    stamp[at] = order
    distinct: I64 = np.compress(np.take(stamp, at) == order, index)
    return distinct


@dataclass(frozen=True)
class Points:
    """Patches passed in one round, stretch by stretch (a row: `STRETCH` consecutive steps of
    one member along a straight leg): the flat patch index (run included) of each step, rows
    end to end, and `dummy` (a patch index past every run's, never new, never near a target)
    after a row's last step. Step j of row i is passed at tick `base[i] + j`; `linked[i]`: the
    row before it holds the steps just before its first (the same leg, a full row)."""

    gm: I64  # member of each row
    base: I64  # tick of each row's first step
    flat: NDArray[np.signedinteger]  # (rows * STRETCH,)
    linked: Bool

    @staticmethod
    def empty() -> Points:
        """No points."""
        e = np.zeros(0, dtype=np.int64)
        return Points(e, e, e, e.astype(np.bool_))

    @staticmethod
    def starts(
        members: Sequence[int], ticks: Sequence[int], flats: Sequence[int], dummy: int
    ) -> Points:
        """Members standing on patches, each at its tick: one row each."""
        rows = np.full((len(members), STRETCH), dummy, dtype=np.int64)
        rows[:, 0] = flats
        return Points(
            np.array(members, dtype=np.int64),
            np.array(ticks, dtype=np.int64),
            rows.reshape(-1),
            np.zeros(len(members), dtype=np.bool_),
        )

    def __len__(self) -> int:
        return len(self.flat)

    def ticks(self, at: I64) -> I64:
        """The tick at which each point `at` is passed."""
        ticks: I64 = self.base[at >> SHIFT] + (at & (STRETCH - 1))
        return ticks

    def members(self, at: I64) -> I64:
        """The member passing each point `at`."""
        members: I64 = self.gm[at >> SHIFT]
        return members

    def select(self, rows: Bool) -> Points:
        """The rows flagged (in their order): whole members' rows, so links hold."""
        steps = self.flat.reshape(-1, STRETCH)[rows].reshape(-1)
        return Points(self.gm[rows], self.base[rows], steps, self.linked[rows])

    def until(self, end: I64, cells: int, dummy: int) -> Points:
        """The points at or before each run's end tick (the others become `dummy`)."""
        ticks = self.base[:, None] + np.arange(STRETCH)[None, :]
        flat = self.flat.reshape(-1, STRETCH)
        late = ticks > end[np.minimum(flat, dummy - 1) // cells]
        return Points(self.gm, self.base, np.where(late, dummy, flat).reshape(-1), self.linked)
