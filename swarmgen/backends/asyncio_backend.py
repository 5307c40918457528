"""The asyncio backend: a Python package per swarm, a module per member type, simulated
behaviours, and a vendored copy of the runtime."""

from __future__ import annotations

from pathlib import PurePosixPath
from typing import Any

from swarmgen import __version__
from swarmgen.backends import Files
from swarmgen.backends.pyrender import ChartRenderer, event_fields_literal, format_python
from swarmgen.backends.vendor import runtime_files
from swarmgen.chart.model import Chart
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import composition as swarm_composition
from swarmgen.names import IdAllocator, doc_text, one_line, ros_name
from swarmgen.render import render

RUNTIME_MODULES = ("chart", "engine", "member", "simulated", "cli", "replay")
_DEFAULTS = {"Real": 0.0, "Integer": 0, "Boolean": False, "String": ""}


def package_name(model: Model) -> str:
    return f"{ros_name(model.name or 'swarm')}_swarm"


def member_modules(charts: tuple[Chart, ...]) -> dict[str, str]:
    """chart name -> module name (lower snake case, unique)."""
    taken = IdAllocator({"behaviours", "cli"})
    return {chart.name: taken.claim(ros_name(chart.name)) for chart in charts}


def script_specs(charts: tuple[Chart, ...]) -> dict[str, dict[str, Any]]:
    """Simulated behaviours, by name: those whose outcome a transition waits for succeed after
    1 s with default outputs; the others run until preempted (monitors, positioning, ...).
    Every Python backend renders these in its own form."""
    scripts: dict[str, dict[str, Any]] = {}
    for chart in charts:
        nodes = chart.walk()
        waited = {
            e for n in nodes for t in n.transitions for e in t.events if e.startswith("outcome.")
        }
        for node in nodes:
            if node.call is None:
                continue
            info = next(b for b in chart.behaviours if b.name == node.call.behaviour)
            ended = any(
                e == f"outcome.{node.id}" or e.startswith(f"outcome.{node.id}.") for e in waited
            )
            if not ended:
                scripts.setdefault(info.name, {"forever": True})
                continue
            outputs = {name: _DEFAULTS.get(type_ or "") for name, type_ in info.outputs}
            scripts[info.name] = {"duration": 1.0, "outcome": "succeeded", "outputs": outputs}
    return dict(sorted(scripts.items()))


def default_scripts(charts: tuple[Chart, ...]) -> str:
    """`script_specs` as a `{name: Script(...)}` literal for runtime/simulated.py."""
    items = []
    for name, spec in script_specs(charts).items():
        if spec.get("forever"):
            items.append(f"{name!r}: Script(forever=True)")
        else:
            items.append(
                f"{name!r}: Script(outcome={spec['outcome']!r}, duration={spec['duration']!r}, "
                f"outputs={spec['outputs']!r})"
            )
    return "{" + ", ".join(items) + "}"


def signatures(charts: tuple[Chart, ...]) -> str:
    seen = {b.name: b for chart in charts for b in chart.behaviours}
    items = [
        f"{name!r}: ({b.kind!r}, {tuple(n for n, _ in b.inputs)!r}, {tuple(n for n, _ in b.outputs)!r}, {b.outcomes!r})"
        for name, b in sorted(seen.items())
    ]
    return "{" + ", ".join(items) + "}"


class AsyncioBackend:
    name = "asyncio"

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        if not charts:
            return {}  # no state machine, nothing to run
        package = PurePosixPath(package_name(model))
        modules = member_modules(charts)
        source = charts[0].source if charts else model.source
        common = {"version": __version__, "source": one_line(source), "runtime": "._runtime"}
        files: Files = {}
        for chart in charts:
            files[package / f"{modules[chart.name]}.py"] = render_member(chart, common)
        members = {c.member: modules[c.name] for c in charts if c.member}
        composition = swarm_composition(model)
        files[package / "__init__.py"] = format_python(
            render(
                "asyncio/package_init.py.j2",
                **common,
                model=doc_text(model.name),
                package=str(package),
                first_member=doc_text(next(iter(members), "")),
                modules=sorted(modules.values()),
                member_modules="{" + ", ".join(f"{k!r}: {v}" for k, v in members.items()) + "}",
                composition=repr(composition),
            )
        )
        files.update(support_files("asyncio", package, common, charts, RUNTIME_MODULES))
        return files


def support_files(
    templates: str,
    package: PurePosixPath,
    common: dict[str, str],
    charts: tuple[Chart, ...],
    runtime_modules: tuple[str, ...],
) -> Files:
    """`__main__.py`, the simulated behaviours and the vendored runtime: what every Python
    package backend ships beside its member modules (from its own templates)."""
    main = render(f"{templates}/main.py.j2", **common, package=str(package))
    behaviours = render(
        f"{templates}/behaviours.py.j2",
        **common,
        signatures=signatures(charts),
        scripts=default_scripts(charts),
    )
    return {
        package / "__main__.py": format_python(main),
        package / "behaviours.py": format_python(behaviours),
        **runtime_files(package / "_runtime", runtime_modules),
    }


def render_member(chart: Chart, common: dict[str, str]) -> str:
    code = ChartRenderer(chart).render()
    scopes = {e.ident: e.scope or "swarm" for e in chart.events}
    what = f"member type {chart.member}" if chart.member else f"state machine {chart.machine}"
    text = render(
        "asyncio/member.py.j2",
        **common,
        what=doc_text(what),
        doc=doc_text(f"Behaviour of {what} (state machine {chart.machine})."),
        chart_name=repr(chart.name),
        member_type=repr(chart.member),
        machine=repr(chart.machine),
        event_scopes=repr(scopes),
        event_fields=event_fields_literal(chart),
        code=code,
    )
    return format_python(text)
