"""Turning at the grid's edge: the members' random draws, kept in blocks, and the length of a
straight leg, vectorised over members or, for a few of them, in plain Python.

A member's stream is counter-based (splitmix64): its draw k is `mix64(key + k * GOLDEN)` mod
2**64, so a draw depends only on the member's key and the draw's number. `Draws` keeps, per
member, the cosine and sine of the directions of its next `KEPT` draws, computed for many
members at once (numpy), and a count of the draws taken: a turn reads its candidates there
instead of mixing and taking the cosine and sine of 8 fresh draws. The values are those the
turn computed itself before: the same draws, the same expression for the angle, the same
`np.cos`/`np.sin` (whose value for an angle does not depend on where it sits in an array: the
batch's results already rely on that, since how runs are batched changes the arrays).

A turn chooses the first candidate direction that keeps the member inside, and the leg runs
until the next step would leave the grid (`longest`). The plain-Python turn (`turn_one`) does
the same IEEE additions, multiplications, divisions and comparisons as the numpy one and reads
the same cosines and sines, so it gives the same bits; it serves the last few members of a
round, where numpy's per-call cost would dominate.
"""

from __future__ import annotations

import math

import numpy as np

from swarmgen.sim.grid import BLOCK, F64, I64, U64, Bool, mix64

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
KEPT = 64  # draws kept per member; a turn uses about 2 (a block of BLOCK at most, usually)
_DRAWS = np.arange(1, KEPT + 1, dtype=np.uint64) * GOLDEN  # k * gamma, wrapping
_COLUMNS = np.arange(BLOCK, dtype=np.int64)
_NEXT = np.array([[0.0], [1.0]])  # a step count and the one after it, as rows
_TO_UNIT = 1.0 / 9007199254740992.0  # 2**-53: the top 53 bits of a draw as a number in [0, 1)
TRIES = 16  # blocks of candidates before a member heads for the centre (vanishingly rare)


