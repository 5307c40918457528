"""black's line splitting (its linegen: transform_line, the right-hand, delimiter and left-hand
splits) over the leaves of one statement, for `pyformat`: a line is kept when it fits and has no
magic trailing comma, else split the way black splits it. A form black treats in a way not
reproduced here raises `Unsupported`.
"""

from __future__ import annotations

import tokenize
import unicodedata
from dataclasses import field

from swarmgen.records import dataclass

LINE_LENGTH = 100
INDENT = "    "
OPENING = {"(": ")", "[": "]", "{": "}"}
CLOSING = {v: k for k, v in OPENING.items()}
COMPREHENSION_PRIORITY = 20
COMMA_PRIORITY = 18
LOGIC_PRIORITY = 14
COMPARATOR_PRIORITY = 10
COMPARATORS = {"<", ">", "==", "!=", "<=", ">=", "in", "is"}
TERNARY_PRIORITY = 16
DOT_PRIORITY = 1
# black's priorities of the other delimiters: a split at one of them is not reproduced here
MATH_PRIORITIES = {"|": 9, "^": 8, "&": 7, "<<": 6, ">>": 6, "+": 5, "-": 5}
MATH_PRIORITIES |= {"*": 4, "/": 4, "//": 4, "%": 4, "@": 4, "**": 1}
SPLITTABLE = {COMPREHENSION_PRIORITY, COMMA_PRIORITY, LOGIC_PRIORITY, COMPARATOR_PRIORITY}
KEYWORDS = {"and", "or", "not", "in", "is", "if", "else", "for", "return", "lambda", "await"}
KEYWORDS |= {"yield", "raise", "del", "assert", "import", "from", "with", "as", "elif", "while"}


class Unsupported(Exception):
    """A statement this formatter does not reproduce; the caller formats it with black."""


@dataclass
class Leaf:
    """One token of a logical line: its text, kind and the whitespace black puts before it."""

    text: str
    kind: int
    prefix: str = ""
    match: int = -1  # index of the matching bracket in the logical line, -1 otherwise
    atom: bool = False  # an opening bracket of a literal or parenthesised expression

    @property
    def is_comma(self) -> bool:
        """A `,` operator."""
        return self.kind == tokenize.OP and self.text == ","


@dataclass
class Line:
    """A run of leaves printed on one line at `depth` (black's `Line`)."""

    depth: int
    leaves: list[Leaf]
    inside: bool = False  # inside brackets (a body of a split)
    is_def: bool = False
    explode: bool = False  # black's should_split_rhs: one element per line
    rhs_parens: bool = False  # the leaves after `=` / `return` sit in black's invisible parens

    # the text, made once: a line is measured and compared several times while it is split
    # (its leaves are complete before the first time: `delimiter_split` adds its comma first)
    text: str | None = field(default=None, init=False, repr=False, compare=False)

    def render(self) -> str:
        """The line's text, indentation included."""
        if self.text is None:
            parts = [self.leaves[0].text] + [leaf.prefix + leaf.text for leaf in self.leaves[1:]]
            self.text = INDENT * self.depth + "".join(parts)
        return self.text


def width(text: str) -> int:
    """Display width as black counts it; text with wide or zero-width characters is left to
    black (its width table is not reproduced here)."""
    if text.isascii():
        return len(text)
    for char in text:
        if unicodedata.east_asian_width(char) in "WF" or unicodedata.combining(char):
            raise Unsupported("wide or combining characters")
        if unicodedata.category(char) in {"Mn", "Me", "Cf"}:
            raise Unsupported("zero-width characters")
    return len(text)


def fits(line: Line) -> bool:
    """black's is_line_short_enough."""
    return width(line.render()) <= LINE_LENGTH


# --- splitting (black's linegen: transform_line, rhs, delimiter_split, left_hand_split)


def new_line(depth: int, leaves: list[Leaf], **options: bool) -> Line:
    """A line over `leaves` (copies, brackets matched anew within the line)."""
    copies = [Leaf(leaf.text, leaf.kind, leaf.prefix, -1, leaf.atom) for leaf in leaves]
    if copies:
        copies[0].prefix = ""
    _match_local(copies)
    return Line(depth, copies, **options)


def _match_local(leaves: list[Leaf]) -> None:
    stack: list[int] = []
    for i, leaf in enumerate(leaves):
        if leaf.kind == tokenize.OP and leaf.text in OPENING:
            stack.append(i)
        elif leaf.kind == tokenize.OP and leaf.text in CLOSING and stack:
            j = stack.pop()
            leaves[j].match, leaf.match = i, j


