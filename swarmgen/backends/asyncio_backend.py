"""The asyncio backend: a Python package per swarm, a module per member type, simulated
behaviours, and a vendored copy of the runtime."""

from __future__ import annotations

from swarmgen.backends.pycommon import (
    PackageBackend,
    member_modules,
    member_view,
    package_name,
    script_specs,
)
from swarmgen.backends.pyrender import chart_code, format_python
from swarmgen.chart.model import Chart
from swarmgen.render import render

RUNTIME_MODULES = (
    "values",
    "chart",
    "host",
    "microstep",
    "plans",
    "configuration",
    "engine",
    "sends",
    "sessions",
    "member",
    "simulated",
    "args",
    "cli",
    "replay",
    "plugins",
    "faults",
    "netoptions",
    "transport",
    "station",
)

# `replay`, `sim` and the tests name these here, where the asyncio package is made.
__all__ = [
    "RUNTIME_MODULES",
    "AsyncioBackend",
    "member_modules",
    "package_name",
    "render_member",
    "script_specs",
]


def render_member(chart: Chart, common: dict[str, str]) -> str:
    """A member module: helper functions, then `build()` with the chart's builder calls."""
    code = chart_code(chart)
    return format_python(render("asyncio/member.py.j2", **member_view(chart, common, code)))


class AsyncioBackend(PackageBackend):
    """The asyncio package: member modules over the vendored standard-library runtime."""

    name = "asyncio"
    runtime_modules = RUNTIME_MODULES
    member = staticmethod(render_member)
