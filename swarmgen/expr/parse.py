"""The expression language's precedence-climbing parser: guards, actions and bindings."""

from __future__ import annotations

from collections.abc import Callable
from typing import NoReturn

from swarmgen.expr.errors import error_at, escape_char, show
from swarmgen.expr.lex import Lexer, Tok
from swarmgen.expr.render import to_text
from swarmgen.expr.tree import (
    COMPARISONS,
    EVENT_META,
    MAX_DEPTH,
    MAX_TEXT,
    NOT_PREC,
    PREC,
    RESERVED,
    SYSTEM_VARIABLES,
    UNARY_PREC,
    Attr,
    Binary,
    Binding,
    BinOp,
    Const,
    Else,
    EventField,
    Expr,
    InState,
    Invalid,
    ListOf,
    Name,
    StartsWith,
    System,
    Unary,
    UnOp,
    Value,
)

_BINOPS: dict[str, BinOp] = {
    "or": "or", "||": "or", "and": "and", "&&": "and",
    "==": "==", "!=": "!=", "<": "<", "<=": "<=", ">": ">", ">=": ">=",
    "+": "+", "-": "-", "*": "*", "/": "/", "%": "%",
}  # fmt: skip
_UNOPS: dict[str, UnOp] = {"not": "not", "!": "not", "-": "-", "+": "+"}
_CONSTANTS: dict[str, Value] = {
    "true": True, "True": True, "false": False, "False": False, "null": None, "None": None,
}  # fmt: skip
_COMPOUND = frozenset({"+=", "-=", "*=", "/=", "%="})
# Operators borrowed from Java/C/ECMAScript that get a message of their own.
_EXPLAINED = _COMPOUND | {"++", "--", "===", "!==", "**", "//"}
_NOT_BINDING = "a binding must be `name = expression`"

# A parsed expression together with its depth: the depth limit keeps the recursive renderers
# (and pydantic's own recursion) far from Python's recursion limit.
_Node = tuple[Expr, int]


def _binop(tok: Tok) -> BinOp | None:
    return _BINOPS.get(tok.text) if tok.kind in ("word", "op") else None


def _unop(tok: Tok) -> UnOp | None:
    return _UNOPS.get(tok.text) if tok.kind in ("word", "op") else None


def _show_tok(tok: Tok) -> str:
    if tok.kind == "eof":
        return "end of text"
    return "end of line" if tok.kind == "nl" else show(tok.text)


def _is_path(e: Expr) -> bool:
    return isinstance(e, Name | EventField | Attr)


