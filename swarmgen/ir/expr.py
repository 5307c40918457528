"""The expression and action language of guards, effects and behaviour argument bindings.

Guards are side-effect-free expressions (literals, member data names, ``event.<field>``,
comparisons, ``and``/``or``/``not``, arithmetic). Effects are one action per line:
``raise <event>(field = expr, ...)``, ``send <event>(field = expr, ...)`` or
``name = expression``. Bindings are one ``name = expression`` per line.

Model text is hostile input: it is parsed by a hand-written tokenizer and a precedence-climbing
parser (never ``eval`` nor Python's ``ast``), every identifier in the tree is validated, and the
renderers quote strings with the target language's own escaping, so neither a name nor a string
can inject code into the generated ECMAScript or Python.
"""

from __future__ import annotations

import json
import keyword
import math
import re
import string
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Annotated, Literal, NoReturn, assert_never

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, field_validator

MAX_TEXT = 10_000
MAX_DEPTH = 100
# ECMAScript numbers are doubles: larger integers would silently change value in the SCXML.
MAX_INT = 2**53 - 1

RESERVED = frozenset(
    {"and", "or", "not", "true", "false", "True", "False", "null", "None", "else", "event"}
)

BinOp = Literal["or", "and", "==", "!=", "<", "<=", ">", ">=", "+", "-", "*", "/", "%"]
UnOp = Literal["not", "-", "+"]
Value = bool | int | float | str | None


# --- errors


class ExprError(Exception):
    """A syntax error in model text, located by 0-based offset, line and column."""

    def __init__(
        self, message: str, offset: int, line: int, col: int, hint: str | None = None
    ) -> None:
        # All fields go to Exception.args so that the error pickles (multiprocessing) intact.
        super().__init__(message, offset, line, col, hint)
        self.message = message
        self.offset = offset
        self.line = line
        self.col = col
        self.hint = hint

    def __str__(self) -> str:
        text = f"line {self.line + 1}, column {self.col + 1}: {self.message}"
        return f"{text} (hint: {self.hint})" if self.hint else text


def _error(text: str, offset: int, message: str, hint: str | None = None) -> ExprError:
    line = text.count("\n", 0, offset)
    col = offset - (text.rfind("\n", 0, offset) + 1)
    return ExprError(message, offset, line, col, hint)


def _escape_char(c: str) -> str:
    code = ord(c)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def _show(text: str, limit: int = 30) -> str:
    """Quote model text for a message: clipped, and without raw control characters."""
    clipped = text if len(text) <= limit else text[: limit - 1] + "…"
    return "'" + "".join(c if c.isprintable() else _escape_char(c) for c in clipped) + "'"


# --- tree


def _ident(value: str) -> str:
    if not value.isidentifier():
        raise ValueError(f"{value!r} is not an identifier")
    # Dunder names reach interpreter internals (__class__, __proto__): keep them out entirely.
    if value.startswith("__"):
        raise ValueError(f"{value!r}: names starting with '__' are reserved")
    return value


def _data_name(value: str) -> str:
    if value in RESERVED:
        raise ValueError(f"{value!r} is a keyword of the expression language")
    return _ident(value)


Ident = Annotated[str, AfterValidator(_ident)]
DataName = Annotated[str, AfterValidator(_data_name)]


def _check_value(value: Value) -> Value:
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError("numbers must be finite")
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > MAX_INT:
        raise ValueError(f"integers must lie within ±{MAX_INT}")
    if isinstance(value, str) and any(0xD800 <= ord(c) <= 0xDFFF for c in value):
        raise ValueError("strings must not contain lone surrogates")
    return value


def _not_else(value: Expr) -> Expr:
    if isinstance(value, Else):
        raise ValueError("`else` can only be a whole guard")
    return value


def _path(value: Expr) -> Expr:
    if not isinstance(value, Name | EventField | Attr):
        raise ValueError("attribute access needs a name on the left")
    return value


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


class Const(_Model):
    """A literal: boolean, integer, float, string or null."""

    kind: Literal["literal"] = "literal"
    value: Value

    @field_validator("value")
    @classmethod
    def check_value(cls, value: Value) -> Value:
        return _check_value(value)


