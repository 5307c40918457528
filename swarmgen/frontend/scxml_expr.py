"""The ECMAScript subset of SCXML documents, translated into swarmgen's expression language.

What swarmgen's emitter writes (docs/scxml.md) reads back to the expression it came from:
`$sg.field(_event, "f")` and `_event.data.f` are `event.f`, `$sg.div`/`$sg.mod` are `/` and `%`,
`===`/`!==` are `==`/`!=`, `&&`/`||`/`!` are `and`/`or`/`not`. Anything else (calls, `typeof`,
assignment, `_event.name`) is an `ExprUnsupported` for the caller to report where it stands.
The parser is a hand-written precedence climber over a bounded token list: the text is input.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable

from swarmgen import expr
from swarmgen.records import dataclass

MAX_TEXT = expr.MAX_TEXT
_TOKEN = re.compile(
    r"""\s*(?:(?P<num>\d+(?:\.\d*)?(?:[eE][+-]?\d+)?|\.\d+(?:[eE][+-]?\d+)?)"""
    r"""|(?P<str>"(?:[^"\\]|\\.)*"|'(?:[^'\\]|\\.)*')"""
    r"""|(?P<name>[A-Za-z_$][A-Za-z0-9_$]*)"""
    r"""|(?P<op>\+\+|--|===|!==|==|!=|<=|>=|&&|\|\||[-+*/%<>!(),.\[\]{}:]))"""
)
_LEVELS: tuple[dict[str, str], ...] = (  # lowest precedence first: JS operator -> swarmgen's
    {"||": "or"},
    {"&&": "and"},
    {"===": "==", "!==": "!=", "==": "==", "!=": "!="},
    {"<": "<", "<=": "<=", ">": ">", ">=": ">="},
    {"+": "+", "-": "-"},
    {"*": "*", "/": "/", "%": "%"},
)
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_PROCESSOR = "http://www.w3.org/TR/scxml/#SCXMLEventProcessor"
_MARKERS = {"$sg.tick": "tick", "$sg.spin": "spin"}


class ExprUnsupported(Exception):
    """The text is outside the subset; the message says why."""


@dataclass(frozen=True)
class InState:
    """`In('id')`: a state-configuration test, read as a join's sources (never an expression)."""

    state: str


@dataclass(frozen=True)
class Marker:
    """`$sg.tick()` (`$sg.tick(_event)` as older documents write it) or `$sg.spin()`: the step bound's bookkeeping, which the emitter
    writes again from the model (docs/scxml.md), so the reader drops it."""

    name: str


Piece = expr.Expr | InState | Marker


def tokens(text: str) -> list[tuple[str, str]]:
    """(kind, text) of each token; raises ExprUnsupported on anything else."""
    if len(text) > MAX_TEXT:
        raise ExprUnsupported(f"longer than {MAX_TEXT} characters")
    found: list[tuple[str, str]] = []
    at = 0
    while at < len(text):
        if not text[at:].strip():
            break
        match = _TOKEN.match(text, at)
        if match is None or match.end() == at:
            raise ExprUnsupported(f"unexpected character {text[at:].strip()[:1]!r}")
        kind = match.lastgroup or "op"
        if match.group(kind) in ("++", "--"):  # JS's increment, not two signs: an assignment
            raise ExprUnsupported("increment and decrement (++, --) change data: use <assign>")
        found.append((kind, match.group(kind)))
        at = match.end()
    return found


def conjuncts(text: str, name: Callable[[str], str]) -> list[Piece]:
    """The `&&`-separated parts of a cond at its top level, each translated (In() and the
    step bound's markers kept apart)."""
    parts: list[list[tuple[str, str]]] = [[]]
    depth = 0
    for token in tokens(text):
        depth += {"(": 1, "[": 1, ")": -1, "]": -1}.get(token[1], 0) if token[0] == "op" else 0
        if depth == 0 and token == ("op", "&&"):
            parts.append([])
        else:
            parts[-1].append(token)
    if not all(parts):
        raise ExprUnsupported("an operand of && is missing")
    return [_Parser(part, name, allow_markers=True).whole() for part in parts]


def translate(text: str, name: Callable[[str], str]) -> expr.Expr:
    """The swarmgen expression of an ECMAScript expression (`name`: data id -> model name)."""
    found = _Parser(tokens(text), name).whole()
    assert not isinstance(found, InState | Marker)
    return found


def literal(text: str) -> object:
    """A JSON-like value (a `<data expr>` or an event field's default): JSON first (what the
    emitter writes), then a signed literal such as `(-1)`."""
    try:
        return json.loads(text)
    except ValueError:
        pass
    found = translate(text, lambda n: n)
    if isinstance(found, expr.Const):
        return found.value
    if isinstance(found, expr.Unary) and isinstance(found.operand, expr.Const):
        value = found.operand.value
        if isinstance(value, int | float) and not isinstance(value, bool):
            return -value if found.op == "-" else value
    raise ExprUnsupported("not a literal value")


