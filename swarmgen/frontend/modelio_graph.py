"""Modelio's `.exml` object graph, read from the XML but not yet given UML meaning.

An `.exml` file is one root object: `<EXT><OBJECT>` with `<ID name mc uid>` (its metaclass, e.g.
`Standard.State`, and its uid), `<PID>` (its owner, in another file), `<ATTRIBUTES><ATT name>`
and `<DEPENDENCIES>`, whose `<COMP relation>` hold owned objects (`<OBJECT>`, or `<COMPID>`
naming one stored in its own file) and whose `<LINK relation>` reference objects by uid
(`<REFOBJ><ID/></REFOBJ>`, `<ID/>` or `<FOREIGNID/>`, an object of another model component).
References carry the target's name and metaclass, so a reader can name what it cannot find.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import field

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.frontend.safexml import InputError
from swarmgen.frontend.scxml_raw import Builder
from swarmgen.records import dataclass
from swarmgen.span import Span


@dataclass(frozen=True)
class Ref:
    """A reference to an object by uid, with the name and metaclass the file gives it."""

    uid: str
    name: str
    mc: str
    node: etree._Element
    foreign: bool = False  # a FOREIGNID: an object of another model component (a library type)


@dataclass(eq=False)
class MObject:
    """One Modelio object: metaclass, uid, name, attributes, owned objects and links."""

    mc: str
    uid: str
    name: str
    node: etree._Element  # its <ID> element (the line and column of spans)
    b: Builder  # the builder of the file it stands in (spans name that file)
    attrs: dict[str, str] = field(default_factory=dict)
    comps: list[tuple[str, MObject]] = field(default_factory=list)
    comp_refs: list[tuple[str, Ref]] = field(default_factory=list)
    links: list[tuple[str, Ref]] = field(default_factory=list)
    parent: MObject | None = None
    pid: Ref | None = None

    def owned(self, relation: str) -> list[MObject]:
        """The objects this one owns through `relation`, in file order."""
        return [o for r, o in self.comps if r == relation]

    def link(self, relation: str) -> Ref | None:
        """The first object this one references through `relation`, or None."""
        return next((ref for r, ref in self.links if r == relation), None)

    def text(self, name: str) -> str:
        """An attribute's text, stripped ('' when absent)."""
        return self.attrs.get(name, "").strip()

    def path(self) -> str:
        """The qualified name, `Owner::Machine::State` (unnamed regions left out)."""
        names: list[str] = []
        current: MObject | None = self
        while current is not None:
            if current.name:
                names.append(current.name)
            top = current
            current = current.parent
        if top.pid is not None and top.pid.name:
            names.append(top.pid.name)
        return "::".join(reversed(names))

    def span(self) -> Span:
        """Where the object stands: its file, the line and column of its <ID>, uid and path."""
        at = self.b.span(self.node)
        return Span(file=at.file, line=at.line, col=at.col, xmi_id=self.uid, path=self.path())

    def walk(self) -> Iterator[MObject]:
        """This object and every object it owns, depth first in file order."""
        yield self
        for _, child in self.comps:
            yield from child.walk()


def read_ext(b: Builder, root: etree._Element) -> MObject:
    """The root object of a parsed `.exml` document (InputError, SG068, when malformed)."""
    if root.tag != "EXT":
        raise InputError(dg.MODELIO_BAD_MODEL.at(b.span(root), "root", member=b.file, tag=root.tag))
    top = root.find("OBJECT")
    if top is None:
        raise InputError(dg.MODELIO_BAD_MODEL.at(b.span(root), what="<EXT>"))
    return _object(b, top, None)


def _object(b: Builder, node: etree._Element, parent: MObject | None) -> MObject:
    ident = node.find("ID")
    if ident is None or not ident.get("uid"):
        where = parent.name if parent is not None else "the file's root"
        raise InputError(dg.MODELIO_BAD_MODEL.at(b.span(node), what=f"an <OBJECT> in '{where}'"))
    found = MObject(
        mc=str(ident.get("mc", "")),
        uid=str(ident.get("uid")),
        name=str(ident.get("name", "")),
        node=ident,
        b=b,
        parent=parent,
    )
    pid = node.find("PID")
    if pid is not None and pid.get("uid"):
        found.pid = _ref(pid)
    for att in node.iterfind("ATTRIBUTES/ATT"):
        found.attrs[str(att.get("name", ""))] = att.text or ""
    if found.attrs.get("Name"):
        found.name = found.attrs["Name"]
    for group in node.iterfind("DEPENDENCIES/*"):
        relation = str(group.get("relation", ""))
        if group.tag == "COMP":
            for kid in group.iterchildren(tag=etree.Element):
                if kid.tag == "OBJECT":
                    found.comps.append((relation, _object(b, kid, found)))
                elif kid.get("uid"):
                    found.comp_refs.append((relation, _ref(kid)))
        elif group.tag == "LINK":
            for kid in group.iterchildren(tag=etree.Element):
                target = kid.find("ID") if kid.tag == "REFOBJ" else kid
                if target is not None and target.get("uid"):
                    found.links.append((relation, _ref(target)))
    return found


def _ref(node: etree._Element) -> Ref:
    return Ref(
        uid=str(node.get("uid")),
        name=str(node.get("name", "")),
        mc=str(node.get("mc", "")),
        node=node,
        foreign=node.tag == "FOREIGNID",
    )


def index_objects(roots: list[MObject]) -> dict[str, MObject]:
    """Every object of every file by uid; a uid used twice is SG068 (InputError)."""
    index: dict[str, MObject] = {}
    for root in roots:
        for obj in root.walk():
            first = index.get(obj.uid)
            if first is not None:
                where = first.b.span(first.node).location()
                raise InputError(
                    dg.MODELIO_BAD_MODEL.at(
                        obj.span(), "duplicate", uid=obj.uid, name=obj.name, where=where
                    )
                )
            index[obj.uid] = obj
    return index