class Name(_Model):
    """A member data name."""

    kind: Literal["name"] = "name"
    name: DataName


class EventField(_Model):
    """``event.<field>``: a field of the event that triggered the transition."""

    kind: Literal["event_field"] = "event_field"
    field: Ident


class Attr(_Model):
    """``obj.name`` where obj is a name, an event field or another attribute access."""

    kind: Literal["attr"] = "attr"
    obj: Annotated[Expr, AfterValidator(_path)]
    name: Ident


class Unary(_Model):
    kind: Literal["unary"] = "unary"
    op: UnOp
    operand: Operand


class Binary(_Model):
    kind: Literal["binary"] = "binary"
    op: BinOp
    left: Operand
    right: Operand


class Else(_Model):
    """UML's ``else`` guard: true when no other guard of the choice holds."""

    kind: Literal["else"] = "else"


Expr = Annotated[
    Const | Name | EventField | Attr | Unary | Binary | Else, Field(discriminator="kind")
]
Operand = Annotated[Expr, AfterValidator(_not_else)]

for _cls in (Attr, Unary, Binary):
    _cls.model_rebuild()


class Arg(_Model):
    """``field = expr`` inside ``raise``/``send``."""

    name: Ident
    value: Operand


def _unique_args(args: tuple[Arg, ...]) -> tuple[Arg, ...]:
    names = [a.name for a in args]
    if len(set(names)) != len(names):
        raise ValueError("duplicate argument names")
    return args


class Assign(_Model):
    kind: Literal["assign"] = "assign"
    target: DataName
    value: Operand


class Raise(_Model):
    """Raise an event for this member only."""

    kind: Literal["raise"] = "raise"
    event: Ident
    args: Annotated[tuple[Arg, ...], AfterValidator(_unique_args)] = ()


class Send(_Model):
    """Send an event to the swarm."""

    kind: Literal["send"] = "send"
    event: Ident
    args: Annotated[tuple[Arg, ...], AfterValidator(_unique_args)] = ()


Action = Annotated[Assign | Raise | Send, Field(discriminator="kind")]


class Binding(_Model):
    """``name = expr``: one argument binding of a behaviour call."""

    name: DataName
    value: Operand


# --- tokens

TokKind = Literal["num", "str", "word", "op", "nl", "eof"]


@dataclass(frozen=True, slots=True)
class _Tok:
    kind: TokKind
    text: str
    offset: int
    value: Value = None


