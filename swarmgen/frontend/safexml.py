"""Reading an XML model file safely, shared by every XML front end (XMI, SCXML, Modelio .exml).

Bounded: the size is enforced while reading (a FIFO or /proc file reports 0). Safe: no DTDs,
entities, network or XInclude; an encoding Python cannot decode is refused before parsing (the
source text is decoded again for columns and excerpts).
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.inputs import InputRefused, read_limited
from swarmgen.span import Span

MAX_BYTES = 64 * 1024 * 1024


class InputError(Exception):
    """The input cannot be read as a model at all; carries the diagnostic to report."""

    def __init__(self, diagnostic: Diagnostic) -> None:
        super().__init__(diagnostic.message)
        self.diagnostic = diagnostic


def read_bounded(path: Path, shown: str) -> bytes:
    """The file's bytes, read with the size limit enforced while reading: a FIFO, a device or a
    /proc file (which report a size of 0) would otherwise be read forever."""
    span = Span(file=shown)
    try:
        data = read_limited(path, MAX_BYTES)
    except InputRefused as err:
        if str(err).startswith("is larger than"):
            raise InputError(_too_large(path, span)) from None
        raise InputError(dg.UNREADABLE.at(span, error=str(err))) from None
    if not data.strip():
        raise InputError(dg.UNREADABLE.at(span, "empty"))
    return data


def _too_large(path: Path, span: Span) -> Diagnostic:
    limit = MAX_BYTES // 2**20
    try:
        mib = path.stat().st_size / 2**20
    except OSError:
        return dg.TOO_LARGE.at(span, "file-unknown-size", limit=limit)
    return dg.TOO_LARGE.at(span, "file", mib=mib, limit=limit)


def parse_safely(data: bytes, shown: str) -> etree._ElementTree:
    """The parsed document, or InputError: not well-formed, a DTD or entity, XInclude, or an
    encoding Python cannot decode."""
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
    _check_declared_encoding(head, shown)
    try:
        tree = etree.ElementTree(etree.fromstring(data, parser))
    except etree.XMLSyntaxError as err:
        line, col = err.position or (0, 0)  # libxml2 columns are 1-based already
        message = _POSITION_SUFFIX.sub("", str(err.msg or err).split(" (line")[0])
        if message.startswith("Unsupported encoding"):  # a name Python knows, libxml2 not
            name = message.partition(":")[2].strip()
            raise InputError(_bad_encoding(name, shown, _encoding_col(head))) from None
        raise InputError(
            dg.NOT_XML.at(Span(file=shown, line=line, col=max(col, 1)), error=message)
        ) from None
    if tree.docinfo.internalDTD is not None:  # a DOCTYPE past the first 4 KiB
        raise InputError(_forbidden_dtd(shown, _line_of(text, b"<!DOCTYPE")))
    for namespace in _XINCLUDE_NAMESPACES:
        include = next(tree.getroot().iter(f"{{{namespace}}}*"), None)
        if include is not None:
            raise InputError(
                dg.FORBIDDEN_XML.at(
                    Span(file=shown, line=node_line(include) or 1, col=1), "xinclude"
                )
            )
    return tree


# The XML declaration's encoding name (on the ASCII-compatible text, see _ascii_compatible).
_DECLARED_ENCODING = re.compile(rb"^<\?xml\s[^>]*?\bencoding\s*=\s*([\"'])(.*?)\1")


def _check_declared_encoding(head: bytes, shown: str) -> None:
    """An encoding name that Python cannot decode is refused before parsing: libxml2 (iconv)
    knows names Python does not (ARMSCII-8, TCVN), and the source text is decoded again for
    columns and excerpts."""
    match = _DECLARED_ENCODING.match(head)
    if match is None:
        return
    name = match.group(2).decode("ascii", errors="replace")
    if _text_codec(name) is None:
        raise InputError(_bad_encoding(name, shown, match.start(2) + 1))


def _encoding_col(head: bytes) -> int:
    match = _DECLARED_ENCODING.match(head)
    return match.start(2) + 1 if match else 1


def _text_codec(name: str) -> codecs.CodecInfo | None:
    """The codec of a text encoding name, None for an unknown one or a bytes-to-bytes codec
    (`rot13`, `base64`): `bytes.decode` refuses those too."""
    try:
        info = codecs.lookup(name) if name.strip() else None
    except (LookupError, ValueError):  # ValueError: a NUL in the name
        return None
    return info if info is not None and getattr(info, "_is_text_encoding", True) else None


def _bad_encoding(name: str, shown: str, col: int) -> Diagnostic:
    span = Span(file=shown, line=1, col=max(col, 1))
    if not name.strip():
        return dg.NOT_XML.at(span, "empty-encoding")
    return dg.NOT_XML.at(span, "encoding", encoding=quoted(name))


def quoted(text: str, limit: int = 40) -> str:
    """`text` quoted for a message: clipped, and non-printable characters shown as `?`."""
    clipped = text if len(text) <= limit else text[: limit - 1] + "…"
    return "'" + "".join(c if c.isprintable() else "?" for c in clipped) + "'"


def decoded(data: bytes, encoding: str, shown: str) -> str:
    """The source text for columns and excerpts, in the encoding libxml2 used."""
    try:
        return data.decode(encoding, errors="replace")
    except (LookupError, UnicodeError):  # a codec that refuses even with errors="replace"
        raise InputError(_bad_encoding(encoding, shown, 1)) from None


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
    return dg.FORBIDDEN_XML.at(Span(file=shown, line=line, col=1))


def _line_of(data: bytes, needle: bytes) -> int:
    at = data.find(needle)
    return data.count(b"\n", 0, at) + 1 if at >= 0 else 1


def node_line(node: etree._Element) -> int:
    """The element's source line (0 when lxml does not know it)."""
    value: object = node.sourceline  # lxml-stubs type it as `...`
    return value if isinstance(value, int) else 0
