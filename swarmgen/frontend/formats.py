"""The input formats, in one table, and `load`: which reader a file goes to is decided by its
content (an archive's magic bytes, an XML document's root element), never by its suffix.

Each reader is named by module and function and imported only when a file needs it, so
validating an XMI model does not import the SCXML reader.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path
from typing import cast

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawModel
from swarmgen.frontend.safexml import InputError, decoded, node_line, parse_safely, read_bounded
from swarmgen.frontend.xmi import is_xmi_root
from swarmgen.records import dataclass
from swarmgen.span import Span

Loaded = tuple[RawModel | None, list[Diagnostic]]
TreeReader = Callable[[etree._ElementTree, str, str], Loaded]  # (tree, source text, shown name)
BytesReader = Callable[[bytes, str], Loaded]  # (the file's bytes, shown name)

SCXML_NAMESPACE = "http://www.w3.org/2005/07/scxml"


@dataclass(frozen=True)
class XmlFormat:
    """An XML format: the root elements it accepts and the reader (`module:function`)."""

    name: str
    accepts: Callable[[str | None, str], bool]  # (root namespace or None, root local name)
    reader: str


@dataclass(frozen=True)
class BinaryFormat:
    """A format that is not XML, known by the bytes it starts with, and its reader."""

    name: str
    magic: bytes
    reader: str


def _is_scxml_root(namespace: str | None, local: str) -> bool:
    return local == "scxml" and namespace in (None, SCXML_NAMESPACE)


def _is_exml_root(namespace: str | None, local: str) -> bool:
    return local == "EXT" and namespace is None


# Read before any XML parsing: a zip (Modelio's .ramc model component) is not XML.
BINARY_FORMATS: tuple[BinaryFormat, ...] = (
    BinaryFormat("ramc", b"PK\x03\x04", "swarmgen.frontend.modelio:from_archive"),
)
# The first format whose `accepts` holds reads the document; any other root is SG004.
XML_FORMATS: tuple[XmlFormat, ...] = (
    XmlFormat("xmi", is_xmi_root, "swarmgen.frontend.xmi:from_tree"),
    XmlFormat("scxml", _is_scxml_root, "swarmgen.frontend.scxml:from_tree"),
    XmlFormat("exml", _is_exml_root, "swarmgen.frontend.modelio:from_tree"),
)


def load(path: Path) -> Loaded:
    """Read one model file of any supported format. Returns the raw model (None if unreadable)
    and the diagnostics."""
    shown = str(path)
    try:
        data = read_bounded(path, shown)
        binary = next((f for f in BINARY_FORMATS if data.startswith(f.magic)), None)
        if binary is not None:
            return cast(BytesReader, _function(binary.reader))(data, shown)
        tree = parse_safely(data, shown)
        read = _tree_reader(tree, shown)
        text = decoded(data, tree.docinfo.encoding or "utf-8", shown)
    except InputError as err:
        return None, [err.diagnostic]
    return read(tree, text, shown)


def _tree_reader(tree: etree._ElementTree, shown: str) -> TreeReader:
    root = tree.getroot()
    qname = etree.QName(root)
    for fmt in XML_FORMATS:
        if fmt.accepts(qname.namespace, qname.localname):
            return cast(TreeReader, _function(fmt.reader))
    span = Span(file=shown, line=node_line(root) or 1, col=1)
    raise InputError(dg.NOT_XMI.at(span, tag=root.tag))


def _function(target: str) -> object:
    module_name, _, function = target.partition(":")
    return cast(object, getattr(importlib.import_module(module_name), function))