def delimiters(line: Line) -> dict[int, int]:
    """Index of a leaf -> priority of a split after it, at bracket depth 0 (black's tracker)."""
    found: dict[int, int] = {}
    depth = 0
    comprehension = False  # a `for` seen at depth 0: then `in` and `if` belong to it
    for i, leaf in enumerate(line.leaves):
        if leaf.kind == tokenize.OP and leaf.text in CLOSING:
            depth -= 1
        if depth == 0 and i:
            if leaf.kind == tokenize.NAME and leaf.text == "for" and line.inside:
                comprehension = True
                found[i - 1] = COMPREHENSION_PRIORITY
            elif comprehension and leaf.kind == tokenize.NAME and leaf.text in {"in", "if"}:
                if leaf.text == "if":
                    found[i - 1] = COMPREHENSION_PRIORITY
            else:
                _delimiter(line.leaves, i, found)
        if leaf.kind == tokenize.OP and leaf.text in OPENING:
            depth += 1
    return found


def _delimiter(leaves: list[Leaf], i: int, found: dict[int, int]) -> None:
    leaf, prev = leaves[i], leaves[i - 1]
    if leaf.is_comma:
        found[i] = COMMA_PRIORITY
    elif leaf.text in {"and", "or"} and leaf.kind == tokenize.NAME:
        found[i - 1] = LOGIC_PRIORITY
    elif leaf.text in COMPARATORS or (leaf.text == "not" and prev.text != "is"):
        if leaf.text == "not" and (i + 1 >= len(leaves) or leaves[i + 1].text != "in"):
            return  # unary `not`: no delimiter
        if leaf.text == "in" and prev.text == "not":
            return  # the second word of `not in`
        found[i - 1] = COMPARATOR_PRIORITY
    elif leaf.kind == tokenize.NAME and leaf.text in {"if", "else"}:
        found[i - 1] = TERNARY_PRIORITY
    elif leaf.kind == tokenize.NAME and leaf.text == "lambda":
        found[i - 1] = 99  # black does not split lambda parameters: nor is it reproduced here
    elif leaf.kind == tokenize.OP and leaf.text in MATH_PRIORITIES and _binary(prev):
        found[i - 1] = MATH_PRIORITIES[leaf.text]
    elif leaf.kind == tokenize.OP and leaf.text == "." and prev.text in CLOSING:
        found[i - 1] = DOT_PRIORITY
    elif leaf.kind == tokenize.STRING and prev.kind == tokenize.STRING:
        found[i - 1] = 12  # implicit concatenation


def _binary(prev: Leaf) -> bool:
    """An operator after this leaf is binary (not a sign, nor `*args`)."""
    if prev.kind == tokenize.OP:
        return prev.text in CLOSING
    return not (prev.kind == tokenize.NAME and prev.text in KEYWORDS)


def magic_trailing_comma(line: Line) -> bool:
    """A closing bracket after a comma, but not of a one-tuple or one-element subscript."""
    text = line.render()
    if ",)" not in text and ",]" not in text and ",}" not in text:
        return False  # closing brackets have no space before them: no comma right before one
    for i, leaf in enumerate(line.leaves):
        if not i or leaf.kind != tokenize.OP or leaf.text not in CLOSING:
            continue
        if not line.leaves[i - 1].is_comma:
            continue
        if leaf.text == "}" or leaf.match < 0:
            return True
        opening = line.leaves[leaf.match]
        inner = new_line(0, line.leaves[leaf.match + 1 : i])
        one = list(delimiters(inner).values()).count(COMMA_PRIORITY) == 1
        if leaf.text == "]" and (opening.atom or not one):
            return True
        if leaf.text == ")" and not one:
            return True
    return False


def transform(line: Line) -> list[Line]:
    """black's transform_line: the line itself when it fits, else its split lines, each
    transformed again."""
    if not line.explode and not magic_trailing_comma(line) and fits(line):
        return [line]
    if line.is_def:
        splits = [left_hand_split]
    elif line.inside:
        splits = [delimiter_split, right_hand_split]
    else:
        splits = [right_hand_split]
    for split in splits:
        try:
            result = split(line)
        except CannotSplit:
            continue
        if len(result) == 1 and result[0].render() == line.render():
            continue
        return [done for part in result for done in transform(part)]
    return [line]  # no split applies: black prints the line as it is, too long


class CannotSplit(Exception):
    """This kind of split does not apply to the line (black's CannotSplit)."""


