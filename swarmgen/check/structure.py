"""Structural rules of state machines: initial states, pseudostates, finals, submachines."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import (
    FinalState,
    Machine,
    Model,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    Transition,
    TriggerKind,
)
from swarmgen.ir.query import ModelIndex, initial_of, outgoing, walk

_TRANSIENT = {PseudoKind.CHOICE, PseudoKind.JUNCTION, PseudoKind.FORK}


def check_initial_states(model: Model) -> list[Diagnostic]:
    """Every region that can be entered by default needs exactly one initial pseudostate.

    A region of a composite state that no transition targets (entered only through a fork or
    by transitions to its substates) may go without one, as UML allows.
    """
    found: list[Diagnostic] = []
    for machine in model.machines:
        targeted = {t.target for t in machine.transitions}
        for region in machine.regions:
            found.extend(_region_initial(machine, region, needs_initial=True))
        for placed in walk(machine):
            if isinstance(placed.vertex, State):
                entered = placed.vertex.id in targeted
                for region in placed.vertex.regions:
                    found.extend(_region_initial(machine, region, needs_initial=entered))
    return found


def _region_initial(machine: Machine, region: Region, needs_initial: bool) -> list[Diagnostic]:
    initials = initial_of(region)
    if len(initials) > 1:
        return [
            dg.DUPLICATE_INITIAL.at(
                initials[1].span,
                notes=[dg.DUPLICATE_INITIAL.note("first-at", where=initials[0].span.location())],
                region=region.name or machine.name,
                count=len(initials),
            )
        ]
    states = [v for v in region.vertices if isinstance(v, State | FinalState)]
    if not initials and states and needs_initial:
        return [
            dg.MISSING_INITIAL.at(
                region.span, region=region.name or machine.name, first=states[0].name
            )
        ]
    return []


def check_pseudostates(model: Model) -> list[Diagnostic]:
    """Report finals with outgoing transitions and misused pseudostates."""
    found: list[Diagnostic] = []
    for machine in model.machines:
        leaving = outgoing(machine)
        for placed in walk(machine):
            vertex = placed.vertex
            out = leaving.get(vertex.id, [])
            if isinstance(vertex, FinalState) and out:
                found.append(dg.FINAL_WITH_OUTGOING.at(out[0].span, state=vertex.name))
            if isinstance(vertex, Pseudostate):
                found.extend(_pseudostate_rules(vertex, out))
    return found


def _pseudostate_rules(vertex: Pseudostate, out: list[Transition]) -> list[Diagnostic]:
    label = f"{vertex.kind.value} '{vertex.name}'" if vertex.name else vertex.kind.value
    if vertex.kind == PseudoKind.INITIAL:
        if len(out) != 1:
            return [dg.BAD_INITIAL_TRANSITION.at(vertex.span, label=label, count=len(out))]
        if out[0].triggers or out[0].guard is not None:
            return [dg.BAD_INITIAL_TRANSITION.at(out[0].span, "trigger", label=label)]
    if vertex.kind in _TRANSIENT and not out:
        return [dg.BAD_PSEUDOSTATE.at(vertex.span, "no-outgoing", label=label)]
    if vertex.kind in _TRANSIENT | {PseudoKind.JOIN}:
        with_triggers = [t for t in out if t.triggers]
        if with_triggers:
            return [dg.BAD_PSEUDOSTATE.at(with_triggers[0].span, "trigger", label=label)]
    if vertex.kind in {PseudoKind.SHALLOW_HISTORY, PseudoKind.DEEP_HISTORY} and len(out) > 1:
        return [dg.BAD_PSEUDOSTATE.at(vertex.span, "several-defaults", label=label)]
    return []


def check_submachines(model: Model) -> list[Diagnostic]:
    """A machine may not contain itself, directly or through other submachines."""
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    reported: set[frozenset[str]] = set()
    for machine in model.machines:
        cycle = _cycle_from(index, machine.id, [machine.id])
        if cycle and frozenset(cycle) not in reported:
            reported.add(frozenset(cycle))
            names = " -> ".join(index.machines[m].name for m in cycle)
            found.append(dg.SUBMACHINE_CYCLE.at(machine.span, machine=machine.name, cycle=names))
    return found


def _cycle_from(index: ModelIndex, start: str, path: list[str]) -> list[str] | None:
    machine = index.machines.get(path[-1])
    if machine is None:
        return None
    for sub in dict.fromkeys(index.submachines(machine)):
        if sub == start:
            return [*path, sub]
        if sub not in path:
            found = _cycle_from(index, start, [*path, sub])
            if found:
                return found
    return None


def check_outcomes(model: Model) -> list[Diagnostic]:
    """Outcome triggers need a behaviour in their state, and one that can produce them."""
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    for machine in model.machines:
        states = {p.vertex.id: p.vertex for p in walk(machine) if isinstance(p.vertex, State)}
        for transition in machine.transitions:
            state = states.get(transition.source)
            for trigger in transition.triggers:
                if trigger.kind != TriggerKind.OUTCOME:
                    continue
                call = state.activity if state is not None else None
                if call is None:
                    found.append(
                        dg.OUTCOME_WITHOUT_BEHAVIOUR.at(
                            trigger.span,
                            outcome=trigger.name,
                            state=_name_of(machine, transition.source),
                        )
                    )
                    continue
                behaviour = index.behaviours[call.behaviour]
                if trigger.name not in behaviour.outcomes:
                    found.append(
                        dg.UNKNOWN_OUTCOME.at(
                            trigger.span,
                            notes=[
                                dg.UNKNOWN_OUTCOME.note(
                                    "outcomes", outcomes=", ".join(behaviour.outcomes)
                                )
                            ],
                            behaviour=behaviour.name,
                            outcome=trigger.name,
                        )
                    )
    return found


def _name_of(machine: Machine, vertex_id: str) -> str:
    for placed in walk(machine):
        if placed.vertex.id == vertex_id:
            return placed.vertex.name
    return vertex_id
