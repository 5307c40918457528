"""Statements printed in black's layout from their parts, so `pyformat` copies them.

The renderers know the shape of their long statements (`b.transition(...)`, `b.node(...)`,
`smach.StateMachine.add(...)`): a callee and a list of arguments, some of them calls or list and
dict literals in turn. `statement` lays such a call out the way black (pinned, line length 100)
splits it, and records the laid-out text (`pyknown`), so that `pyformat`
copies the lines instead of reading the statement into tokens and splitting it again.

black's rule, for the forms accepted here (every delimiter at a line's bracket depth 0 is a
comma, no comments, no magic trailing commas):

- the line fits in 100 columns: one line;
- else the last bracket splits it: `callee(` (or `name=[`, `"key": {`), the contents one level
  deeper, the closing bracket (with the `,` that followed it);
- the contents stay on one line when they fit, unless the bracket is a list, dict or set
  literal with more than one element: then, as when they do not fit, one element per line with
  a trailing comma, each element laid out again; a sole element that does not fit is split at
  its own last bracket.

Anything outside these forms (an argument text with operators, odd spacing, escapes, string
prefixes, a head or an atom that does not fit) is not laid out: `statement` returns the one-line
text, which `pyformat` formats as before. tests/test_black_stable.py holds `layout` to black on
random argument lists.
"""

from __future__ import annotations

import functools
import keyword
import re
from collections.abc import Sequence

from swarmgen.backends import pyformat, pyknown
from swarmgen.records import dataclass

INDENT = "    "
LINE_LENGTH = pyformat.LINE_LENGTH
CLOSERS = {"(": ")", "[": "]", "{": "}"}


@dataclass(frozen=True)
class Call:
    """`callee(args...)`: a dotted name called with positional or keyword arguments."""

    callee: str
    args: tuple[Arg, ...]

    @functools.cached_property
    def text(self) -> str:
        """The one-line text (made once: a layout measures it at every level)."""
        return f"{self.callee}({', '.join(flat(a) for a in self.args)})"


@dataclass(frozen=True)
class Seq:
    """A list, dict or set literal (`[`, `{`): black puts one element per line when it splits
    one with several (a tuple is passed as an atom: its one-element form is not laid out)."""

    opening: str
    items: tuple[Arg, ...]

    @functools.cached_property
    def text(self) -> str:
        """The one-line text."""
        return self.opening + ", ".join(flat(i) for i in self.items) + CLOSERS[self.opening]


@dataclass(frozen=True)
class Kw:
    """An element with a prefix: a keyword argument (`name=`) or a dict entry (`'key': `)."""

    prefix: str
    value: Node


# An atom is source text kept whole: a literal, a name, `name=value`, a short tuple.
Node = str | Call | Seq
Arg = Node | Kw

_CALLEE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*")
# The code outside string literals (each literal replaced by `@`) of a whole statement may hold
# only names, numbers, brackets, `.`, `=`, `,`, `: `, a unary `-` and single spaces after `,` or
# `:`: then black's only delimiters in it are commas and it rewrites nothing but the quotes.
_ALLOWED = re.compile(r"[A-Za-z0-9_.=()\[\]{},: @-]*")
_REWRITTEN = re.compile(
    r"(?<![,:]) |  |:(?! )|,(?![ )])|, [)\]}]|,[\]}]|[(\[{] |==|(?<![A-Za-z0-9_])="
    r"|(?<![(\[{ =])-|[)\]}@]\.|(?<![A-Za-z0-9_)\]}])\.|\.(?![A-Za-z0-9_])"
    r"|@@|@[A-Za-z0-9_(\[{]|[A-Za-z0-9_)\]}]@"
    # numbers black re-spells (`0XFF`, `1E5`, `10J`): only digits with a lowercase `e` or `j`
    r"|(?<![A-Za-z0-9_])\d[0-9_.]*[a-df-ik-z]|(?<![A-Za-z0-9_])\d[0-9_.a-z]*[A-Z]"
)


def flat(node: Arg) -> str:
    """The one-line text of a node."""
    if isinstance(node, str):
        return node
    if isinstance(node, Kw):
        return node.prefix + flat(node.value)
    return node.text