def delimiter_split(line: Line) -> list[Line]:
    """One line per element at the line's strongest delimiter; commas get a trailing one."""
    found = delimiters(line)
    last = len(line.leaves) - 1
    priorities = [p for i, p in found.items() if i != last]
    if not priorities:
        raise CannotSplit("no delimiters")
    top = max(priorities)
    if top not in SPLITTABLE:
        raise Unsupported("a split at a delimiter black treats specially")
    if any(leaf.text in {"*", "**", "async"} for leaf in line.leaves):
        raise Unsupported("unpacking in a split")
    lines: list[Line] = []
    start = 0
    for i in range(len(line.leaves)):
        if found.get(i) == top:
            lines.append(new_line(line.depth, line.leaves[start : i + 1], inside=True))
            start = i + 1
    if start < len(line.leaves):
        lines.append(new_line(line.depth, line.leaves[start:], inside=True))
    if top == COMMA_PRIORITY and not lines[-1].leaves[-1].is_comma:
        lines[-1].leaves.append(Leaf(",", tokenize.OP))
    return lines


def rhs_start(line: Line) -> int:
    """Index of the first leaf in black's invisible parentheses of the statement, else -1."""
    if line.inside or line.is_def:
        return -1
    first = line.leaves[0]
    if first.kind == tokenize.NAME and first.text == "return":
        return 1
    depth = 0
    for i, leaf in enumerate(line.leaves):
        if leaf.kind == tokenize.OP and leaf.text in OPENING:
            depth += 1
        elif leaf.kind == tokenize.OP and leaf.text in CLOSING:
            depth -= 1
        elif depth == 0 and leaf.kind == tokenize.OP and leaf.text == "=":
            return i + 1
    return -1


def right_hand_split(line: Line) -> list[Line]:
    """Head up to the last opening bracket, body, tail from its closing bracket on; the
    optional parentheses of an assignment or return value are omitted where black omits them."""
    start = rhs_start(line)
    if start > 0:
        body = new_line(0, line.leaves[start:])
        if delimiters(body):
            raise Unsupported("black keeps the optional parentheses")
    close = len(line.leaves) - 1
    while close >= 0 and not (
        line.leaves[close].kind == tokenize.OP and line.leaves[close].text in CLOSING
    ):
        close -= 1
    if close < 0 or (start > 0 and line.leaves[close].match < start):
        if start > 0:
            raise Unsupported("no bracket inside the optional parentheses")
        raise CannotSplit("no brackets")
    opening = line.leaves[close].match
    if start > 0 and not _prefer_omitting(line, start, opening):
        raise Unsupported("black keeps the optional parentheses")
    return _bracket_split(line, opening, close)


def _prefer_omitting(line: Line, start: int, opening: int) -> bool:
    """black's _prefer_split_rhs_oop_over_rhs for the forms emitted here."""
    if line.leaves[start - 1].text != "=":
        return True
    lhs = line.leaves[: start - 1]
    if not any(leaf.text in OPENING or leaf.text in CLOSING for leaf in lhs):
        return True
    head = new_line(line.depth, line.leaves[:start])
    if width(head.render() + "(") > LINE_LENGTH - 1:
        return True
    after = line.leaves[start:opening]
    if any(leaf.kind == tokenize.OP and leaf.text in CLOSING for leaf in after):
        return True
    return fits(new_line(line.depth, line.leaves[: opening + 1]))


def _bracket_split(line: Line, opening: int, close: int) -> list[Line]:
    head = new_line(line.depth, line.leaves[: opening + 1], inside=line.inside)
    inner = line.leaves[opening + 1 : close]
    tail = new_line(line.depth, line.leaves[close:], inside=line.inside)
    if not inner:
        raise CannotSplit("empty body")
    body = new_line(line.depth + 1, inner, inside=True)
    if line.is_def and not any(leaf.is_comma for leaf in body.leaves):
        raise Unsupported("a one-parameter def split")
    found = delimiters(body)
    last = len(body.leaves) - 1
    top = max((p for i, p in found.items() if i != last), default=0)
    trailing = body.leaves[-1].is_comma
    body.explode = top == COMMA_PRIORITY and (trailing or line.leaves[opening].atom)
    result = [head, body]
    if tail.leaves:
        result.append(tail)
    for part in (head, tail):
        if part.leaves and not fits(part):
            raise Unsupported("head or tail too long")
    return result


def left_hand_split(line: Line) -> list[Line]:
    """A def header: head up to the parameters' bracket, the parameters, the rest."""
    for i, leaf in enumerate(line.leaves):
        if leaf.kind == tokenize.OP and leaf.text == "(":
            return _bracket_split(line, i, leaf.match)
    raise Unsupported("a def without parameters")