_DIGITS = frozenset(string.digits)
_NUMBER = re.compile(r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
# Longest first. Java/C-isms (++, +=, ===, **) are tokens of their own so that the parser can
# explain them instead of reporting a puzzling error one character later.
_OPERATORS = (
    "===", "!==",
    "==", "!=", "<=", ">=", "&&", "||", "++", "--", "+=", "-=", "*=", "/=", "%=", "**", "//",
    "+", "-", "*", "/", "%", "<", ">", "(", ")", ",", ".", "=", "!", ";",
)  # fmt: skip
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


class _Lexer:
    """Splits text into tokens. Newlines separate statements only outside parentheses."""

    def __init__(self, text: str, statements: bool) -> None:
        self.text = text
        self.statements = statements
        self.tokens: list[_Tok] = []
        self.depth = 0

    def fail(self, offset: int, message: str, hint: str | None = None) -> NoReturn:
        raise _error(self.text, offset, message, hint)

    def run(self) -> list[_Tok]:
        i, n = 0, len(self.text)
        while i < n:
            i = self.step(i)
        self.tokens.append(_Tok("eof", "", n))
        return self.tokens

    def step(self, i: int) -> int:
        c = self.text[i]
        if c == "\n":
            if self.statements and self.depth == 0:
                self.tokens.append(_Tok("nl", c, i))
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
        match = _NUMBER.match(self.text, start)
        assert match is not None  # step() only calls us on a digit or '.<digit>'
        lexeme = match.group()
        self.tokens.append(_Tok("num", lexeme, start, self.number_value(lexeme, start)))
        return match.end()

    def number_value(self, lexeme: str, start: int) -> int | float:
        if any(c in lexeme for c in ".eE"):
            value = float(lexeme)
            if not math.isfinite(value):
                self.fail(start, f"number {_show(lexeme)} is too large")
            return value
        # The length test comes first: int() refuses very long digit strings with ValueError.
        if len(lexeme) > 20 or int(lexeme) > MAX_INT:
            self.fail(
                start,
                f"integer {_show(lexeme)} is too large",
                hint=f"integers must lie within ±{MAX_INT} (exact in ECMAScript)",
            )
        return int(lexeme)

    def word(self, start: int) -> int:
        end = start + 1
        while end < len(self.text) and ("_" + self.text[end]).isidentifier():
            end += 1
        lexeme = self.text[start:end]
        if lexeme.startswith("__"):
            self.fail(start, f"names starting with `__` are reserved: {_show(lexeme)}")
        self.tokens.append(_Tok("word", lexeme, start))
        return end

    def string(self, start: int) -> int:
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
        self.tokens.append(_Tok("str", self.text[start : i + 1], start, "".join(chars)))
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
                f"unknown escape {_show(chr(92) + e)} in string",
                hint="known escapes: \\\\ \\' \\\" \\n \\t \\r \\xHH \\uHHHH \\UHHHHHHHH",
            )
        digits = self.text[i + 2 : i + 2 + _HEX_ESCAPES[e]]
        # int(..., 16) would also accept '_' and spaces: check the digits ourselves.
        valid = len(digits) == _HEX_ESCAPES[e] and all(d in string.hexdigits for d in digits)
        if not valid or int(digits, 16) > 0x10FFFF:
            self.fail(i, f"invalid escape {_show(self.text[i : i + 2 + len(digits)])}")
        return chr(int(digits, 16)), i + 2 + len(digits)

    def operator(self, i: int) -> int:
        for op in _OPERATORS:
            if self.text.startswith(op, i):
                self.depth = self.depth + 1 if op == "(" else self.depth
                self.depth = max(0, self.depth - 1) if op == ")" else self.depth
                self.tokens.append(_Tok("op", op, i))
                return i + len(op)
        c = self.text[i]
        hint = _CHAR_HINTS.get(c)
        if c == "[" and not self.text[:i].strip():
            hint = "UML shows guards in brackets; write the guard without `[ ]`"
        self.fail(i, f"unknown character {_show(c)}", hint)


# --- parser

_BINOPS: dict[str, BinOp] = {
    "or": "or", "||": "or", "and": "and", "&&": "and",
    "==": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">=",
    "+": "+", "-": "-", "*": "*", "/": "/", "%": "%",
}  # fmt: skip
_UNOPS: dict[str, UnOp] = {"not": "not", "!": "not", "-": "-", "+": "+"}
_PREC: dict[BinOp, int] = {
    "or": 1, "and": 2,
    "==": 4, "!=": 4, "<": 4, "<=": 4, ">": 4, ">=": 4,
    "+": 5, "-": 5, "*": 6, "/": 6, "%": 6,
}  # fmt: skip
_NOT_PREC = 3  # prefix `not` sits between `and` and the comparisons, as in Python
_UNARY_PREC = 7
_ATOM_PREC = 9
_COMPARISONS = frozenset({"==", "!=", "<", "<=", ">", ">="})
_CONSTANTS: dict[str, Value] = {
    "true": True, "True": True, "false": False, "False": False, "null": None, "None": None,
}  # fmt: skip
_COMPOUND = frozenset({"+=", "-=", "*=", "/=", "%="})
# Operators borrowed from Java/C/ECMAScript that get a message of their own.
_EXPLAINED = _COMPOUND | {"++", "--", "===", "!==", "**", "//"}
_NOT_ACTION = "an action must be `name = expression`, `raise <event>(...)` or `send <event>(...)`"
_NOT_BINDING = "a binding must be `name = expression`"

# A parsed expression together with its depth: the depth limit keeps the recursive renderers
# (and pydantic's own recursion) far from Python's recursion limit.
_Node = tuple[Expr, int]


def _binop(tok: _Tok) -> BinOp | None:
    return _BINOPS.get(tok.text) if tok.kind in ("word", "op") else None


