"""A formatter for the Python swarmgen generates: black's output (pinned version, line length 100)
for the forms the templates and `pyrender` emit, without importing black.

The input is template text (already black-formatted) with generated statements in it: builder
calls, helper functions, literals. Each logical line is kept as written when it fits and has no
magic trailing comma (after black's string-quote normalisation); a longer one is split the way
black's line generator splits it (`pysplit`: right-hand split at the last bracket, optional
parentheses after `=`/`return` omitted, one element per line with a trailing comma for collection
literals and for bodies that still do not fit, left-hand split of `def` headers); black's
blank-line rules follow (`pyblank`). A statement outside these forms raises `Unsupported`;
`pyrender.format_python` then formats that statement with black, so the output never depends on
this module being complete (tests/test_black_stable.py counts those).

Most physical lines are whole statements that fit and need nothing but the quote change: those
are copied without Python's tokenizer (`quick_line`, an exact test that says "tokenize it" when
in doubt); so are statements the renderers printed in black's layout (`pylayout`, which records
them: `pyknown`); every other statement is tokenized on its own.
"""

from __future__ import annotations

import functools
import io
import re
import tokenize
from collections.abc import Callable, Iterator
from dataclasses import field

from swarmgen.backends.pyblank import Entry, blank_lines
from swarmgen.backends.pyknown import laid_out
from swarmgen.backends.pysplit import (
    CLOSING,
    COMMA_PRIORITY,
    KEYWORDS,
    LINE_LENGTH,
    OPENING,
    Leaf,
    Line,
    Unsupported,
    delimiters,
    magic_trailing_comma,
    new_line,
    rhs_start,
    transform,
    width,
)
from swarmgen.records import dataclass

__all__ = [
    "LINE_LENGTH",
    "STATS",
    "STRINGS",
    "Unsupported",
    "format_source",
    "normalize_plain",
    "normalize_string",
    "plain_brackets",
    "plain_pieces",
    "requote",
]


@dataclass
class Stats:
    """How often `format_source` handed a statement to the fallback (kept for the tests)."""

    fallbacks: int = 0
    samples: list[str] = field(default_factory=list)


STATS = Stats()

_PATTERNS: dict[str, re.Pattern[str]] = {}


def _compile(pattern: str) -> re.Pattern[str]:
    if pattern not in _PATTERNS:
        _PATTERNS[pattern] = re.compile(pattern)
    return _PATTERNS[pattern]


def _sub_twice(regex: re.Pattern[str], replacement: str, original: str) -> str:
    return regex.sub(replacement, regex.sub(replacement, original))


def normalize_string(value: str) -> str:
    """black's string normalisation: double quotes unless they need more escapes."""
    prefix_end = len(value) - len(value.lstrip("furbFURB"))
    prefix = value[:prefix_end]
    if prefix != prefix.lower() or "u" in prefix:
        raise Unsupported("string prefix to normalise")
    body_quoted = value[prefix_end:]
    if not prefix and "\\" not in value:  # the common case, repr() of plain text: no regex
        if body_quoted[0] == '"' and body_quoted[:3] != '"""':
            return value
        if body_quoted[0] == "'" and body_quoted[:3] != "'''" and '"' not in body_quoted:
            return f'"{body_quoted[1:-1]}"'
    if body_quoted[:3] in {'"""', "'''"}:
        if body_quoted[:3] == "'''":
            raise Unsupported("triple single quotes")
        return value
    orig, new = ("'", '"') if body_quoted[0] == "'" else ('"', "'")
    body = body_quoted[1:-1]
    unescaped_new = _compile(rf"(([^\\]|^)(\\\\)*){new}")
    escaped_new = _compile(rf"([^\\]|^)\\((?:\\\\)*){new}")
    escaped_orig = _compile(rf"([^\\]|^)\\((?:\\\\)*){orig}")
    if "r" in prefix:
        if body.count(new) != body.count(f"\\{new}"):
            return value
        new_body = body
    else:
        new_body = _sub_twice(escaped_new, rf"\1\2{new}", body)
        if body != new_body:
            body = new_body
            value = f"{prefix}{orig}{body}{orig}"
        new_body = _sub_twice(escaped_orig, rf"\1\2{orig}", new_body)
        new_body = _sub_twice(unescaped_new, rf"\1\\{new}", new_body)
    if "f" in prefix:
        if orig == '"' and "\\" not in body and "'" not in body:
            return value  # black keeps it: as many escapes, and double quotes already
        raise Unsupported("f-string quotes")
    if new_body.count("\\") > body.count("\\"):
        return value
    if new_body.count("\\") == body.count("\\") and orig == '"':
        return value
    return f"{prefix}{new}{new_body}{new}"


