"""Mermaid text: `stateDiagram-v2` per machine, a `flowchart` for the swarm composition.

Names are hostile until escaped. Every model text goes into a quoted label or a description
after `:`, with every character outside a small safe set written as a Mermaid entity code
(`#35;` for `#`, `#quot;`-style numeric codes for quotes, `#10;` for a newline): Mermaid turns
those into placeholders before it parses, so no name can close a label, end a statement, start a
comment or a directive. Ids are safe identifiers that avoid the grammar's keywords.
"""

from __future__ import annotations

import re

from swarmgen.graph import labels, styles, view
from swarmgen.graph.structure import Composition, NodeKind
from swarmgen.graph.styles import Style
from swarmgen.graph.view import Diagram, Edge, Shape, Vertex
from swarmgen.ir.nodes import BehaviourKind, HardwareKind, PseudoKind
from swarmgen.names import IdAllocator

SUFFIX = ".mmd"
INDENT = "    "
_SAFE = frozenset(
    "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 _.,=+-*/()!?'@$^~"
)
_NAMED = {"\n": "#10;", "\r": "#13;", "\t": "#9;"}
# A text made only of `_SAFE` characters (most labels) is kept as it is, without the loop.
_ALL_SAFE = re.compile("[" + re.escape("".join(sorted(_SAFE))) + "]*")
# Words the state-diagram lexer matches wherever a statement starts, whatever follows.
_KEYWORDS = ("default", "state", "note", "class", "scale", "hide", "acc", "style", "click", "href",
             "end")  # fmt: skip
_DIRECTION = re.compile("direction", re.IGNORECASE)

BEHAVIOUR_CLASSES = {
    BehaviourKind.COMPLEX: "complexBehaviour",
    BehaviourKind.SWARM_BEHAVIOR: "swarmBehaviour",
    BehaviourKind.SWARM_FUNCTION: "swarmFunction",
    BehaviourKind.HARDWARE_FUNCTION: "hardwareFunction",
}
HARDWARE_CLASSES = {
    HardwareKind.SENSOR: "sensor",
    HardwareKind.ACTUATOR: "actuator",
    HardwareKind.CONTROLLER: "controller",
    HardwareKind.COMMUNICATION_INTERFACE: "communication",
}


def text(raw: str) -> str:
    """Model text for a quoted label or a description: entity codes for everything unsafe."""
    if _ALL_SAFE.fullmatch(raw):
        return _DIRECTION.sub(lambda m: f"#{ord(m.group()[0])};{m.group()[1:]}", raw)
    out = []
    for ch in raw:
        if ch in _SAFE or (ord(ch) > 127 and ch.isprintable()):
            out.append(ch)
        elif ch in _NAMED:
            out.append(_NAMED[ch])
        elif ch.isprintable():
            out.append(f"#{ord(ch)};")
        else:
            out.append("#65533;")  # a control or format character: shown as the replacement sign
    # `direction TB` anywhere on a line switches the layout: keep the word from appearing
    return _DIRECTION.sub(lambda m: f"#{ord(m.group()[0])};{m.group()[1:]}", "".join(out))


def _safe_id(vid: str) -> str:
    lower = vid.lower()
    if lower.startswith(_KEYWORDS) or lower.startswith("s_"):
        vid = f"s_{vid}"
    return _DIRECTION.sub("dir", vid)


def _style(style: Style, width: str = "1px") -> str:
    return f"fill:{style.fill},stroke:{style.stroke},stroke-width:{width},color:#000000"


