"""Simulated behaviours: each takes a scripted time, may emit events, then ends with a scripted
outcome and outputs (or runs until it is preempted). Standard library only."""

from __future__ import annotations

import asyncio
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from swarmgen.runtime.member import Behaviour, Outcome, Request


@dataclass(frozen=True)
class Script:
    """What a simulated behaviour does: its outcome, duration, outputs and emitted events."""

    outcome: str = "succeeded"
    duration: float = 1.0  # seconds, before time_scale
    outputs: Mapping[str, Any] = field(default_factory=dict)
    emit: tuple[
        tuple[str, Mapping[str, Any] | None, str], ...
    ] = ()  # (event, data, scope) at the end
    forever: bool = False  # runs until preempted (monitors, positioning, ...)


class SimulatedLibrary:
    """A `Library` of scripted behaviours; `cancelled` counts preemptions (for tests)."""

    def __init__(self, scripts: Mapping[str, Script], time_scale: float = 1.0) -> None:
        self.scripts = dict(scripts)
        self.time_scale = time_scale
        self.started: list[tuple[str, str, str]] = []  # (member id, state, behaviour)
        self.cancelled: list[tuple[str, str, str]] = []

    def get(self, name: str) -> Behaviour | None:
        """The scripted behaviour for `name` (None: no script)."""
        script = self.scripts.get(name)
        if script is None:
            return None

        async def run(request: Request) -> Outcome:
            key = (request.member_id, request.state, request.behaviour)
            self.started.append(key)
            try:
                if script.forever:
                    await asyncio.Event().wait()
                await asyncio.sleep(script.duration * self.time_scale)
                for event, data, scope in script.emit:
                    request.emit(event, data, scope)
                return Outcome(script.outcome, dict(script.outputs))
            except asyncio.CancelledError:
                self.cancelled.append(key)
                raise

        return run