# --- the lines copied without the tokenizer

# A plain one-line string literal: no prefix, backslash or other quote character inside.
_STRINGS = re.compile(r"""('[^'"]*'|"[^"]*")""")
# Whitespace the tokenized path drops (after an opening bracket, before a closing one or a
# comma), a comma after an opening bracket or before `]` or `}` (the magic trailing commas not
# told apart here), optional parentheses after `=` or `return`.
_SLOW_FORMS = re.compile(r"[(\[{][ ,]| [)\]},]|,[\]}]|=\s*\(|return\s*\(")
_PUNCTUATION = re.compile(r",\)|[()\[\]{},]")
# `"""text"""` alone on its line, the text printable with no quote, backslash or space at its ends
_ONE_LINE_DOCSTRING = re.compile(r'(?:    )*"""[!#-\[\]-~](?:[ !#-\[\]-~]*[!#-\[\]-~])?"""')
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_")


STRINGS = _STRINGS  # for `pylayout`, which reads statements the same way


def normalize_plain(text: str) -> str | None:
    """`text` (a line or part of one) with black's quote change, when its strings are plain
    one-line literals and it holds no comment, escape, string prefix or second statement
    (`_plain`); None otherwise. Brackets need not balance."""
    plain = _plain(text)
    if plain is None:
        return None
    indent, _, pieces = plain
    return text[:indent] + _requoted(pieces)


def plain_brackets(text: str) -> bool:
    """The brackets of `text` (plain, `_plain`) match and it has no magic trailing comma."""
    pieces = _STRINGS.split(text)
    return _plain_brackets(_PUNCTUATION.findall("0".join(pieces[::2])))


def plain_pieces(text: str) -> list[str] | None:
    """The pieces (code, string, code, ..., code) of a `text` that begins with no space, when
    `normalize_plain` accepts it and `plain_brackets` holds; None otherwise. One reading of the
    text for the three questions `pylayout` asks of each statement."""
    plain = _plain(text)
    if plain is None:
        return None
    pieces = plain[2]
    return pieces if _plain_brackets(_PUNCTUATION.findall("0".join(pieces[::2]))) else None


def requote(text: str) -> str:
    """black's quote change over `text` whose every string is a plain one-line literal (as
    `normalize_plain` accepts), whatever its brackets or lines."""
    return _requoted(_STRINGS.split(text))


def _requoted(pieces: list[str]) -> str:
    """Code and plain string pieces joined, `'...'` printed `"..."` (no quote inside)."""
    for i in range(1, len(pieces), 2):
        if pieces[i][0] == "'":
            pieces[i] = f'"{pieces[i][1:-1]}"'
    return "".join(pieces)


@functools.lru_cache(maxsize=1 << 16)
def quick_line(line: str) -> str | None:
    """`line` as the tokenized path prints it, when that is a copy with black's quote change
    (a whole statement on one line that fits, with only plain string literals and nothing black
    rewrites); None when in doubt. `line` begins a statement and is no comment or blank line.
    Memoised (in this process, bounded): the helper functions' lines are asked for when they
    are laid out and again when each module that prints them is formatted, and the smach and
    asyncio members print the same bodies."""
    if len(line) <= LINE_LENGTH and _ONE_LINE_DOCSTRING.fullmatch(line) and line.isascii():
        return line  # black's docstring rules keep it: no space, quote or escape to adjust
    plain = _plain(line) if len(line) <= LINE_LENGTH else None
    if plain is None:
        return None
    indent, body, pieces = plain
    if _SLOW_FORMS.search(body) or not _plain_brackets(_PUNCTUATION.findall("0".join(pieces[::2]))):
        return None  # the statement goes on, or black rewrites it (a magic trailing comma, ...)
    return line[:indent] + _requoted(pieces)


