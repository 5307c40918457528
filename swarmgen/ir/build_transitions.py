"""Building transitions: their ends, triggers (events, outcomes, time), guards and effects."""

from __future__ import annotations

from dataclasses import field
from typing import Literal

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.frontend.raw import RawElement
from swarmgen.ir.build_bodies import actions_of, bodies_of, quote_error
from swarmgen.ir.build_context import (
    Builder,
    label,
)
from swarmgen.ir.literals import (
    literal_value,
)
from swarmgen.ir.nodes import (
    DEFAULT_OUTCOMES,
    Behaviour,
    OpaqueCode,
    Transition,
    Trigger,
    TriggerKind,
)
from swarmgen.records import dataclass

_EVENT_TYPES = {"SignalEvent", "TimeEvent", "CallEvent", "ChangeEvent", "AnyReceiveEvent", "Signal"}


@dataclass
class MachineContext:
    """One machine's transitions, collected from its regions, and the vertices they may join."""

    transitions: list[RawElement] = field(default_factory=list)
    vertices: dict[str, RawElement] = field(default_factory=dict)


# The error events the engine (and Qt SCXML) raise: a trigger of one of these names takes them
# (`error` every one, by SCXML's prefix rule).
ERROR_EVENTS = frozenset({"error", "error.execution", "error.communication"})


def read_transition(b: Builder, element: RawElement, ctx: MachineContext) -> Transition | None:
    """The transition `element` of the machine in `ctx`, or None when an end is missing."""
    source = b.ref(element, "source")
    target = b.ref(element, "target")
    if source is None or target is None:
        if not element.ref_values("source") or not element.ref_values("target"):
            b.diags.append(dg.BAD_TARGET.at(element.span, name=element.name))
        return None
    for end, which in ((source, "source"), (target, "target")):
        if end.id not in ctx.vertices:
            kind = end.uml_type or end.feature
            b.diags.append(
                dg.BAD_TARGET.at(element.span, "not-a-state", end=which, name=end.name, kind=kind)
            )
            return None
    source_behaviour = _source_behaviour(b, source)
    opaque: list[OpaqueCode] = []
    guard, guard_text = _guard(b, element)
    return Transition(
        id=element.id or element.span.path,
        name=element.name,
        source=source.id or "",
        target=target.id or "",
        triggers=tuple(
            t
            for raw in element.kids("trigger")
            if (t := _trigger(b, raw, source_behaviour)) is not None
        ),
        guard=guard,
        guard_text=guard_text,
        effect=actions_of(b, element.first("effect"), "effect", opaque),
        opaque=tuple(opaque),
        kind=_transition_kind(b, element),
        eventless=element.attrs.get("eventless") == "true",
        reenters=_reenters(b, element, ctx),
        span=element.span,
    )


def _reenters(b: Builder, element: RawElement, ctx: MachineContext) -> str | None:
    """The state the transition exits and enters again as a whole (`Transition.reenters`)."""
    if not element.ref_values("reenters"):
        return None
    found = b.ref(element, "reenters")
    if found is None:
        return None  # reported by `ref`
    if found.id not in ctx.vertices and found.uml_type != "StateMachine":
        kind = found.uml_type or found.feature
        b.diags.append(
            dg.BAD_TARGET.at(
                element.span, "not-a-state", end="reenters", name=found.name, kind=kind
            )
        )
        return None
    return found.id


_TRANSITION_KINDS: dict[str, Literal["external", "internal", "local"]] = {
    "external": "external",
    "internal": "internal",
    "local": "local",
}


def _transition_kind(b: Builder, element: RawElement) -> Literal["external", "internal", "local"]:
    text = element.attrs.get("kind", "external")
    if text not in _TRANSITION_KINDS:
        b.diags.append(
            dg.UNKNOWN_KIND.at(element.span, "transition", label=label(element), kind=text)
        )
    return _TRANSITION_KINDS.get(text, "external")


def _source_behaviour(b: Builder, source: RawElement) -> Behaviour | None:
    activity = source.first("doActivity")
    if activity is None:
        return None
    values = activity.ref_values("specification")
    operation = b.raw.resolve(values[0]) if values else None
    return b.behaviours.get(operation.id or "") if operation is not None else None


