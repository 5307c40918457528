"""The value rule (docs/semantics.md): every member datum and event field always holds a typed
value, the model's default or else its type's zero, the same in Python, in the SCXML datamodel
and in ROS messages (whose fields are never unset either). Decided here, once, for every output.

Values are JSON-like: bool, int, float, str, and dicts (field name -> value) for data types.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from swarmgen.ir.nodes import DataType, Property, Value

_REAL = {"real", "double", "float", "number"}
_INTEGER = {"integer", "int", "long", "unlimitednatural"}
_BOOL = {"boolean", "bool"}
_STRING = {"string", "str"}
MAX_NESTING = 32  # a data type that contains itself (directly or not) stops here


def zero(type_name: str | None, datatypes: Mapping[str, DataType], depth: int = 0) -> Any:
    """The zero of a type: 0.0, 0, False, "", a data type's fields' initial values. An untyped
    item's zero is 0 (a number is what guards compare untyped data with)."""
    if type_name is None:
        return 0
    lowered = type_name.strip().lower()
    if lowered in _REAL:
        return 0.0
    if lowered in _INTEGER:
        return 0
    if lowered in _BOOL:
        return False
    if lowered in _STRING:
        return ""
    datatype = datatypes.get(type_name)
    if datatype is None or depth >= MAX_NESTING:
        return 0 if datatype is None else {}
    return {f.name: initial(f, datatypes, depth + 1) for f in datatype.fields}


def initial(prop: Property, datatypes: Mapping[str, DataType], depth: int = 0) -> Any:
    """The value an item holds before anything writes it: its default, typed, else its zero."""
    if prop.default is None:
        return zero(prop.type, datatypes, depth)
    return typed(prop.default, prop.type)


def typed(value: Value, type_name: str | None) -> Value:
    """A default in its declared type: `battery: Real = 100` holds 100.0 (ROS float64)."""
    lowered = (type_name or "").strip().lower()
    if lowered in _REAL and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value
