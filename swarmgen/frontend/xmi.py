"""A tolerant, safe reader of XMI exports (Modelio EMF/OMG, Eclipse UML2, Papyrus, OMG XMI 2.x).

Tolerant: elements and stereotypes are matched by local name, never by namespace URI; missing
`xmi:type` is inferred from the feature; references may be attribute id lists, `xmi:idref`
children or `href`s. Safe: no DTDs, entities, network or XInclude; size and depth are bounded.
"""

from __future__ import annotations

import re
from dataclasses import field
from pathlib import Path
from typing import cast

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication
from swarmgen.frontend.safexml import (
    InputError,
    decoded,
    node_line,
    parse_safely,
    quoted,
    read_bounded,
)
from swarmgen.records import dataclass
from swarmgen.span import Span

MAX_DEPTH = 200
MAX_ELEMENTS = 3_000_000
# lxml reads each attribute value by a linear search of its element's attributes, so reading an
# element's attributes costs the square of their number (100,000 took 40 s). Exports carry fewer
# than 20 per element; 256 keeps the cost per byte of input that of an ordinary model.
MAX_ATTRIBUTES = 256

# EMF leaves out xmi:type when it equals the feature's declared type (formats.md 1.2).
_DEFAULT_TYPES = {
    "region": "Region",
    "transition": "Transition",
    "trigger": "Trigger",
    "ownedAttribute": "Property",
    "ownedEnd": "Property",
    "generalization": "Generalization",
    "ownedParameter": "Parameter",
    "ownedRule": "Constraint",
    "connectionPoint": "Pseudostate",
    "connection": "ConnectionPointReference",
    "ownedOperation": "Operation",
    "ownedReception": "Reception",
    "ownedComment": "Comment",
    "ownedLiteral": "EnumerationLiteral",
    "profileApplication": "ProfileApplication",
    "eAnnotations": "EAnnotation",
    "when": "TimeExpression",
    "interfaceRealization": "InterfaceRealization",
}
# Elements that only wrap XMI bookkeeping or vendor data: skipped whole.
_SKIPPED = {"Extension", "Documentation"}


_PLAIN, _XMI_TYPE, _XMI_ID, _OTHER = range(4)  # the roles of an attribute name (_Context.role)


@dataclass
class _Context:
    file: str
    lines: list[str]
    diagnostics: list[Diagnostic]
    index: dict[str, RawElement]
    line_cursor: dict[int, int]
    count: int = 0
    stereotype_ids: dict[str, Span] = field(default_factory=dict)
    # `{uri}local` -> (uri, local), split once per distinct name: a 10,000-state model has
    # ~80,000 elements but a few dozen tag and attribute names (etree.QName per use was a third
    # of the load time).
    names: dict[str, tuple[str | None, str]] = field(default_factory=dict)
    roles: dict[str, tuple[int, str]] = field(default_factory=dict)  # see `role`

    def split(self, name: str) -> tuple[str | None, str]:
        """The namespace URI (None without one) and the local name of a tag or attribute."""
        found = self.names.get(name)
        if found is None:
            qname = etree.QName(name)
            found = self.names[name] = (qname.namespace, qname.localname)
        return found

    def role(self, key: str) -> tuple[int, str]:
        """What an attribute name is to an element (`_PLAIN` with its local name, `_XMI_TYPE`,
        `_XMI_ID`, or `_OTHER`: another namespace's, ignored), decided once per name."""
        namespace, local = self.split(key)
        if namespace is None:
            role = (_PLAIN, local)
        elif _is_xmi_uri(namespace) and local in ("type", "id"):
            role = (_XMI_TYPE if local == "type" else _XMI_ID, local)
        else:
            role = (_OTHER, local)
        self.roles[key] = role
        return role


def load(path: Path) -> tuple[RawModel | None, list[Diagnostic]]:
    """Read one XMI file. Returns the raw model (None if unreadable) and the diagnostics."""
    shown = str(path)
    try:
        data = read_bounded(path, shown)
        tree = parse_safely(data, shown)
        _check_root(tree, shown)
        text = decoded(data, tree.docinfo.encoding or "utf-8", shown)
    except InputError as err:
        return None, [err.diagnostic]
    return from_tree(tree, text, shown)


def is_xmi_root(namespace: str | None, local: str) -> bool:
    """Whether a document with this root element is an XMI (or bare UML) export."""
    return local == "XMI" or (
        local in {"Model", "Package", "Profile"} and "UML" in (namespace or "").upper()
    )


