"""The servers process's side of the exact lockstep barrier (docs/detailed.md, "The lockstep
barrier"): what it sent to and received from the members, and its reports.

The process answers wave w of step k (a probe on `/world/settle/probe`): at once in the step's
`clock` phase, and in its `step` phase once every member has acted on step k. A world without
the barrier (no probes) gets one report per step, wave 1, once every member has acted. `idle` is false while a goal was accepted but its execution has not started, or a
behaviour has ended but its result is not sent yet: both go on in a later executor turn.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Callable
from typing import Any


class Counters:
    """Per channel what was sent and received, the work under way, and the probes."""

    def __init__(self, by: str, publish: Callable[[str], None]) -> None:
        """`by`: the reports' sender name; `publish`: sends one report (JSON text)."""
        self.by = by
        self.publish = publish
        self.sent: Counter[str] = Counter()
        self.received: Counter[str] = Counter()
        self.busy = 0
        self.acted = -1  # the last step every member has acted on
        self.wave: tuple[int, int] = (-1, 0)  # the latest probe: (k, wave)
        self.phase = "step"  # its phase: `clock` (answered at once) or `step` (after acting)
        self._last: str | None = None

    def listen(self, channel: str) -> None:
        """A subscription of a broadcast channel exists (its count starts at 0)."""
        self.received[channel] += 0

    def probe(self, text: str) -> None:
        """A probe `{"k", "wave"}`: answered now if the step has been acted on, else after."""
        try:
            raw = json.loads(text)
            self.wave = (int(raw["k"]), int(raw["wave"]))
        except (ValueError, KeyError, TypeError):
            return
        self.phase = str(raw.get("phase", "step"))
        self._last = None  # a new wave is always answered
        self.report()

    def step_done(self, k: int, settle: bool) -> None:
        """Every member has acted on step k: its report."""
        self.acted = k
        self._last = None
        self.report(settle)

    def changed(self) -> None:
        """A count or the work under way changed: a new report, if the world probes (a world
        without the barrier gets one report per step, as before)."""
        if self.wave[0] >= 0:
            self.report()

    def report(self, settle: bool = False) -> None:
        """The report of the latest wave of the acted step, when something changed."""
        if self.wave[0] < 0:  # a world without the barrier: one report per step, wave 1
            k, wave = self.acted, 1
        elif self.phase == "clock" or self.wave[0] == self.acted:
            k, wave = self.wave  # `clock`: the step's poses are still to come, nothing to wait for
        else:
            return  # acted on an older step, or on this one before its probe came
        if k < 0:
            return
        body: dict[str, Any] = {
            "k": k,
            "wave": wave,
            "by": self.by,
            "settle": settle,
            "sent": dict(self.sent),
            "received": dict(self.received),
            "idle": self.busy == 0,
        }
        text = json.dumps(body, sort_keys=True)
        if text != self._last:
            self._last = text
            self.publish(text)
