"""Names in guards, effects and bindings: member data, event fields, events raised or sent."""

from __future__ import annotations

from collections.abc import Iterable

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir import expr
from swarmgen.ir.nodes import Model, Property, State, Transition, TriggerKind
from swarmgen.ir.query import ModelIndex, walk
from swarmgen.span import Span

_NO_EVENT = frozenset[str]()


def check_expressions(model: Model) -> list[Diagnostic]:
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    for machine in model.machines:
        scope = index.data_scope[machine.id]
        states = {p.vertex.id: p.vertex for p in walk(machine) if isinstance(p.vertex, State)}
        for transition in machine.transitions:
            fields = _event_fields(index, transition, states)
            if transition.guard is not None:
                found.extend(_names(transition.guard, scope, fields, transition.span, "guard"))
            found.extend(
                _actions(index, transition.effect, scope, fields, transition.span, "effect")
            )
        for state in states.values():
            found.extend(_actions(index, state.entry, scope, _NO_EVENT, state.span, "entry action"))
            found.extend(_actions(index, state.exit, scope, _NO_EVENT, state.span, "exit action"))
            found.extend(_bindings(index, state, scope))
    return found


def _event_fields(
    index: ModelIndex, transition: Transition, states: dict[str, State]
) -> frozenset[str] | None:
    """Fields every trigger of the transition carries; None when no trigger is typed."""
    per_trigger: list[frozenset[str]] = []
    for trigger in transition.triggers:
        if trigger.kind == TriggerKind.EVENT and trigger.event in index.events:
            per_trigger.append(frozenset(f.name for f in index.events[trigger.event].fields))
        elif trigger.kind == TriggerKind.OUTCOME:
            state = states.get(transition.source)
            call = state.activity if state is not None else None
            behaviour = index.behaviours.get(call.behaviour) if call is not None else None
            per_trigger.append(
                frozenset(o.name for o in behaviour.outputs) if behaviour else _NO_EVENT
            )
        elif trigger.kind in {TriggerKind.CALL, TriggerKind.ANY} or (
            trigger.kind == TriggerKind.EVENT and trigger.event is None
        ):
            return None  # untyped events (plain UML models): their fields are unknown
        else:
            per_trigger.append(_NO_EVENT)
    if not per_trigger:
        return _NO_EVENT
    return frozenset.intersection(*per_trigger)


def _names(
    e: expr.Expr, scope: dict[str, Property], fields: frozenset[str] | None, span: Span, what: str
) -> list[Diagnostic]:
    found = []
    for name in sorted(expr.free_names(e) - scope.keys()):
        found.append(
            dg.diag(
                dg.UNKNOWN_NAME,
                f"{what} uses '{name}', which is not member data",
                span,
                hint=_suggest(name, scope) or "declare it as an attribute of the member type",
            )
        )
    if fields is not None:
        for name in sorted(expr.event_fields(e) - fields):
            found.append(
                dg.diag(
                    dg.UNKNOWN_FIELD,
                    f"{what} reads event.{name}, but the triggering event has no field '{name}'",
                    span,
                    notes=[f"its fields are: {', '.join(sorted(fields)) or 'none'}"],
                )
            )
    return found


def _suggest(name: str, scope: Iterable[str]) -> str | None:
    lowered = name.lower()
    for candidate in sorted(scope):
        if candidate.lower() == lowered or candidate.replace("_", "").lower() == lowered.replace(
            "_", ""
        ):
            return f"did you mean '{candidate}'?"
    return None


def _actions(
    index: ModelIndex,
    actions: tuple[expr.Action, ...],
    scope: dict[str, Property],
    fields: frozenset[str] | None,
    span: Span,
    what: str,
) -> list[Diagnostic]:
    found: list[Diagnostic] = []
    for action in actions:
        if isinstance(action, expr.Assign):
            if action.target not in scope:
                found.append(
                    dg.diag(
                        dg.UNKNOWN_NAME,
                        f"{what} assigns '{action.target}', which is not member data",
                        span,
                        hint=_suggest(action.target, scope)
                        or "declare it as an attribute of the member type",
                    )
                )
            found.extend(_names(action.value, scope, fields, span, what))
            continue
        for arg in action.args:
            found.extend(_names(arg.value, scope, fields, span, what))
        found.extend(_event_use(index, action, span, what))
    return found


def _event_use(
    index: ModelIndex, action: expr.Raise | expr.Send, span: Span, what: str
) -> list[Diagnostic]:
    event = index.events_by_name.get(action.event)
    verb = "raises" if isinstance(action, expr.Raise) else "sends"
    if event is None:
        if not index.model.uses_profile and not index.model.events:
            return []
        return [
            dg.diag(
                dg.UNKNOWN_EVENT,
                f"{what} {verb} '{action.event}', which is not a declared event",
                span,
                hint=f"declare a Signal «SwarmEvent» named '{action.event}'",
            )
        ]
    declared = {f.name for f in event.fields}
    return [
        dg.diag(
            dg.EVENT_ARGUMENT,
            f"{what} {verb} '{event.name}' with field '{arg.name}', which the event does not have",
            span,
            notes=[f"its fields are: {', '.join(sorted(declared)) or 'none'}"],
        )
        for arg in action.args
        if arg.name not in declared
    ]


def _bindings(index: ModelIndex, state: State, scope: dict[str, Property]) -> list[Diagnostic]:
    if state.activity is None:
        return []
    behaviour = index.behaviours.get(state.activity.behaviour)
    if behaviour is None:
        return []
    inputs = {p.name for p in behaviour.inputs}
    found: list[Diagnostic] = []
    for binding in state.activity.bindings:
        if binding.name not in inputs:
            found.append(
                dg.diag(
                    dg.BINDING_ERROR,
                    f"'{behaviour.name}' has no input '{binding.name}'",
                    state.activity.span,
                    notes=[f"its inputs are: {', '.join(sorted(inputs)) or 'none'}"],
                )
            )
        found.extend(
            _names(binding.value, scope, _NO_EVENT, state.activity.span, "argument binding")
        )
    # inputs that are neither bound nor member data: see hardware.check_parameters (per member)
    return found
