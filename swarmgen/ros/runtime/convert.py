"""Model values <-> fields of declared ROS 2 messages, by the messages' own introspection.

A message class describes its fields in `SLOT_TYPES` (rosidl's type objects: BasicType,
NamespacedType, Array, BoundedSequence, UnboundedSequence, (Bounded|Unbounded)(W)String), in
the order of `get_fields_and_field_types()`. Values go in strictly: a value that the field
cannot hold as it is (a string for a `float64`, 300 for a `uint8`, 1e39 for a `float32`) is a
`ConversionError`, never a silent zero (the generated Python setters do not check ranges, and
a bad value would only fail when rclpy serialises the message, inside the executor). Values
come out as plain Python values: dicts for messages, lists for arrays and sequences.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Mapping, Sequence
from functools import cache
from typing import Any

_INT_BITS = {"int8": 8, "int16": 16, "int32": 32, "int64": 64}
_UINT_BITS = {"uint8": 8, "uint16": 16, "uint32": 32, "uint64": 64, "char": 8, "octet": 8}
_FLOATS = {"float": 3.4028234663852886e38, "double": None, "long double": None}


class ConversionError(ValueError):
    """A value that the message field cannot hold, or a field path the message does not have."""


def fields(message_type: Any) -> dict[str, Any]:
    """Field name -> rosidl type object of a message class, in definition order."""
    names = list(message_type.get_fields_and_field_types())
    return dict(zip(names, message_type.SLOT_TYPES, strict=True))


@cache
def nested_class(namespaces: tuple[str, ...], name: str) -> Any:
    """The class of a nested message type (`geometry_msgs`, `msg`, `Pose`)."""
    return getattr(importlib.import_module(".".join(namespaces)), name)


def _slot_class(slot: Any) -> Any:
    return nested_class(tuple(slot.namespaces), slot.name)


def to_field(slot: Any, value: Any, where: str) -> Any:
    """`value` as the field of rosidl type `slot` holds it (ConversionError if it cannot)."""
    kind = type(slot).__name__
    if kind == "BasicType":
        return to_basic(slot.typename, value, where)
    if kind in ("UnboundedString", "BoundedString", "UnboundedWString", "BoundedWString"):
        if not isinstance(value, str):
            raise ConversionError(f"{where}: expected a string, got {_shown(value)}")
        limit = getattr(slot, "maximum_size", None)
        if limit is not None and len(value) > int(limit):
            raise ConversionError(f"{where}: string longer than {limit}")
        return value
    if kind == "NamespacedType":
        return to_message(_slot_class(slot), value, where)
    if kind in ("Array", "BoundedSequence", "UnboundedSequence"):
        return _sequence(slot, value, where)
    raise ConversionError(f"{where}: unsupported field type {kind}")


def to_basic(typename: str, value: Any, where: str) -> Any:
    """`value` as a field of the rosidl basic type `typename` (`double`, `int64`, `boolean`,
    ...) holds it (ConversionError if it cannot)."""
    if typename == "boolean":
        if not isinstance(value, bool):
            raise ConversionError(f"{where}: expected a bool, got {_shown(value)}")
        return value
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if typename in _FLOATS:
        if not number:
            raise ConversionError(f"{where}: expected a number, got {_shown(value)}")
        limit = _FLOATS[typename]
        if limit is not None and math.isfinite(value) and abs(value) > limit:
            raise ConversionError(f"{where}: {value!r} is out of range for {typename}")
        return float(value)
    if typename in _INT_BITS or typename in _UINT_BITS:
        if not number or (isinstance(value, float) and not value.is_integer()):
            raise ConversionError(f"{where}: expected an integer, got {_shown(value)}")
        whole = int(value)
        if typename in _INT_BITS:
            low, high = -(2 ** (_INT_BITS[typename] - 1)), 2 ** (_INT_BITS[typename] - 1) - 1
        else:
            low, high = 0, 2 ** _UINT_BITS[typename] - 1
        if not low <= whole <= high:
            raise ConversionError(f"{where}: {whole} is out of range for {typename}")
        return bytes([whole]) if typename == "octet" else whole
    if typename in ("wchar",) and isinstance(value, str) and len(value) == 1:
        return value
    raise ConversionError(f"{where}: unsupported field type {typename}")


def _sequence(slot: Any, value: Any, where: str) -> list[Any]:
    if isinstance(value, str | bytes | Mapping) or not isinstance(value, Sequence):
        raise ConversionError(f"{where}: expected a list, got {_shown(value)}")
    kind = type(slot).__name__
    size = getattr(slot, "size", None) if kind == "Array" else None
    limit = getattr(slot, "maximum_size", None) if kind == "BoundedSequence" else None
    if size is not None and len(value) != int(size):
        raise ConversionError(f"{where}: expected {size} items, got {len(value)}")
    if limit is not None and len(value) > int(limit):
        raise ConversionError(f"{where}: more than {limit} items")
    return [to_field(slot.value_type, item, f"{where}[{i}]") for i, item in enumerate(value)]


def to_message(message_type: Any, value: Any, where: str = "message") -> Any:
    """A message of `message_type` from a dict of its fields (absent fields keep their
    default; an existing message of the type is taken as it is)."""
    if isinstance(value, message_type):
        return value
    if not isinstance(value, Mapping):
        raise ConversionError(f"{where}: expected an object, got {_shown(value)}")
    slots = fields(message_type)
    message = message_type()
    for name, item in value.items():
        if name not in slots:
            raise ConversionError(f"{where}: {message_type.__name__} has no field {name!r}")
        if item is not None:
            setattr(message, name, to_field(slots[name], item, f"{where}.{name}"))
    return message


def build(message_type: Any, assignments: Sequence[tuple[str, Any]], where: str) -> Any:
    """A message of `message_type` with the value of each (field path, value) set; a None
    value leaves its field at the default (an input the behaviour was not given). The empty
    path is the whole message (a dict of its fields), set before the paths inside it."""
    message = message_type()
    for path, value in sorted(assignments, key=lambda item: item[0] != ""):
        if value is None:
            continue
        if path == "":
            message = to_message(message_type, value, where)
            continue
        *parents, last = check_path(message_type, path)
        owner = message
        for name in parents:
            owner = getattr(owner, name)
        slot = fields(type(owner))[last]
        setattr(owner, last, to_field(slot, value, f"{where}.{path}"))
    return message


def check_path(message_type: Any, path: str) -> list[str]:
    """The names along a field path (`pose.position.x`); ConversionError if a name is not a
    field of the message it is looked up in."""
    if path == "":  # the whole message
        return []
    names = path.split(".")
    current = message_type
    for depth, name in enumerate(names):
        slots = fields(current) if current is not None else {}
        if name not in slots:
            raise ConversionError(f"{message_type.__name__} has no field {path!r}")
        slot = slots[name]
        last = depth == len(names) - 1
        current = _slot_class(slot) if type(slot).__name__ == "NamespacedType" else None
        if current is None and not last:
            raise ConversionError(f"{message_type.__name__}: {name!r} in {path!r} is no message")
    return names


def get_path(message: Any, path: str) -> Any:
    """The plain value at a field path of a message (the empty path: all of it)."""
    value = message
    for name in path.split(".") if path else ():
        value = getattr(value, name)
    return plain(value)


def plain(value: Any) -> Any:
    """A message field as a plain Python value: dicts, lists, bool, int, float, str."""
    if hasattr(value, "get_fields_and_field_types"):
        return {name: plain(getattr(value, name)) for name in value.get_fields_and_field_types()}
    if isinstance(value, bytes):  # an octet field, or an array of them
        return value[0] if len(value) == 1 else list(value)
    if isinstance(value, str | bool | int | float):
        return value
    if hasattr(value, "tolist"):  # numpy arrays and scalars, array.array
        return plain(value.tolist())
    if isinstance(value, list | tuple):
        return [plain(item) for item in value]
    return value


def renamed(value: Any, renames: Sequence[Any], to_ros: bool) -> Any:
    """A model value with its dict keys renamed to the ROS field names (`to_ros`) or back, by
    `renames`: (model key, ROS name, renames inside) triples; lists are renamed item by item."""
    if not renames:
        return value
    if isinstance(value, list | tuple):
        return [renamed(item, renames, to_ros) for item in value]
    if not isinstance(value, Mapping):
        return value
    table = {(m if to_ros else r): (r if to_ros else m, inner) for m, r, inner in renames}
    result: dict[str, Any] = {}
    for key, item in value.items():
        name, inner = table.get(key, (key, ()))
        result[name] = renamed(item, inner, to_ros)
    return result


def filled(value: Any, blanks: Any) -> Any:
    """A model value read from ROS with its empty enumeration fields given their zero, the
    first literal (no literal is empty: `""` means not given). `blanks` is a literal (the value
    is an enumeration's) or (model key, blanks) pairs of a data type's fields; lists are filled
    item by item; () leaves the value as it is."""
    if not blanks:
        return value
    if isinstance(value, list | tuple):
        return [filled(item, blanks) for item in value]
    if isinstance(blanks, str):
        return blanks if value == "" else value
    if not isinstance(value, Mapping):
        return value
    table = dict(blanks)
    return {key: filled(item, table.get(key, ())) for key, item in value.items()}


def _shown(value: Any) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text[:40]}{'...' if len(text) > 40 else ''}"
