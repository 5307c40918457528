"""Names in guards, effects and bindings: member data, event fields, events raised or sent."""

from __future__ import annotations

import re
from collections.abc import Iterable

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import FinalState, Model, Property, State, Transition, TriggerKind
from swarmgen.ir.query import ModelIndex, walk
from swarmgen.names import identifier
from swarmgen.span import Span

_NO_EVENT = frozenset[str]()
# the datum an assignment's location starts with: `x`, `x.y`, `x["y"]`
_ROOT = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:$|[.\[])")


def check_expressions(model: Model) -> list[Diagnostic]:
    """Report unknown names, event fields and events in guards, actions and bindings."""
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
        for placed in walk(machine):
            final = placed.vertex
            if isinstance(final, FinalState):
                for actions, what in ((final.entry, "entry action"), (final.exit, "exit action")):
                    found.extend(_actions(index, actions, scope, _NO_EVENT, final.span, what))
                done = [a.value for a in final.donedata] + [final.done_content] * bool(
                    final.done_content
                )
                for value in done:
                    if value is not None:
                        found.extend(_names(value, scope, _NO_EVENT, final.span, "done data"))
        for transition in machine.transitions:
            found.extend(_misplaced_blocks(transition.effect, transition.span, "effect", top=False))
        for state in states.values():
            for actions in (state.entry, state.exit):
                found.extend(_misplaced_blocks(actions, state.span, "entry or exit action"))
        for state in states.values():
            found.extend(_actions(index, state.entry, scope, _NO_EVENT, state.span, "entry action"))
            found.extend(_actions(index, state.exit, scope, _NO_EVENT, state.span, "exit action"))
            found.extend(_bindings(index, state, scope))
            for invoke in state.invokes:  # its params' names are the child's (not checked here)
                found += [
                    _invalid(invoke.span, "invoke", "reads", node)
                    for param in invoke.params
                    for node in expr.walk(param.value)
                    if isinstance(node, expr.Invalid)
                ]
    return found + _unknown_states(model)


def _misplaced_blocks(
    actions: tuple[expr.Action, ...], span: Span, what: str, top: bool = True
) -> list[Diagnostic]:
    """`block ... end` stands only at the top of an entry or exit behaviour (SCXML's separate
    `<onentry>`/`<onexit>` elements; nothing else can spell it)."""
    nested = [a for a in actions if not (top and isinstance(a, expr.Block))]
    inner = [b for a in actions if isinstance(a, expr.Block) for b in a.actions]
    if any(isinstance(a, expr.Block) for a in expr.flat((*nested, *inner))):
        return [
            dg.EFFECT_SYNTAX.at(
                span,
                what=what,
                error="has a block where none may stand",
                hint="`block ... end` stands only at the top of an entry or exit action",
            )
        ]
    return []


def _unknown_states(model: Model) -> list[Diagnostic]:
    """`In("S")` where no state of the model is named S (nor has S as an SCXML id: a name
    made an identifier, or a qualified `A__B`; lowering resolves it: `chart.instates`)."""
    known = {p.vertex.name for m in model.machines for p in walk(m) if p.vertex.name}
    known |= {identifier(name) for name in known}
    found: list[Diagnostic] = []
    for machine in model.machines:
        places: list[tuple[tuple[expr.Action, ...], expr.Expr | None, Span, str]] = [
            (t.effect, t.guard, t.span, "transition") for t in machine.transitions
        ]
        for placed in walk(machine):
            if isinstance(placed.vertex, State):
                vertex = placed.vertex
                actions = (*vertex.entry, *vertex.exit)
                places.append((actions, None, vertex.span, "entry or exit action"))
        for actions, guard, span, what in places:
            exprs = [guard] if guard is not None else []
            exprs += [e for a in expr.flat(actions) for e in expr.action_exprs(a)]
            for name in sorted({s for e in exprs for s in expr.in_states(e)}):
                if name not in known and "__" not in name:
                    found.append(dg.UNKNOWN_NAME.at(span, "state", what=what, name=name))
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
        elif trigger.kind in {TriggerKind.CALL, TriggerKind.ANY, TriggerKind.DONE} or (
            trigger.kind == TriggerKind.EVENT and trigger.event is None
        ):
            return None  # untyped events (plain UML models): their fields are unknown
        else:
            per_trigger.append(_NO_EVENT)
    if not per_trigger:
        source = states.get(transition.source)
        completion = source is not None and bool(source.regions) and not transition.eventless
        # a composite state's completion: done.state.<id>, whose fields its final states' done
        # data gives (untyped)
        return None if completion else _NO_EVENT
    return frozenset.intersection(*per_trigger)


def _names(
    e: expr.Expr, scope: dict[str, Property], fields: frozenset[str] | None, span: Span, what: str
) -> list[Diagnostic]:
    found = []
    for name in sorted(expr.free_names(e) - scope.keys()):
        found.append(_unknown_name(span, dg.DEFAULT, what, name, scope))
    for node in expr.walk(e):  # an SCXML document's undeclared reference: fails when it runs
        if isinstance(node, expr.Invalid):
            found.append(_invalid(span, what, "reads", node))
    if fields is not None:
        for name in sorted(expr.event_fields(e) - fields):
            found.append(
                dg.UNKNOWN_FIELD.at(
                    span,
                    notes=[_listing(dg.UNKNOWN_FIELD, "fields", fields)],
                    what=what,
                    name=name,
                )
            )
    return found