def _plain(line: str) -> tuple[int, str, list[str]] | None:
    """The indentation, text and pieces (code, string, code, ..., code) of a line whose strings
    are plain one-line literals and that holds no comment, escape or second statement."""
    if not line.isascii() or not line.isprintable():
        return None  # a character whose width or meaning is not checked here
    body = line.lstrip(" ")
    indent = len(line) - len(body)
    if indent % 4 or body[-1] == " " or "\\" in body or "'''" in body or '"""' in body:
        return None  # odd indentation, trailing space, escapes, continuations, triple quotes
    pieces = _STRINGS.split(body)
    code = pieces[::2]
    for i, text in enumerate(code):
        if "'" in text or '"' in text or "#" in text or ";" in text:
            return None  # another kind of string, a comment, several statements
        if i + 1 < len(code) and text and text[-1] in _NAME_CHARS:
            return None  # a string prefix (f, r, b, u)
    return indent, body, pieces


def one_line_statement(line: str) -> Logical | None:
    """A statement on one plain line (`_plain`) as the tokenizer would read it, without the
    tokenizer: tokens matched with its own pattern (`tokenize.PseudoToken`); None when in doubt."""
    plain = _plain(line)
    if plain is None or not _balanced(_BRACKET_MARKS.findall("0".join(plain[2][::2]))):
        return None  # the statement goes on past this line, or is not plain
    indent, body, _ = plain
    leaves: list[Leaf] = []
    pos = 0
    while pos < len(body):
        found = _PSEUDO_TOKEN.match(body, pos)
        if found is None or found.start(1) == found.end(1):
            return None
        start, pos = found.span(1)
        token = body[start:pos]
        kind = _kind(token)
        if kind is None:
            return None
        text = normalize_string(token) if kind == tokenize.STRING else token
        leaves.append(Leaf(text, kind, _joint(leaves, token, kind, body[found.start() : start])))
    _match_brackets(leaves)
    return Logical(line[:indent], leaves, [line])


# re.UNICODE (the default for text) as tokenize compiles it: one compilation serves both
_PSEUDO_TOKEN = re.compile(tokenize.PseudoToken, re.UNICODE)
_BRACKET_MARKS = re.compile(r"[()\[\]{}]")


def _kind(token: str) -> int | None:
    """The token type the tokenizer gives `token` (its own tests, in its order)."""
    initial = token[0]
    if initial in "0123456789" or (initial == "." and token not in {".", "..."}):
        return tokenize.NUMBER
    if initial in "'\"":
        return tokenize.STRING
    if initial.isidentifier():
        return tokenize.NAME
    return None if initial in "#\\\r\n" else tokenize.OP


def _joint(leaves: list[Leaf], token: str, kind: int, space: str) -> str:
    """`_prefix` for a token read by `one_line_statement` (`space`: the whitespace before it)."""
    if not leaves or (kind == tokenize.OP and (token in CLOSING or token == ",")):
        return ""
    prev = leaves[-1]
    if prev.kind == tokenize.OP and prev.text in OPENING:
        return ""
    return space


def _balanced(brackets: list[str]) -> bool:
    depth = 0
    for bracket in brackets:
        depth += 1 if bracket in OPENING else -1
        if depth < 0:
            return False
    return depth == 0


def _plain_brackets(punctuation: list[str]) -> bool:
    """The brackets match, and every `,)` ends a bracket with one comma directly inside (a
    one-tuple or a call of one argument: black's magic trailing comma is any other)."""
    commas: list[int] = []  # per open bracket, the commas directly inside it
    for mark in punctuation:
        if mark in OPENING:
            commas.append(0)
        elif mark == ",":
            if commas:
                commas[-1] += 1
        elif not commas:
            return False  # a closing bracket before its opening one
        elif commas.pop() and mark == ",)":
            return False  # a trailing comma after others: magic
    return not commas


# --- reading logical lines


@dataclass
class Logical:
    """One statement of the source: its leaves, its indentation and its source lines."""

    indent: str
    leaves: list[Leaf]
    source: list[str]
    comment: str = ""  # a trailing comment on the statement's last line


def _prefix(prev: tokenize.TokenInfo, tok: tokenize.TokenInfo, line: str) -> str:
    """The whitespace before `tok` (on `line`): as written on the same line, else black's for a
    joint."""
    if tok.type == tokenize.OP and (tok.string in CLOSING or tok.string == ","):
        return ""
    if prev.type == tokenize.OP and prev.string in OPENING:
        return ""
    if prev.end[0] == tok.start[0]:
        return line[prev.end[1] : tok.start[1]]
    return " "


