"""Renderings of expressions: canonical model text, SCXML ECMAScript, and Python."""

from __future__ import annotations

import json
import keyword
import re
from collections.abc import Callable
from typing import assert_never

from swarmgen.expr.errors import escape_char
from swarmgen.expr.tree import (
    ATOM_PREC,
    COMPARISONS,
    NOT_PREC,
    PREC,
    UNARY_PREC,
    Attr,
    Binary,
    Const,
    Else,
    EventField,
    Expr,
    InState,
    Invalid,
    ListOf,
    Name,
    Raise,
    Send,
    StartsWith,
    System,
    Unary,
    Value,
)

_EVENT = System(name="_event")
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
            _TEXT_ESCAPES.get(c) or (c if c.isprintable() else escape_char(c)) for c in value
        )
        return f'"{body}"'
    return _number_text(value)


def _text_prec(e: Expr) -> int:
    if isinstance(e, Binary):
        return PREC[e.op]
    if isinstance(e, Unary):
        return NOT_PREC if e.op == "not" else UNARY_PREC
    if _is_number(e) and to_text(e).startswith("-"):
        return UNARY_PREC
    return ATOM_PREC


def _paren(text: str, needed: bool) -> str:
    return f"({text})" if needed else text


def _unary_text(u: Unary) -> str:
    inner = to_text(u.operand)
    if u.op == "not":
        return "not " + _paren(inner, _text_prec(u.operand) < NOT_PREC)
    if u.op == "-" and _is_number(u.operand) and not inner.startswith("-"):
        return f"-({inner})"  # `-1` would parse back as the literal -1
    if _text_prec(u.operand) < UNARY_PREC:
        return f"{u.op}({inner})"
    return u.op + (" " if inner[0] in "+-" else "") + inner  # `--x` would lex as `--`


def _binary_text(b: Binary) -> str:
    prec = PREC[b.op]
    left, right = _text_prec(b.left), _text_prec(b.right)
    # Comparisons do not associate, so an equal-precedence left operand needs parentheses too.
    left_paren = left < prec or (b.op in COMPARISONS and left == prec)
    return f"{_paren(to_text(b.left), left_paren)} {b.op} {_paren(to_text(b.right), right <= prec)}"


def to_text(expr: Expr) -> str:
    """Canonical model-language text: ``parse_expr(to_text(e)) == e``."""
    match expr:
        case Const(enum=str()):
            return f"{expr.enum}.{expr.value}"
        case Const():
            return _const_text(expr.value)
        case Name():
            return expr.name
        case EventField():
            return f"event.{expr.field}"
        case System():
            return expr.name
        case InState():
            return f"In({_const_text(expr.state)})"
        case Invalid():
            return f"invalid({_const_text(expr.location)})"
        case ListOf():
            return "[" + ", ".join(to_text(i) for i in expr.items) + "]"
        case Attr():
            return f"{to_text(expr.obj)}.{expr.name}"
        case Unary():
            return _unary_text(expr)
        case Binary():
            return _binary_text(expr)
        case StartsWith():
            return f"startswith({to_text(expr.text)}, {to_text(expr.prefix)})"
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


def event_text(action: Raise | Send) -> str:
    """The event of a `raise`/`send` as written: its name, or `(expr)` when computed."""
    if isinstance(action, Raise) and action.named is not None:
        return f"({to_text(action.named)})"
    return str(action.event)


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
        case System():
            return expr.name  # the SCXML datamodel's own system variables
        case InState():
            return f"In({_js_string(expr.state)})"
        case Invalid():  # throws: Qt SCXML raises error.execution
            return f"$sg.invalid({_js_string(expr.location)})"
        case ListOf():
            return "[" + ", ".join(to_ecmascript(i, name) for i in expr.items) + "]"
        case Attr() if expr.obj == _EVENT:
            # W3C's fields as swarmgen gives them: "" where Qt leaves one undefined, `{}` for
            # no data (the support script's `$sg.meta`, docs/semantics.md)
            return f"$sg.meta(_event, {_js_string(expr.name)})"
        case Attr():
            return to_ecmascript(expr.obj, name) + _js_member(expr.name)
        case Unary():
            op = "!" if expr.op == "not" else expr.op
            return f"({op}{to_ecmascript(expr.operand, name)})"
        case Binary():
            return _js_binary(expr, name)
        case StartsWith():  # `$sg.startswith`: both strings, else it throws (error.execution)
            text, prefix = to_ecmascript(expr.text, name), to_ecmascript(expr.prefix, name)
            return f"$sg.startswith({text}, {prefix})"
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
        case System():
            return f"ctx.system({expr.name!r})"
        case InState():
            return f"ctx.is_active({expr.state!r})"
        case Invalid():  # raises: error.execution
            return f"ctx.invalid({expr.location!r})"
        case ListOf():
            return "[" + ", ".join(to_python(i, name, event_field) for i in expr.items) + "]"
        case Attr():
            return _py_attr(to_python(expr.obj, name, event_field), expr.name)
        case Unary():
            op = "not " if expr.op == "not" else expr.op
            return f"({op}{to_python(expr.operand, name, event_field)})"
        case Binary():
            left = to_python(expr.left, name, event_field)
            return f"({left} {expr.op} {to_python(expr.right, name, event_field)})"
        case StartsWith():  # both strings, else it raises (error.execution)
            text = to_python(expr.text, name, event_field)
            return f"ctx.startswith({text}, {to_python(expr.prefix, name, event_field)})"
        case Else():
            return "True"
        case _:
            assert_never(expr)
