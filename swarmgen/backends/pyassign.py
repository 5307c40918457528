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
_OPENING = re.compile(r"[(\[{]")
_PUNCTUATION = re.compile(r"[()\[\]{},]")
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
    # a trailing comma after the last of several elements of the value: black explodes that
    # bracket whether or not the comma is there when the line without it is still too long
    trailing = pieces[-1][-3:] in _TRAILING
    if trailing:
        pieces[-1] = pieces[-1][:-3] + pieces[-1][-1]
        body = body[:-3] + body[-1]
        if indent + len(body) <= pylayout.LINE_LENGTH:
            return None  # it would fit: the magic comma alone explodes it
    masked = "".join(p if i % 2 == 0 else "@" * len(p) for i, p in enumerate(pieces))
    head = _TARGET.match(masked)
    prefix = head.group(1) if head is not None else ""
    if head is not None and not _target(prefix):
        return None
    code = "@".join(pieces[::2])[len(prefix) :]  # the value's code, each string one `@`
    if not pylayout.plain_shape(code):
        return None
    node = _Reader(body, masked).node(len(prefix), len(body))
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


class _Reader:
    """The nodes of a statement's text, read with its brackets matched once (`masked`: the
    text with each string's characters as `@`; its brackets balance)."""

    def __init__(self, text: str, masked: str) -> None:
        self.text, self.masked = text, masked
        self.closing: dict[int, int] = {}  # opening bracket -> its closing bracket
        self.commas: dict[int, list[int]] = {-1: []}  # opening bracket -> its commas
        stack = [-1]
        for found in _PUNCTUATION.finditer(masked):
            at, char = found.start(), found.group()
            if char == ",":
                self.commas[stack[-1]].append(at)
            elif char in _OPENERS:
                stack.append(at)
                self.commas[at] = []
            else:
                self.closing[stack.pop()] = at

    def node(self, start: int, end: int) -> Node | None:
        """The node of the element `text[start:end]`, None if not read here."""
        masked = self.masked
        if _OPENING.search(masked, start, end) is None:
            return self.text[start:end]  # an atom: a literal or a name
        call = _CALLEE.match(masked, start, end)
        opening = call.end() - 1 if call is not None else start
        if masked[opening] not in _OPENERS or self.closing[opening] != end - 1:
            return self.text[start:end]  # brackets inside an atom (`x[0]`, `f(x).y`)
        items = self._items(opening)
        if call is not None:
            callee = self.text[start:opening]
            if items is None or keyword.iskeyword(callee.split(".")[0]):
                return None
            return Call(callee, tuple(items))
        if masked[opening] == "(" and (items is None or len(items) < 2):
            return self.text[start:end]  # a tuple of one or none (`(x,)`, `()`): an atom
        return None if items is None else Seq(masked[opening], tuple(items))

    def _items(self, opening: int) -> list[Kw | Node] | None:
        """The elements inside a bracket; None for a trailing comma or an element not read."""
        close = self.closing[opening]
        if close == opening + 1:
            return []
        items: list[Kw | Node] = []
        start = opening + 1
        for comma in [*self.commas[opening], close]:
            item = self._element(start, comma)
            if item is None:
                return None
            items.append(item)
            start = comma + 2  # `, ` (the plain shape has one space after a comma)
        return items

    def _element(self, start: int, end: int) -> Kw | Node | None:
        if start >= end:
            return None  # a trailing comma: magic to black
        for prefix in (
            _KEYWORD.match(self.masked, start, end),
            _KEY.match(self.masked, start, end),
        ):
            if prefix is not None:
                value = self.node(prefix.end(), end)
                return None if value is None else Kw(self.text[start : prefix.end()], value)
        return self.node(start, end)
