"""The property language's trees (docs/verify.md, "User properties").

A property is one temporal operator over state formulas:

    always P | never P | eventually P | P leads to Q | P until Q

and a state formula combines, with `not`, `and`, `or` and parentheses:

- `UAV in Tracking`: some UAV is in the state `Tracking` (`every UAV in Tracking`: all of them);
- `count(UAV in Tracking) <= 2`: how many UAVs are in it, compared with a number;
- `UAV.battery > 10`: every UAV's datum compares so (`some UAV.battery > 10`: at least one);
- `targetFound`: the event is sent in this step (by a member, or by the station);
- `true`, `false`.

Every node keeps the offset of its first character in the property's text, for located errors.
Trees are frozen dataclasses: properties are parsed once per model and never change.
"""

from __future__ import annotations

from typing import Literal

from swarmgen.records import dataclass

Comparison = Literal["==", "!=", "<", "<=", ">", ">="]
Quantifier = Literal["some", "every"]
Temporal = Literal["always", "never", "eventually", "leads to", "until"]
Scalar = bool | int | float | str


@dataclass(frozen=True, slots=True)
class Bool:
    """`true` or `false`."""

    value: bool
    offset: int = 0


@dataclass(frozen=True, slots=True)
class InState:
    """`[some|every] TYPE in STATE`: members of a type in a state (some, unless `every`)."""

    quantifier: Quantifier
    member: str
    state: str
    offset: int = 0
    state_offset: int = 0


@dataclass(frozen=True, slots=True)
class Datum:
    """`[some|every] TYPE.datum OP value`: members' data compared with a constant (every
    member, unless `some`)."""

    quantifier: Quantifier
    member: str
    datum: str
    op: Comparison
    value: Scalar
    offset: int = 0
    datum_offset: int = 0


@dataclass(frozen=True, slots=True)
class Count:
    """`count(TYPE in STATE) OP n`: how many members of a type are in a state."""

    member: str
    state: str
    op: Comparison
    value: int
    offset: int = 0
    state_offset: int = 0


@dataclass(frozen=True, slots=True)
class Occurs:
    """An event name: the event is sent in this step."""

    event: str
    offset: int = 0


@dataclass(frozen=True, slots=True)
class Not:
    """`not P`."""

    operand: Formula
    offset: int = 0


@dataclass(frozen=True, slots=True)
class Both:
    """`P and Q` (`kind` "and") or `P or Q` (`kind` "or")."""

    kind: Literal["and", "or"]
    left: Formula
    right: Formula
    offset: int = 0


Atom = Bool | InState | Datum | Count | Occurs
Formula = Atom | Not | Both


@dataclass(frozen=True, slots=True)
class Property:
    """A parsed property: its temporal operator and formulas (`right` for `leads to` and
    `until` only), and its text."""

    kind: Temporal
    left: Formula
    right: Formula | None
    text: str


def atoms(formula: Formula) -> list[Atom]:
    """The formula's atoms, left to right."""
    if isinstance(formula, Not):
        return atoms(formula.operand)
    if isinstance(formula, Both):
        return atoms(formula.left) + atoms(formula.right)
    return [formula]


def property_atoms(prop: Property) -> list[Atom]:
    """Every atom of the property, left to right."""
    return atoms(prop.left) + (atoms(prop.right) if prop.right is not None else [])


def has_events(formula: Formula) -> bool:
    """Whether the formula reads an event (holds at a step, not in a state)."""
    return any(isinstance(a, Occurs) for a in atoms(formula))
