"""A tolerant, safe reader of XMI exports (Modelio EMF/OMG, Eclipse UML2, Papyrus, OMG XMI 2.x).

Tolerant: elements and stereotypes are matched by local name, never by namespace URI; missing
`xmi:type` is inferred from the feature; references may be attribute id lists, `xmi:idref`
children or `href`s. Safe: no DTDs, entities, network or XInclude; size and depth are bounded.
"""

from __future__ import annotations

import codecs
import re
from dataclasses import dataclass, field
from pathlib import Path

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawElement, RawModel, StereotypeApplication
from swarmgen.span import Span

MAX_BYTES = 64 * 1024 * 1024
MAX_DEPTH = 200
MAX_ELEMENTS = 3_000_000

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


@dataclass
class _Context:
    file: str
    lines: list[str]
    diagnostics: list[Diagnostic]
    index: dict[str, RawElement]
    line_cursor: dict[int, int]
    count: int = 0
    stereotype_ids: dict[str, Span] = field(default_factory=dict)


class InputError(Exception):
    """The input cannot be read as a model at all; carries the diagnostic to report."""

    def __init__(self, diagnostic: Diagnostic) -> None:
        super().__init__(diagnostic.message)
        self.diagnostic = diagnostic


def load(path: Path) -> tuple[RawModel | None, list[Diagnostic]]:
    """Read one XMI file. Returns the raw model (None if unreadable) and the diagnostics."""
    shown = str(path)
    try:
        data = _read_bounded(path, shown)
        tree = _parse_safely(data, shown)
        _check_root(tree, shown)
    except InputError as err:
        return None, [err.diagnostic]
    text = data.decode(tree.docinfo.encoding or "utf-8", errors="replace")
    ctx = _Context(shown, text.splitlines(), [], {}, {})
    root = tree.getroot()
    try:
        model = _build(root, ctx)
    except InputError as err:
        return None, [err.diagnostic]
    return model, ctx.diagnostics


def _read_bounded(path: Path, shown: str) -> bytes:
    span = Span(file=shown)
    try:
        if path.is_dir():
            raise InputError(dg.diag(dg.UNREADABLE, "is a directory, not a model file", span))
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise InputError(
                dg.diag(
                    dg.TOO_LARGE,
                    f"file is {size / 2**20:.0f} MiB; the limit is {MAX_BYTES // 2**20} MiB",
                    span,
                    hint="split the model into smaller files",
                )
            )
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputError(dg.diag(dg.UNREADABLE, "no such file", span)) from None
    except OSError as err:
        raise InputError(dg.diag(dg.UNREADABLE, f"cannot read: {err.strerror}", span)) from None
    if not data.strip():
        raise InputError(dg.diag(dg.UNREADABLE, "file is empty", span))
    return data


def _parse_safely(data: bytes, shown: str) -> etree._ElementTree:
    parser = etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        huge_tree=False,
        remove_blank_text=False,
    )
    text = _ascii_compatible(data)  # UTF-16/32 would hide "<!ENTITY" from a byte search
    head = text[:4096].lstrip()
    if b"<!DOCTYPE" in head or b"<!ENTITY" in text:
        raise InputError(_forbidden_dtd(shown, _line_of(text, b"<!")))
    try:
        tree = etree.ElementTree(etree.fromstring(data, parser))
    except etree.XMLSyntaxError as err:
        line, col = err.position or (0, 0)  # libxml2 columns are 1-based already
        message = _POSITION_SUFFIX.sub("", str(err.msg or err).split(" (line")[0])
        raise InputError(
            dg.diag(
                dg.NOT_XML,
                f"not well-formed XML: {message}",
                Span(file=shown, line=line, col=max(col, 1)),
            )
        ) from None
    if tree.docinfo.internalDTD is not None:  # a DOCTYPE past the first 4 KiB
        raise InputError(_forbidden_dtd(shown, _line_of(text, b"<!DOCTYPE")))
    for namespace in _XINCLUDE_NAMESPACES:
        include = next(tree.getroot().iter(f"{{{namespace}}}*"), None)
        if include is not None:
            raise InputError(
                dg.diag(
                    dg.FORBIDDEN_XML,
                    "XInclude is not allowed in model files; the included file is not read",
                    Span(file=shown, line=_line(include) or 1, col=1),
                    hint="remove the xi:include element; a model is exported as one file",
                )
            )
    return tree


