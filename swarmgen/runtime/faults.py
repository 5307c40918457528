"""The network transport's fault layer, for tests (standard library only).

Faults act where datagrams are received, so each receiver loses its own copies, as on a radio:
a datagram is lost with a probability, else delivered once or twice, each copy delayed; and a
**partition** cuts a set of members (and the others from them) for a window of mission time.
Mission time is the station's clock (seconds since it started sending its events), which every
station event carries (`clock`, Unix time): all processes of a run then agree on a window to the
host's clock accuracy, whatever their start-up times. Before a process has heard the station it
knows no mission time, and no partition is in force for it.

Seeded: a run's losses are reproducible (the partitions draw nothing).
"""

from __future__ import annotations

import math
import random
from collections.abc import Collection
from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class Partition:
    """Members `ids` cut off from every other process (and those from them) during
    `start <= mission time < end`. `station` names the ground station."""

    ids: frozenset[str]
    start: float
    end: float

    def cuts(self, sender: str, receivers: Collection[str], mission_time: float) -> bool:
        """A datagram from `sender` to a process with the members `receivers` is lost: the
        window is on and every receiver is on the other side of the cut from the sender."""
        if not self.start <= mission_time < self.end:
            return False
        inside = sender in self.ids
        return bool(receivers) and all((r in self.ids) != inside for r in receivers)

    def __str__(self) -> str:
        return f"{','.join(sorted(self.ids))}@{self.start:g}-{self.end:g}"


def parse_partition(text: str) -> Partition:
    """`uav_1,ugv_2@1.5-3`: the members cut off and the window in seconds of mission time;
    ValueError says what is wrong."""
    ids, separator, window = text.rpartition("@")
    start, dash, end = window.partition("-")
    if not separator or not dash:
        raise ValueError(f"expected IDS@START-END (seconds of mission time), got {text!r}")
    members = frozenset(filter(None, (i.strip() for i in ids.split(","))))
    if not members:
        raise ValueError(f"{text!r}: no member id before '@'")
    try:
        low, high = float(start), float(end)
    except ValueError:
        raise ValueError(f"{text!r}: the window is not two numbers START-END") from None
    if not (math.isfinite(low) and math.isfinite(high) and 0 <= low < high):
        raise ValueError(f"{text!r}: expected 0 <= START < END, finite")
    return Partition(members, low, high)


@dataclass(slots=True)
class Faults:
    """Injected datagram faults, applied to each datagram received: cut by a partition, else
    dropped with probability `drop`, else delivered twice with probability `duplicate`, each
    copy delayed by a uniform 0-`delay` seconds (so datagrams overtake each other)."""

    drop: float = 0.0
    duplicate: float = 0.0
    delay: float = 0.0
    seed: int = 0
    partitions: tuple[Partition, ...] = ()
    rng: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)

    @property
    def active(self) -> bool:
        """Some fault is injected."""
        return self.drop > 0 or self.duplicate > 0 or self.delay > 0 or bool(self.partitions)

    def cut(self, sender: str, receivers: Collection[str], mission_time: float | None) -> bool:
        """The partition in force, if any, loses a datagram from `sender` to `receivers`."""
        if mission_time is None:
            return False
        return any(p.cuts(sender, receivers, mission_time) for p in self.partitions)

    def copies(self) -> list[float]:
        """The delays of the copies of one received datagram (none: it is lost)."""
        if self.drop > 0 and self.rng.random() < self.drop:
            return []
        count = 2 if self.duplicate > 0 and self.rng.random() < self.duplicate else 1
        return [self.rng.uniform(0.0, self.delay) if self.delay > 0 else 0.0 for _ in range(count)]


def finite_rate(text: str) -> float:
    """A probability 0-1 (argparse type helper); ValueError otherwise."""
    value = float(text)
    if not math.isfinite(value) or not 0.0 <= value <= 1.0:
        raise ValueError(f"expected a probability 0-1, got {text!r}")
    return value