def from_tree(
    tree: etree._ElementTree, text: str, shown: str
) -> tuple[RawModel | None, list[Diagnostic]]:
    """The raw model of a parsed XMI document (`text`: its decoded source, for columns)."""
    ctx = _Context(shown, text.splitlines(), [], {}, {})
    try:
        model = _build(tree.getroot(), ctx)
    except InputError as err:
        return None, [err.diagnostic]
    return model, ctx.diagnostics


def _check_root(tree: etree._ElementTree, shown: str) -> None:
    root = tree.getroot()
    qname = etree.QName(root)
    if not is_xmi_root(qname.namespace, qname.localname):
        span = Span(file=shown, line=node_line(root) or 1, col=1)
        raise InputError(dg.NOT_XMI.at(span, tag=root.tag))


def _build(root: etree._Element, ctx: _Context) -> RawModel:
    roots: list[RawElement] = []
    stereotypes: list[StereotypeApplication] = []
    if etree.QName(root).localname == "XMI":
        for child in root.iterchildren(tag=etree.Element):
            qname = etree.QName(child)
            uri = qname.namespace or ""
            if qname.localname in _SKIPPED:
                continue
            if _is_uml_uri(uri) or _is_xmi_uri(uri):
                roots.append(_convert(child, None, "", ctx, 1))
            else:
                stereotypes.append(_stereotype(child, ctx))
    else:
        roots.append(_convert(root, None, "", ctx, 1))
    return RawModel(ctx.file, roots, ctx.index, stereotypes, _exporter(roots, root))


_UML_URI = re.compile(r"(/uml2/\d|spec/UML|/UML$|^http://www\.omg\.org/spec/UML)")


def _is_uml_uri(uri: str) -> bool:
    return bool(_UML_URI.search(uri))


def _is_xmi_uri(uri: str) -> bool:
    return "/XMI" in uri or uri.endswith("XMI")


def _exporter(roots: list[RawElement], xml_root: etree._Element) -> str:
    for root in roots:
        for annotation in root.kids("eAnnotations"):
            if annotation.attrs.get("source") == "Objing":
                return "modelio"
    # keys first: reading every value of an element is quadratic in lxml (see MAX_ATTRIBUTES)
    key = next((k for k in xml_root.attrib if str(k).endswith("}version")), None)
    version = str(xml_root.get(key, "")) if key is not None else ""
    return "uml2-5/papyrus" if version == "20131001" else "uml"


def _convert(
    node: etree._Element, parent: RawElement | None, parent_path: str, ctx: _Context, depth: int
) -> RawElement:
    """Convert an element and its subtree; iterative over children to keep depth bounded."""
    element = _make_element(node, parent, parent_path, ctx, depth)
    stack = [(node, element, depth)]
    while stack:
        xml_node, raw, level = stack.pop()
        pending: list[tuple[etree._Element, RawElement, int]] = []
        for child in xml_node.iterchildren(tag=etree.Element):
            local = ctx.split(child.tag)[1]
            if local in _SKIPPED:
                continue
            if _is_reference(child, ctx):
                raw.child_refs.setdefault(local, []).append(_ref_of(child))
                continue
            kid = _make_element(child, raw, raw.path, ctx, level + 1)
            raw.children.append(kid)
            pending.append((child, kid, level + 1))
        stack.extend(reversed(pending))
    return element


def _make_element(
    node: etree._Element, parent: RawElement | None, parent_path: str, ctx: _Context, depth: int
) -> RawElement:
    ctx.count += 1
    line = node_line(node)
    if depth > MAX_DEPTH or ctx.count > MAX_ELEMENTS:
        span = Span(file=ctx.file, line=line, col=1)
        if depth > MAX_DEPTH:
            raise InputError(dg.TOO_LARGE.at(span, "depth", limit=MAX_DEPTH))
        raise InputError(dg.TOO_LARGE.at(span, "elements", limit=MAX_ELEMENTS))
    namespace, feature = ctx.split(node.tag)
    attrs: dict[str, str] = {}
    xmi_type = xmi_id = ""
    roles = ctx.roles
    for key, value in _attributes(node, ctx, line):
        role = roles.get(key) or ctx.role(key)
        if role[0] == _PLAIN:
            attrs[role[1]] = value
        elif role[0] == _XMI_TYPE:
            xmi_type = value
        elif role[0] == _XMI_ID:
            xmi_id = value
    uml_type = _infer_type(feature, xmi_type, namespace or "", attrs)
    name = attrs.get("name", "")
    path = f"{parent_path}::{name}" if parent_path and name else (name or parent_path)
    text = (node.text or "").strip() if len(node) == 0 else ""
    column = _column(node, line, ctx, feature)
    element = RawElement(
        feature, uml_type, xmi_id or None, attrs, ctx.file, line, column, path, text
    )
    element.parent = parent
    if xmi_id:
        _register(element, ctx)
    return element


