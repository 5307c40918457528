"""The world's building blocks: grid geometry, start placements, the counter-based random mixer
and the patches passed in one round (`Points`); see `world` for the model they serve."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

INF = int(np.iinfo(np.int32).max)  # "never": a patch not (yet) seen
I64 = NDArray[np.int64]
F64 = NDArray[np.float64]
U64 = NDArray[np.uint64]
Bool = NDArray[np.bool_]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
MEMBER_KEY = np.uint64(0xD1B54A32D192ED03)
BLOCK = 8  # turn directions drawn at once
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
    order = np.arange(len(index), dtype=np.int32)
    stamp[index] = order
    distinct: I64 = index[stamp[index] == order]
    return distinct


@dataclass(frozen=True)
class Points:
    """Patches passed in one round, piece by piece (a piece is a straight stretch of one
    member): per point the tick it is passed and its flat patch index (run included); the
    points of piece i start at `first[i]`."""

    gm: I64  # member of each piece
    first: I64  # index of each piece's first point
    tick: I64
    flat: I64

    @staticmethod
    def empty() -> Points:
        """No points."""
        e = np.zeros(0, dtype=np.int64)
        return Points(e, e, e, e)

    def __len__(self) -> int:
        return len(self.flat)

    def piece(self, at: I64) -> I64:
        """The piece of each point `at`."""
        return np.searchsorted(self.first, at, side="right") - 1

    def ticks(self, at: I64) -> I64:
        """The tick at which each point `at` is passed."""
        return self.tick[at]

    def members(self, at: I64) -> I64:
        """The member passing each point `at`."""
        return self.gm[self.piece(at)]

    def select(self, pieces: Bool) -> Points:
        """The points of the pieces flagged (in their order)."""
        sizes = np.diff(self.first, append=len(self.flat))
        keep = np.repeat(pieces, sizes)
        kept = sizes[pieces]
        return Points(self.gm[pieces], np.cumsum(kept) - kept, self.tick[keep], self.flat[keep])

    def until(self, end: I64, cells: int) -> Points:
        """The points at or before each run's end tick (pieces become one per point)."""
        keep = np.flatnonzero(self.tick <= end[self.flat // cells])
        return Points(
            self.gm[self.piece(keep)], np.arange(len(keep)), self.tick[keep], self.flat[keep]
        )
