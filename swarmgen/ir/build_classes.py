"""Building the classes: data types, hardware with its capabilities, member types and swarms."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.frontend.raw import RawElement
from swarmgen.ir.build_context import (
    HARDWARE_KINDS,
    Builder,
    is_part,
    short,
)
from swarmgen.ir.build_transitions import constraint_text
from swarmgen.ir.literals import (
    INTEGER_TEXT,
)
from swarmgen.ir.nodes import (
    DataType,
    Enumeration,
    HardwareComponent,
    MemberType,
    Part,
    Property,
    Swarm,
    SwarmProperty,
)
from swarmgen.names import identifier


def class_ancestry(b: Builder, classes: list[RawElement]) -> dict[str, tuple[str, ...]]:
    """For every class id: the names of itself and all its ancestors (UML generalisation)."""
    parents: dict[str, list[RawElement]] = {}
    for cls in classes:
        parents[cls.id or ""] = [
            g for gen in cls.kids("generalization") if (g := b.ref(gen, "general")) is not None
        ]
    result: dict[str, tuple[str, ...]] = {}
    for cls in classes:
        seen: dict[str, str] = {}
        stack = [cls]
        while stack:
            current = stack.pop()
            if (current.id or "") in seen:
                continue
            seen[current.id or ""] = current.name
            stack.extend(parents.get(current.id or "", []))
        result[cls.id or ""] = tuple(sorted(set(seen.values())))
    return result


def read_datatype(b: Builder, element: RawElement) -> DataType:
    """A DataType with its fields and, when stereotyped «RosMessage», the ROS message it is."""
    app = b.stereotype(element, {"RosMessage"})
    ros_type = (app.tags.get("rosType") or "").strip() if app is not None else ""
    return DataType(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        fields=tuple(b.prop(a) for a in element.kids("ownedAttribute")),
        ros_type=ros_type or None,
        span=element.span,
    )


def read_enumeration(element: RawElement) -> Enumeration:
    """An Enumeration with its literals' names (unnamed and repeated literals are dropped)."""
    literals = (lit.name for lit in element.kids("ownedLiteral") if lit.name)
    return Enumeration(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        literals=tuple(dict.fromkeys(literals)),
        span=element.span,
    )


def read_hardware(
    b: Builder, element: RawElement, ancestry: dict[str, tuple[str, ...]]
) -> HardwareComponent | None:
    """A «Sensor», «Actuator», ... class with its capabilities, or None if not hardware."""
    app = b.stereotype(element, HARDWARE_KINDS)
    if app is None:
        return None
    generals = [
        g for gen in element.kids("generalization") if (g := b.ref(gen, "general")) is not None
    ]
    return HardwareComponent(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        kind=HARDWARE_KINDS[app.name],
        generals=tuple(g.name for g in generals),
        capabilities=ancestry.get(element.id or "", (element.name,)),
        parameters=tuple(b.prop(a) for a in element.kids("ownedAttribute") if not is_part(a)),
        communication_type=app.tags.get("communicationType") or None,
        communication_params=app.tags.get("communicationParams") or None,
        communication_span=app.span if app.name == "CommunicationInterface" else None,
        span=element.span,
    )


def _part(b: Builder, attribute: RawElement, target: RawElement) -> Part:
    return Part(
        name=attribute.name,
        type_id=target.id or "",
        type_name=target.name,
        count=_count(b, attribute),
        span=attribute.span,
    )


def _count(b: Builder, attribute: RawElement) -> int:
    upper = attribute.first("upperValue")
    if upper is None:
        return 1
    text = upper.attrs.get("value", "1").strip()
    # ASCII digits only: str.isdigit() also takes `²`, which int() refuses (an internal error)
    if INTEGER_TEXT.fullmatch(text) and text[0] not in "+-" and len(text) <= 18:
        return int(text)
    b.diags.append(
        dg.BAD_MULTIPLICITY.at(attribute.span, part=attribute.name, multiplicity=short(text))
    )
    return 1


def read_member(b: Builder, element: RawElement, hardware_ids: set[str]) -> MemberType | None:
    """A «SwarmMember» class: its hardware parts, data and machine; None if not a member."""
    app = b.stereotype(element, {"SwarmMember"})
    if app is None:
        return None
    parts: list[Part] = []
    data: list[Property] = []
    for attribute in element.kids("ownedAttribute"):
        target = b.ref(attribute, "type")
        if (
            target is not None
            and (target.id in hardware_ids or is_part(attribute))
            and (target.uml_type in {"Class", "Component"})
        ):
            parts.append(_part(b, attribute, target))
        else:
            data.append(b.prop(attribute))
    return MemberType(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        role=app.tags.get("role") or None,
        hardware=tuple(parts),
        data=tuple(data),
        machine=_classifier_machine(b, element),
        span=element.span,
    )


def _classifier_machine(b: Builder, element: RawElement) -> str | None:
    chosen = b.ref(element, "classifierBehavior", {"StateMachine"})
    if chosen is not None:
        return chosen.id
    owned = [e for e in element.kids("ownedBehavior") if e.uml_type == "StateMachine"]
    if not owned:
        b.diags.append(dg.MEMBER_WITHOUT_MACHINE.at(element.span, member=element.name))
        return None
    return owned[0].id


def read_swarm(b: Builder, element: RawElement, member_ids: set[str]) -> Swarm | None:
    """A «Swarm» class with its member parts, or None if not a swarm."""
    if b.stereotype(element, {"Swarm"}) is None:
        return None
    parts = []
    for attribute in element.kids("ownedAttribute"):
        target = b.ref(attribute, "type")
        if target is not None and target.id in member_ids:
            parts.append(_part(b, attribute, target))
    properties = []
    for number, rule in enumerate(element.kids("ownedRule"), start=1):
        if b.stereotype(rule, {"Property"}) is not None:
            name = rule.name or f"property {number}"
            properties.append(
                SwarmProperty(name=name, text=constraint_text(rule, ""), span=rule.span)
            )
    return Swarm(
        id=element.id or element.span.path,
        name=element.name,
        ident=identifier(element.name),
        members=tuple(parts),
        properties=tuple(properties),
        span=element.span,
    )