def _attributes(node: etree._Element, ctx: _Context, line: int) -> list[tuple[str, str]]:
    """The element's attributes, refused past MAX_ATTRIBUTES before any value is read (counting
    them is linear, reading them is not)."""
    attrib = node.attrib
    count = len(attrib)
    if count > MAX_ATTRIBUTES:
        raise InputError(
            dg.TOO_LARGE.at(
                Span(file=ctx.file, line=line, col=_column(node, line, ctx)),
                "attributes",
                element=quoted(etree.QName(node).localname)[1:-1],
                count=count,
                limit=MAX_ATTRIBUTES,
            )
        )
    # lxml's keys and values are str (its stubs also allow bytes): no copies per value.
    return cast(list[tuple[str, str]], attrib.items())


def _infer_type(feature: str, xmi_type: str, uri: str, attrs: dict[str, str]) -> str:
    if xmi_type:
        return xmi_type.rsplit(":", 1)[-1]
    if uri and _is_uml_uri(uri):  # a qualified root such as <uml:Model>
        return feature
    if feature == "subvertex":
        return "Pseudostate" if "kind" in attrs else "State"
    return _DEFAULT_TYPES.get(feature, "")


def _column(node: etree._Element, line: int, ctx: _Context, local: str | None = None) -> int:
    """lxml gives no columns: find the tag's `<` on its line, left to right across elements.
    `local` is the element's local name when the caller has it already."""
    if not 0 < line <= len(ctx.lines):
        return 1
    text = ctx.lines[line - 1]
    prefix = node.prefix
    local = ctx.split(node.tag)[1] if local is None else local
    tag = f"<{prefix}:{local}" if prefix else f"<{local}"
    at = text.find(tag, ctx.line_cursor.get(line, 0))
    if at < 0:
        return 1
    ctx.line_cursor[line] = at + 1
    return at + 1


def _register(element: RawElement, ctx: _Context) -> None:
    assert element.id is not None
    first = ctx.index.get(element.id)
    if first is None:
        ctx.index[element.id] = element
        return
    note = dg.DUPLICATE_ID.note("first-used", where=first.span.location())
    ctx.diagnostics.append(dg.DUPLICATE_ID.at(element.span, notes=[note], id=element.id))


def _is_reference(node: etree._Element, ctx: _Context) -> bool:
    """`<type href="..."/>` or `<memberEnd xmi:idref="..."/>`: a reference, not an element."""
    if len(node):
        return False
    return any(ctx.split(str(k))[1] in _REFERENCE_KEYS for k in node.attrib)


_REFERENCE_KEYS = frozenset({"href", "idref"})


def _ref_of(node: etree._Element) -> str:
    for key in node.attrib:  # keys, then one value: linear however many attributes
        if etree.QName(key).localname in {"idref", "href"}:
            return str(node.get(key, ""))
    return ""


def _stereotype(node: etree._Element, ctx: _Context) -> StereotypeApplication:
    qname = etree.QName(node)
    line = node_line(node)
    bases: list[str] = []
    tags: dict[str, str] = {}
    xmi_id = None
    for key, value in _attributes(node, ctx, line):
        aq = etree.QName(key)
        if aq.namespace and _is_xmi_uri(aq.namespace):
            xmi_id = str(value) if aq.localname == "id" else xmi_id
        elif aq.localname.startswith("base_"):
            bases.extend(str(value).split())
        elif aq.namespace is None:
            tags[aq.localname] = str(value)
    for child in node.iterchildren(tag=etree.Element):  # multi-valued tags as child elements
        local = etree.QName(child).localname
        value = _ref_of(child) or (child.text or "").strip()
        if local.startswith("base_"):
            bases.append(value.rsplit("#", 1)[-1])
            continue
        tags[local] = f"{tags[local]} {value}" if local in tags else value
    span = Span(
        file=ctx.file, line=line, col=_column(node, line, ctx), xmi_id=xmi_id, path=qname.localname
    )
    if xmi_id:
        first = ctx.stereotype_ids.get(xmi_id) or (
            ctx.index[xmi_id].span if xmi_id in ctx.index else None
        )
        if first is not None:
            note = dg.DUPLICATE_ID.note("first-used", where=first.location())
            ctx.diagnostics.append(dg.DUPLICATE_ID.at(span, notes=[note], id=xmi_id))
        ctx.stereotype_ids.setdefault(xmi_id, span)
    name = qname.localname.rsplit(".", 1)[-1]
    return StereotypeApplication(name, qname.namespace or "", tuple(bases), tags, span)
