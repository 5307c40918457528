"""The value rule (docs/semantics.md): every member datum and event field always holds a typed
value, the model's default or else its type's zero, the same in Python, in the SCXML datamodel
and in ROS messages (whose fields are never unset either). Decided here, once, for every output.

Values are JSON-like: bool, int, float, str, dicts (field name -> value) for data types, the
literal's name (a str) for enumerations, lists for sequences (multiplicity `*` or above 1).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from swarmgen.ir.nodes import DataType, Enumeration, Property, Value
from swarmgen.ir.primitives import Primitive, primitive
from swarmgen.runtime.values import zero_like

MAX_NESTING = 32  # a data type that contains itself (directly or not) stops here
NO_ENUMS: Mapping[str, Enumeration] = MappingProxyType({})


def zero(
    type_name: str | None,
    datatypes: Mapping[str, DataType],
    depth: int = 0,
    enums: Mapping[str, Enumeration] = NO_ENUMS,
) -> Any:
    """The zero of a type: 0.0, 0, False, "", an enumeration's first literal, a data type's
    fields' initial values. An untyped item's zero is 0 (a number is what guards compare untyped
    data with)."""
    if type_name is None:
        return 0
    kind = primitive(type_name)
    if kind is not None:
        return kind.zero
    enumeration = enums.get(type_name)
    if enumeration is not None:
        return enumeration.literals[0] if enumeration.literals else ""
    datatype = datatypes.get(type_name)
    if datatype is None or depth >= MAX_NESTING:
        return 0 if datatype is None else {}
    return {f.name: initial(f, datatypes, depth + 1, enums) for f in datatype.fields}


def initial(
    prop: Property,
    datatypes: Mapping[str, DataType],
    depth: int = 0,
    enums: Mapping[str, Enumeration] = NO_ENUMS,
) -> Any:
    """The value an item holds before anything writes it: its default, typed, else its zero;
    a sequence's is empty, or holds its one default (UML gives an attribute one default)."""
    if prop.many:
        return [] if prop.default is None else [typed(prop.default, prop.type)]
    if prop.default is None:
        return zero(prop.type, datatypes, depth, enums)
    return typed(prop.default, prop.type)


def typed(value: Value, type_name: str | None) -> Value:
    """A default in its declared type: `battery: Real = 100` holds 100.0 (ROS float64)."""
    if (
        primitive(type_name) is Primitive.REAL
        and isinstance(value, int)
        and not isinstance(value, bool)
    ):
        return float(value)
    return value


def blank(
    prop: Property,
    held: Any,
    datatypes: Mapping[str, DataType],
    enums: Mapping[str, Enumeration] = NO_ENUMS,
    depth: int = 0,
) -> Any:
    """What an output the behaviour did not give is written as (`held`: the datum's initial
    value): its type's zero without the model's defaults, so [] for a sequence, an
    enumeration's first literal, each field's blank for a data type; an untyped datum's is
    the zero of the kind of value it holds."""
    if prop.many:
        return []
    enumeration = enums.get(prop.type or "")
    if enumeration is not None:
        return enumeration.literals[0] if enumeration.literals else ""
    kind = primitive(prop.type)
    if kind is not None:
        return kind.zero
    datatype = datatypes.get(prop.type or "")
    if datatype is not None and isinstance(held, Mapping) and depth < MAX_NESTING:
        return {
            f.name: blank(f, held.get(f.name), datatypes, enums, depth + 1) for f in datatype.fields
        }
    return zero_like(held)
