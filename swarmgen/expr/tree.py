"""The expression language's tree: limits, operator precedence, nodes, and queries over them."""

import math
import re
from collections.abc import Iterable, Iterator
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, field_validator

from swarmgen import fastnode

MAX_TEXT = 10_000
MAX_DEPTH = 100
# ECMAScript numbers are doubles: larger integers would silently change value in the SCXML.
MAX_INT = 2**53 - 1

# W3C SCXML's system variables, read-only (docs/semantics.md, "System variables")
SYSTEM_VARIABLES = frozenset({"_event", "_sessionid", "_name", "_ioprocessors"})
# the fields of `_event` (W3C 5.10.1); `_event.data.f` is `event.f`
EVENT_META = frozenset({"name", "type", "sendid", "origin", "origintype", "invokeid", "data"})
RESERVED = frozenset(
    {"and", "or", "not", "true", "false", "True", "False", "null", "None", "else", "event"}
    | SYSTEM_VARIABLES
)

BinOp = Literal["or", "and", "==", "!=", "<", "<=", ">", ">=", "+", "-", "*", "/", "%"]
UnOp = Literal["not", "-", "+"]
Value = bool | int | float | str | None

# --- operator precedence (the parser's and the canonical text's)

PREC: dict[BinOp, int] = {
    "or": 1, "and": 2,
    "==": 4, "!=": 4, "<": 4, "<=": 4, ">": 4, ">=": 4,
    "+": 5, "-": 5, "*": 6, "/": 6, "%": 6,
}  # fmt: skip
NOT_PREC = 3  # prefix `not` sits between `and` and the comparisons, as in Python
UNARY_PREC = 7
ATOM_PREC = 9
COMPARISONS = frozenset({"==", "!=", "<", "<=", ">", ">="})


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

# An event's name in `raise`/`send`: a name, or W3C's dotted tokens (`foo.bar`, `In-s11p112`:
# letters, digits, `_` and `-`), read as one by the statement parser (`statements`)
EVENT_NAME = re.compile(r"(?!__)[^\W\d][\w-]*(?:\.[\w-]+)*")


def _event_name(value: str) -> str:
    if EVENT_NAME.fullmatch(value) is None:
        raise ValueError(f"{value!r} is not an event name")
    return value


EventName = Annotated[str, AfterValidator(_event_name)]
DataName = Annotated[str, AfterValidator(_data_name)]


def _check_value(value: Value) -> Value:
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError("numbers must be finite")
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > MAX_INT:
        raise ValueError(f"integers must lie within ±{MAX_INT}")
    if isinstance(value, str) and any(0xD800 <= ord(c) <= 0xDFFF for c in value):
        raise ValueError("strings must not contain lone surrogates")
    return value


def _not_else(value: "Expr") -> "Expr":
    if isinstance(value, Else):
        raise ValueError("`else` can only be a whole guard")
    return value


def _path(value: "Expr") -> "Expr":
    if not isinstance(value, Name | EventField | Attr | System):
        raise ValueError("attribute access needs a name on the left")
    return value


class _Model(BaseModel):
    # validators built on first need: most nodes never need them (`swarmgen.fastnode`)
    model_config = ConfigDict(frozen=True, extra="forbid", defer_build=True)

    def __init__(self, /, **data: Any) -> None:
        """The node of `data`: as given when validation would keep it so, else validated."""
        if not fastnode.fill(self, data):
            super().__init__(**data)


class Const(_Model):
    """A literal: boolean, integer, float, string or null; `Mode.search` is the string
    `search` with `enum` set to `Mode` (an enumeration literal, resolved by `ir.build`)."""

    kind: Literal["literal"] = "literal"
    value: Value
    enum: Ident | None = None

    @field_validator("value")
    @classmethod
    def check_value(cls, value: Value) -> Value:
        """Refuse literal values some target cannot hold exactly."""
        return _check_value(value)


class Name(_Model):
    """A member data name."""

    kind: Literal["name"] = "name"
    name: DataName


class EventField(_Model):
    """``event.<field>``: a field of the event that triggered the transition."""

    kind: Literal["event_field"] = "event_field"
    field: Ident