def _match_brackets(leaves: list[Leaf]) -> None:
    stack: list[int] = []
    for i, leaf in enumerate(leaves):
        if leaf.kind != tokenize.OP:
            continue
        if leaf.text in OPENING:
            prev = leaves[i - 1] if i else None
            leaf.atom = leaf.text == "{" or not (
                prev is not None
                and (
                    (prev.kind == tokenize.NAME and prev.text not in KEYWORDS)
                    or prev.kind == tokenize.STRING
                    or (prev.kind == tokenize.OP and prev.text in CLOSING)
                )
            )
            stack.append(i)
        elif leaf.text in CLOSING:
            if not stack:
                raise Unsupported("unbalanced brackets")
            j = stack.pop()
            leaves[j].match, leaf.match = i, j


class _Doubt(Exception):
    """Reading statement by statement met a case it does not handle: read the whole source."""


_SKIP = {tokenize.INDENT, tokenize.DEDENT, tokenize.ENCODING, tokenize.ENDMARKER}


def logical_lines(source: str) -> list[Logical | str]:
    """The source as statements and verbatim lines (blank lines, comments, multi-line strings),
    the whole source through one tokenizer."""
    lines = source.splitlines()
    out: list[Logical | str] = []
    _read(tokenize.generate_tokens(io.StringIO(source).readline), lines, out)
    return out


def _statement_at(lines: list[str], start: int, out: list[Logical | str], end: str) -> int:
    """The statement that begins at `lines[start]`, tokenized alone (a tokenizer reads lines only
    as it needs them, so it stops at the statement's end), appended to `out`; returns the index
    of the line after it. `end`: how the source's last line ends ("\n" or "")."""
    position = start

    def readline() -> str:
        nonlocal position
        position += 1
        if position > len(lines):
            return ""
        return lines[position - 1] + ("\n" if position < len(lines) else end)

    return start + _read(tokenize.generate_tokens(readline), lines, out, start, one=True)


def _read(
    tokens: Iterator[tokenize.TokenInfo],
    lines: list[str],
    out: list[Logical | str],
    offset: int = 0,
    one: bool = False,
) -> int:
    """Statements and verbatim lines of `tokens` (rows counted from `lines[offset]`) appended to
    `out`; with `one`, only the first statement, and the row of its end is returned."""
    toks: list[tokenize.TokenInfo] = []
    comment = ""
    for tok in tokens:
        if tok.type in _SKIP:
            continue
        if tok.type == tokenize.COMMENT:
            if toks and tok.start[0] != toks[-1].end[0]:
                raise Unsupported("comment inside a statement")
            if toks:
                comment = tok.string
            continue
        if tok.type == tokenize.NL:
            if one and not toks:
                raise _Doubt("a blank line before the statement")
            if not toks:
                row = offset + tok.start[0]
                out.append(lines[row - 1].rstrip() if row <= len(lines) else "")
            continue
        if tok.type != tokenize.NEWLINE:
            toks.append(tok)
            continue
        first, last = offset + toks[0].start[0], offset + toks[-1].end[0]
        if any(t.type == tokenize.STRING and t.start[0] != t.end[0] for t in toks):
            out.extend(line.rstrip() for line in lines[first - 1 : last])  # docstrings: as written
        else:
            out.append(_logical(toks, lines, comment, offset))
        if one:  # the row of the NEWLINE: a continuation line may follow the last token
            return tok.start[0]
        toks, comment = [], ""
    if one:
        raise _Doubt("no statement")
    return len(lines)


def _logical(
    toks: list[tokenize.TokenInfo], lines: list[str], comment: str, offset: int
) -> Logical:
    leaves = []
    for i, tok in enumerate(toks):
        text = normalize_string(tok.string) if tok.type == tokenize.STRING else tok.string
        prefix = _prefix(toks[i - 1], tok, lines[offset + tok.start[0] - 1]) if i else ""
        leaves.append(Leaf(text, tok.type, prefix))
    _match_brackets(leaves)
    first, last = offset + toks[0].start[0], offset + toks[-1].end[0]
    return Logical(" " * toks[0].start[1], leaves, lines[first - 1 : last], comment)


# --- the module