def _invalid(span: Span, what: str, verb: str, node: expr.Invalid) -> Diagnostic:
    """SG158: a reference that is no location, kept to fail when it runs (W3C's semantics)."""
    return dg.INVALID_LOCATION.at(span, what=what, verb=verb, location=node.location)


def _declared_invalid(
    span: Span, what: str, node: expr.Invalid, scope: dict[str, Property]
) -> list[Diagnostic]:
    """SG159: `invalid("x") = e` where x is member data, which the emitted `<assign>` (the
    location as written) would assign where Python fails (the SCXML reader never makes one)."""
    root = _ROOT.match(node.location)
    if root is None or root.group(1) not in scope:
        return []
    values = {"what": what, "location": node.location, "name": root.group(1)}
    return [dg.DECLARED_INVALID_LOCATION.at(span, **values)]


def _unknown_name(
    span: Span, variant: str, what: str, name: str, scope: Iterable[str]
) -> Diagnostic:
    """SG112 (`variant`: a use or "assigns"), hinting at the member data spelt alike if any."""
    near = _near(name, scope)
    if near is None:
        return dg.UNKNOWN_NAME.at(span, variant, what=what, name=name)
    variant = "near" if variant == dg.DEFAULT else f"{variant}-near"
    return dg.UNKNOWN_NAME.at(span, variant, what=what, name=name, near=near)


def _near(name: str, scope: Iterable[str]) -> str | None:
    """The member data whose name differs from `name` only in case or underscores."""
    lowered = name.lower()
    for candidate in sorted(scope):
        if candidate.lower() == lowered or candidate.replace("_", "").lower() == lowered.replace(
            "_", ""
        ):
            return candidate
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
    for action in expr.flat(actions):
        if isinstance(action, expr.Assign):
            assigned = action.target
            if isinstance(assigned, expr.Invalid):  # an SCXML document's: fails when it runs
                found.append(_invalid(span, what, "assigns", assigned))
                found.extend(_declared_invalid(span, what, assigned, scope))
            elif assigned not in scope and assigned not in expr.SYSTEM_VARIABLES:
                found.append(_unknown_name(span, "assigns", what, assigned, scope))
            found.extend(_names(action.value, scope, fields, span, what))
            continue
        if isinstance(action, expr.Done):
            found.append(
                dg.EFFECT_SYNTAX.at(
                    span,
                    what=what,
                    error="gives done(...), the done data of a final state",
                    hint="only a final state's entry action gives done data",
                )
            )
            continue
        if isinstance(action, expr.ForEach):
            for target in (action.item, action.index):
                if target is not None and target not in scope:
                    found.append(_unknown_name(span, "assigns", what, target, scope))
        if isinstance(action, expr.Raise) and action.into is not None and action.into not in scope:
            found.append(_unknown_name(span, "assigns", what, action.into, scope))
        if isinstance(action, expr.Block):
            continue  # its actions follow (`flat`); where it stands: `_misplaced_blocks`
        if isinstance(action, expr.Cancel | expr.If | expr.ForEach | expr.Log):
            for value in expr.action_exprs(action):
                found.extend(_names(value, scope, fields, span, what))
            continue
        for value in expr.action_exprs(action):
            found.extend(_names(value, scope, fields, span, what))
        found.extend(_event_use(index, action, span, what))
    return found


def _event_use(
    index: ModelIndex, action: expr.Raise | expr.Send, span: Span, what: str
) -> list[Diagnostic]:
    if action.event is None:  # `raise (expr)`: a name computed when it runs (any event's)
        return []
    event = index.events_by_name.get(action.event)
    verb = "raises" if isinstance(action, expr.Raise) else "sends"
    if event is None:
        if not index.model.uses_profile and not index.model.events:
            return []
        return [dg.UNKNOWN_EVENT.at(span, "action", what=what, verb=verb, event=action.event)]
    declared = {f.name for f in event.fields}
    return [
        dg.EVENT_ARGUMENT.at(
            span,
            notes=[_listing(dg.EVENT_ARGUMENT, "fields", declared)],
            what=what,
            verb=verb,
            event=event.name,
            field=arg.name,
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
                dg.BINDING_ERROR.at(
                    state.activity.span,
                    "no-input",
                    notes=[_listing(dg.BINDING_ERROR, "inputs", inputs)],
                    behaviour=behaviour.name,
                    name=binding.name,
                )
            )
        found.extend(
            _names(binding.value, scope, _NO_EVENT, state.activity.span, "argument binding")
        )
    # inputs that are neither bound nor member data: see hardware.check_parameters (per member)
    return found


def _listing(code: dg.Code, what: str, names: Iterable[str]) -> str:
    """The note listing what an event or behaviour has (`its fields are: a, b`), or none."""
    shown = ", ".join(sorted(names))
    return code.note(what, **{what: shown}) if shown else code.note(f"no-{what}")