class System(_Model):
    """A system variable: `_event` (read through its fields: `_event.name`), `_sessionid`,
    `_name`, `_ioprocessors` (W3C 5.10); read-only."""

    kind: Literal["system"] = "system"
    name: Literal["_event", "_sessionid", "_name", "_ioprocessors"]


def _state_name(value: str) -> str:
    if not value or not value.isprintable() or len(value) > 200:
        raise ValueError("a state name is 1 to 200 printable characters")
    return value


class InState(_Model):
    """``In("S")``: whether the state named S (or of chart id S) is active (W3C's `In()`)."""

    kind: Literal["in"] = "in"
    state: Annotated[str, AfterValidator(_state_name)]


def _location_text(value: str) -> str:
    if not value or not value.isprintable() or len(value) > 200:
        raise ValueError("a location is 1 to 200 printable characters")
    return value


class Invalid(_Model):
    """``invalid("foo.bar")``: a location the document never declares, or text that is no
    location (an SCXML document's reference, kept as written): reading it, or assigning it,
    fails when it runs, W3C's error.execution (5.4, 5.9, 6.4), as the SCXML reader reads a
    document whose data the datamodel checks only then (docs/scxml-input.md)."""

    kind: Literal["invalid"] = "invalid"
    location: Annotated[str, AfterValidator(_location_text)]


class Attr(_Model):
    """``obj.name`` where obj is a name, an event field or another attribute access."""

    kind: Literal["attr"] = "attr"
    obj: Annotated["Expr", AfterValidator(_path)]
    name: Ident


class ListOf(_Model):
    """``[a, b, ...]``: a sequence of the items' values (what `for` iterates, W3C's arrays)."""

    kind: Literal["list"] = "list"
    items: tuple["Operand", ...] = ()


class Unary(_Model):
    """A prefix operator (`not`, `-`) applied to an operand."""

    kind: Literal["unary"] = "unary"
    op: UnOp
    operand: "Operand"


class Binary(_Model):
    """A binary operator (arithmetic, comparison, `and`/`or`) between two operands."""

    kind: Literal["binary"] = "binary"
    op: BinOp
    left: "Operand"
    right: "Operand"


class StartsWith(_Model):
    """``startswith(text, prefix)``: whether the string `text` begins with the string `prefix`
    (both strings: another value is an error when it runs, error.execution)."""

    kind: Literal["startswith"] = "startswith"
    text: "Operand"
    prefix: "Operand"


class Else(_Model):
    """UML's ``else`` guard: true when no other guard of the choice holds."""

    kind: Literal["else"] = "else"


Expr = Annotated[
    Const
    | Name
    | EventField
    | System
    | InState
    | Invalid
    | ListOf
    | Attr
    | Unary
    | Binary
    | StartsWith
    | Else,
    Field(discriminator="kind"),
]
Operand = Annotated[Expr, AfterValidator(_not_else)]


class Arg(_Model):
    """``field = expr`` inside ``raise``/``send``."""

    name: Ident
    value: Operand


def _unique_args(args: tuple[Arg, ...]) -> tuple[Arg, ...]:
    names = [a.name for a in args]
    if len(set(names)) != len(names):
        raise ValueError("duplicate argument names")
    return args


def _location(value: str) -> str:
    return value if value in SYSTEM_VARIABLES else _data_name(value)


# what an assignment may name: member data, or a system variable (read-only: W3C's
# error.execution when the assignment runs, docs/semantics.md)
Location = Annotated[str, AfterValidator(_location)]


class Assign(_Model):
    """``name = expr``: set a member data item. To a system variable (`_sessionid = e`) or an
    invalid location (`invalid("x") = e`) it sets nothing and raises error.execution when it
    runs (W3C 5.10: system variables are read-only; 5.4: a location that is none)."""

    kind: Literal["assign"] = "assign"
    target: Location | Invalid
    value: Operand


DelayUnit = Literal["ms", "s", ""]


class Delay(_Model):
    """``after <amount> <unit>`` of a delayed ``raise``: milliseconds or seconds, or no unit,
    when the amount's value is a duration string (``"1.5s"``, ``"200ms"``: SCXML's
    ``delayexpr``)."""

    amount: Operand
    unit: DelayUnit = "ms"


