"""`<data src>`: a datum's value read from a file when the document is compiled (W3C 5.3).

The file is a relative `file:` URI (or a plain relative path) naming a file inside the
document's own directory: no other scheme, no absolute path, nothing that resolves outside
that directory (`..`, a link), at most `MAX_SRC_BYTES` of UTF-8 text. Its text is the datum's
inline content, read as an inline `<data>` is (JSON, else an expression's text). Anything else
is SG061, at the `<data>`: the compiler reads no file the document's author did not put beside
it, and the generated code holds the value, never the path.
"""

from __future__ import annotations

from pathlib import Path

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.frontend.scxml_raw import Builder

MAX_SRC_BYTES = 64 * 1024


def inline_src(b: Builder, data: etree._Element) -> bool:
    """Replace the `<data>`'s `src` by the file's text as its inline content; False (reported)
    when the file cannot be read safely or `src` comes with `expr` or content."""
    src = str(data.get("src"))
    if data.get("expr") is not None or len(data) or (data.text or "").strip():
        _refuse(b, data, src, "src, expr and inline content exclude each other (W3C 5.3)")
        return False
    found = _located(b, src)
    if isinstance(found, str):
        _refuse(b, data, src, found)
        return False
    text = _text(found)
    if text is None:
        _refuse(b, data, src, f"not UTF-8 text of at most {MAX_SRC_BYTES} bytes")
        return False
    del data.attrib["src"]
    data.text = text
    return True


def _located(b: Builder, src: str) -> Path | str:
    """The file `src` names inside the document's directory, or why it names none."""
    name = src.removeprefix("file:")
    if not name or "://" in src or ":" in name or "%" in name or "\\" in name:
        return "only a relative file: URI next to the document is read"
    if Path(name).is_absolute():
        return "an absolute path; name a file next to the document"
    document = Path(b.file)
    if not document.is_file():
        return "the document is not a file, so no directory to read from"
    base = document.resolve().parent
    target = (base / name).resolve()
    if not target.is_relative_to(base):
        return "the file is outside the document's directory"
    if not target.is_file():
        return "no such file next to the document"
    return target


def _text(path: Path) -> str | None:
    """The file's text, or None when it is too large or not UTF-8."""
    with path.open("rb") as handle:
        raw = handle.read(MAX_SRC_BYTES + 1)
    if len(raw) > MAX_SRC_BYTES:
        return None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return None


def _refuse(b: Builder, data: etree._Element, src: str, why: str) -> None:
    b.report(
        dg.SCXML_BAD_DOCUMENT,
        data,
        "bad-value",
        attribute="src",
        value=src[:200],
        element="data",
        why=why,
    )
