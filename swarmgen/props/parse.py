"""The property language's recursive-descent parser, over the expression language's tokens
(`swarmgen.expr.lex`): the same numbers, strings, names and located syntax errors."""

from __future__ import annotations

from collections.abc import Callable
from typing import NoReturn, cast

from swarmgen.expr.errors import ExprError, error_at, show
from swarmgen.expr.lex import Lexer, Tok
from swarmgen.props.tree import (
    Bool,
    Both,
    Comparison,
    Count,
    Datum,
    Formula,
    InState,
    Not,
    Occurs,
    Property,
    Quantifier,
    Scalar,
    Temporal,
)

MAX_TEXT = 2_000  # characters of one property
MAX_DEPTH = 50  # nested parentheses and `not`s
_COMPARISONS = frozenset({"==", "!=", "<", "<=", ">", ">="})
_KEYWORDS = frozenset(
    {"always", "never", "eventually", "leads", "to", "until", "and", "or", "not", "in",
     "count", "some", "every", "true", "false"}
)  # fmt: skip
_PREFIX: dict[str, Temporal] = {"always": "always", "never": "never", "eventually": "eventually"}


class _Parser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.tokens = Lexer(text, statements=False).run()
        self.at = 0
        self.depth = 0

    @property
    def tok(self) -> Tok:
        return self.tokens[self.at]

    def fail(self, offset: int, message: str, hint: str | None = None) -> NoReturn:
        raise error_at(self.text, offset, message, hint)

    def word(self, text: str) -> bool:
        return self.tok.kind == "word" and self.tok.text == text

    def take(self) -> Tok:
        tok = self.tok
        self.at += 1
        return tok

    def expect_word(self, text: str, hint: str | None = None) -> Tok:
        if not self.word(text):
            self.fail(self.tok.offset, f"expected `{text}`, found {_shown(self.tok)}", hint)
        return self.take()

    def expect_op(self, text: str) -> Tok:
        if not (self.tok.kind == "op" and self.tok.text == text):
            self.fail(self.tok.offset, f"expected `{text}`, found {_shown(self.tok)}")
        return self.take()

    def name(self, what: str) -> Tok:
        if self.tok.kind != "word" or self.tok.text in _KEYWORDS:
            self.fail(self.tok.offset, f"expected {what}, found {_shown(self.tok)}")
        return self.take()

    def prop(self) -> Property:
        kind = _PREFIX.get(self.tok.text) if self.tok.kind == "word" else None
        if kind is not None:
            self.take()
            left, right = self.formula(), None
        else:
            left = self.formula()
            if self.word("leads"):
                self.take()
                self.expect_word("to", hint="write `P leads to Q`")
                kind, right = "leads to", self.formula()
            elif self.word("until"):
                self.take()
                kind, right = "until", self.formula()
            else:
                self.fail(
                    self.tok.offset,
                    f"expected `leads to` or `until`, found {_shown(self.tok)}",
                    hint="a property is `always P`, `never P`, `eventually P`, "
                    "`P leads to Q` or `P until Q`",
                )
        if self.tok.kind != "eof":
            self.fail(self.tok.offset, f"unexpected {_shown(self.tok)} after the property")
        return Property(kind, left, right, self.text)

    def formula(self) -> Formula:
        left = self.conjunction()
        while self.word("or"):
            offset = self.take().offset
            left = Both("or", left, self.conjunction(), offset)
        return left

    def conjunction(self) -> Formula:
        left = self.negation()
        while self.word("and"):
            offset = self.take().offset
            left = Both("and", left, self.negation(), offset)
        return left

    def negation(self) -> Formula:
        if self.word("not") or (self.tok.kind == "op" and self.tok.text == "!"):
            offset = self.take().offset
            return Not(self.nested(self.negation), offset)
        return self.atom()

    def nested(self, parse: Callable[[], Formula]) -> Formula:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            self.fail(self.tok.offset, f"the property nests more than {MAX_DEPTH} levels deep")
        found = parse()
        self.depth -= 1
        return found

    def atom(self) -> Formula:
        tok = self.tok
        if tok.kind == "op" and tok.text == "(":
            self.take()
            inner = self.nested(self.formula)
            self.expect_op(")")
            return inner
        if tok.kind != "word":
            self.fail(tok.offset, f"expected a state, count, datum or event, found {_shown(tok)}")
        if tok.text in ("true", "false"):
            self.take()
            return Bool(tok.text == "true", tok.offset)
        if tok.text == "count":
            return self.count()
        quantifier: Quantifier | None = None
        if tok.text in ("some", "every"):
            quantifier = cast("Quantifier", self.take().text)
        name = self.name("a member type or an event")
        if self.word("in"):
            self.take()
            state = self.name("a state name")
            return InState(quantifier or "some", name.text, state.text, tok.offset, state.offset)
        if self.tok.kind == "op" and self.tok.text == ".":
            self.take()
            datum = self.name("a datum name")
            op, value = self.comparison()
            return Datum(
                quantifier or "every", name.text, datum.text, op, value, tok.offset, datum.offset
            )
        if quantifier is not None:
            self.fail(self.tok.offset, f"expected `in` or `.` after '{name.text}'")
        return Occurs(name.text, tok.offset)

    def count(self) -> Count:
        offset = self.take().offset
        self.expect_op("(")
        member = self.name("a member type")
        self.expect_word("in", hint="write `count(TYPE in STATE)`")
        state = self.name("a state name")
        self.expect_op(")")
        op, value = self.comparison()
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(offset, "a count compares with a whole number")
        return Count(member.text, state.text, op, value, offset, state.offset)

    def comparison(self) -> tuple[Comparison, Scalar]:
        tok = self.tok
        if not (tok.kind == "op" and tok.text in _COMPARISONS):
            self.fail(tok.offset, f"expected a comparison (== != < <= > >=), found {_shown(tok)}")
        self.take()
        sign = 1
        if self.tok.kind == "op" and self.tok.text == "-":
            self.take()
            sign = -1
        value = self.tok
        if value.kind == "num" and isinstance(value.value, int | float):
            self.take()
            return cast("Comparison", tok.text), sign * value.value
        if sign == 1 and value.kind == "str" and isinstance(value.value, str):
            self.take()
            return cast("Comparison", tok.text), value.value
        if sign == 1 and value.kind == "word" and value.text in ("true", "false"):
            self.take()
            return cast("Comparison", tok.text), value.text == "true"
        self.fail(value.offset, f"expected a number, string, true or false, found {_shown(value)}")


def _shown(tok: Tok) -> str:
    return "the end of the property" if tok.kind == "eof" else f"`{show(tok.text)}`"


def parse_property(text: str) -> Property:
    """The property `text` as a tree; `ExprError` (located) when it is not one."""
    if len(text) > MAX_TEXT:
        raise error_at(text, MAX_TEXT, f"a property has at most {MAX_TEXT} characters")
    if not text.strip():
        raise error_at(text, 0, "the property is empty")
    return _Parser(text).prop()


__all__ = ["ExprError", "parse_property"]
