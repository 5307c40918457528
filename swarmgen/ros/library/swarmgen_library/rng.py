"""A counter-based random stream: splitmix64, the same generator as the abstract world's.

Draw k (k = 1, 2, ...) of a stream with key K is `mix64(K + k * GOLDEN)` mod 2**64, turned into
a uniform number in [0, 1) from its top 53 bits, exactly as `swarmgen.sim.grid` /
`swarmgen.sim.turns.Draws` compute it with numpy. A draw depends only on the key and its
number: nothing is shared between members or runs, so the order in which members are stepped
cannot change a number, and the abstract world's member key gives the very same draws.
"""

from __future__ import annotations

MASK = (1 << 64) - 1
GOLDEN = 0x9E3779B97F4A7C15
MEMBER_KEY = 0xD1B54A32D192ED03  # the abstract world's per-member key step


def mix64(z: int) -> int:
    """splitmix64's finaliser on a 64-bit word."""
    z &= MASK
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


def member_key(run_key: int, member: int) -> int:
    """The stream key of member `member` of a run, as the abstract world derives it."""
    return mix64(run_key + member * MEMBER_KEY)


class Stream:
    """Uniform numbers in [0, 1) from a key; `draws` counts what was taken."""

    def __init__(self, key: int) -> None:
        """A stream that starts at draw 1 of `key` (any integer, taken mod 2**64)."""
        self.key = key & MASK
        self.draws = 0

    def uniform(self) -> float:
        """The next number of the stream."""
        self.draws += 1
        z = mix64(self.key + self.draws * GOLDEN)
        return (z >> 11) * (1.0 / 9007199254740992.0)