def _unop(tok: _Tok) -> UnOp | None:
    return _UNOPS.get(tok.text) if tok.kind in ("word", "op") else None


def _show_tok(tok: _Tok) -> str:
    if tok.kind == "eof":
        return "end of text"
    return "end of line" if tok.kind == "nl" else _show(tok.text)


def _is_path(e: Expr) -> bool:
    return isinstance(e, Name | EventField | Attr)


class _Parser:
    def __init__(self, text: str, statements: bool) -> None:
        if len(text) > MAX_TEXT:
            raise _error(
                text,
                MAX_TEXT,
                f"text is too long ({len(text)} characters; the limit is {MAX_TEXT})",
            )
        self.text = text
        self.statements = statements
        self.toks = _Lexer(text, statements).run()
        self.pos = 0
        self.nest = 0

    # token access

    def peek(self, ahead: int = 0) -> _Tok:
        return self.toks[min(self.pos + ahead, len(self.toks) - 1)]

    def advance(self) -> _Tok:
        tok = self.toks[self.pos]
        if tok.kind != "eof":
            self.pos += 1
        return tok

    def prev(self) -> _Tok | None:
        return self.toks[self.pos - 1] if self.pos else None

    @staticmethod
    def is_op(text: str, tok: _Tok) -> bool:
        return tok.kind == "op" and tok.text == text

    def at_end_of_statement(self) -> bool:
        tok = self.peek()
        return tok.kind in ("nl", "eof") or self.is_op(";", tok)

    def fail(self, tok: _Tok, message: str, hint: str | None = None) -> NoReturn:
        raise _error(self.text, tok.offset, message, hint)

    # depth bookkeeping

    def deeper(self, node: Expr, depth: int, tok: _Tok) -> _Node:
        if depth + 1 > MAX_DEPTH:
            self.too_deep(tok)
        return node, depth + 1

    def enter(self, tok: _Tok) -> None:
        self.nest += 1
        if self.nest > MAX_DEPTH:
            self.too_deep(tok)

    def too_deep(self, tok: _Tok) -> NoReturn:
        self.fail(tok, f"expression is nested too deeply (more than {MAX_DEPTH} levels)")

    # expressions

    def expr(self, min_prec: int = 0) -> _Node:
        left = self.prefix(min_prec)
        while (op := _binop(self.peek())) is not None and _PREC[op] >= min_prec:
            tok = self.advance()
            right = self.expr(_PREC[op] + 1)
            node = Binary(op=op, left=left[0], right=right[0])
            left = self.deeper(node, max(left[1], right[1]), tok)
            if op in _COMPARISONS:
                self.no_chain(node)
        return left

    def no_chain(self, first: Binary) -> None:
        tok = self.peek()
        op = _binop(tok)
        if op not in _COMPARISONS:
            return
        self.advance()
        third, _ = self.expr(_PREC[op] + 1)  # only to quote it in the message
        a, b, c = (_clip(to_text(e)) for e in (first.left, first.right, third))
        self.fail(
            tok,
            f"chained comparison `{a} {first.op} {b} {op} {c}` is not supported",
            hint=f"write `{a} {first.op} {b} and {b} {op} {c}`",
        )

    def prefix(self, min_prec: int) -> _Node:
        tok = self.peek()
        op = _unop(tok)
        if op is None:
            return self.postfix()
        if op == "not" and min_prec > _NOT_PREC:
            self.fail(tok, f"{_show(tok.text)} needs parentheses here", hint="write `a == (not b)`")
        self.advance()
        if op == "-" and self.peek().kind == "num":
            # Fold `-<number>` into a negative literal (to_text writes `-(1)` for the unary form).
            num = self.advance()
            assert isinstance(num.value, int | float)
            return Const(value=-num.value), 1
        self.enter(tok)
        operand = self.expr(_NOT_PREC) if op == "not" else self.prefix(_UNARY_PREC)
        self.nest -= 1
        return self.deeper(Unary(op=op, operand=operand[0]), operand[1], tok)

    def postfix(self) -> _Node:
        node = self.primary()
        while self.is_op(".", self.peek()):
            dot = self.advance()
            if not _is_path(node[0]):
                self.fail(dot, "attribute access needs a name on the left")
            name = self.peek()
            if name.kind != "word":
                self.fail(name, "expected a field name after '.'")
            self.advance()
            node = self.deeper(Attr(obj=node[0], name=name.text), node[1], name)
        tok = self.peek()
        if self.is_op("(", tok) and _is_path(node[0]):
            self.fail(
                tok,
                "function calls are not part of the expression language",
                hint="guards and effects cannot call operations; a state's doActivity calls "
                "behaviours",
            )
        return node

    def primary(self) -> _Node:
        tok = self.peek()
        if tok.kind in ("num", "str"):
            self.advance()
            return Const(value=tok.value), 1
        if tok.kind == "word":
            return self.word()
        if self.is_op("(", tok):
            return self.group()
        self.expected_expression(tok)

    def word(self) -> _Node:
        tok = self.peek()
        if tok.text in _CONSTANTS:
            self.advance()
            return Const(value=_CONSTANTS[tok.text]), 1
        if tok.text in ("and", "or", "not"):
            self.expected_expression(tok)
        if tok.text == "else":
            self.else_misplaced(tok)
        self.advance()
        if tok.text != "event":
            return Name(name=tok.text), 1
        if not self.is_op(".", self.peek()):
            self.fail(tok, "`event` needs a field: event.<field>")
        self.advance()
        field = self.peek()
        if field.kind != "word":
            self.fail(field, "expected a field name after 'event.'")
        self.advance()
        return EventField(field=field.text), 1

    def group(self) -> _Node:
        opening = self.advance()
        self.enter(opening)
        inner = self.expr(0)
        self.close(opening)
        self.nest -= 1
        return inner

    def close(self, opening: _Tok) -> None:
        tok = self.peek()
        if self.is_op(")", tok):
            self.advance()
            return
        if tok.kind in ("nl", "eof") or self.is_op(";", tok):
            where = _error(self.text, opening.offset, "")
            self.fail(
                tok,
                "missing ')'",
                hint=f"the '(' at line {where.line + 1}, column {where.col + 1} is never closed",
            )
        self.unexpected(tok)

    def expect_end(self) -> None:
        tok = self.peek()
        if tok.kind != "eof":
            self.unexpected(tok)

    # error reporting

    def expected_expression(self, tok: _Tok) -> NoReturn:
        if tok.kind == "op" and tok.text in _EXPLAINED:
            self.unexpected(tok)
        prev = self.prev()
        if prev is not None and prev.kind != "nl" and not self.is_op(";", prev):
            self.fail(tok, f"expected an expression after {_show_tok(prev)}")
        if tok.kind in ("eof", "nl") or self.is_op(";", tok):
            self.fail(tok, "expected an expression")
        self.fail(tok, f"unexpected token {_show_tok(tok)}")

    def unexpected(self, tok: _Tok) -> NoReturn:
        t = tok.text if tok.kind == "op" else ""
        x = self.subject()
        if t == "=":
            self.fail(tok, "`==` expected, `=` is assignment", hint="write `a == b` to compare")
        if t in ("++", "--"):
            self.fail(tok, f"`{t}` is not supported; write `{x} = {x} {t[0]} 1`")
        if t in _COMPOUND:
            self.fail(tok, f"`{t}` is not supported; write `{x} = {x} {t[0]} ...`")
        if t in ("===", "!=="):
            self.fail(tok, f"`{t}` is not supported; write `{t[:2]}`")
        if t in ("**", "//"):
            self.fail(tok, f"`{t}` is not supported", hint="use `*` and `/`")
        if tok.kind == "word" and tok.text == "else":
            self.else_misplaced(tok)
        self.fail(tok, f"unexpected token {_show_tok(tok)}", self.unexpected_hint(tok))

    def else_misplaced(self, tok: _Tok) -> NoReturn:
        self.fail(tok, "`else` is only allowed as a whole guard", hint="write `not (...)`")

    def subject(self) -> str:
        """The name an increment-like operator applies to, for quoting it in the message."""
        for tok in (self.prev(), self.peek(1)):
            if tok is not None and tok.kind == "word" and tok.text not in RESERVED:
                return tok.text
        return "x"

    def unexpected_hint(self, tok: _Tok) -> str | None:
        if self.is_op(";", tok) and not self.statements:
            return "a guard is a single expression"
        if self.is_op(")", tok):
            return "unbalanced parentheses"
        prev = self.prev()
        if prev is not None and prev.kind in ("word", "num", "str") and tok.kind != "op":
            return f"is an operator missing between {_show(prev.text)} and {_show(tok.text)}?"
        return None

    # statements

    def statements_of(self, one: Callable[[], None]) -> None:
        while True:
            while self.peek().kind == "nl" or self.is_op(";", self.peek()):
                self.advance()
            if self.peek().kind == "eof":
                return
            one()
            if not self.at_end_of_statement():
                self.unexpected(self.peek())

    def action(self) -> Assign | Raise | Send:
        tok = self.peek()
        # `send = 1` assigns member data named `send`
        if (
            tok.kind == "word"
            and tok.text in ("raise", "send")
            and not self.is_op("=", self.peek(1))
        ):
            return self.event_action()
        target, value = self.assignment(_NOT_ACTION)
        return Assign(target=target, value=value)

    def assignment(self, what: str) -> tuple[str, Expr]:
        start = self.peek()
        lhs, _ = self.expr(0)
        tok = self.peek()
        if not self.is_op("=", tok):
            if self.at_end_of_statement():
                self.fail(start, what, hint=_assign_hint(lhs))
            self.unexpected(tok)
        if not isinstance(lhs, Name):
            self.fail(start, f"can only assign to member data names, not `{_clip(to_text(lhs))}`")
        self.advance()
        value, _ = self.expr(0)
        return lhs.name, value

    def event_action(self) -> Raise | Send:
        verb = self.advance()
        name = self.peek()
        if name.kind != "word":
            self.fail(name, f"expected an event name after '{verb.text}'")
        self.advance()
        args = self.arguments() if self.is_op("(", self.peek()) else ()
        if verb.text == "raise":
            return Raise(event=name.text, args=args)
        return Send(event=name.text, args=args)

    def arguments(self) -> tuple[Arg, ...]:
        opening = self.advance()
        args: list[Arg] = []
        while not self.is_op(")", self.peek()):
            args.append(self.argument({a.name for a in args}))
            if not self.is_op(",", self.peek()):
                break
            self.advance()
        self.close(opening)
        return tuple(args)

    def argument(self, seen: set[str]) -> Arg:
        name = self.peek()
        if name.kind != "word":
            self.fail(name, f"expected an argument `name = expression`, found {_show_tok(name)}")
        if name.text in seen:
            self.fail(name, f"duplicate argument '{name.text}'")
        self.advance()
        if not self.is_op("=", self.peek()):
            self.fail(
                self.peek(),
                f"expected '=' after argument name '{name.text}'",
                hint="event arguments are written `field = expression`",
            )
        self.advance()
        value, _ = self.expr(0)
        return Arg(name=name.text, value=value)


