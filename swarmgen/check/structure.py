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
            dg.diag(
                dg.DUPLICATE_INITIAL,
                f"region '{region.name or machine.name}' has {len(initials)} initial pseudostates",
                initials[1].span,
                notes=[f"the first is at {initials[0].span.location()}"],
                hint="keep one initial pseudostate per region",
            )
        ]
    states = [v for v in region.vertices if isinstance(v, State | FinalState)]
    if not initials and states and needs_initial:
        return [
            dg.diag(
                dg.MISSING_INITIAL,
                f"region '{region.name or machine.name}' has states but no initial pseudostate",
                region.span,
                hint=f"add an initial pseudostate with a transition to the first state (e.g. '{states[0].name}')",
            )
        ]
    return []


def check_pseudostates(model: Model) -> list[Diagnostic]:
    found: list[Diagnostic] = []
    for machine in model.machines:
        leaving = outgoing(machine)
        for placed in walk(machine):
            vertex = placed.vertex
            out = leaving.get(vertex.id, [])
            if isinstance(vertex, FinalState) and out:
                found.append(
                    dg.diag(
                        dg.FINAL_WITH_OUTGOING,
                        f"transition leaves final state '{vertex.name}'",
                        out[0].span,
                        hint="a final state ends its region; use an ordinary state instead",
                    )
                )
            if isinstance(vertex, Pseudostate):
                found.extend(_pseudostate_rules(vertex, out))
    return found


def _pseudostate_rules(vertex: Pseudostate, out: list[Transition]) -> list[Diagnostic]:
    label = f"{vertex.kind.value} '{vertex.name}'" if vertex.name else vertex.kind.value
    if vertex.kind == PseudoKind.INITIAL:
        if len(out) != 1:
            return [
                dg.diag(
                    dg.BAD_INITIAL_TRANSITION,
                    f"{label} has {len(out)} outgoing transitions; it needs exactly one",
                    vertex.span,
                )
            ]
        if out[0].triggers or out[0].guard is not None:
            return [
                dg.diag(
                    dg.BAD_INITIAL_TRANSITION,
                    f"the transition from {label} has a trigger or guard",
                    out[0].span,
                    hint="an initial transition fires at once; move the trigger to the next transition",
                )
            ]
    if vertex.kind in _TRANSIENT and not out:
        return [dg.diag(dg.BAD_PSEUDOSTATE, f"{label} has no outgoing transition", vertex.span)]
    if vertex.kind in _TRANSIENT | {PseudoKind.JOIN}:
        with_triggers = [t for t in out if t.triggers]
        if with_triggers:
            return [
                dg.diag(
                    dg.BAD_PSEUDOSTATE,
                    f"a transition leaving {label} has a trigger",
                    with_triggers[0].span,
                    hint="transitions out of choice, junction, fork and join pseudostates fire at once",
                )
            ]
    if vertex.kind in {PseudoKind.SHALLOW_HISTORY, PseudoKind.DEEP_HISTORY} and len(out) > 1:
        return [
            dg.diag(
                dg.BAD_PSEUDOSTATE, f"{label} has more than one default transition", vertex.span
            )
        ]
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
            found.append(
                dg.diag(
                    dg.SUBMACHINE_CYCLE,
                    f"state machine '{machine.name}' contains itself: {names}",
                    machine.span,
                    hint="a submachine state must not (even indirectly) reuse the machine it belongs to",
                )
            )
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
                        dg.diag(
                            dg.OUTCOME_WITHOUT_BEHAVIOUR,
                            f"transition waits for outcome '{trigger.name}', but "
                            f"'{_name_of(machine, transition.source)}' runs no behaviour",
                            trigger.span,
                            hint="give the state a doActivity, or use a triggerless (completion) transition",
                        )
                    )
                    continue
                behaviour = index.behaviours[call.behaviour]
                if trigger.name not in behaviour.outcomes:
                    found.append(
                        dg.diag(
                            dg.UNKNOWN_OUTCOME,
                            f"'{behaviour.name}' cannot end with outcome '{trigger.name}'",
                            trigger.span,
                            notes=[f"its outcomes are: {', '.join(behaviour.outcomes)}"],
                            hint="add the outcome to the behaviour's `outcomes` tag, or fix the trigger",
                        )
                    )
    return found


def _name_of(machine: Machine, vertex_id: str) -> str:
    for placed in walk(machine):
        if placed.vertex.id == vertex_id:
            return placed.vertex.name
    return vertex_id