class _StateWriter:
    def __init__(self, diagram: Diagram) -> None:
        self.d = diagram
        self.lines: list[str] = []
        self.ids = IdAllocator()
        self.mid: dict[str, str] = {}
        everything = ([diagram.root] if diagram.root else []) + diagram.vertices()
        self.vertex: dict[str, Vertex] = {v.id: v for v in everything}
        for v in everything:
            self.mid[v.id] = self.ids.claim(_safe_id(v.id))
        self.starts = self._starts()
        self.classes: dict[str, list[str]] = {}

    def _starts(self) -> set[str]:
        """Initial pseudostates drawn as `[*]`: in a region, with every transition out of them
        going to a vertex of the same region and none coming in."""
        leaving: dict[str, list[Edge]] = {}  # indexed once: a scan per vertex is quadratic
        for e in self.d.edges:
            leaving.setdefault(e.source, []).append(e)
        entered = {e.target for e in self.d.edges}
        starts = set()
        for v in self.vertex.values():
            if v.shape != PseudoKind.INITIAL or v.id not in self.d.region_of:
                continue
            region = self.d.region_of[v.id]
            out = leaving.get(v.id, [])
            if v.id not in entered and all(self.d.region_of.get(e.target) == region for e in out):
                starts.add(v.id)
        return starts

    def ref(self, vid: str) -> str:
        return "[*]" if vid in self.starts else self.mid[vid]

    def classify(self, name: str, vid: str) -> None:
        self.classes.setdefault(name, []).append(self.mid[vid])

    def write(self) -> str:
        d = self.d
        members = f" (run by {', '.join(d.members)})" if d.members else ""
        self.lines += [
            f"%% swarmgen: state machine {text(labels.clip(d.name, 80))}{text(members)}",
            "stateDiagram-v2",
        ]
        local: dict[str, list[Edge]] = {}
        crossing: list[Edge] = []
        regions = {r.id for r in d.all_regions()}
        for edge in d.edges:
            home = d.region_of.get(edge.source)
            if home in regions and home == d.region_of.get(edge.target):
                local.setdefault(str(home), []).append(edge)
            else:
                crossing.append(edge)
        self.local = local
        for point in d.points:
            self.declare(point, 1)
        if d.root is not None:
            self.declare(d.root, 1)
        else:
            for region in d.regions:
                self.region_body(region, 1)
        for edge in crossing:
            self.edge(edge, 1)
        self.legend()
        self.styles()
        return "\n".join(self.lines) + "\n"

    def region_body(self, region: view.Region, depth: int) -> None:
        for vertex in region.vertices:
            self.declare(vertex, depth)
        for edge in self.local.get(region.id, []):
            self.edge(edge, depth)

    def edge(self, edge: Edge, depth: int) -> None:
        label = f" : {text(edge.label)}" if edge.label else ""
        self.lines.append(
            f"{INDENT * depth}{self.ref(edge.source)} --> {self.ref(edge.target)}{label}"
        )

    def declare(self, v: Vertex, depth: int) -> None:
        pad = INDENT * depth
        mid = self.mid[v.id]
        if v.id in self.starts:
            return
        match v.shape:
            case PseudoKind.CHOICE | PseudoKind.JUNCTION:
                self.lines.append(f"{pad}state {mid} <<choice>>")
            case PseudoKind.FORK:
                self.lines.append(f"{pad}state {mid} <<fork>>")
            case PseudoKind.JOIN:
                self.lines.append(f"{pad}state {mid} <<join>>")
            case Shape.STATE:
                self.state(v, depth)
            case _:
                self.lines.append(f'{pad}state "{text(_pseudo_label(v))}" as {mid}')
                self.classify("final" if v.shape == Shape.FINAL else "pseudo", v.id)

    def state(self, v: Vertex, depth: int) -> None:
        pad = INDENT * depth
        mid = self.mid[v.id]
        lines = [*v.lines]
        if v.link is not None:
            lines.append(f"→ {v.link}{SUFFIX}")
        self.classify(BEHAVIOUR_CLASSES[v.kind] if v.kind else "plain", v.id)
        if not v.composite:
            self.lines.append(f'{pad}state "{text(v.name)}" as {mid}')
            self.lines += [f"{pad}{mid} : {text(line)}" for line in lines]
            for point in v.points:
                self.declare(point, depth)
            return
        # Mermaid has no descriptions on composite states: extra lines go into the title.
        title = "<br/>".join(text(line) for line in [v.name, *lines])
        self.lines.append(f'{pad}state "{title}" as {mid}')
        self.lines.append(f"{pad}state {mid} {{")
        for i, region in enumerate(v.regions):
            if i:
                self.lines.append(f"{pad}{INDENT}--")
            if i == 0:
                for point in v.points:
                    self.declare(point, depth + 1)
            self.region_body(region, depth + 1)
        self.lines.append(f"{pad}}}")

    def legend(self) -> None:
        kinds = self.d.kinds()
        if not kinds:
            return
        lid = self.ids.claim("legend")
        self.lines.append(f'{INDENT}state "legend" as {lid}')
        self.lines.append(f"{INDENT}state {lid} {{")
        for kind in kinds:
            kid = self.ids.claim(f"legend_{BEHAVIOUR_CLASSES[kind]}")
            self.lines.append(f'{INDENT * 2}state "{styles.BEHAVIOUR_STYLES[kind].title}" as {kid}')
            self.classes.setdefault(BEHAVIOUR_CLASSES[kind], []).append(kid)
        self.lines.append(f"{INDENT}}}")

    def styles(self) -> None:
        defs = {
            **{BEHAVIOUR_CLASSES[k]: _style(s) for k, s in styles.BEHAVIOUR_STYLES.items()},
            "plain": _style(styles.NEUTRAL),
            "final": _style(styles.NEUTRAL, "3px"),
            "pseudo": "fill:#ffffff,stroke:#333333,stroke-width:1px,color:#000000",
        }
        for name, style in defs.items():
            if name in self.classes:
                self.lines.append(f"{INDENT}classDef {name} {style}")
        for name in defs:
            if name in self.classes:
                self.lines.append(f"{INDENT}class {','.join(self.classes[name])} {name}")