_POSITION_SUFFIX = re.compile(r", line \d+, column \d+$")
_XINCLUDE_NAMESPACES = ("http://www.w3.org/2001/XInclude", "http://www.w3.org/2003/XInclude")
# XML in UTF-16/32, recognised by its byte order mark or its first character '<' (XML 1.0 F.1).
_WIDE_ENCODINGS = (
    (codecs.BOM_UTF32_LE, "utf-32"),
    (codecs.BOM_UTF32_BE, "utf-32"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
    (b"<\x00\x00\x00", "utf-32-le"),
    (b"\x00\x00\x00<", "utf-32-be"),
    (b"<\x00", "utf-16-le"),
    (b"\x00<", "utf-16-be"),
)


def _ascii_compatible(data: bytes) -> bytes:
    """The document re-encoded as UTF-8 if it is in UTF-16/32; otherwise unchanged."""
    for prefix, codec in _WIDE_ENCODINGS:
        if data.startswith(prefix):
            return data.decode(codec, errors="replace").encode("utf-8")
    return data


def _forbidden_dtd(shown: str, line: int) -> Diagnostic:
    return dg.diag(
        dg.FORBIDDEN_XML,
        "document type declarations and entities are not allowed in model files",
        Span(file=shown, line=line, col=1),
        hint="XMI exports never need a DTD; remove the <!DOCTYPE ...> block",
    )


def _line_of(data: bytes, needle: bytes) -> int:
    at = data.find(needle)
    return data.count(b"\n", 0, at) + 1 if at >= 0 else 1


def _check_root(tree: etree._ElementTree, shown: str) -> None:
    root = tree.getroot()
    local = etree.QName(root).localname
    uri = etree.QName(root).namespace or ""
    if local == "XMI" or (local in {"Model", "Package", "Profile"} and "UML" in uri.upper()):
        return
    raise InputError(
        dg.diag(
            dg.NOT_XMI,
            f"root element <{root.tag}> is not xmi:XMI or uml:Model",
            Span(file=shown, line=_line(root) or 1, col=1),
            hint="export the model from Modelio with File > Export > XMI",
        )
    )


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
    version = next((v for k, v in xml_root.attrib.items() if str(k).endswith("}version")), "")
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
            if etree.QName(child).localname in _SKIPPED:
                continue
            if _is_reference(child):
                raw.child_refs.setdefault(etree.QName(child).localname, []).append(_ref_of(child))
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
    line = _line(node)
    if depth > MAX_DEPTH or ctx.count > MAX_ELEMENTS:
        limit = (
            f"nesting deeper than {MAX_DEPTH}"
            if depth > MAX_DEPTH
            else f"more than {MAX_ELEMENTS} elements"
        )
        raise InputError(
            dg.diag(dg.TOO_LARGE, f"model has {limit}", Span(file=ctx.file, line=line, col=1))
        )
    qname = etree.QName(node)
    attrs: dict[str, str] = {}
    xmi_type = xmi_id = ""
    for key, value in node.attrib.items():
        aq = etree.QName(key)
        if aq.namespace is None:
            attrs[aq.localname] = str(value)
        elif _is_xmi_uri(aq.namespace):
            if aq.localname == "type":
                xmi_type = str(value)
            elif aq.localname == "id":
                xmi_id = str(value)
    feature = qname.localname
    uml_type = _infer_type(feature, xmi_type, qname.namespace or "", attrs)
    name = attrs.get("name", "")
    path = f"{parent_path}::{name}" if parent_path and name else (name or parent_path)
    text = (node.text or "").strip() if len(node) == 0 else ""
    column = _column(node, line, ctx)
    element = RawElement(
        feature, uml_type, xmi_id or None, attrs, ctx.file, line, column, path, text
    )
    element.parent = parent
    if xmi_id:
        _register(element, ctx)
    return element


def _infer_type(feature: str, xmi_type: str, uri: str, attrs: dict[str, str]) -> str:
    if xmi_type:
        return xmi_type.rsplit(":", 1)[-1]
    if uri and _is_uml_uri(uri):  # a qualified root such as <uml:Model>
        return feature
    if feature == "subvertex":
        return "Pseudostate" if "kind" in attrs else "State"
    return _DEFAULT_TYPES.get(feature, "")


def _line(node: etree._Element) -> int:
    value: object = node.sourceline  # lxml-stubs type it as `...`
    return value if isinstance(value, int) else 0


def _column(node: etree._Element, line: int, ctx: _Context) -> int:
    """lxml gives no columns: find the tag's `<` on its line, left to right across elements."""
    if not 0 < line <= len(ctx.lines):
        return 1
    text = ctx.lines[line - 1]
    prefix = node.prefix
    tag = (
        f"<{prefix}:{etree.QName(node).localname}" if prefix else f"<{etree.QName(node).localname}"
    )
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
    ctx.diagnostics.append(
        dg.diag(
            dg.DUPLICATE_ID,
            f"xmi:id '{element.id}' is used twice",
            element.span,
            notes=[f"first used at {first.span.location()}"],
            hint="ids must be unique; re-export the model or rename one id",
        )
    )


def _is_reference(node: etree._Element) -> bool:
    """`<type href="..."/>` or `<memberEnd xmi:idref="..."/>`: a reference, not an element."""
    if len(node):
        return False
    keys = {etree.QName(k).localname for k in node.attrib}
    return "href" in keys or "idref" in keys


def _ref_of(node: etree._Element) -> str:
    for key, value in node.attrib.items():
        if etree.QName(key).localname in {"idref", "href"}:
            return str(value)
    return ""


def _stereotype(node: etree._Element, ctx: _Context) -> StereotypeApplication:
    qname = etree.QName(node)
    line = _line(node)
    bases: list[str] = []
    tags: dict[str, str] = {}
    xmi_id = None
    for key, value in node.attrib.items():
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
            ctx.diagnostics.append(
                dg.diag(
                    dg.DUPLICATE_ID,
                    f"xmi:id '{xmi_id}' is used twice",
                    span,
                    notes=[f"first used at {first.location()}"],
                    hint="ids must be unique; re-export the model or rename one id",
                )
            )
        ctx.stereotype_ids.setdefault(xmi_id, span)
    name = qname.localname.rsplit(".", 1)[-1]
    return StereotypeApplication(name, qname.namespace or "", tuple(bases), tags, span)