class _Parser:
    def __init__(self, text: str, statements: bool) -> None:
        if len(text) > MAX_TEXT:
            raise error_at(
                text,
                MAX_TEXT,
                f"text is too long ({len(text)} characters; the limit is {MAX_TEXT})",
            )
        self.text = text
        self.statements = statements
        self.toks = Lexer(text, statements).run()
        self.last = len(self.toks) - 1  # the eof token: peeking past it stays on it
        self.pos = 0
        self.nest = 0

    # token access

    def peek(self, ahead: int = 0) -> Tok:
        at = self.pos + ahead
        return self.toks[at] if at < self.last else self.toks[-1]

    def advance(self) -> Tok:
        tok = self.toks[self.pos]
        if tok.kind != "eof":
            self.pos += 1
        return tok

    def prev(self) -> Tok | None:
        return self.toks[self.pos - 1] if self.pos else None

    @staticmethod
    def is_op(text: str, tok: Tok) -> bool:
        return tok.kind == "op" and tok.text == text

    def at_end_of_statement(self) -> bool:
        tok = self.peek()
        return tok.kind in ("nl", "eof") or self.is_op(";", tok)

    def fail(self, tok: Tok, message: str, hint: str | None = None) -> NoReturn:
        raise error_at(self.text, tok.offset, message, hint)

    # depth bookkeeping

    def deeper(self, node: Expr, depth: int, tok: Tok) -> _Node:
        if depth + 1 > MAX_DEPTH:
            self.too_deep(tok)
        return node, depth + 1

    def enter(self, tok: Tok) -> None:
        self.nest += 1
        if self.nest > MAX_DEPTH:
            self.too_deep(tok)

    def too_deep(self, tok: Tok) -> NoReturn:
        self.fail(tok, f"expression is nested too deeply (more than {MAX_DEPTH} levels)")

    # expressions

    def expr(self, min_prec: int = 0) -> _Node:
        left = self.prefix(min_prec)
        while (op := _binop(self.peek())) is not None and PREC[op] >= min_prec:
            tok = self.advance()
            right = self.expr(PREC[op] + 1)
            node = Binary(op=op, left=left[0], right=right[0])
            left = self.deeper(node, max(left[1], right[1]), tok)
            if op in COMPARISONS:
                self.no_chain(node)
        return left

    def no_chain(self, first: Binary) -> None:
        tok = self.peek()
        op = _binop(tok)
        if op not in COMPARISONS:
            return
        self.advance()
        third, _ = self.expr(PREC[op] + 1)  # only to quote it in the message
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
        if op == "not" and min_prec > NOT_PREC:
            self.fail(tok, f"{show(tok.text)} needs parentheses here", hint="write `a == (not b)`")
        self.advance()
        if op == "-" and self.peek().kind == "num":
            # Fold `-<number>` into a negative literal (to_text writes `-(1)` for the unary form).
            num = self.advance()
            assert isinstance(num.value, int | float)
            return Const(value=-num.value), 1
        self.enter(tok)
        operand = self.expr(NOT_PREC) if op == "not" else self.prefix(UNARY_PREC)
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
        if self.is_op("[", tok) and _is_path(node[0]):
            self.fail(tok, "indexing is not part of the expression language")
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
        if self.is_op("[", tok):
            return self.list_of()
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
        if tok.text in SYSTEM_VARIABLES:
            return self.system(tok)
        if tok.text == "In" and self.is_op("(", self.peek()):
            return self.in_state()
        if tok.text == "invalid" and self.is_op("(", self.peek()):
            return self.invalid()
        if tok.text == "startswith" and self.is_op("(", self.peek()):
            return self.starts_with()
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

    def in_state(self) -> _Node:
        """`In("S")`: a state's name (or chart id) in quotes."""
        opening = self.advance()
        name = self.peek()
        if name.kind != "str" or not isinstance(name.value, str):
            self.fail(name, 'In() takes a state name in quotes: In("Searching")')
        self.advance()
        self.close(opening)
        try:
            return InState(state=name.value), 1
        except ValueError as err:
            self.fail(name, str(err).splitlines()[-1])

    def invalid(self) -> _Node:
        """`invalid("foo.bar")`: a location that is none, error.execution when it runs."""
        opening = self.advance()
        text = self.peek()
        if text.kind != "str" or not isinstance(text.value, str):
            self.fail(text, 'invalid() takes the location as written, in quotes: invalid("x")')
        self.advance()
        self.close(opening)
        try:
            return Invalid(location=text.value), 1
        except ValueError as err:
            self.fail(text, str(err).splitlines()[-1])

    def starts_with(self) -> _Node:
        """`startswith(text, prefix)`: whether the string text begins with the string prefix."""
        opening = self.advance()
        self.enter(opening)
        text, text_depth = self.expr(0)
        comma = self.peek()
        if not self.is_op(",", comma):
            self.fail(comma, "startswith() takes two strings: startswith(text, prefix)")
        self.advance()
        prefix, prefix_depth = self.expr(0)
        self.close(opening)
        self.nest -= 1
        return StartsWith(text=text, prefix=prefix), max(text_depth, prefix_depth) + 1

    def system(self, tok: Tok) -> _Node:
        """A system variable; `_event` only through one of its fields."""
        variable = System(name=tok.text)  # one of SYSTEM_VARIABLES
        if tok.text == "_ioprocessors" and self.is_op(".", self.peek()):
            return self.processor(variable)
        if tok.text != "_event":
            return variable, 1
        if not self.is_op(".", self.peek()):
            self.fail(tok, "`_event` needs a field: _event.name, _event.type, ...")
        self.advance()
        field = self.peek()
        if field.kind != "word" or field.text not in EVENT_META:
            known = ", ".join(sorted(EVENT_META))
            self.fail(field, f"`_event` has the fields {known}")
        self.advance()
        return Attr(obj=variable, name=field.text), 2

    def processor(self, variable: System) -> _Node:
        """`_ioprocessors.scxml.location`: the SCXML event processor's address (this session's
        `#_scxml_<sessionid>`, W3C 5.10; the only processor, so the only path)."""
        for expected in ("scxml", "location"):
            self.advance()  # the '.'
            word = self.peek()
            if word.kind != "word" or word.text != expected:
                self.fail(word, "`_ioprocessors` is read as _ioprocessors.scxml.location")
            self.advance()
            if expected == "scxml" and not self.is_op(".", self.peek()):
                self.fail(self.peek(), "`_ioprocessors` is read as _ioprocessors.scxml.location")
        return Attr(obj=Attr(obj=variable, name="scxml"), name="location"), 3

    def list_of(self) -> _Node:
        """`[a, b, ...]`: a sequence literal."""
        opening = self.advance()
        self.enter(opening)
        items: list[Expr] = []
        depth = 1
        while not self.is_op("]", self.peek()):
            item, item_depth = self.expr(0)
            items.append(item)
            depth = max(depth, item_depth + 1)
            if not self.is_op(",", self.peek()):
                break
            self.advance()
        tok = self.peek()
        if not self.is_op("]", tok):
            if tok.kind in ("nl", "eof") or self.is_op(";", tok):
                self.fail(tok, "missing ']'")
            self.unexpected(tok)
        self.advance()
        self.nest -= 1
        return ListOf(items=tuple(items)), depth

    def group(self) -> _Node:
        opening = self.advance()
        self.enter(opening)
        inner = self.expr(0)
        self.close(opening)
        self.nest -= 1
        return inner

    def close(self, opening: Tok) -> None:
        tok = self.peek()
        if self.is_op(")", tok):
            self.advance()
            return
        if tok.kind in ("nl", "eof") or self.is_op(";", tok):
            where = error_at(self.text, opening.offset, "")
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

    def expected_expression(self, tok: Tok) -> NoReturn:
        if tok.kind == "op" and tok.text in _EXPLAINED:
            self.unexpected(tok)
        prev = self.prev()
        if prev is not None and prev.kind != "nl" and not self.is_op(";", prev):
            self.fail(tok, f"expected an expression after {_show_tok(prev)}")
        if tok.kind in ("eof", "nl") or self.is_op(";", tok):
            self.fail(tok, "expected an expression")
        self.fail(tok, f"unexpected token {_show_tok(tok)}")

    def unexpected(self, tok: Tok) -> NoReturn:
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

    def else_misplaced(self, tok: Tok) -> NoReturn:
        self.fail(tok, "`else` is only allowed as a whole guard", hint="write `not (...)`")

    def subject(self) -> str:
        """The name an increment-like operator applies to, for quoting it in the message."""
        for tok in (self.prev(), self.peek(1)):
            if tok is not None and tok.kind == "word" and tok.text not in RESERVED:
                return tok.text
        return "x"

    def unexpected_hint(self, tok: Tok) -> str | None:
        if self.is_op(";", tok) and not self.statements:
            return "a guard is a single expression"
        if self.is_op(")", tok):
            return "unbalanced parentheses"
        prev = self.prev()
        if prev is not None and prev.kind in ("word", "num", "str") and tok.kind != "op":
            return f"is an operator missing between {show(prev.text)} and {show(tok.text)}?"
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

    def assignment(self, what: str) -> tuple[str | Invalid, Expr]:
        start = self.peek()
        if start.text in SYSTEM_VARIABLES and self.is_op("=", self.peek(1)):
            self.advance()  # read-only (`_event` too): error.execution when it runs (W3C)
            self.advance()
            return start.text, self.expr(0)[0]
        lhs, _ = self.expr(0)
        tok = self.peek()
        if not self.is_op("=", tok):
            if self.at_end_of_statement():
                self.fail(start, what, hint=_assign_hint(lhs))
            self.unexpected(tok)
        if not isinstance(lhs, Name | Invalid):
            self.fail(start, f"can only assign to member data names, not `{_clip(to_text(lhs))}`")
        self.advance()
        value, _ = self.expr(0)
        return lhs.name if isinstance(lhs, Name) else lhs, value