def _guard(b: Builder, element: RawElement) -> tuple[expr.Expr | None, str | None]:
    values = element.ref_values("guard")
    if values:
        constraint = b.ref(element, "guard", {"Constraint"})
    else:
        constraint = element.first("guard") or element.first("ownedRule")
    if constraint is None:
        return None, None
    text = constraint_text(constraint)
    if not text.strip():
        return None, None
    try:
        return b.expression(text), text
    except expr.ExprError as err:
        error = quote_error(text, err)
        b.diags.append(dg.GUARD_SYNTAX.at(constraint.span, error=error, hint=err.hint))
        return None, text


def constraint_text(constraint: RawElement, fallback: str | None = None) -> str:
    """A Constraint's text: its specification's body (or value), else `fallback` (the
    constraint's name when None)."""
    spec = constraint.first("specification")
    if spec is not None:
        if spec.uml_type == "OpaqueExpression":
            return bodies_of(spec)[1]
        if "value" in spec.attrs:
            return spec.attrs["value"]
    return constraint.name if fallback is None else fallback


def _trigger(b: Builder, element: RawElement, behaviour: Behaviour | None) -> Trigger | None:
    event = b.ref(element, "event", _EVENT_TYPES)
    if event is None:
        if element.ref_values("event"):
            return None  # already reported as dangling or of the wrong kind
        return _named_trigger(b, element, element.name, None, behaviour)
    kind = event.uml_type
    if kind == "TimeEvent":
        return _time_trigger(b, element, event)
    if kind == "CallEvent":
        operation = b.ref(event, "operation")
        name = operation.name if operation is not None else event.name
        return Trigger(kind=TriggerKind.CALL, name=name, span=element.span)
    if kind == "AnyReceiveEvent":
        return Trigger(kind=TriggerKind.ANY, name="*", span=element.span)
    if kind == "ChangeEvent":
        b.diags.append(dg.UNSUPPORTED.at(element.span, "change-event"))
        return None
    signal = event if kind == "Signal" else b.ref(event, "signal", {"Signal"})
    if signal is not None:
        return _named_trigger(b, element, signal.name, signal, behaviour)
    return _named_trigger(b, element, event.name or element.name, None, behaviour)


def _named_trigger(
    b: Builder,
    element: RawElement,
    name: str,
    signal: RawElement | None,
    behaviour: Behaviour | None,
) -> Trigger | None:
    """Outcome first: a name its state's behaviour can produce is that outcome (docs/profile.md)."""
    if behaviour is not None and name in behaviour.outcomes:
        return Trigger(kind=TriggerKind.OUTCOME, name=name, span=element.span)
    event = (
        b.events_by_signal.get(signal.id or "")
        if signal is not None
        else b.events_by_name.get(name)
    )
    if event is not None:
        return Trigger(kind=TriggerKind.EVENT, name=event.name, event=event.id, span=element.span)
    if name.removesuffix(".*") in ERROR_EVENTS:  # W3C's platform errors (docs/semantics.md)
        return Trigger(kind=TriggerKind.ERROR, name=name.removesuffix(".*"), span=element.span)
    done = name.removesuffix(".*")
    if done in ("done", "done.state", "done.invoke") or (
        done.startswith(("done.state.", "done.invoke.")) and not done.endswith(".")
    ):
        # another state's completion (its own is a triggerless transition): docs/semantics.md
        return Trigger(kind=TriggerKind.DONE, name=done, span=element.span)
    if name in DEFAULT_OUTCOMES or behaviour is not None:
        return Trigger(kind=TriggerKind.OUTCOME, name=name, span=element.span)
    if not name:
        b.diags.append(dg.UNKNOWN_EVENT.at(element.span, "unnamed"))
        return None
    if b.declares_events:
        b.diags.append(dg.UNKNOWN_EVENT.at(element.span, name=name))
        return None
    return Trigger(kind=TriggerKind.EVENT, name=name, span=element.span)


def _time_trigger(b: Builder, element: RawElement, event: RawElement) -> Trigger | None:
    when = event.first("when")
    expression = when.first("expr") if when is not None else None
    value = literal_value(expression) if expression is not None else None
    if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
        b.diags.append(dg.UNSUPPORTED.at(element.span, "time-event", event=event.name))
        return None
    return Trigger(kind=TriggerKind.TIME, name=event.name, delay_ms=int(value), span=element.span)