class Raise(_Model):
    """Raise an event for this member only; with a delay, it arrives after it (W3C: a delayed
    `<send>` to the session's own external queue), cancellable by its send id."""

    kind: Literal["raise"] = "raise"
    # None: `raise (expr)`, the name `named` computes (the parser gives one of the two; an
    # event's fields, `args`, or its whole data, `content`, not both)
    event: EventName | None = None
    args: Annotated[tuple[Arg, ...], AfterValidator(_unique_args)] = ()
    # `raise (expr)`: W3C's <send eventexpr>, the event's name computed when the action runs
    named: Operand | None = None
    # `raise e(expr)`: the event's data is this value (W3C's <send> with <content>)
    content: Operand | None = None
    delay: Delay | None = None
    sendid: Ident | None = None  # `as <name>`: what `cancel <name>` names
    # `to <expr>`: W3C's <send target>: this member's session (`"#_scxml_" + _sessionid`), or
    # `"#_internal"`; another session is error.communication, anything else error.execution
    target: Operand | None = None
    # `via <expr>`: W3C's <send type|typeexpr>: the SCXML event processor (its URI or "scxml")
    # is the only one; any other value is error.execution and nothing is sent
    via: Operand | None = None
    into: DataName | None = None  # `into <datum>`: W3C's idlocation, the generated send id


class Send(_Model):
    """Send an event to the swarm."""

    kind: Literal["send"] = "send"
    event: EventName
    args: Annotated[tuple[Arg, ...], AfterValidator(_unique_args)] = ()


class Done(_Model):
    """``done(f = expr, ...)``: a final state's done data (W3C `<donedata>`): the fields of the
    `done.state.<parent>` event entering the final state raises. Only in a final state's entry."""

    kind: Literal["done"] = "done"
    args: Annotated[tuple[Arg, ...], AfterValidator(_unique_args)] = ()
    content: Operand | None = None  # `done(expr)`: the event's data is this value (W3C <content>)


class Log(_Model):
    """``log [label,] expr``: the value goes to the member's log (W3C `<log>`); no trace or
    state changes, an expression that fails raises error.execution as any other."""

    kind: Literal["log"] = "log"
    label: str = ""
    value: Operand


class Cancel(_Model):
    """``cancel <name>``: drop the delayed events raised `as <name>` that are still pending;
    ``cancel (expr)``: those of the send id the expression gives (W3C's `sendidexpr`)."""

    kind: Literal["cancel"] = "cancel"
    sendid: Ident | None = None
    expr: Operand | None = None


class Branch(_Model):
    """One branch of an `if`: its condition (None: `else`) and its actions."""

    cond: Operand | None = None
    actions: tuple["Action", ...] = ()


class If(_Model):
    """``if c then ... elif c then ... else ... end``: the first branch whose condition holds
    runs (a condition that fails is false and raises error.execution, W3C's `<if>`)."""

    kind: Literal["if"] = "if"
    branches: tuple[Branch, ...]


class Block(_Model):
    """``block ... end``: an error in it ends only it (W3C: each `<onentry>`/`<onexit>` is a
    block of its own); only at the top of an entry or exit behaviour."""

    kind: Literal["block"] = "block"
    actions: tuple["Action", ...] = ()


class ForEach(_Model):
    """``for item[, index] in array do ... end``: the actions once per item of a copy of the
    sequence, `item` and `index` (from 0) written to member data first (W3C's `<foreach>`)."""

    kind: Literal["foreach"] = "foreach"
    array: Operand
    item: DataName
    index: DataName | None = None
    actions: tuple["Action", ...] = ()


Action = Annotated[
    Assign | Raise | Send | Cancel | If | ForEach | Done | Log | Block,
    Field(discriminator="kind"),
]
# Branch, If, Block and ForEach refer to `Action`, defined after them: with `defer_build` the
# forward reference is resolved when a class is first validated (never, when fastnode fills it).


def flat(actions: Iterable[Action]) -> Iterator[Action]:
    """The actions and, for an `if`, the actions of every branch (pre-order)."""
    for action in actions:
        yield action
        if isinstance(action, If):
            for branch in action.branches:
                yield from flat(branch.actions)
        if isinstance(action, ForEach | Block):
            yield from flat(action.actions)


class Binding(_Model):
    """``name = expr``: one argument binding of a behaviour call."""

    name: DataName
    value: Operand
