"""Backends: one table of code generators behind a small protocol.

Each backend renders the lowered charts of a model (`swarmgen.chart`) into files under its own
folder of the output directory. Logic lives in Python view models; templates stay thin.
"""

from __future__ import annotations

from pathlib import PurePosixPath
from typing import Protocol

from swarmgen.chart.model import Chart
from swarmgen.ir.nodes import Model

Files = dict[PurePosixPath, str]


class Backend(Protocol):
    name: str

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        """Files relative to the backend's folder (`asyncio/`, `smach/`, ...)."""
        ...


def registry() -> dict[str, Backend]:
    """All built-in backends by name, in output order (imported lazily: start-up stays fast)."""
    from swarmgen.backends.asyncio_backend import AsyncioBackend
    from swarmgen.backends.rclpy_backend import RclpyBackend
    from swarmgen.backends.smach_backend import SmachBackend

    backends: list[Backend] = [AsyncioBackend(), SmachBackend(), RclpyBackend()]
    return {b.name: b for b in backends}


def names() -> list[str]:
    return ["asyncio", "smach", "rclpy"]
