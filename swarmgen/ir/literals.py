"""UML ValueSpecifications as values: literals read in XML Schema's lexical forms, checked
against what every target holds exactly and against the property's primitive type.

A literal that is not a value of its kind (`LiteralInteger "abc"`, `LiteralReal "nan"`) is a
`BadLiteral`, which `ir.build` reports (SG122) instead of emitting a string or garbage.
"""

from __future__ import annotations

import math
import re

from swarmgen.frontend.raw import RawElement
from swarmgen.ir.nodes import Value
from swarmgen.ir.primitives import Primitive, primitive
from swarmgen.records import dataclass

MAX_SAFE_INTEGER = 2**53 - 1  # ECMAScript holds no larger integer exactly


@dataclass(frozen=True)
class BadLiteral:
    """A ValueSpecification whose text is not a value of its kind (`LiteralInteger "abc"`)."""

    problem: str  # completes "default value 'abc' of 'x' ..."
    hint: str


# XML Schema's lexical forms, ASCII only: Python's int() and float() also take `1_000`, `٣`,
# `nan` and `infinity`, which no other target reads the same way.
INTEGER_TEXT = re.compile(r"[+-]?[0-9]+")
_REAL_TEXT = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_BOOLEAN_TEXT = {"true": True, "false": False, "1": True, "0": False}
_INTEGER_HINT = f"write a decimal integer between -{MAX_SAFE_INTEGER} and {MAX_SAFE_INTEGER}"
_REAL_HINT = "write a finite decimal number such as 2.5 or 1e3"


def literal_text(spec: RawElement) -> str:
    """The lexical text of a ValueSpecification (its `value`, else its `symbol`)."""
    return spec.attrs.get("value", spec.attrs.get("symbol", ""))


def literal_value(spec: RawElement) -> Value | BadLiteral:
    """The value of a UML ValueSpecification (EMF omits defaults: a bare LiteralInteger is 0)."""
    raw = spec.attrs.get("value")
    kind = spec.uml_type
    if kind == "LiteralNull":
        return None
    if kind == "LiteralBoolean":
        text = (raw or "false").strip().lower()
        if text in _BOOLEAN_TEXT:
            return _BOOLEAN_TEXT[text]
        return BadLiteral("is not a Boolean", "write true or false")
    if kind == "LiteralUnlimitedNatural" and (raw or "").strip() == "*":
        return BadLiteral("is unlimited (*), not a number", _INTEGER_HINT)
    if kind in {"LiteralInteger", "LiteralUnlimitedNatural"}:
        return _integer(raw or "0")
    if kind == "LiteralReal":
        return _real(raw or "0")
    if kind == "Expression" and "symbol" in spec.attrs:  # how Modelio writes reals and the rest
        text = spec.attrs["symbol"].strip()
        if INTEGER_TEXT.fullmatch(text):
            return _integer(text)
        return _real(text) if _REAL_TEXT.fullmatch(text) else spec.attrs["symbol"]
    if kind == "OpaqueExpression":
        return "\n".join(b.text for b in spec.kids("body"))
    return raw if raw is not None else spec.name if kind != "LiteralString" else ""


def _integer(text: str) -> int | BadLiteral:
    text = text.strip()
    if not INTEGER_TEXT.fullmatch(text):
        return BadLiteral("is not a decimal integer", _INTEGER_HINT)
    if len(text.lstrip("+-").lstrip("0")) > 16:  # beyond 2**53, before int() meets 10**5000
        return BadLiteral("cannot be represented exactly in the generated code", _INTEGER_HINT)
    return int(text)


def _real(text: str) -> float | BadLiteral:
    text = text.strip()
    if not _REAL_TEXT.fullmatch(text):
        return BadLiteral("is not a decimal number", _REAL_HINT)
    value = float(text)
    if not math.isfinite(value):
        return BadLiteral("is out of range: it would be infinite", _REAL_HINT)
    return value


# what a default of each primitive type may be (a String default is any text)
_TYPE_OF_VALUE: dict[Primitive, tuple[type, ...]] = {
    Primitive.INTEGER: (int,),
    Primitive.REAL: (int, float),
    Primitive.BOOLEAN: (bool,),
}


def unrepresentable(value: Value, type_name: str | None) -> BadLiteral | None:
    """Numbers every target holds exactly (ECMAScript has no integers beyond 2**53), of the
    property's primitive type when it has one."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > MAX_SAFE_INTEGER:
        return BadLiteral("cannot be represented exactly in the generated code", _INTEGER_HINT)
    kind_of = primitive(type_name)
    wanted = None if kind_of is None else _TYPE_OF_VALUE.get(kind_of)
    if value is None or wanted is None:
        return None
    if isinstance(value, bool) != (bool in wanted) or not isinstance(value, wanted):
        kind = _KIND_NAMES.get(type(value), "text")
        return BadLiteral(
            f"is {kind}, not a value of its type {type_name}", "give a default of the declared type"
        )
    return None


_KIND_NAMES = {bool: "a Boolean", int: "an integer", float: "a real number"}