def _assign_hint(lhs: Expr) -> str | None:
    if isinstance(lhs, Binary) and lhs.op == "==" and isinstance(lhs.left, Name):
        right = _clip(to_text(lhs.right))
        return f"did you mean `{lhs.left.name} = {right}`? `==` compares, `=` assigns"
    return None


def _clip(text: str, limit: int = 40) -> str:
    text = "".join(c if c.isprintable() else escape_char(c) for c in text)
    return text if len(text) <= limit else text[: limit - 1] + "…"


# --- public parse functions


def parse_expr(text: str) -> Expr:
    """Parse a guard or any other single expression; raises ExprError."""
    if text.strip() == "else" and len(text) <= MAX_TEXT:
        return Else()
    parser = _Parser(text, statements=False)
    node, _ = parser.expr(0)
    parser.expect_end()
    if isinstance(node, ListOf) and len(node.items) == 1:  # `[x > 1]`: a guard in UML's brackets
        raise error_at(
            text,
            0,
            "a guard is not a list",
            "UML shows guards in brackets; write the guard without `[ ]`",
        )
    return node


def parse_bindings(text: str) -> tuple[Binding, ...]:
    """Parse behaviour argument bindings: one `name = expression` per line (or `;`)."""
    parser = _Parser(text, statements=True)
    bindings: list[Binding] = []

    def one() -> None:
        start = parser.peek()
        name, value = parser.assignment(_NOT_BINDING)
        if isinstance(name, Invalid):
            parser.fail(start, "a binding names a behaviour argument, not an invalid location")
        if any(b.name == name for b in bindings):
            parser.fail(start, f"duplicate binding '{name}'")
        bindings.append(Binding(name=name, value=value))

    parser.statements_of(one)
    return tuple(bindings)