def format_source(source: str, fallback: Callable[[str, int], str], quick: bool = True) -> str:
    """`source` as black prints it; `fallback(statement, indent)` formats a statement
    (dedented, with the line length less its indentation) this module does not reproduce.
    `quick=False`: every statement through one tokenizer, no line copied (the reference the
    tests hold the quick paths to)."""
    lines = source.splitlines()
    entries: list[Entry | None] = []  # None: a blank line
    # splitlines also ends lines at \r, \f and other characters where the tokenizer does not:
    # then, and when reading statement by statement is in doubt, one tokenizer reads it all
    if quick and len(lines) == source.count("\n") + (not source.endswith("\n")):
        try:
            return _format_lines(lines, entries, fallback, "\n" if source.endswith("\n") else "")
        except _Doubt:
            entries.clear()
    for item in logical_lines(source):
        entries.append(_entry(item, fallback))
    return "\n".join(blank_lines(entries)) + "\n"


def _format_lines(
    lines: list[str], entries: list[Entry | None], fallback: Callable[[str, int], str], end: str
) -> str:
    """format_source over lines that begin statements or are copied (`quick_line`), the
    others tokenized statement by statement."""
    from swarmgen.backends.pyassign import layout_line  # it reads with this module's helpers

    i, count = 0, len(lines)
    items: list[Logical | str] = []
    while i < count:
        line = lines[i]
        code = line.lstrip(" \t")
        if not code or code[0] == "#":  # the tokenizer's blank and comment lines
            entries.append(_entry(line.rstrip(), fallback))
            i += 1
            continue
        laid = laid_out(lines, i)
        if laid:
            entries.append(Entry((len(line) - len(code)) // 4, lines[i : i + laid], code))
            i += laid
            continue
        quick = quick_line(line)
        if quick is not None:
            entries.append(Entry((len(quick) - len(code)) // 4, [quick], code))
            i += 1
            continue
        split = layout_line(line) if len(line) > LINE_LENGTH else None
        if split is not None:  # a long literal or call, read back into `pylayout`'s nodes
            entries.append(Entry((len(line) - len(code)) // 4, split, code))
            i += 1
            continue
        statement = one_line_statement(line)
        if statement is not None:
            entries.append(_entry(statement, fallback))
            i += 1
            continue
        i = _statement_at(lines, i, items, end)
        entries.extend(_entry(item, fallback) for item in items)
        items.clear()
    return "\n".join(blank_lines(entries)) + "\n"


def _entry(item: Logical | str, fallback: Callable[[str, int], str]) -> Entry | None:
    """A verbatim line or a statement printed (with black for a form not reproduced here)."""
    if isinstance(item, str):
        stripped = item.lstrip()
        depth = (len(item) - len(stripped)) // 4
        return Entry(depth, [item], stripped) if stripped else None
    try:
        lines = format_statement(item)
    except Unsupported as why:
        STATS.fallbacks += 1
        STATS.samples.append(f"{why}: {item.source[0].strip()[:80]}")
        lines = _fallback(item, fallback)
    return Entry(len(item.indent) // 4, lines, lines[0].lstrip())


def format_statement(item: Logical) -> list[str]:
    """A statement's lines as black prints them."""
    if len(item.indent) % 4:
        raise Unsupported("indentation not in steps of four")
    first = item.leaves[0]
    is_def = first.text == "def" or (first.text == "async" and item.leaves[1].text == "def")
    line = Line(len(item.indent) // 4, item.leaves, is_def=is_def)
    start = rhs_start(line)
    last = len(line.leaves) - 1
    if start > 0 and line.leaves[start].text == "(" and line.leaves[start].match == last:
        inner = new_line(0, line.leaves[start + 1 : last], inside=True)
        if COMMA_PRIORITY not in delimiters(inner).values():  # a tuple keeps its parentheses
            raise Unsupported("redundant parentheses black removes")
    if item.comment:
        text = line.render() + "  " + item.comment
        if magic_trailing_comma(line) or width(text) > LINE_LENGTH or len(item.source) > 1:
            raise Unsupported("a comment in a long statement")
        if not item.comment.startswith("# "):
            raise Unsupported("a comment to normalise")
        return [text]
    return [part.render() for part in transform(line)]


def _fallback(item: Logical, fallback: Callable[[str, int], str]) -> list[str]:
    text = "\n".join(line[len(item.indent) :] for line in item.source) + "\n"
    header = item.leaves[-1].text == ":"
    formatted = fallback(text + ("    pass\n" if header else ""), len(item.indent))
    lines = formatted.rstrip("\n").split("\n")
    if header:
        lines = lines[:-1]
    return [(item.indent + line) if line else line for line in lines]
