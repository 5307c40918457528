"""From a model file to the `System` to explore: validation, the member types' engines built
from the asyncio backend's generated modules (as `simulate` builds them), the composition, the
station's events, and where the model's states and events are (for located diagnostics)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import field
from pathlib import Path

from swarmgen import diagnostics as dg
from swarmgen.errors import SwarmgenError
from swarmgen.ir.nodes import FinalState, Model, State
from swarmgen.ir.query import composition, sessions, walk
from swarmgen.records import dataclass
from swarmgen.span import Span
from swarmgen.verify.domains import endings
from swarmgen.verify.kinds import make_kind
from swarmgen.verify.state import thaw
from swarmgen.verify.system import System

DEFAULT_ABORT = "missionAbort"
MAX_MEMBERS = 64  # members of one composition (each is a position of every state)


class VerifyError(SwarmgenError):
    """The command cannot verify as asked (a bad `--members`, an unknown abort event)."""


@dataclass
class Loaded:
    """A validated model and its system, or the validation's diagnostics when it has errors."""

    path: Path
    diagnostics: list[dg.Diagnostic]
    model: Model | None = None
    system: System | None = None
    counts: dict[str, int] = field(default_factory=dict)
    names: dict[str, dict[str, str]] = field(default_factory=dict)  # type -> node id -> name


def parse_members(text: str | None) -> dict[str, int]:
    """`UAV=2,UGV=1` as counts; `VerifyError` on anything else."""
    counts: dict[str, int] = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        name, sep, number = item.partition("=")
        if not sep or not number.strip().isdigit():
            raise VerifyError(f"--members: '{item.strip()}' is not TYPE=COUNT")
        counts[name.strip()] = int(number)
    return counts


def load(
    path: Path,
    members: Mapping[str, int] | None = None,
    abort: Sequence[str] = (),
    emit_bound: int = 1,
    interfaces: Sequence[Path] = (),
    *,
    station_bound: int = 1,
) -> Loaded:
    """Validate the model and compose its swarm; `members` overrides counts of the model's
    swarm, `abort` names the abort events (default: `missionAbort` when the model has it)."""
    from swarmgen import pipeline
    from swarmgen.sim.machines import machines_of, run_module

    validation = pipeline.validate(path, interfaces)
    loaded = Loaded(path, list(validation.diagnostics), validation.model)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        return loaded
    model = validation.model
    if sessions(model):  # a child session's state is no part of a member's snapshot
        raise VerifyError(
            "the model invokes SCXML sessions (<invoke>), which the verifier does not explore"
        )
    machines = machines_of(path, validation)  # validated once, above
    counts = _counts(composition(model), members or {}, machines.types())
    emits = {b.name: b.emits for b in model.behaviours}
    kinds = []
    for machine in machines.members:
        # a chart of its own: the verifier instruments its entries, so it cannot share
        # `sim.machines.build_chart`'s copy
        chart, scopes = run_module(machine)
        kind_emits = {b: emits.get(b, ()) for b in machine.outputs}
        kind = make_kind(machine.member_type, chart, scopes, kind_emits)
        kind.endings = endings(model, chart, machine.member_type, thaw(kind.initial.data) or {})
        kinds.append(kind)
        loaded.names[machine.member_type] = dict(chart.names)
    used = {e for m in machines.members for e in m.scopes}
    station = [e.name for e in model.events if e.sender == "station" and e.name in used]
    aborts = _aborts(abort, station)
    loaded.system = System(kinds, counts, station, aborts, emit_bound, station_bound)
    loaded.counts = counts
    return loaded


def _counts(
    model_counts: Mapping[str, int], override: Mapping[str, int], types: Sequence[str]
) -> dict[str, int]:
    unknown = sorted(set(override) - set(types))
    if unknown:
        raise VerifyError(
            f"--members: no member type {', '.join(map(repr, unknown))}; "
            f"choose from: {', '.join(types)}"
        )
    counts = {t: override.get(t, model_counts.get(t, 0)) for t in types}
    if sum(counts.values()) == 0:
        raise VerifyError("the swarm has no members to verify; give counts with --members")
    if sum(counts.values()) > MAX_MEMBERS:
        raise VerifyError(f"--members: more than {MAX_MEMBERS} members")
    return counts


def _aborts(named: Sequence[str], station: Sequence[str]) -> list[str]:
    if not named:
        return [DEFAULT_ABORT] if DEFAULT_ABORT in station else []
    unknown = [a for a in named if a not in station]
    if unknown:
        choices = ", ".join(station) or "none"
        raise VerifyError(
            f"--abort: '{unknown[0]}' is not a station event of the model's members "
            f"(station events: {choices})"
        )
    return list(named)


def state_span(model: Model, member_type: str, name: str) -> Span:
    """Where the state called `name` of the member type's machine is (the model file when no
    vertex has that name)."""
    machine_id = next((m.machine for m in model.member_types if m.name == member_type), None)
    for machine in model.machines:
        if machine.id != machine_id:
            continue
        for placed in walk(machine):
            if isinstance(placed.vertex, State | FinalState) and placed.vertex.name == name:
                return placed.vertex.span
    return Span(file=model.source)


def event_span(model: Model, name: str) -> Span:
    """Where the event called `name` is declared."""
    return next((e.span for e in model.events if e.name == name), Span(file=model.source))


def swarm_span(model: Model) -> Span:
    """Where the (first) swarm composition is declared."""
    return model.swarms[0].span if model.swarms else Span(file=model.source)