class Draws:
    """Every member's stream: its key, the draws taken, and the directions of the next ones."""

    def __init__(self, keys: U64) -> None:
        """Streams with these keys (one per member), nothing drawn yet."""
        self.key: U64 = np.asarray(keys, dtype=np.uint64)
        count = len(self.key)
        self.drawn: I64 = np.zeros(count, dtype=np.int64)  # draws taken
        self.base: I64 = np.zeros(count, dtype=np.int64)  # draws taken when the rows were filled
        self.cos: F64 = np.empty(count * KEPT, dtype=np.float64)  # (member, draw) flattened
        self.sin: F64 = np.empty(count * KEPT, dtype=np.float64)
        self.fill(np.arange(count, dtype=np.int64), self.drawn)

    def fill(self, g: I64, drawn: I64) -> None:
        """Members `g`, having taken `drawn` draws: keep the directions of their next ones."""
        self.base[g] = drawn
        z = mix64((self.key[g] + drawn.astype(np.uint64) * GOLDEN)[:, None] + _DRAWS[None, :])
        angle = (2.0 * math.pi) * ((z >> np.uint64(11)).astype(np.float64) * _TO_UNIT)
        rows = (g[:, None] * KEPT + np.arange(KEPT)[None, :]).reshape(-1)
        self.cos[rows] = np.cos(angle).reshape(-1)
        self.sin[rows] = np.sin(angle).reshape(-1)

    def candidates(self, g: I64, drawn: I64) -> tuple[F64, F64]:
        """The cosine and sine of the next BLOCK draws of members `g`, having taken `drawn`
        draws: two (len(g), BLOCK) arrays. Members whose kept draws run short are filled again
        (with those past the half used, so that fills come together)."""
        off = drawn - self.base[g]
        if (off > KEPT - BLOCK).any() or (off < 0).any():
            stale = (off > KEPT // 2) | (off < 0)
            self.fill(np.compress(stale, g), np.compress(stale, drawn))
            off = drawn - self.base[g]
        at = (g * KEPT + off)[:, None] + _COLUMNS
        return self.cos.take(at), self.sin.take(at)

    def one(self, member: int, drawn: int) -> tuple[list[float], list[float]]:
        """The cosines and sines of a member's next BLOCK draws (plain floats)."""
        off = drawn - int(self.base[member])
        if not 0 <= off <= KEPT - BLOCK:
            self.fill(np.array([member], dtype=np.int64), np.array([drawn], dtype=np.int64))
            off = 0
        at = member * KEPT + off
        cos: list[float] = self.cos[at : at + BLOCK].tolist()
        sin: list[float] = self.sin[at : at + BLOCK].tolist()
        return cos, sin


def inside(u: F64, w: F64, width: int, height: int) -> Bool:
    """Whether positions (patch-corner coordinates) are on the grid."""
    ok: Bool = (u >= 0) & (u < width) & (w >= 0) & (w < height)
    return ok


def longest(ox: F64, oy: F64, dx: F64, dy: F64, width: int, height: int) -> I64:
    """How many steps each body can go straight before its next step would leave the grid.
    The closed form is checked (and corrected) with the position expression itself."""
    big = float(width + height)
    with np.errstate(divide="ignore", invalid="ignore"):
        nx = np.where(dx > 0, width - ox, -ox) / dx  # dx == 0: +-inf or nan
        ny = np.where(dy > 0, height - oy, -oy) / dy
    limit = np.fmin(np.where(dx == 0, big, nx), np.where(dy == 0, big, ny))
    # clip's bounds (never NaN here), as two ufuncs: np.clip costs more per call
    n: I64 = np.minimum(np.maximum(limit, 0.0), big).astype(np.int64)  # >= 0: floor
    for _ in range(4):
        # steps n and n + 1 at once (rows 0 and 1), with the position expression itself
        steps = n.astype(np.float64) + _NEXT
        ok = inside(ox + steps * dx, oy + steps * dy, width, height)
        out = (n > 0) & ~ok[0]
        more = ~out & ok[1]
        if not (out.any() or more.any()):
            break
        n -= out
        n += more
    return n


def longest_one(ox: float, oy: float, dx: float, dy: float, width: int, height: int) -> int:
    """`longest` for one body, with the same operations on plain floats."""
    big = float(width + height)
    nx = big if dx == 0 else ((width - ox) if dx > 0 else -ox) / dx
    ny = big if dy == 0 else ((height - oy) if dy > 0 else -oy) / dy
    n = int(min(max(min(nx, ny), 0.0), big))  # neither is NaN; floor of a number >= 0
    for _ in range(4):
        at, after = float(n), float(n) + 1.0
        out = n > 0 and not _inside_one(ox + at * dx, oy + at * dy, width, height)
        more = not out and _inside_one(ox + after * dx, oy + after * dy, width, height)
        if not (out or more):
            break
        n += int(more) - int(out)
    return n


def _inside_one(u: float, w: float, width: int, height: int) -> bool:
    return u >= 0 and u < width and w >= 0 and w < height


def turn_one(
    draws: Draws, member: int, ox: float, oy: float, width: int, height: int
) -> tuple[float, float]:
    """A new direction for a member standing at (ox, oy): its first candidate that keeps it
    inside (the draws up to it are taken), or the centre's after TRIES blocks."""
    drawn = int(draws.drawn[member])
    for _ in range(TRIES):
        cos, sin = draws.one(member, drawn)
        for j in range(BLOCK):
            if _inside_one(cos[j] + ox, sin[j] + oy, width, height):
                draws.drawn[member] = drawn + j + 1
                return cos[j], sin[j]
        drawn += BLOCK
    draws.drawn[member] = drawn
    cx, cy = width / 2 - ox, height / 2 - oy
    norm = float(np.hypot(np.array([cx]), np.array([cy]))[0])  # numpy's hypot, as in `turn`
    return cx / norm, cy / norm
