"""The compiled machines the simulator runs: each member type's generated asyncio module."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmgen.records import dataclass
from swarmgen.runtime.chart import Chart
from swarmgen.runtime.engine import OUTCOME_PREFIX
from swarmgen.sim.scenario import SimulationError

if TYPE_CHECKING:
    from swarmgen.chart.model import Chart as ChartModel
    from swarmgen.pipeline import Validation


@dataclass(frozen=True)
class MemberMachine:
    """One member type's compiled behaviour: the module the asyncio backend generates for it
    (importing `swarmgen.runtime` instead of a vendored copy), plus what the library needs."""

    member_type: str
    chart_name: str
    code: str
    outputs: dict[str, tuple[tuple[str, str | None], ...]]  # behaviour -> (output, type)
    scopes: dict[str, str]  # event -> "swarm" | "local"
    # (behaviour or event, output or field) -> its initial value: the shape of the model's
    # type (a pose's nested fields) that the library fills in
    initials: dict[tuple[str, str], Any]
    # behaviour -> the events its `emits` tag names (a simulated behaviour sends only those)
    emits: dict[str, tuple[str, ...]] = field(default_factory=dict)


@dataclass(frozen=True)
class Machines:
    """The compiled member machines of a model and its swarm composition."""

    model: str
    source: str
    members: tuple[MemberMachine, ...]
    composition: dict[str, int]

    def types(self) -> list[str]:
        """The member types, in model order."""
        return [m.member_type for m in self.members]


def compile_machines(model: Path) -> Machines:
    """Validate and lower the model, and render each member type's module with the asyncio
    backend, exactly as `swarmgen compile` does."""
    return compile_variants(model, ({},))[0]


def compile_variants(
    model: Path,
    data: Sequence[Mapping[str, Mapping[str, Any]]],
    validation: Validation | None = None,
) -> list[Machines]:
    """`compile_machines` once per entry of `data` (member type -> datum -> the default it
    starts with instead of the model's: a sweep's data parameters), validating once (or not
    at all, given the model's `validation` already made)."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    if validation is None:
        validation = pipeline.validate(model)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        raise SimulationError(dg.refusal_line(model, validation.diagnostics))
    return [machines_of(model, validation, overrides) for overrides in data]


def machines_of(
    model: Path, validation: Validation, data: Mapping[str, Mapping[str, Any]] | None = None
) -> Machines:
    """The member modules of a model validated without errors (`data`: defaults in place of
    the model's, as in `compile_variants`)."""
    from swarmgen import __version__
    from swarmgen.backends.asyncio_backend import render_member
    from swarmgen.ir.query import composition as swarm_composition

    assert validation.model is not None  # the caller refused the others
    common = {"version": __version__, "source": model.name, "runtime": "swarmgen.runtime"}
    members = []
    for chart in validation.charts:  # lowered once, by validate
        if chart.member is None:
            continue  # a stand-alone machine: no member runs it
        member = chart.member
        chart = _with_defaults(chart, (data or {}).get(member, {}))
        members.append(
            MemberMachine(
                member,
                chart.name,
                render_member(chart, common),
                {b.name: b.outputs for b in chart.behaviours},
                {e.name: e.scope or "swarm" for e in chart.events},
                _initials(chart),
                {b.name: b.emits for b in validation.model.behaviours},
            )
        )
    if not members:
        raise SimulationError(f"{model}: no member type has a state machine; nothing to simulate")
    composition = swarm_composition(validation.model)
    return Machines(validation.model.name, model.name, tuple(members), composition)


def _with_defaults(chart: ChartModel, defaults: Mapping[str, Any]) -> ChartModel:
    """The chart with these data defaults (by datum name) as the data's initial values (the
    values the rendered module starts its members with; `sim.params` typed them)."""
    if not defaults:
        return chart
    data = tuple(
        replace(d, initial=defaults[d.name]) if d.name in defaults else d for d in chart.data
    )
    return replace(chart, data=data)


def _initials(chart: ChartModel) -> dict[tuple[str, str], Any]:
    """The initial values of the chart's behaviour outputs and event fields."""
    found: dict[tuple[str, str], Any] = {}
    for behaviour in chart.behaviours:
        found.update(((behaviour.name, k), v) for k, v in behaviour.output_initials)
    for event in chart.events:
        found.update(((event.name, k), v) for k, v in event.defaults)
    return found


_BUILT: dict[str, tuple[Chart, dict[str, str]]] = {}


def build_chart(machine: MemberMachine) -> tuple[Chart, dict[str, str]]:
    """Run the generated module and its `build()` (once per process)."""
    key = hashlib.sha256(machine.code.encode()).hexdigest()
    if key not in _BUILT:
        _BUILT[key] = run_module(machine)
    return _BUILT[key]


def run_module(machine: MemberMachine) -> tuple[Chart, dict[str, str]]:
    """A new chart from the generated module's `build()`, and its event scopes. The code is
    swarmgen's own rendering (model text only in string literals)."""
    namespace: dict[str, Any] = {"__name__": f"swarmgen_sim_{machine.chart_name}"}
    exec(compile(machine.code, f"<generated {machine.chart_name}>", "exec"), namespace)
    return namespace["build"](), dict(namespace["EVENT_SCOPES"])


def waited_outcomes(chart: Chart) -> dict[str, frozenset[str]]:
    """Per state with a behaviour: the outcomes some transition waits for ('*': any)."""
    descriptors = {e for n in chart.nodes.values() for t in n.transitions for e in t.events}
    waited: dict[str, frozenset[str]] = {}
    for node in chart.nodes.values():
        if node.call is None:
            continue
        prefix = f"{OUTCOME_PREFIX}{node.id}."
        names = {d[len(prefix) :] for d in descriptors if d.startswith(prefix)}
        if names & {"*", ""} or descriptors & {"*", "outcome", "outcome.*", prefix[:-1]}:
            names = {"*"}
        waited[node.id] = frozenset(n for n in names if n)
    return waited