def statement(depth: int, callee: str, args: Sequence[Arg]) -> str:
    """A bare call statement for a template line `depth` levels deep: its first line without
    the indentation (the template puts it there), further lines with theirs; in black's layout
    and recorded for `pyformat` when `layout` is sure of it, else the one-line text."""
    call = Call(callee, tuple(args))
    lines = layout(call, depth)
    if lines is None:
        return flat(call)
    pyknown.register_laid_out(lines)
    return "\n".join(lines)[len(INDENT) * depth :]


def layout(call: Call, depth: int) -> list[str] | None:
    """The lines (indentation included, quotes normalised) black prints for the statement
    `call` at `depth`; None when the statement is not in the forms reproduced here."""
    if not _CALLEE.fullmatch(call.callee) or keyword.iskeyword(call.callee.split(".")[0]):
        return None
    text = flat(call)  # begins with the callee: no space before it
    pieces = pyformat.plain_pieces(text)
    if pieces is None or not _plain_shape(_DIGITS.sub("0", "@".join(pieces[::2]))):
        return None
    lines = _split("", call, "", depth, top=True)
    if lines is None:
        return None
    # plain one-line literals only (checked above), and no line ends inside one: the quote
    # change keeps every width, and one pass over all the lines makes it
    return pyformat.requote("\n".join(lines)).split("\n")


# The statement's code outside strings (each literal read as `@`) must be in the narrow form
# black only re-quotes (`_plain_shape`). Every run of digits is read as `0`: both patterns see
# digits only through classes holding every digit and repeat them with `*`, so the shape
# matches exactly when the code does. Statements differ mostly in their strings and numbers
# (`_cond_12`), so a few dozen shapes cover a chart and `_REWRITTEN`'s scan (its lookbehinds
# are tried at every position) runs once per shape.
_DIGITS = re.compile(r"\d+")
_TOKEN = re.compile(r"'[^'\"]*'|\"[^'\"]*\"|[A-Za-z0-9_.]+")


@functools.lru_cache(maxsize=4096)
def _plain_shape(code: str) -> bool:
    """The code of a statement (strings as `@`, digit runs as `0`) is in the narrow form."""
    return _ALLOWED.fullmatch(code) is not None and _REWRITTEN.search(code) is None


def plain_shape(code: str) -> bool:
    """The code of a statement or value (each string literal as `@`) is in the narrow form:
    black's only delimiters in it are commas and it rewrites nothing but the quotes."""
    return _plain_shape(_DIGITS.sub("0", code))


def split_node(prefix: str, node: Call | Seq, depth: int) -> list[str] | None:
    """The lines of `prefix + node` at `depth` split as black splits a statement that ends with
    `node`'s bracket (no quote change); None when not in the forms reproduced here."""
    return _split(prefix, node, "", depth)


def _split(prefix: str, node: Node, suffix: str, depth: int, top: bool = False) -> list[str] | None:
    """The lines of `prefix + node + suffix` at `depth`, split as black splits it."""
    text = INDENT * depth + prefix + flat(node) + suffix
    if len(text) <= LINE_LENGTH:
        return [text]
    if isinstance(node, str):
        # one of several elements that is one token (a name, a number, a plain string): black
        # has nothing to split in it and leaves it too long; any other atom is not reproduced
        return [text] if suffix == "," and _TOKEN.fullmatch(node) else None
    if isinstance(node, Call):
        if not top and node.callee.count(".") > 1:
            return None  # an attribute chain: black's dot delimiters are not reproduced here
        opening, items = node.callee + "(", node.args
    else:
        opening, items = node.opening, node.items
    head = INDENT * depth + prefix + opening
    tail = INDENT * depth + CLOSERS[opening[-1]] + suffix
    if not items or len(head) > LINE_LENGTH or len(tail) > LINE_LENGTH:
        return None
    inner = INDENT * (depth + 1) + ", ".join(flat(i) for i in items)
    if len(inner) <= LINE_LENGTH and not (isinstance(node, Seq) and len(items) > 1):
        return [head, inner, tail]
    body: list[str] = []
    for item in items:
        # several elements: one per line, each with its comma; a sole one: split again
        ending = "," if len(items) > 1 else ""
        lines = _item(item, ending, depth + 1)
        if lines is None:
            return None
        body.extend(lines)
    return [head, *body, tail]


def _item(item: Arg, ending: str, depth: int) -> list[str] | None:
    if isinstance(item, Kw):
        return _split(item.prefix, item.value, ending, depth)
    return _split("", item, ending, depth)
