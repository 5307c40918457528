"""The expression language's tokenizer: model text to tokens, with located errors."""

from __future__ import annotations

import math
import re
import string
from typing import Literal, NoReturn

from swarmgen.expr.errors import error_at, show
from swarmgen.expr.tree import MAX_INT, Value
from swarmgen.records import dataclass

TokKind = Literal["num", "str", "word", "op", "nl", "eof"]


@dataclass(frozen=True, slots=True)
class Tok:
    """A token: its kind, its text, where it starts, and the value of a literal."""

    kind: TokKind
    text: str
    offset: int
    value: Value = None


_DIGITS = frozenset(string.digits)
_ASCII_WORD = re.compile(r"[A-Za-z0-9_]*")  # matches everywhere, possibly empty
_NUMBER = re.compile(r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
# Longest first. Java/C-isms (++, +=, ===, **) are tokens of their own so that the parser can
# explain them instead of reporting a puzzling error one character later.
_OPERATORS = (
    "===", "!==",
    "==", "!=", "<=", ">=", "&&", "||", "++", "--", "+=", "-=", "*=", "/=", "%=", "**", "//",
    "+", "-", "*", "/", "%", "<", ">", "(", ")", "[", "]", ",", ".", "=", "!", ";",
)  # fmt: skip
# The operators by first character, longest first: the same first match as scanning the whole
# tuple, without trying thirty prefixes per operator token.
_BY_FIRST: dict[str, tuple[str, ...]] = {}
for _op in _OPERATORS:
    _BY_FIRST.setdefault(_op[0], ())
    _BY_FIRST[_op[0]] += (_op,)
_SIMPLE_ESCAPES = {"\\": "\\", "'": "'", '"': '"', "n": "\n", "t": "\t", "r": "\r"}
_HEX_ESCAPES = {"x": 2, "u": 4, "U": 8}
_CHAR_HINTS = {
    "&": "write `and` (or `&&`)",
    "|": "write `or` (or `||`)",
    "[": "indexing is not part of the expression language",
    "]": "indexing is not part of the expression language",
    "?": "conditional expressions are not part of the expression language",
    "{": "blocks are not part of the language: one action per line",
    "}": "blocks are not part of the language: one action per line",
}


class Lexer:
    """Splits text into tokens. Newlines separate statements only outside parentheses."""

    def __init__(self, text: str, statements: bool) -> None:
        self.text = text
        self.statements = statements
        self.tokens: list[Tok] = []
        self.depth = 0

    def fail(self, offset: int, message: str, hint: str | None = None) -> NoReturn:
        """Raise an ExprError pointing at `offset` in the text."""
        raise error_at(self.text, offset, message, hint)

    def run(self) -> list[Tok]:
        """Tokenize the whole text, ending with an `eof` token."""
        i, n = 0, len(self.text)
        while i < n:
            i = self.step(i)
        self.tokens.append(Tok("eof", "", n))
        return self.tokens

    def step(self, i: int) -> int:
        """Read the token (or skip the blank) at `i`; returns the next index."""
        c = self.text[i]
        if c == "\n":
            if self.statements and self.depth == 0:
                self.tokens.append(Tok("nl", c, i))
            return i + 1
        if c.isspace():
            return i + 1
        # ASCII digits only: str.isdigit() would also accept e.g. Arabic-Indic digits.
        if c in _DIGITS or (c == "." and self.text[i + 1 : i + 2] in _DIGITS):
            return self.number(i)
        if c in "'\"":
            return self.string(i)
        if c.isidentifier():
            return self.word(i)
        return self.operator(i)

    def number(self, start: int) -> int:
        """Read a number literal at `start`; returns the next index."""
        match = _NUMBER.match(self.text, start)
        assert match is not None  # step() only calls us on a digit or '.<digit>'
        lexeme = match.group()
        self.tokens.append(Tok("num", lexeme, start, self.number_value(lexeme, start)))
        return match.end()

    def number_value(self, lexeme: str, start: int) -> int | float:
        """The value of a number lexeme, refusing what the targets cannot hold exactly."""
        if any(c in lexeme for c in ".eE"):
            value = float(lexeme)
            if not math.isfinite(value):
                self.fail(start, f"number {show(lexeme)} is too large")
            return value
        # The length test comes first: int() refuses very long digit strings with ValueError.
        if len(lexeme) > 20 or int(lexeme) > MAX_INT:
            self.fail(
                start,
                f"integer {show(lexeme)} is too large",
                hint=f"integers must lie within ±{MAX_INT} (exact in ECMAScript)",
            )
        return int(lexeme)

    def word(self, start: int) -> int:
        """Read a name at `start` (refusing reserved `__` names); returns the next index."""
        # ASCII letters, digits and `_` in one regex step (for an ASCII character that is what
        # continuing an identifier means); the loop takes any other character that continues one.
        ascii_run = _ASCII_WORD.match(self.text, start + 1)
        assert ascii_run is not None  # the pattern also matches the empty string
        end = ascii_run.end()
        while end < len(self.text) and ("_" + self.text[end]).isidentifier():
            end += 1
        lexeme = self.text[start:end]
        if lexeme.startswith("__"):
            self.fail(start, f"names starting with `__` are reserved: {show(lexeme)}")
        self.tokens.append(Tok("word", lexeme, start))
        return end

    def string(self, start: int) -> int:
        """Read a quoted string at `start`, decoding escapes; returns the next index."""
        quote, i, chars = self.text[start], start + 1, []
        while True:
            if i >= len(self.text) or self.text[i] == "\n":
                self.fail(start, "unterminated string", hint=f"close it with {quote}")
            at, c = i, self.text[i]
            if c == quote:
                break
            if c == "\\":
                c, i = self.escape(start, i)
            else:
                i += 1
            if 0xD800 <= ord(c) <= 0xDFFF:
                self.fail(at, "strings must not contain lone surrogates")
            chars.append(c)
        self.tokens.append(Tok("str", self.text[start : i + 1], start, "".join(chars)))
        return i + 1

    def escape(self, start: int, i: int) -> tuple[str, int]:
        """Decode the escape at text[i] == '\\'; returns the character and the next index."""
        if i + 1 >= len(self.text):
            self.fail(start, "unterminated string")
        e = self.text[i + 1]
        if e in _SIMPLE_ESCAPES:
            return _SIMPLE_ESCAPES[e], i + 2
        if e not in _HEX_ESCAPES:
            self.fail(
                i,
                f"unknown escape {show(chr(92) + e)} in string",
                hint="known escapes: \\\\ \\' \\\" \\n \\t \\r \\xHH \\uHHHH \\UHHHHHHHH",
            )
        digits = self.text[i + 2 : i + 2 + _HEX_ESCAPES[e]]
        # int(..., 16) would also accept '_' and spaces: check the digits ourselves.
        valid = len(digits) == _HEX_ESCAPES[e] and all(d in string.hexdigits for d in digits)
        if not valid or int(digits, 16) > 0x10FFFF:
            self.fail(i, f"invalid escape {show(self.text[i : i + 2 + len(digits)])}")
        return chr(int(digits, 16)), i + 2 + len(digits)

    def operator(self, i: int) -> int:
        """Read an operator at `i` (tracking parentheses), or fail with a hint."""
        for op in _BY_FIRST.get(self.text[i], ()):
            if self.text.startswith(op, i):
                self.depth = self.depth + 1 if op == "(" else self.depth
                self.depth = max(0, self.depth - 1) if op == ")" else self.depth
                self.tokens.append(Tok("op", op, i))
                return i + len(op)
        c = self.text[i]
        hint = _CHAR_HINTS.get(c)
        if c == "[" and not self.text[:i].strip():
            hint = "UML shows guards in brackets; write the guard without `[ ]`"
        self.fail(i, f"unknown character {show(c)}", hint)
