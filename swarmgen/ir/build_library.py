"""Building the behaviour library (stereotyped operations) and the swarm events (signals)."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.frontend.raw import RawElement, StereotypeApplication
from swarmgen.ir.build_context import (
    BEHAVIOUR_KINDS,
    Builder,
)
from swarmgen.ir.nodes import (
    DEFAULT_OUTCOMES,
    Behaviour,
    Event,
    RosBinding,
)
from swarmgen.names import event_name, identifier


def read_behaviour(b: Builder, element: RawElement) -> Behaviour | None:
    """A behaviour operation of the library (its stereotype, parameters, outcomes, ROS binding)."""
    app = b.stereotype(element, BEHAVIOUR_KINDS)
    if app is None:
        return None
    params = list(element.kids("ownedParameter"))
    inputs = [p for p in params if p.attrs.get("direction", "in") in {"in", "inout"}]
    outputs = [p for p in params if p.attrs.get("direction", "in") in {"out", "inout", "return"}]
    extra = app.tags.get("outcomes", "").replace(",", " ").split()
    outcomes = tuple(dict.fromkeys((*DEFAULT_OUTCOMES, *extra)))
    for outcome in outcomes:
        _check_outcome_name(b, element, app, outcome)
    ros_kind = b.tag_choice(app, "rosKind", ("action", "service", "topic"))
    ros = None
    if ros_kind is not None:
        ros = RosBinding(
            kind=ros_kind,
            name=app.tags.get("rosName") or None,
            type=app.tags.get("rosType") or None,
        )
    return Behaviour(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        kind=BEHAVIOUR_KINDS[app.name],
        library=_library_name(b, element),
        inputs=tuple(b.prop(p) for p in inputs),
        outputs=tuple(b.prop(p) for p in outputs),
        outcomes=outcomes,
        requires=tuple(_requires(b, app)),
        emits=tuple(dict.fromkeys(app.tags.get("emits", "").replace(",", " ").split())),
        ros=ros,
        span=element.span,
    )


def _check_outcome_name(
    b: Builder, element: RawElement, app: StereotypeApplication, outcome: str
) -> None:
    """An outcome travels by its own name (the behaviour returns `lost.far`) as a token of the
    event `done.invoke.<state>.<outcome>`: SCXML matches event descriptors by dot-separated
    prefix, so `lost.far` fired the `lost` transition. Only names that are their own
    identifier are safe in every engine and in SMACH's outcome keys (docs/profile.md)."""
    if identifier(outcome) == outcome:
        return
    b.diags.append(
        dg.BAD_OUTCOME_NAME.at(
            app.span, outcome=outcome, name=element.name, suggestion=identifier(outcome)
        )
    )


def _requires(b: Builder, app: StereotypeApplication) -> list[str]:
    names = []
    for token in app.tags.get("requires", "").replace(",", " ").split():
        target = b.raw.resolve(token)  # an id is accepted as well as a class name
        names.append(target.name if target is not None else token)
    return names


def _library_name(b: Builder, element: RawElement) -> str:
    current = element.parent
    fallback = ""
    while current is not None:
        if current.uml_type == "Package":
            if b.stereotype(current, {"BehaviorLibrary"}) is not None:
                return current.name
            fallback = fallback or current.name
        current = current.parent
    return fallback


def read_event(b: Builder, element: RawElement) -> Event:
    """A signal as an event, with its «SwarmEvent» sender and scope if it has them."""
    app = b.stereotype(element, {"SwarmEvent"})
    sender = scope = None
    if app is not None:
        sender = b.tag_choice(app, "sender", ("station", "member"))
        scope = b.tag_choice(app, "scope", ("local", "swarm"))
    return Event(
        id=element.id or element.span.path,
        name=element.name,
        ident=event_name(element.name),
        fields=tuple(b.prop(a) for a in element.kids("ownedAttribute")),
        sender=sender,
        scope=scope,
        swarm_event=app is not None,
        span=element.span,
    )
