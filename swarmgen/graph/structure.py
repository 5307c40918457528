"""What the composition diagram shows, independent of the output format: swarms, member types
(with counts), hardware parts (with kinds) and generalisations, computed once from the IR."""

from __future__ import annotations

from enum import StrEnum

from swarmgen.graph.styles import HARDWARE_STYLES
from swarmgen.ir import nodes as ir
from swarmgen.ir.query import ModelIndex
from swarmgen.ir.query import composition as swarm_composition
from swarmgen.names import IdAllocator, identifier
from swarmgen.records import dataclass

COMPOSITION_STEM = "swarm"


class NodeKind(StrEnum):
    """What a box of the composition diagram stands for."""

    SWARM = "swarm"
    MEMBER = "member"
    HARDWARE = "hardware"
    CLASS = "class"  # a general class that is not a hardware component


@dataclass(frozen=True)
class Box:
    """One box of the composition diagram: a swarm, member type, hardware or other class."""

    id: str
    name: str
    kind: NodeKind
    stereotype: str | None = None  # «Swarm», «Sensor», ...
    lines: tuple[str, ...] = ()
    hardware: ir.HardwareKind | None = None


@dataclass(frozen=True)
class Link:
    """An arrow: a composite part with its count, or a generalisation."""

    source: str
    target: str
    label: str
    generalisation: bool = False  # else a composite part


@dataclass(frozen=True)
class Composition:
    """The boxes and links of one composition diagram, in drawing order."""

    name: str  # the model's name
    boxes: tuple[Box, ...]
    links: tuple[Link, ...]

    def hardware_kinds(self) -> list[ir.HardwareKind]:
        """The hardware kinds shown, in legend order."""
        shown = {b.hardware for b in self.boxes}
        return [k for k in HARDWARE_STYLES if k in shown]


def _part_label(part: ir.Part) -> str:
    return part.name if part.count == 1 else f"{part.name} [{part.count}]"


def _member_lines(model: ir.Model, member: ir.MemberType) -> tuple[str, ...]:
    """Role, machine and, when several swarm parts have this type, the swarm's total of it
    (`query.composition`, the count the backends and the simulator run): each part's arrow
    shows only its own count. One part: no total line, its arrow says it."""
    lines: list[str] = []
    if member.role:
        lines.append(f"role: {member.role}")
    machine = ModelIndex(model).machines.get(member.machine or "")
    if machine is not None:
        lines.append(f"machine: {machine.name}")
    parts = sum(p.type_name == member.name for s in model.swarms for p in s.members)
    if parts > 1:
        total = swarm_composition(model).get(member.name, 0)
        lines.append(f"members: {total} ({parts} parts)")
    return tuple(lines)


def _shown_hardware(
    model: ir.Model,
    member: ir.MemberType | None,
    by_id: dict[str, ir.HardwareComponent],
    by_name: dict[str, ir.HardwareComponent],
) -> list[ir.HardwareComponent]:
    """Every hardware class, or with `member` its parts' classes and their ancestors."""
    if member is None:
        return list(model.hardware)
    queue = [by_id[p.type_id] for p in member.hardware if p.type_id in by_id]
    seen: set[str] = set()
    while queue:
        component = queue.pop(0)
        if component.id in seen:
            continue
        seen.add(component.id)
        queue.extend(by_name[g] for g in component.generals if g in by_name)
    return [h for h in model.hardware if h.id in seen]


def _generalisations(
    shown: list[ir.HardwareComponent],
    by_name: dict[str, ir.HardwareComponent],
    box_of: dict[str, str],
    ids: IdAllocator,
    boxes: list[Box],
    links: list[Link],
) -> None:
    """Generalisation links of the shown hardware; a general class that is no hardware
    component gets a box of its own (appended after the others, in first-use order)."""
    extra: dict[str, str] = {}
    for component in shown:
        for general in component.generals:
            if general in by_name and by_name[general].id in box_of:
                target = box_of[by_name[general].id]
            else:
                if general not in extra:
                    extra[general] = ids.claim(f"type_{identifier(general, 'class')}")
                    boxes.append(Box(extra[general], general, NodeKind.CLASS))
                target = extra[general]
            links.append(Link(box_of[component.id], target, "", generalisation=True))


def composition(model: ir.Model, member: ir.MemberType | None = None) -> Composition:
    """Swarms -> member types (with counts) -> hardware parts (with kinds) -> generalisations.
    With `member`, only what concerns that member type."""
    ids = IdAllocator()
    members = [member] if member is not None else list(model.member_types)
    member_ids = {m.id for m in members}
    swarms = [
        s for s in model.swarms if member is None or any(p.type_id in member_ids for p in s.members)
    ]
    by_id = {h.id: h for h in model.hardware}
    by_name: dict[str, ir.HardwareComponent] = {}
    for component in model.hardware:
        by_name.setdefault(component.name, component)

    shown = _shown_hardware(model, member, by_id, by_name)
    boxes: list[Box] = []
    links: list[Link] = []
    box_of: dict[str, str] = {}
    for swarm in swarms:
        sid = ids.claim(f"swarm_{swarm.ident}")
        box_of[swarm.id] = sid
        boxes.append(Box(sid, swarm.name, NodeKind.SWARM, "Swarm"))
    for m in members:
        mid = ids.claim(f"member_{m.ident}")
        box_of[m.id] = mid
        boxes.append(Box(mid, m.name, NodeKind.MEMBER, "SwarmMember", _member_lines(model, m)))
    for component in shown:
        hid = ids.claim(f"hw_{component.ident}")
        box_of[component.id] = hid
        lines: list[str] = []
        if component.communication_type:
            lines.append(f"type: {component.communication_type}")
        boxes.append(
            Box(hid, component.name, NodeKind.HARDWARE, str(component.kind), tuple(lines),
                component.kind)
        )  # fmt: skip
    _generalisations(shown, by_name, box_of, ids, boxes, links)
    for swarm in swarms:
        for part in swarm.members:
            if part.type_id in box_of and part.type_id in member_ids:
                links.append(Link(box_of[swarm.id], box_of[part.type_id], _part_label(part)))
    for m in members:
        for part in m.hardware:
            if part.type_id in box_of:
                links.append(Link(box_of[m.id], box_of[part.type_id], _part_label(part)))
    # parts first, generalisations after: the order of the text follows the reading order
    links.sort(key=lambda link: link.generalisation)
    return Composition(model.name, tuple(boxes), tuple(links))