def _pseudo_label(v: Vertex) -> str:
    match v.shape:
        case Shape.FINAL:
            return f"◉ {v.name}"
        case PseudoKind.INITIAL:
            return "●"
        case PseudoKind.SHALLOW_HISTORY:
            return "H"
        case PseudoKind.DEEP_HISTORY:
            return "H*"
        case PseudoKind.TERMINATE:
            return f"✕ {v.name}"
        case PseudoKind.ENTRY_POINT:
            return f"▷ {v.name}"
        case _:
            return f"⊗ {v.name}"


def state_diagram(diagram: Diagram) -> str:
    """The Mermaid `stateDiagram-v2` of one machine's diagram."""
    return _StateWriter(diagram).write()


def composition(comp: Composition) -> str:
    """The Mermaid `flowchart` of the swarm composition and hardware."""
    ids = IdAllocator()
    mid = {box.id: ids.claim(box.id) for box in comp.boxes}
    lines = [f"%% swarmgen: swarm composition and hardware of {text(labels.clip(comp.name, 80))}"]
    lines.append("flowchart LR")
    classes: dict[str, list[str]] = {}
    for box in comp.boxes:
        parts = ([f"«{box.stereotype}»"] if box.stereotype else []) + [box.name, *box.lines]
        label = "<br/>".join(text(p) for p in parts)
        lines.append(f'{INDENT}{mid[box.id]}["{label}"]')
        if box.hardware is not None:
            cls = HARDWARE_CLASSES[box.hardware]
        else:
            cls = {NodeKind.SWARM: "swarm", NodeKind.MEMBER: "member"}.get(box.kind, "type")
        classes.setdefault(cls, []).append(mid[box.id])
    for link in comp.links:
        arrow = "-.->" if link.generalisation else "-->"
        label = "is a" if link.generalisation else link.label
        lines.append(f'{INDENT}{mid[link.source]} {arrow}|"{text(label)}"| {mid[link.target]}')
    defs = {
        "swarm": _style(styles.SWARM_STYLE, "2px"),
        "member": _style(styles.MEMBER_STYLE),
        **{HARDWARE_CLASSES[k]: _style(s) for k, s in styles.HARDWARE_STYLES.items()},
        "type": _style(styles.CLASS_STYLE),
    }
    for name, style in defs.items():
        if name in classes:
            lines.append(f"{INDENT}classDef {name} {style}")
    for name in defs:
        if name in classes:
            lines.append(f"{INDENT}class {','.join(classes[name])} {name}")
    return "\n".join(lines) + "\n"
