"""Outputs: one table of everything `compile` writes (SCXML, code backends, diagrams) behind a
small protocol. Every list of outputs (the CLI's `--backend` of compile and replay, the pipeline,
the docs) is derived from `names()` and `runnable()`.

Each output renders the lowered charts of a model (`swarmgen.chart`) into files under its own
folder of the output directory. Logic lives in Python view models; templates stay thin.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import PurePosixPath
from typing import TYPE_CHECKING, Protocol

from swarmgen.records import dataclass

if TYPE_CHECKING:  # annotations only: `compile --help` must not import pydantic and the charts
    from swarmgen.chart.model import Chart
    from swarmgen.ir.nodes import Model
    from swarmgen.ros.idl_index import InterfaceIndex
    from swarmgen.scxml.emit import ScxmlDocument

Files = dict[PurePosixPath, str]
# Always written: the output README lists its documents, and it is the reference every backend
# is tested against; `--backend NAME` selects outputs besides it.
SCXML = "scxml"


class Backend(Protocol):
    """An output: renders the validated model and its charts as files in its own folder."""

    name: str

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        """Files relative to the backend's folder (`asyncio/`, `smach/`, ...)."""
        ...


class ScxmlOutput:
    """The SCXML documents, one per chart; keeps them for the output README (counts)."""

    name = SCXML

    def __init__(self) -> None:
        self.documents: tuple[ScxmlDocument, ...] = ()

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        """`<chart>.scxml` per chart."""
        from swarmgen.scxml.emit import serialize

        self.documents = tuple(serialize(chart) for chart in charts)
        return {PurePosixPath(f"{d.name}.scxml"): d.text for d in self.documents}


class DiagramsOutput:
    """Mermaid diagrams of every machine and of the swarm composition (`swarmgen.graph`)."""

    name = "diagrams"

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        """`<machine>.mmd` per machine and `swarm.mmd`."""
        from swarmgen import graph

        return graph.files(model, "mermaid")


def _asyncio() -> Backend:
    from swarmgen.backends.asyncio_backend import AsyncioBackend

    return AsyncioBackend()


def _smach() -> Backend:
    from swarmgen.backends.smach_backend import SmachBackend

    return SmachBackend()


def _rclpy(interfaces: InterfaceIndex | None) -> Backend:
    from swarmgen.backends.rclpy_backend import RclpyBackend

    return RclpyBackend(interfaces)


@dataclass(frozen=True)
class _Entry:
    make: Callable[..., Backend]  # imported lazily: start-up (and `--help`) stays fast
    runnable: bool  # `swarmgen replay` can run what it writes
    interfaces: bool = False  # made with the interface index (declared ROS types)


# The single list of outputs, in output order.
_TABLE: dict[str, _Entry] = {
    SCXML: _Entry(ScxmlOutput, runnable=True),
    "asyncio": _Entry(_asyncio, runnable=True),
    "smach": _Entry(_smach, runnable=True),
    "rclpy": _Entry(_rclpy, runnable=True, interfaces=True),
    "diagrams": _Entry(DiagramsOutput, runnable=False),
}


def registry(interfaces: InterfaceIndex | None = None) -> dict[str, Backend]:
    """A fresh instance of every output by name, in output order. The outputs that use
    declared ROS types (rclpy) get `interfaces`, the index the check resolved them in; the
    protocol stays `render(model, charts)` for every output."""
    return {
        name: entry.make(interfaces) if entry.interfaces else entry.make()
        for name, entry in _TABLE.items()
    }


def names(*leaving_out: str) -> list[str]:
    """Every output's name but those left out, in output order (without importing them)."""
    return [name for name in _TABLE if name not in leaving_out]


def runnable() -> list[str]:
    """The outputs `swarmgen replay` can run, in output order."""
    return [name for name, entry in _TABLE.items() if entry.runnable]


def selection(requested: Sequence[str] | None) -> list[str]:
    """The outputs a compile writes, in output order: all (None), or SCXML and those named."""
    if requested is None:
        return names()
    return [name for name in names() if name == SCXML or name in requested]
