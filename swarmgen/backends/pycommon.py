"""What the Python package backends (asyncio, smach, rclpy) share beyond chart rendering
(`pyrender`): package and module names, the simulated behaviours' scripts and signatures, the
support files, the view of a member module, and the package of the asyncio and smach backends."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import PurePosixPath
from typing import Any

from swarmgen import __version__
from swarmgen.backends import Files
from swarmgen.backends.pyrender import event_fields_literal, format_python
from swarmgen.backends.pytypes import MODULE, render_types
from swarmgen.backends.vendor import runtime_files
from swarmgen.chart.model import Chart
from swarmgen.generated import header
from swarmgen.ir.network import swarm_network
from swarmgen.ir.nodes import Model
from swarmgen.ir.primitives import zero_of
from swarmgen.ir.query import composition as swarm_composition
from swarmgen.names import IdAllocator, doc_text, one_line, ros_name
from swarmgen.render import render

# Module names of the asyncio and smach packages that member modules must not take.
PACKAGE_MODULES = ("behaviours", "cli", MODULE)


def package_name(model: Model) -> str:
    """The Python package of the asyncio and smach backends (and of `replay`)."""
    return f"{ros_name(model.name or 'swarm')}_swarm"


def member_modules(
    charts: Iterable[Chart], reserved: Iterable[str] = PACKAGE_MODULES, suffix: str = ""
) -> dict[str, str]:
    """chart name -> module name (lower snake case, unique, clear of `reserved`); a taken name
    tries `<name><suffix>` before numbering."""
    taken = IdAllocator(reserved)
    modules = {}
    for chart in charts:
        name = ros_name(chart.name)
        modules[chart.name] = taken.claim(name, f"{name}{suffix}") if suffix else taken.claim(name)
    return modules


def common_view(charts: tuple[Chart, ...], **extra: str) -> dict[str, str]:
    """What every template of a Python backend sees: version, source and the `@generated` line."""
    source = one_line(charts[0].source)
    return {"version": __version__, "source": source, "header": header(source), **extra}


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
        ended = _waited_ids(waited)
        for node in nodes:
            if node.call is None:
                continue
            info = next(b for b in chart.behaviours if b.name == node.call.behaviour)
            if node.id not in ended:
                scripts.setdefault(info.name, {"forever": True})
                continue
            outputs = {name: zero_of(type_) for name, type_ in info.outputs}
            scripts[info.name] = {"duration": 1.0, "outcome": "succeeded", "outputs": outputs}
    return dict(sorted(scripts.items()))


def _waited_ids(waited: set[str]) -> set[str]:
    """The node ids whose outcome some `outcome.<id>` or `outcome.<id>.<outcome>` event waits
    for: each event names its id, or a prefix of it up to a dot (ids may hold dots). A set, so
    that the look-up per node does not go over every event."""
    ids: set[str] = set()
    for event in waited:
        rest = event[len("outcome.") :]
        ids.add(rest)
        ids.update(rest[:i] for i, char in enumerate(rest) if char == ".")
    return ids


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
    """`SIGNATURES` of behaviours.py: behaviour -> (type, inputs, outputs, outcomes)."""
    seen = {b.name: b for chart in charts for b in chart.behaviours}
    items = [
        f"{name!r}: ({b.kind!r}, {tuple(n for n, _ in b.inputs)!r}, "
        f"{tuple(n for n, _ in b.outputs)!r}, {b.outcomes!r})"
        for name, b in sorted(seen.items())
    ]
    return "{" + ", ".join(items) + "}"


def member_view(
    chart: Chart,
    common: dict[str, str],
    code: object,
    role: str = "",
    member_type: str | None = None,
    header_text: Callable[[str], str] = doc_text,
) -> dict[str, Any]:
    """The view of a member module: its `@generated` line, docstring, constants and code.
    `role` ends the docstring's sentence; `header_text` escapes the header's member text."""
    what = f"member type {chart.member}" if chart.member else f"state machine {chart.machine}"
    return {
        **common,
        "header": header(common["source"], header_text(what)),
        "what": doc_text(what),
        "doc": doc_text(f"Behaviour of {what} (state machine {chart.machine}){role}."),
        "chart_name": repr(chart.name),
        "member_type": repr(chart.member if member_type is None else member_type),
        "machine": repr(chart.machine),
        "event_scopes": repr({e.ident: e.scope or "swarm" for e in chart.events}),
        "event_fields": event_fields_literal(chart),
        "code": code,
    }


class PackageBackend:
    """A backend that writes one Python package per swarm (asyncio, smach): `package_files`
    with the subclass's name, runtime modules and member module renderer."""

    name: str
    runtime_modules: tuple[str, ...]
    member: Callable[[Chart, dict[str, str]], str]

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        """The swarm's package (see `package_files`)."""
        return package_files(model, charts, self.name, self.runtime_modules, type(self).member)


def package_files(
    model: Model,
    charts: tuple[Chart, ...],
    backend: str,
    runtime_modules: tuple[str, ...],
    render_member: Callable[[Chart, dict[str, str]], str],
) -> Files:
    """The package of the asyncio and smach backends: member modules, `__init__.py` (from the
    backend's templates), `__main__.py`, the simulated behaviours, the typed
    behaviours (`behaviour_types.py`) and the vendored runtime."""
    if not charts:
        return {}  # no state machine, nothing to run
    package = PurePosixPath(package_name(model))
    modules = member_modules(charts)
    common = common_view(charts, runtime="._runtime")
    files: Files = {}
    for chart in charts:
        files[package / f"{modules[chart.name]}.py"] = render_member(chart, common)
    members = {c.member: modules[c.name] for c in charts if c.member}
    network = swarm_network(model)
    init = render(
        f"{backend}/package_init.py.j2",
        **common,
        model=doc_text(model.name),
        package=str(package),
        first_member=doc_text(next(iter(members), "")),
        modules=sorted(modules.values()),
        member_modules="{" + ", ".join(f"{k!r}: {v}" for k, v in members.items()) + "}",
        composition=repr(swarm_composition(model)),
        network=repr(network.values),
        network_sources=one_line(", ".join(network.sources)) if network.sources else "none given",
        exports=repr(["COMPOSITION", "MEMBER_TYPES", "NETWORK", *sorted(modules.values())]),
    )
    files[package / "__init__.py"] = format_python(init)
    main = render("common/main.py.j2", **common, package=str(package))
    behaviours = render(
        f"{backend}/behaviours.py.j2",
        **common,
        signatures=signatures(charts),
        scripts=default_scripts(charts),
    )
    files[package / "__main__.py"] = format_python(main)
    files[package / "behaviours.py"] = format_python(behaviours)
    typed = render_types(model, charts, str(package), common)
    files[package / f"{MODULE}.py"] = format_python(typed)
    files.update(runtime_files(package / "_runtime", runtime_modules))
    return files
