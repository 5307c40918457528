"""Events and outcomes across the swarm: triggers nobody can fire, sends nobody hears, and
behaviour outcomes a state does not handle."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model, State, TriggerKind
from swarmgen.ir.query import ModelIndex, outgoing, walk
from swarmgen.names import dot_prefixes

# `preempted` ends a behaviour only because its state is being left: nobody waits for it.
_UNWAITED = {"preempted"}


def _sent_by_members(model: Model) -> set[str] | None:
    """Events that effects send or raise, or that library behaviours emit (`emits` tag); None
    when a member computes an event's name (`raise (expr)`): then any event may be sent."""
    sent = {name for b in model.behaviours for name in b.emits}
    for machine in model.machines:
        actions = [a for t in machine.transitions for a in t.effect]
        for placed in walk(machine):
            if isinstance(placed.vertex, State):
                actions += [*placed.vertex.entry, *placed.vertex.exit]
        raised = [a for a in expr.flat(actions) if isinstance(a, expr.Raise | expr.Send)]
        if any(a.event is None for a in raised):
            return None
        sent |= {a.event for a in raised if a.event is not None}
    return sent


def check_events(model: Model) -> list[Diagnostic]:
    """Report events nobody sends, events nobody handles and unhandled behaviour outcomes."""
    if not any(e.swarm_event for e in model.events):
        return []  # plain UML models: their environment sends the signals
    members = _sent_by_members(model)
    sent = members if members is not None else set()
    station = {e.name for e in model.events if e.sender == "station"}
    triggered: dict[str, list[object]] = {}
    found: list[Diagnostic] = []
    heard = dot_prefixes(sent | station)
    for machine in model.machines:
        for transition in machine.transitions:
            for trigger in transition.triggers:
                if trigger.kind != TriggerKind.EVENT:
                    continue
                triggered.setdefault(trigger.name, []).append(trigger)
                if trigger.name not in heard and members is not None:
                    found.append(dg.NEVER_SENT.at(trigger.span, event=trigger.name))
    for event in model.events:
        if (event.name in sent or event.name in station) and not (
            dot_prefixes({event.name}) & triggered.keys()
        ):
            found.append(dg.NEVER_HANDLED.at(event.span, event=event.name))
    return found


def check_unhandled_outcomes(model: Model) -> list[Diagnostic]:
    """A state that handles some outcomes of its behaviour should handle all it can produce;
    a state that handles none treats its behaviour as running until preempted."""
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    for machine in model.machines:
        leaving = outgoing(machine)  # once per machine, not a scan per state
        for placed in walk(machine):
            state = placed.vertex
            if not isinstance(state, State) or state.activity is None:
                continue
            transitions = leaving.get(state.id, [])
            if any(not t.triggers and not t.eventless for t in transitions):
                continue  # a completion transition handles every outcome
            handled = {
                tr.name for t in transitions for tr in t.triggers if tr.kind == TriggerKind.OUTCOME
            }
            if not handled:
                continue
            behaviour = index.behaviours[state.activity.behaviour]
            for outcome in behaviour.outcomes:
                if outcome in handled or outcome in _UNWAITED:
                    continue
                found.append(
                    dg.UNHANDLED_OUTCOME.at(
                        state.span,
                        state=state.name,
                        handled=", ".join(sorted(handled)),
                        behaviour=behaviour.name,
                        outcome=outcome,
                    )
                )
    return found