def json_fields(text: str) -> list[tuple[str, str]] | None:
    """(name, value as the language's text) of each member of a JSON object whose names are identifiers and whose
    values are scalars (an event's data sent as `<content>{"f": 1}</content>`: its fields), or
    None when the text is no such object."""
    try:
        found = json.loads(text)
    except ValueError:
        return None
    if not isinstance(found, dict) or not found:
        return None
    fields = []
    for name, value in found.items():
        if not _IDENT.fullmatch(name) or name.startswith("__"):
            return None
        if value is None or not isinstance(value, bool | int | float | str):
            return None
        try:
            fields.append((name, expr.to_text(expr.Const(value=value))))
        except ValueError:  # a value the language cannot hold exactly
            return None
    return fields


class _Parser:
    def __init__(
        self, toks: list[tuple[str, str]], name: Callable[[str], str], allow_markers: bool = False
    ) -> None:
        self.toks, self.at, self.name, self.allow_markers = toks, 0, name, allow_markers
        self.depth = 0

    def whole(self) -> Piece:
        found = self.special() if self.allow_markers else None
        if found is None:
            found = self.level(0)
        if self.at != len(self.toks):
            raise ExprUnsupported(f"unexpected {self.toks[self.at][1]!r}")
        return found

    def peek(self) -> str:
        return self.toks[self.at][1] if self.at < len(self.toks) else ""

    def take(self, wanted: str | None = None) -> tuple[str, str]:
        if self.at >= len(self.toks):
            raise ExprUnsupported("the expression ends too early")
        token = self.toks[self.at]
        if wanted is not None and token[1] != wanted:
            raise ExprUnsupported(f"expected {wanted!r}, found {token[1]!r}")
        self.at += 1
        return token

    def special(self) -> Piece | None:
        """`In('s')`, `$sg.tick()` (or `$sg.tick(_event)`), `$sg.spin()` as a whole conjunct."""
        texts = [t[1] for t in self.toks]
        is_in = texts[:2] == ["In", "("] and texts[3:] == [")"] and len(texts) == 4
        if is_in and self.toks[2][0] == "str":
            self.at = 4
            return InState(_string(self.toks[2][1]))
        joined = "".join(texts)
        for text, marker in _MARKERS.items():
            if joined in (f"{text}(_event)", f"{text}()"):
                self.at = len(self.toks)
                return Marker(marker)
        return None

    def level(self, index: int) -> expr.Expr:
        if index == len(_LEVELS):
            return self.unary()
        self.depth += 1
        if self.depth > expr.MAX_DEPTH:
            raise ExprUnsupported(f"nested deeper than {expr.MAX_DEPTH} levels")
        left = self.level(index + 1)
        ops = _LEVELS[index]
        while self.peek() in ops and self.toks[self.at][0] == "op":
            op = ops[self.take()[1]]
            right = self.level(index + 1)
            left = expr.Binary(op=op, left=left, right=right)
            if index in (2, 3) and self.peek() in ops:
                raise ExprUnsupported("comparisons do not chain in swarmgen's language")
        self.depth -= 1
        return left

    def unary(self) -> expr.Expr:
        if self.peek() in ("!", "-", "+") and self.toks[self.at][0] == "op":
            op = {"!": "not"}.get(self.take()[1], self.toks[self.at - 1][1])
            self.depth += 1
            if self.depth > expr.MAX_DEPTH:
                raise ExprUnsupported(f"nested deeper than {expr.MAX_DEPTH} levels")
            operand = self.unary()
            self.depth -= 1
            return expr.Unary(op=op, operand=operand)
        return self.postfix(self.primary())

    def primary(self) -> expr.Expr:
        kind, text = self.take()
        if kind == "num":
            number = float(text) if any(c in text for c in ".eE") else int(text)
            return expr.Const(value=number)
        if kind == "str":
            return expr.Const(value=_string(text))
        if text == "(":
            inner = self.level(0)
            self.take(")")
            return inner
        if text == "[":  # an array literal: swarmgen's sequence
            items: list[expr.Expr] = []
            while self.peek() != "]":
                items.append(self.level(0))
                if self.peek() != ",":
                    break
                self.take(",")
            self.take("]")
            return expr.ListOf(items=tuple(items))
        if kind == "name":
            return self.named(text)
        raise ExprUnsupported(f"unexpected {text!r}")

    def named(self, text: str) -> expr.Expr:
        constants: dict[str, expr.Value] = {"true": True, "false": False, "null": None}
        if text in constants:
            return expr.Const(value=constants[text])
        if text == "$sg":
            return self.support_call()
        if text == "_event":
            return self.event_field()
        if text in ("_sessionid", "_name", "_ioprocessors"):
            return self.postfix(expr.System(name=text))
        if text == "In" and self.peek() == "(":  # In('S') inside an expression
            self.take("(")
            kind, state = self.take()
            self.take(")")
            if kind != "str":
                raise ExprUnsupported("In() needs a state id in quotes")
            return expr.InState(state=_string(state))
        if text in ("In", "typeof", "new", "function", "this", "undefined"):
            raise ExprUnsupported(f"{text} is not in the subset")
        if self.peek() == "(":
            raise ExprUnsupported(f"calls ({text}(...)) are not in the subset")
        return expr.Name(name=self.name(text))

    def support_call(self) -> expr.Expr:
        self.take(".")
        function = self.take()[1]
        self.take("(")
        if function == "field":
            self.take("_event")
            self.take(",")
            kind, text = self.take()
            self.take(")")
            if kind != "str":
                raise ExprUnsupported("$sg.field needs a field name in quotes")
            return expr.EventField(field=_string(text))
        if function in ("div", "mod"):
            left = self.level(0)
            self.take(",")
            right = self.level(0)
            self.take(")")
            op = "/" if function == "div" else "%"
            return expr.Binary(op=op, left=left, right=right)
        if function == "meta":  # `_event.<field>` as the emitter writes it
            self.take("_event")
            self.take(",")
            kind, text = self.take()
            self.take(")")
            field = _string(text) if kind == "str" else ""
            if field not in expr.EVENT_META:
                raise ExprUnsupported("$sg.meta needs a field of _event in quotes")
            return self.postfix(expr.Attr(obj=expr.System(name="_event"), name=field))
        if function == "startswith":  # `startswith(t, p)` as emitted
            whole = self.level(0)
            self.take(",")
            prefix = self.level(0)
            self.take(")")
            return expr.StartsWith(text=whole, prefix=prefix)
        if function == "invalid":  # `invalid("x")`, a location that is none, as emitted
            kind, text = self.take()
            self.take(")")
            if kind != "str":
                raise ExprUnsupported("$sg.invalid needs a location in quotes")
            return expr.Invalid(location=_string(text))
        raise ExprUnsupported(f"$sg.{function} is only read where the emitter writes it")

    def event_field(self) -> expr.Expr:
        self.take(".")
        field = self.take()[1]
        if field != "data" and field in expr.EVENT_META:  # _event.name, .type, ...
            return self.postfix(expr.Attr(obj=expr.System(name="_event"), name=field))
        if field != "data":
            raise ExprUnsupported(f"_event has no field {field!r}")
        if self.peek() not in (".", "["):
            return self.postfix(expr.Attr(obj=expr.System(name="_event"), name="data"))
        return self.member(expr.EventField(field="_"), first=True)

    def member(self, obj: expr.Expr, first: bool = False) -> expr.Expr:
        if self.peek() == ".":
            self.take(".")
            kind, field = self.take()
            if kind != "name":
                raise ExprUnsupported("a member name must follow '.'")
        elif self.peek() == "[":
            self.take("[")
            kind, field = self.take()
            self.take("]")
            if kind != "str":
                raise ExprUnsupported('only constant member names (["f"]) are supported')
            field = _string(field)
        else:
            raise ExprUnsupported("_event.data is only read field by field")
        if obj == expr.System(name="_ioprocessors") and field in (_PROCESSOR, "scxml"):
            field = "scxml"  # the SCXML event processor, by its URI or its short name
        if not _IDENT.fullmatch(field):
            raise ExprUnsupported(f"member name {field!r} is not an identifier")
        if first:
            return self.postfix(expr.EventField(field=field))
        return expr.Attr(obj=obj, name=field)

    def postfix(self, found: expr.Expr) -> expr.Expr:
        while self.peek() in (".", "["):
            if self.toks[self.at + 1 : self.at + 3] == [("name", "startsWith"), ("op", "(")]:
                found = self.starts_with(found)  # ECMAScript's String.prototype.startsWith
                continue
            found = self.member(found)
        if self.peek() == "(":
            raise ExprUnsupported("calls are not in the subset")
        return found

    def starts_with(self, text: expr.Expr) -> expr.Expr:
        """`t.startsWith(p)` (one argument): swarmgen's `startswith(t, p)`, both strings."""
        self.take(".")
        self.take("startsWith")
        self.take("(")
        prefix = self.level(0)
        self.take(")")
        return expr.StartsWith(text=text, prefix=prefix)


def _string(text: str) -> str:
    body = text[1:-1]
    if text[0] == "'":
        body = body.replace("\\'", "'").replace('"', '\\"')
    try:
        value = json.loads(f'"{body}"')
    except ValueError as err:
        raise ExprUnsupported(f"bad string literal {text}") from err
    assert isinstance(value, str)
    return value
