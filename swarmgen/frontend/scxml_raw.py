"""Making the raw UML tree of an SCXML document: elements with ids, paths and the line and
column of the SCXML element each comes from, stereotype applications, located diagnostics."""

from __future__ import annotations

from dataclasses import field
from typing import Any

from lxml import etree

from swarmgen.diagnostics import Code, Diagnostic
from swarmgen.frontend.raw import RawElement, StereotypeApplication
from swarmgen.frontend.safexml import node_line
from swarmgen.records import dataclass
from swarmgen.span import Span

SCXML_NS = "http://www.w3.org/2005/07/scxml"
SG_NS = "urn:swarmgen:scxml:1"
PROFILE_URI = "http:///schemas/CPSwarm/_L1oOEIo-Ee-0HcfyqRPQXg/0"
PRIMITIVES = {"Integer", "Real", "Boolean", "String", "UnlimitedNatural"}
STATE_TAGS = ("state", "parallel", "final", "history")  # SCXML's state-like elements
_PRIMITIVE_HREF = "pathmap://UML_LIBRARIES/UMLPrimitiveTypes.library.uml#"


def local(node: etree._Element) -> str:
    """An element's local name."""
    return etree.QName(node).localname


def in_scxml(node: etree._Element) -> bool:
    """Whether the element is in the SCXML namespace (or none)."""
    return etree.QName(node).namespace in (None, SCXML_NS)


def in_sg(node: etree._Element) -> bool:
    """Whether the element is in swarmgen's extension namespace."""
    return etree.QName(node).namespace == SG_NS


def sg(node: etree._Element, name: str) -> str | None:
    """An `sg:` attribute's value, or None."""
    value = node.get(f"{{{SG_NS}}}{name}")
    return None if value is None else str(value)


def children(node: etree._Element, *names: str, sg_ns: bool = False) -> list[etree._Element]:
    """Element children in the SCXML (or sg:) namespace, optionally only of these names."""
    test = in_sg if sg_ns else in_scxml
    return [
        kid
        for kid in node.iterchildren(tag=etree.Element)
        if test(kid) and (not names or local(kid) in names)
    ]


@dataclass
class Builder:
    """Collects the raw elements, their id index, stereotypes and diagnostics of one document."""

    file: str
    lines: list[str]
    index: dict[str, RawElement] = field(default_factory=dict)
    stereotypes: list[StereotypeApplication] = field(default_factory=list)
    diagnostics: list[Diagnostic] = field(default_factory=list)
    count: int = 0
    cursor: dict[int, int] = field(default_factory=dict)
    # by element, not id(element): lxml frees a proxy nobody holds, and a later element's proxy
    # could get its id (and so its column); holding the element here keeps its proxy
    columns: dict[etree._Element, int] = field(default_factory=dict)

    def span(self, node: etree._Element | None) -> Span:
        """The span of an SCXML element (line and column)."""
        if node is None:
            return Span(file=self.file, line=1, col=1)
        return Span(file=self.file, line=node_line(node) or 1, col=self.column(node))

    def column(self, node: etree._Element) -> int:
        """lxml gives no columns: the tag's `<` on its line (left to right, as xmi.py does)."""
        key = node
        if key in self.columns:
            return self.columns[key]
        line = node_line(node) or 0
        column = 1
        if 0 < line <= len(self.lines):
            tag = f"<{node.prefix}:{local(node)}" if node.prefix else f"<{local(node)}"
            at = self.lines[line - 1].find(tag, self.cursor.get(line, 0))
            if at >= 0:
                self.cursor[line] = at + 1
                column = at + 1
        self.columns[key] = column
        return column

    def report(
        self, code: Code, node: etree._Element | None, variant: str | None = None, **fields: Any
    ) -> None:
        """Add a located diagnostic."""
        span = self.span(node)
        found = code.at(span, variant, **fields) if variant else code.at(span, **fields)
        self.diagnostics.append(found)

    def fresh_id(self, hint: str) -> str:
        """An id no element has: generated elements have no SCXML id."""
        while True:
            self.count += 1
            candidate = f"_sg{self.count}_{hint}"
            if candidate not in self.index:
                return candidate

    def make(
        self,
        feature: str,
        uml_type: str,
        parent: RawElement | None,
        node: etree._Element | None,
        attrs: dict[str, str] | None = None,
        ident: str | None = None,
        text: str = "",
    ) -> RawElement:
        """A raw element (a fresh id unless `ident`), appended to `parent`'s children."""
        attrs = dict(attrs or {})
        name = attrs.get("name", "")
        base = parent.path if parent is not None else ""
        path = f"{base}::{name}" if base and name else (name or base)
        line = (node_line(node) or 1) if node is not None else 1
        column = self.column(node) if node is not None else 1
        element_id = ident if ident is not None else self.fresh_id(feature)
        element = RawElement(
            feature, uml_type, element_id, attrs, self.file, line, column, path, text
        )
        element.parent = parent
        if parent is not None:
            parent.children.append(element)
        self.index[element_id] = element
        return element

    def typed(self, element: RawElement, type_name: str | None, types: dict[str, str]) -> None:
        """Give a property or parameter its type: a primitive by href, else a type by id."""
        if not type_name:
            return
        if type_name in types:
            element.attrs["type"] = types[type_name]
        elif type_name in PRIMITIVES:
            element.child_refs["type"] = [_PRIMITIVE_HREF + type_name]

    def literal(
        self, owner: RawElement, feature: str, value: object, node: etree._Element | None
    ) -> None:
        """A UML literal (`defaultValue`, `expr`) of a JSON-like scalar; objects give none."""
        if isinstance(value, bool):
            self.make(feature, "LiteralBoolean", owner, node, {"value": str(value).lower()})
        elif isinstance(value, int):
            self.make(feature, "LiteralInteger", owner, node, {"value": str(value)})
        elif isinstance(value, float):
            self.make(feature, "LiteralReal", owner, node, {"value": repr(value)})
        elif isinstance(value, str):
            self.make(feature, "LiteralString", owner, node, {"value": value})

    def stereotype(
        self, name: str, metaclass: str, element: RawElement, tags: dict[str, str]
    ) -> None:
        """Apply a stereotype of the swarm profile to an element."""
        assert element.id is not None
        span = Span(file=self.file, line=element.line, col=element.col, path=name)
        kept = {k: v for k, v in tags.items() if v}
        self.stereotypes.append(StereotypeApplication(name, PROFILE_URI, (element.id,), kept, span))
        del metaclass  # the base_<Metaclass> attribute is the writer's business (xmi_write)