def _assign_hint(lhs: Expr) -> str | None:
    if isinstance(lhs, Binary) and lhs.op == "==" and isinstance(lhs.left, Name):
        right = _clip(to_text(lhs.right))
        return f"did you mean `{lhs.left.name} = {right}`? `==` compares, `=` assigns"
    return None


def _clip(text: str, limit: int = 40) -> str:
    text = "".join(c if c.isprintable() else _escape_char(c) for c in text)
    return text if len(text) <= limit else text[: limit - 1] + "…"


# --- public parse functions


def parse_expr(text: str) -> Expr:
    """Parse a guard or any other single expression; raises ExprError."""
    if text.strip() == "else" and len(text) <= MAX_TEXT:
        return Else()
    parser = _Parser(text, statements=False)
    node, _ = parser.expr(0)
    parser.expect_end()
    return node


def parse_actions(text: str) -> tuple[Action, ...]:
    """Parse an effect (or entry/exit action): statements separated by newlines or `;`."""
    parser = _Parser(text, statements=True)
    actions: list[Action] = []
    parser.statements_of(lambda: actions.append(parser.action()))
    return tuple(actions)


def parse_bindings(text: str) -> tuple[Binding, ...]:
    """Parse behaviour argument bindings: one `name = expression` per line (or `;`)."""
    parser = _Parser(text, statements=True)
    bindings: list[Binding] = []

    def one() -> None:
        start = parser.peek()
        name, value = parser.assignment(_NOT_BINDING)
        if any(b.name == name for b in bindings):
            parser.fail(start, f"duplicate binding '{name}'")
        bindings.append(Binding(name=name, value=value))

    parser.statements_of(one)
    return tuple(bindings)


