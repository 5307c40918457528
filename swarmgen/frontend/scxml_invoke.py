"""W3C `<invoke>` of an SCXML session (docs/scxml-input.md, "Invoke"): the child document,
inline (`<content><scxml>`) or in a file (`src`, read as safely as the document itself), read
by the same reader into a raw model of its own (`RawModel.sessions`), and the state's raw
`invoke` element that names it, with its id or idlocation, type, params, finalize, autoforward.

The inline children are detached from the document before anything else reads it
(`detach`), so the parent's datamodel, ids and checks never see the child's elements.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import field
from pathlib import Path

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.frontend.raw import RawElement, RawModel
from swarmgen.frontend.safexml import InputError, decoded, parse_safely, read_bounded
from swarmgen.frontend.scxml_actions import Actions
from swarmgen.frontend.scxml_raw import Builder, children, in_scxml, local
from swarmgen.frontend.scxml_send import namelist_field
from swarmgen.records import dataclass

SCXML_TYPES = frozenset({"http://www.w3.org/TR/scxml/", "http://www.w3.org/TR/scxml", "scxml"})
MAX_NESTING = 8  # documents invoked inside invoked documents, when read
MAX_DOCUMENTS = 64  # invoked documents one document reads in all (fan-out times nesting)
_READ_ATTRIBUTES = frozenset(
    {"type", "typeexpr", "src", "id", "idlocation", "namelist", "autoforward"}
)

# Reads one child document: (builder of its file, its root element, its folder) -> raw model
ReadChild = Callable[[Builder, etree._Element, Path], RawModel | None]


def detach(root: etree._Element) -> dict[etree._Element, etree._Element]:
    """Each `<invoke>`'s inline `<scxml>`, taken out of the document (nested ones stay in
    their own child): invoke element -> child root."""
    found: dict[etree._Element, etree._Element] = {}
    stack = [root]
    while stack:
        node = stack.pop()
        for kid in node.iterchildren(tag=etree.Element):
            if in_scxml(kid) and local(kid) == "invoke":
                for content in children(kid, "content"):
                    for document in content.iterchildren(tag=etree.Element):
                        if local(document) == "scxml":
                            content.remove(document)
                            found.setdefault(kid, document)
            else:
                stack.append(kid)
    return found


@dataclass
class Invokes:
    """Reads the invokes of one document's states into raw `invoke` elements."""

    b: Builder
    actions: Actions
    inline: dict[etree._Element, etree._Element]  # from `detach`
    folder: Path  # the document's folder: `src` is read below it
    depth: int  # how many documents invoke this one
    read_child: ReadChild
    read: list[int]  # invoked documents read so far for the top document (shared, one item)
    sessions: dict[str, RawModel] = field(default_factory=dict)

    def state(self, node: etree._Element, vertex: RawElement) -> None:
        """The `<invoke>`s of a `<state>`/`<parallel>`, in document order."""
        for invoke in children(node, "invoke"):
            self.invoke(invoke, vertex)

    def invoke(self, node: etree._Element, vertex: RawElement) -> None:
        """One `<invoke>`: its document read, then its raw element (nothing when reported)."""
        if not self._attributes_read(node):
            return
        kind = node.get("type")
        if kind is not None and kind not in SCXML_TYPES:
            why = "swarmgen runs SCXML sessions only (http://www.w3.org/TR/scxml/ or scxml)"
            self.b.report(
                dg.SCXML_UNSUPPORTED,
                node,
                "attribute",
                attribute="type",
                value=kind,
                element="invoke",
                why=why,
            )
            return
        session = self._session(node)
        if session is None:
            return
        key = f"session{len(self.sessions) + 1}"
        self.sessions[key] = session
        attrs = {"session": key}
        for attribute, name in (("id", "invokeid"), ("type", "kind")):
            if node.get(attribute) is not None:
                attrs[name] = str(node.get(attribute))
        if node.get("idlocation") is not None:
            attrs["idlocation"] = self.actions.name(str(node.get("idlocation")))
        if node.get("typeexpr") is not None:
            text = self.actions.text(str(node.get("typeexpr")), node)
            if text is None:
                return
            attrs["kindexpr"] = text
        if node.get("autoforward") == "true":
            attrs["autoforward"] = "true"
        element = self.b.make("invoke", "Invoke", vertex, node, attrs)
        self._params(node, element)
        for finalize in children(node, "finalize"):
            lines = [
                line for kid in finalize.iterchildren(tag=etree.Element)
                for line in self.actions.action(kid)
            ]  # fmt: skip
            if lines:
                self.actions.body(element, "finalize", lines, finalize)

    def _attributes_read(self, node: etree._Element) -> bool:
        for attribute in sorted(map(str, node.attrib)):
            if "}" not in attribute and attribute not in _READ_ATTRIBUTES:
                why = "swarmgen reads no computed document (srcexpr) and no other attribute"
                self.b.report(dg.SCXML_INVOKE, node, "attribute", attribute=attribute, why=why)
                return False
        if node.get("id") is not None and node.get("idlocation") is not None:
            why = "id and idlocation exclude each other"
            self.b.report(dg.SCXML_INVOKE, node, "attribute", attribute="idlocation", why=why)
            return False
        if node.get("type") is not None and node.get("typeexpr") is not None:
            why = "type and typeexpr exclude each other"
            self.b.report(dg.SCXML_INVOKE, node, "attribute", attribute="typeexpr", why=why)
            return False
        return True

    def _params(self, node: etree._Element, element: RawElement) -> None:
        """namelist names and `<param name expr|location>`s: the child's data they set."""
        for ident in str(node.get("namelist", "")).split():
            name = self.actions.namelist_entry(ident, node)  # one that is none: invalid("...")
            if name is not None:
                field = namelist_field(ident)
                self.b.make("param", "", element, node, {"name": field, "value": name})
        for param in children(node, "param"):
            source = param.get("expr") or param.get("location")
            given = param.get("name")
            if source is None or not given:
                why = "a <param> needs a name and an expr or a location"
                self.b.report(dg.SCXML_INVOKE, param, "attribute", attribute="param", why=why)
                continue
            if param.get("expr"):
                text = self.actions.text(str(source), param)
            else:
                text = self.actions.location(str(source), param)
            if text is not None:
                self.b.make("param", "", element, param, {"name": str(given), "value": text})

    def _session(self, node: etree._Element) -> RawModel | None:
        if self.depth >= MAX_NESTING:
            self.b.report(dg.SCXML_INVOKE, node, "nesting", limit=MAX_NESTING)
            return None
        self.read[0] += 1
        if self.read[0] > MAX_DOCUMENTS:
            self.b.report(dg.SCXML_INVOKE, node, "many", limit=MAX_DOCUMENTS)
            return None
        inline = self.inline.get(node)
        src = node.get("src")
        if (inline is None) == (src is None):
            why = "both src and <content>" if inline is not None else "neither src nor <content>"
            self.b.report(dg.SCXML_INVOKE, node, why=why)
            return None
        if inline is not None:
            child = Builder(self.b.file, self.b.lines)
            return self._read(child, inline, self.folder, node)
        return self._from_file(node, str(src))

    def _from_file(self, node: etree._Element, src: str) -> RawModel | None:
        """A `src` document: a relative path (`file:` allowed) below the document's folder,
        read with the reader's size limit and XML hardening."""
        relative = src.removeprefix("file:")
        path = Path(relative)
        if ":" in relative or path.is_absolute() or not relative:
            why = "only a relative file path (or file:path) below the document's folder"
            self.b.report(dg.SCXML_INVOKE, node, "src", src=src, why=why)
            return None
        base = self.folder.resolve()
        target = (base / path).resolve()
        if not target.is_relative_to(base):
            why = "it is outside the document's folder"
            self.b.report(dg.SCXML_INVOKE, node, "src", src=src, why=why)
            return None
        shown = str(Path(self.b.file).parent / path)
        try:
            data = read_bounded(target, shown)
            tree = parse_safely(data, shown)
            text = decoded(data, tree.docinfo.encoding or "utf-8", shown)
        except InputError as err:  # unreadable, too large, not well-formed, a DTD
            self.b.diagnostics.append(err.diagnostic)
            return None
        root = tree.getroot()
        if local(root) != "scxml":
            why = f"its root element is <{local(root)}>, not <scxml>"
            self.b.report(dg.SCXML_INVOKE, node, "src", src=src, why=why)
            return None
        return self._read(Builder(shown, text.splitlines()), root, target.parent, node)

    def _read(
        self, child: Builder, root: etree._Element, folder: Path, node: etree._Element
    ) -> RawModel | None:
        model = self.read_child(child, root, folder)
        self.b.diagnostics += child.diagnostics
        if model is None and not child.diagnostics:
            self.b.report(dg.SCXML_INVOKE, node, why="the document is not read")
        return model
