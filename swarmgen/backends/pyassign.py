"""Long one-line assignments, returns and calls laid out by `pylayout`'s rule, read from text.

The templates print a few per-model literals on one line (`PARAMETERS: tuple[Parameter, ...] =
(...)`, `BEHAVIOURS`, `EVENT_FIELDS`, `SIGNATURES`, `b = ChartBuilder(..., data={...})`): the
renderers give their text, not their parts. `layout_line` reads such a line back into
`pylayout`'s nodes (calls, list, dict and tuple literals, `name=` and `'key': ` elements, atoms
kept whole) and lays it out, so `pyformat` does not tokenize and split it.

black's rule for `TARGET = VALUE` and `return VALUE`, when VALUE is a call of a name (at most
one dot) or a bracketed literal and the head `TARGET = Callee(` fits (pysplit's
`right_hand_split` and `_prefer_omitting` for these forms): the optional parentheses are
omitted and the line splits at VALUE's own bracket, then as `pylayout` splits any bracket. A
tuple of two or more elements explodes as a list does (black's should_split_rhs on an atom).

Only the narrow forms are read: the target is a dotted name, with an optional annotation of
names, subscripts and `...`; the value's code outside strings has `pylayout`'s plain shape; no
trailing comma except a one-element tuple's (then kept as an atom); anything else is None and
`pyformat` formats the line as before. tests/test_black_stable.py holds it to black.
"""

from __future__ import annotations

import keyword
import re

from swarmgen.backends import pyformat, pylayout
from swarmgen.backends.pylayout import Call, Kw, Node, Seq

_NAME = r"[A-Za-z_][A-Za-z0-9_]*"
_TARGET = re.compile(rf"(return |{_NAME}(?:\.{_NAME})*(?:: [^=@]*)? = )")
_DOTTED = re.compile(rf"{_NAME}(?:\.{_NAME})*")
_KEYWORD = re.compile(rf"{_NAME}=(?!=)")
_KEY = re.compile(r"@+: ")  # a dict entry whose key is a string (strings masked as `@`)
_CALLEE = re.compile(rf"{_NAME}(?:\.{_NAME})?\(")
_OPENERS = {"(": ")", "[": "]", "{": "}"}
_CLOSERS = frozenset(")]}")
_TRAILING = frozenset((", )", ", ]", ", }"))


def layout_line(line: str) -> list[str] | None:
    """The lines black prints for the one-line statement `line` (indentation included), when
    it is a long assignment, return or call in the forms read here; None otherwise."""
    body = line.lstrip(" ")
    indent = len(line) - len(body)
    if len(line) <= pylayout.LINE_LENGTH or indent % 4:
        return None
    pieces = pyformat.plain_pieces(body)
    if pieces is None:
        return None
    # a trailing comma after the last of several elements of the value (black explodes that
    # bracket whether or not the comma is there: it ends a line too long to keep)
    trailing = pieces[-1][-3:] in _TRAILING
    if trailing:
        pieces[-1] = pieces[-1][:-3] + pieces[-1][-1]
        body = body[:-3] + body[-1]
    masked = "".join(p if i % 2 == 0 else "@" * len(p) for i, p in enumerate(pieces))
    head = _TARGET.match(masked)
    prefix = head.group(1) if head is not None else ""
    if head is not None and not _target(prefix):
        return None
    code = "@".join(pieces[::2])[len(prefix) :]  # the value's code, each string one `@`
    if not pylayout.plain_shape(code):
        return None
    node = _node(body[len(prefix) :], masked[len(prefix) :])
    if not isinstance(node, Call | Seq) or (trailing and not _several(node)):
        return None
    if not prefix:
        return pylayout.layout(node, indent // 4) if isinstance(node, Call) else None
    lines = pylayout.split_node(prefix, node, indent // 4)
    return None if lines is None else pyformat.requote("\n".join(lines)).split("\n")


def _several(node: Call | Seq) -> bool:
    """A literal of two or more elements (whose trailing comma changes nothing here)."""
    return isinstance(node, Seq) and len(node.items) > 1


def _target(prefix: str) -> bool:
    """`return `, or a dotted name with an annotation black prints as it is, then ` = `."""
    if prefix == "return ":
        return True
    _, colon, annotation = prefix[: -len(" = ")].partition(": ")
    return not colon or _annotation(annotation) == len(annotation)


def _annotation(text: str, at: int = 0) -> int:
    """The end of the annotation (`Name`, `Name[A, B[C, ...]]`, `...`) at `at`, -1 if none."""
    if text.startswith("...", at):
        return at + 3
    name = _DOTTED.match(text, at)
    if name is None:
        return -1
    at = name.end()
    if not text.startswith("[", at):
        return at
    at += 1
    while True:
        at = _annotation(text, at)
        if at < 0:
            return -1
        if text.startswith("]", at):
            return at + 1
        if not text.startswith(", ", at):
            return -1
        at += 2


def _node(text: str, masked: str) -> Node | None:
    """The node of one element's text (`masked`: its strings as `@`), None if not read here."""
    if not any(c in _OPENERS for c in masked):
        return text  # an atom: a literal or a name
    call = _CALLEE.match(masked)
    opening = call.end() - 1 if call is not None else 0
    if masked[opening] not in _OPENERS or _closing(masked, opening) != len(masked) - 1:
        return text if _closing_all(masked) else None  # brackets inside an atom (`x[0]`)
    items = _items(text[opening + 1 : -1], masked[opening + 1 : -1])
    if call is not None:
        callee = text[:opening]
        if items is None or keyword.iskeyword(callee.split(".")[0]):
            return None
        return Call(callee, tuple(items))
    if masked[0] == "(":  # a tuple of several elements, else an atom (`(x,)`, `()`)
        return Seq("(", tuple(items)) if items is not None and len(items) > 1 else text
    return None if items is None else Seq(masked[0], tuple(items))


def _items(text: str, masked: str) -> list[Kw | Node] | None:
    """The elements between a pair of brackets; None for a trailing comma or an unread one."""
    if not text:
        return []
    items: list[Kw | Node] = []
    start = depth = 0
    for i, char in enumerate(masked + ","):
        if char in _OPENERS:
            depth += 1
        elif char in _CLOSERS:
            depth -= 1
        elif char == "," and depth == 0:
            item = _element(text[start:i], masked[start:i])
            if item is None:
                return None
            items.append(item)
            start = i + 2  # `, ` (the plain shape has one space after a comma)
    return items


def _element(text: str, masked: str) -> Kw | Node | None:
    if not text:
        return None  # a trailing comma: magic to black
    for prefix in (_KEYWORD.match(masked), _KEY.match(masked)):
        if prefix is not None:
            value = _node(text[prefix.end() :], masked[prefix.end() :])
            return None if value is None else Kw(text[: prefix.end()], value)
    return _node(text, masked)


def _closing(masked: str, opening: int) -> int:
    """The index of the bracket that closes the one at `opening`."""
    depth = 0
    for i in range(opening, len(masked)):
        if masked[i] in _OPENERS:
            depth += 1
        elif masked[i] in _CLOSERS:
            depth -= 1
            if depth == 0:
                return i
    return -1


def _closing_all(masked: str) -> bool:
    """Every bracket of `masked` is closed within it (an atom is one element)."""
    depth = 0
    for char in masked:
        depth += char in _OPENERS
        depth -= char in _CLOSERS
        if depth < 0:
            return False
    return depth == 0