# --- queries


def _children(e: Expr) -> tuple[Expr, ...]:
    if isinstance(e, Attr):
        return (e.obj,)
    if isinstance(e, Unary):
        return (e.operand,)
    if isinstance(e, Binary):
        return (e.left, e.right)
    return ()


def walk(expr: Expr) -> Iterator[Expr]:
    """All nodes of the tree, pre-order, left to right (iterative: no recursion limit)."""
    stack: list[Expr] = [expr]
    while stack:
        node = stack.pop()
        yield node
        stack.extend(reversed(_children(node)))


def replace_fields(expr: Expr, names: dict[str, str]) -> Expr:
    """`event.<f>` read as the member datum `names[f]` instead (depth is bounded by the parser)."""
    if isinstance(expr, EventField) and expr.field in names:
        return Name(name=names[expr.field])
    if isinstance(expr, Attr):
        return Attr(obj=replace_fields(expr.obj, names), name=expr.name)
    if isinstance(expr, Unary):
        return Unary(op=expr.op, operand=replace_fields(expr.operand, names))
    if isinstance(expr, Binary):
        left, right = replace_fields(expr.left, names), replace_fields(expr.right, names)
        return Binary(op=expr.op, left=left, right=right)
    return expr


def free_names(expr: Expr) -> frozenset[str]:
    """Member data names read by the expression (the root of `a.b` is `a`; no event fields)."""
    return frozenset(n.name for n in walk(expr) if isinstance(n, Name))


