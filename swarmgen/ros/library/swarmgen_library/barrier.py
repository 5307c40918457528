"""The exact lockstep barrier of the world node, without ROS (docs/detailed.md, "The lockstep
barrier").

Termination detection by counting (Mattern's four counters): every reporter (the servers
process, each generated swarm process) sends, per probe wave of step k, a report
`{"k", "wave", "by", "sent": {...}, "received": {...}, "idle"}` with what it has sent and
received so far on the reactive channels. A step is complete when every expected reporter has
answered the current wave, all are idle, the counts balance, and the totals equal those of the
wave before (so nothing moved between the two waves). When the totals of a first wave equal
the last completed step's, one wave is enough: nothing reactive was sent in this step at all.

Channels: a name starting with `/` is a topic every subscriber hears (`/swarm/events`): its
senders count `name`, each subscription counts `name@<subscriber>`, and each of those must equal
the total sent. Any other name is point to point (`goal`, `goal_response`, `result`,
`request`, `response`, `cancel`): the sums of sent and received must be equal.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

Totals = dict[str, int]


@dataclass
class Wave:
    """The reports of one wave of one step, the latest per reporter."""

    k: int
    number: int
    reports: dict[str, dict[str, Any]] = field(default_factory=dict)


def totals(reports: Mapping[str, Mapping[str, Any]], own: Mapping[str, int]) -> Totals:
    """Per channel the total sent (`sent:<c>`) and received (`received:<c>`) over the reports,
    plus `own`, what the world itself sent (its pose topics)."""
    out: Totals = {f"sent:{c}": int(n) for c, n in own.items()}
    for report in reports.values():
        for side in ("sent", "received"):
            counts = report.get(side)
            if not isinstance(counts, dict):
                continue
            for channel, count in counts.items():
                if isinstance(count, int) and not isinstance(count, bool):
                    key = f"{side}:{channel}"
                    out[key] = out.get(key, 0) + count
    return out


def imbalance(sums: Totals) -> Totals:
    """Per channel (or per subscription of a topic) how many messages are still on their way:
    sent minus received; balanced when every value is 0."""
    gaps: Totals = {}
    for key, count in sums.items():
        side, _, channel = key.partition(":")
        if side != "received":
            continue
        if "@" in channel and channel.startswith("/"):
            topic = channel.partition("@")[0]
            gaps[channel] = sums.get(f"sent:{topic}", 0) - count
        elif not channel.startswith("/"):
            gaps[channel] = sums.get(f"sent:{channel}", 0) - count
    for key, count in sums.items():
        side, _, channel = key.partition(":")
        if side == "sent" and not channel.startswith("/") and channel not in gaps:
            gaps[channel] = count  # sent, and nobody has received any yet
    return gaps


class Barrier:
    """The barrier's bookkeeping for one run (the module docstring)."""

    def __init__(self, reporters: tuple[str, ...]) -> None:
        """`reporters`: the `by` of every report a step waits for."""
        self.reporters = reporters
        self.wave = Wave(0, 0)
        self.previous: Totals | None = None  # the totals of the wave before, this step
        self.confirmed: Totals = {}  # the totals of the last completed step
        self.offsets: Totals = {}  # imbalances accepted at a timeout (messages taken as lost)
        self.own: Totals = {}
        self.timeouts = 0
        self.waves = 0  # waves asked for, over the run
        self.stuck: list[dict[str, Any]] = []  # per timeout: who or what the barrier missed

    def begin(self, k: int, own: Mapping[str, int]) -> int:
        """A new step: wave 1 of step k (`own`: the world's counts); its wave number."""
        self.own = dict(own)
        self.wave = Wave(k, 1)
        self.previous = None
        self.waves += 1
        return 1

    def next_phase(self, own: Mapping[str, int]) -> int:
        """The step's second phase (after the poses): its first wave's number."""
        self.own = dict(own)
        self.wave = Wave(self.wave.k, self.wave.number + 1)
        self.previous = None
        self.waves += 1
        return self.wave.number

    def report(self, text: str) -> bool:
        """A report; whether it belongs to the current wave (kept: the latest per reporter)."""
        message = json_object(text)
        if message is None:
            return False
        k, wave = message.get("k"), message.get("wave")
        if k != self.wave.k or wave != self.wave.number:
            return False
        self.wave.reports[str(message.get("by", ""))] = message
        return True

    def decide(self) -> str:
        """`wait` (a report is missing, someone is busy, or messages are on their way),
        `probe` (ask for the next wave: its number is `self.wave.number`) or `done`."""
        reports = self.wave.reports
        if any(name not in reports for name in self.reporters):
            return "wait"
        if not all(reports[name].get("idle") is True for name in self.reporters):
            return "wait"
        sums = totals({n: reports[n] for n in self.reporters}, self.own)
        gaps = imbalance(sums)
        if any(gap != self.offsets.get(channel, 0) for channel, gap in gaps.items()):
            return "wait"
        if sums == self.previous or (self.wave.number == 1 and _reactive(sums, self.own) ==
                                     _reactive(self.confirmed, self.own)):  # fmt: skip
            self.confirmed = sums
            return "done"
        self.previous = sums
        self.wave = Wave(self.wave.k, self.wave.number + 1)
        self.waves += 1
        return "probe"

    def timed_out(self) -> None:
        """The barrier did not complete in time: counted, with what it missed (`stuck`); with
        every report in, the imbalance seen now is taken as lost messages (so one lost message
        costs one timeout, not one per step)."""
        self.timeouts += 1
        reports = {n: r for n, r in self.wave.reports.items() if n in self.reporters}
        sums = totals(reports, self.own)
        gaps = imbalance(sums)
        self.stuck.append({
            "k": self.wave.k, "wave": self.wave.number,
            "missing": [n for n in self.reporters if n not in reports],
            "busy": [n for n, r in reports.items() if r.get("idle") is not True],
            "gaps": {c: g for c, g in gaps.items() if g != self.offsets.get(c, 0)},
        })  # fmt: skip
        if all(n in reports for n in self.reporters):  # partial counts prove nothing lost
            self.offsets = gaps
            self.confirmed = sums


def _reactive(sums: Totals, own: Mapping[str, int]) -> Totals:
    """The totals without the channels the world feeds itself (they grow every step)."""
    return {k: v for k, v in sums.items() if k.partition(":")[2].partition("@")[0] not in own}


def json_object(text: str) -> dict[str, Any] | None:
    """A message's JSON object, or None for anything else (bad JSON, another value)."""
    try:
        value = json.loads(text)
    except (json.JSONDecodeError, TypeError):
        return None
    return value if isinstance(value, dict) else None