def event_fields(expr: Expr) -> frozenset[str]:
    """Fields of the triggering event read by the expression."""
    return frozenset(n.field for n in walk(expr) if isinstance(n, EventField))


# --- renderings

_ASCII_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_TEXT_ESCAPES = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t", "\r": "\\r"}


def _identity(name: str) -> str:
    return name


def _number_text(value: int | float) -> str:
    return repr(value) if isinstance(value, float) else str(value)


def _is_number(e: Expr) -> bool:
    value = e.value if isinstance(e, Const) else None
    return isinstance(value, int | float) and not isinstance(value, bool)


def _const_text(value: Value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        body = "".join(
            _TEXT_ESCAPES.get(c) or (c if c.isprintable() else _escape_char(c)) for c in value
        )
        return f'"{body}"'
    return _number_text(value)


def _text_prec(e: Expr) -> int:
    if isinstance(e, Binary):
        return _PREC[e.op]
    if isinstance(e, Unary):
        return _NOT_PREC if e.op == "not" else _UNARY_PREC
    if _is_number(e) and to_text(e).startswith("-"):
        return _UNARY_PREC
    return _ATOM_PREC


def _paren(text: str, needed: bool) -> str:
    return f"({text})" if needed else text


def _unary_text(u: Unary) -> str:
    inner = to_text(u.operand)
    if u.op == "not":
        return "not " + _paren(inner, _text_prec(u.operand) < _NOT_PREC)
    if u.op == "-" and _is_number(u.operand) and not inner.startswith("-"):
        return f"-({inner})"  # `-1` would parse back as the literal -1
    if _text_prec(u.operand) < _UNARY_PREC:
        return f"{u.op}({inner})"
    return u.op + (" " if inner[0] in "+-" else "") + inner  # `--x` would lex as `--`


def _binary_text(b: Binary) -> str:
    prec = _PREC[b.op]
    left, right = _text_prec(b.left), _text_prec(b.right)
    # Comparisons do not associate, so an equal-precedence left operand needs parentheses too.
    left_paren = left < prec or (b.op in _COMPARISONS and left == prec)
    return f"{_paren(to_text(b.left), left_paren)} {b.op} {_paren(to_text(b.right), right <= prec)}"


def to_text(expr: Expr) -> str:
    """Canonical model-language text: ``parse_expr(to_text(e)) == e``."""
    match expr:
        case Const():
            return _const_text(expr.value)
        case Name():
            return expr.name
        case EventField():
            return f"event.{expr.field}"
        case Attr():
            return f"{to_text(expr.obj)}.{expr.name}"
        case Unary():
            return _unary_text(expr)
        case Binary():
            return _binary_text(expr)
        case Else():
            return "else"
        case _:
            assert_never(expr)


def _js_string(value: str) -> str:
    # JSON is valid ECMAScript; escaping <, > and & as well keeps the literal inert even if a
    # template ever pastes it into XML or HTML without escaping.
    quoted = json.dumps(value, ensure_ascii=True)
    return quoted.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def js_string(value: str) -> str:
    """An ECMAScript string literal, inert in XML and HTML too."""
    return _js_string(value)


def _js_const(value: Value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return _js_string(value)
    return _paren(_number_text(value), _number_text(value).startswith("-"))


def _js_member(name: str) -> str:
    return f".{name}" if _ASCII_IDENT.fullmatch(name) else f"[{_js_string(name)}]"


def _js_binary(b: Binary, name: Callable[[str], str]) -> str:
    left, right = to_ecmascript(b.left, name), to_ecmascript(b.right, name)
    if b.op == "/":
        # `$sg` is the emitted document's support script: a zero divisor is an error, as in
        # Python (error.execution), not Infinity.
        return f"$sg.div({left}, {right})"
    if b.op == "%":
        # Python's %: the sign of the divisor (ECMAScript: of the dividend); zero is an error.
        return f"$sg.mod({left}, {right})"
    op = {"and": "&&", "or": "||"}.get(b.op, b.op)
    return f"({left} {op} {right})"


def to_ecmascript(expr: Expr, name: Callable[[str], str] = _identity) -> str:
    """Render for an SCXML ECMAScript datamodel; `name` maps member data to safe identifiers.
    Division, modulo and event fields call the document's `$sg` support script (`$` never
    appears in an identifier swarmgen makes, so it cannot collide with member data)."""
    match expr:
        case Const():
            return _js_const(expr.value)
        case Name():
            return name(expr.name)
        case EventField():
            # a field the event does not carry is an error (in Python too), not `undefined`
            return f"$sg.field(_event, {_js_string(expr.field)})"
        case Attr():
            return to_ecmascript(expr.obj, name) + _js_member(expr.name)
        case Unary():
            op = "!" if expr.op == "not" else expr.op
            return f"({op}{to_ecmascript(expr.operand, name)})"
        case Binary():
            return _js_binary(expr, name)
        case Else():
            return "true"
        case _:
            assert_never(expr)


def _py_const(value: Value) -> str:
    if isinstance(value, str):
        return repr(value)
    if value is None or isinstance(value, bool):
        return repr(value)
    return _paren(_number_text(value), _number_text(value).startswith("-"))


def _py_attr(obj: str, attr: str) -> str:
    # Non-ASCII names would be NFKC-normalised by Python (aliasing), keywords would not parse.
    if _ASCII_IDENT.fullmatch(attr) and not keyword.iskeyword(attr):
        return f"{obj}.{attr}"
    return f"getattr({obj}, {attr!r})"


def to_python(expr: Expr, name: Callable[[str], str], event_field: Callable[[str], str]) -> str:
    """Render as a fully parenthesised Python expression; callbacks render names and fields."""
    match expr:
        case Const():
            return _py_const(expr.value)
        case Name():
            return name(expr.name)
        case EventField():
            return event_field(expr.field)
        case Attr():
            return _py_attr(to_python(expr.obj, name, event_field), expr.name)
        case Unary():
            op = "not " if expr.op == "not" else expr.op
            return f"({op}{to_python(expr.operand, name, event_field)})"
        case Binary():
            left = to_python(expr.left, name, event_field)
            return f"({left} {expr.op} {to_python(expr.right, name, event_field)})"
        case Else():
            return "True"
        case _:
            assert_never(expr)
