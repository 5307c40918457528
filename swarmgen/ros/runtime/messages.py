"""The ROS side of the swarm: topics, their QoS, the interface package's types, and values
converted between the engine and ROS message fields."""

from __future__ import annotations

import importlib
import json
import math
from functools import cache
from types import ModuleType
from typing import Any

from builtin_interfaces.msg import Time
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from .convert import (
    ConversionError,
    filled,
    nested_class,
    plain,
    renamed,
    to_basic,
    to_message,
)

SWARM_TOPIC = "/swarm/events"
LOCAL_TOPIC = "local_events"  # behaviour events of local scope, inside one member's namespace
STATES_TOPIC = "active_states"
EVENTS_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1000,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
# The latest configuration is kept for late subscribers (a monitor that starts after the swarm).
STATES_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
# A field's renames (`Field.renames`): (model key, ROS field, renames inside), nested.
Renames = tuple[tuple[str, str, tuple[Any, ...]], ...]
_ZEROS: dict[str, Any] = {"string": "", "enum": "", "bool": False, "int64": 0, "float64": 0.0}

_BASIC = {"bool": "boolean", "int64": "int64", "float64": "double"}  # rosidl's type names


def _message_class(type_: str) -> Any:
    package, name = type_.split("/")
    return nested_class((package, "msg"), name)


def _to_message(type_: str, value: Any, renames: Renames, where: str = "") -> Any:
    """A message of `type_` from a model value (ConversionError if it cannot hold it)."""
    return to_message(_message_class(type_), renamed(value, renames, True), where or type_)


def _from_message(type_: str, message: Any, renames: Renames) -> Any:
    """The model value of a message: its plain dict with the model's keys."""
    return renamed(plain(message), renames, False)


def to_ros(type_: str, value: Any, renames: Renames = (), where: str = "value") -> Any:
    """A model value as the ROS field of `type_` holds it, strictly, by the rule of the declared
    interfaces (`convert.py`): None (not given) is the field's zero (`""` for JSON and
    enumeration fields); any other value the field cannot hold as it is raises ConversionError
    (a string for a number, 2.5 or 2**63 for an `int64`, a number for a `string`, a dict that is
    not the message). An array field `T[]` takes a list item by item; a message field
    `pkg/Name` a dict, renamed by `renames` (the field's, `Field.renames`)."""
    if type_.endswith("[]"):
        if value is None:
            return []
        if isinstance(value, str | bytes) or not isinstance(value, list | tuple):
            raise ConversionError(f"{where}: expected a list, got {type(value).__name__}")
        return [to_ros(type_[:-2], v, renames, f"{where}[{i}]") for i, v in enumerate(value)]
    if "/" in type_:
        return _to_message(type_, {} if value is None else value, renames, where)
    if type_ == "json":
        try:
            return "" if value is None else json.dumps(value, sort_keys=True)
        except (TypeError, ValueError) as err:
            raise ConversionError(f"{where}: not JSON: {err}") from None
    if value is None:
        return _ZEROS[type_] if type_ in _ZEROS else _unknown(type_)
    if type_ in ("string", "enum"):
        if isinstance(value, str):
            return value
        raise ConversionError(f"{where}: expected a string, got {type(value).__name__}")
    if type_ not in _ZEROS:
        return _unknown(type_)
    return to_basic(_BASIC[type_], value, where)


def encode(type_: str, value: Any, renames: Renames = ()) -> Any:
    """`to_ros`, leniently: a value the field cannot hold gives the field's zero (the replay's
    filled-in outputs of a `complete`, `served.py`; goals are converted by `to_ros`)."""
    try:
        return to_ros(type_, value, renames)
    except ConversionError:
        if type_.endswith("[]"):
            items = value if isinstance(value, list | tuple) else ()
            return [encode(type_[:-2], item, renames) for item in items]
        return to_ros(type_, None, renames)


def _unknown(type_: str) -> Any:
    raise ValueError(f"unknown field type {type_!r}")


def fits(type_: str, value: Any, renames: Renames = ()) -> bool:
    """`value` is one the ROS field of `type_` carries as it is (None: not given, the zero),
    not one `encode` would replace by the zero: what a behaviour's output must be."""
    if value is None or type_ == "json":
        return True
    if type_.endswith("[]"):
        return isinstance(value, list | tuple) and all(fits(type_[:-2], v, renames) for v in value)
    if "/" in type_:  # every field given, each as its field holds it: the value round-trips
        try:
            message = _to_message(type_, value, renames)
            return bool(_from_message(type_, message, renames) == value)
        except ConversionError:
            return False
    if type_ in ("enum", "string"):
        return isinstance(value, str)
    if type_ == "bool":
        return isinstance(value, bool)
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if type_ == "int64":
        return number and isinstance(value, int) and INT64_MIN <= value <= INT64_MAX
    return number and math.isfinite(float(value)) if type_ == "float64" else False


def decode(type_: str, value: Any, renames: Renames = (), enums: Any = ()) -> tuple[bool, Any]:
    """(present, value) of a ROS field; an empty JSON or enumeration field is absent (no
    literal is empty: the output's zero, the first literal, is written instead), and so is a
    message equal to its zeros (its value is still the plain dict). `enums` (`Field.enums`):
    the enumeration fields inside a message or an array, whose empty strings become their
    first literal (`convert.filled`)."""
    if type_.endswith("[]"):  # rclpy gives numeric arrays as array.array
        return True, [decode(type_[:-2], item, renames, enums)[1] for item in value]
    if "/" in type_:  # the zeros message is "not given": the output's zero is written instead
        return value != type(value)(), filled(_from_message(type_, value, renames), enums)
    if type_ == "json":
        if value == "":
            return False, None
        try:
            return True, json.loads(value)
        except ValueError:
            return True, value
    if type_ == "enum":
        return value != "", value
    if type_ == "float64":
        return True, float(value)
    if type_ == "int64":
        return True, int(value)
    return True, value


def ros_time(seconds: float) -> Time:
    """Seconds since the epoch as a ROS `Time` stamp."""
    whole = math.floor(seconds)
    return Time(sec=int(whole), nanosec=int((seconds - whole) * 1e9))


def from_ros_time(stamp: Any) -> float:
    """A ROS `Time` stamp as seconds since the epoch."""
    return float(stamp.sec) + float(stamp.nanosec) / 1e9


@cache
def _module(name: str) -> ModuleType:
    return importlib.import_module(name)


class Interfaces:
    """The generated interface package's types, imported by name (the runtime is generic)."""

    def __init__(self, package: str) -> None:
        self.package = package
        msg = _module(f"{package}.msg")
        self.Event: Any = msg.Event
        self.ActiveStates: Any = msg.ActiveStates

    def action(self, name: str) -> Any:
        """The action type `name` of the package."""
        return getattr(_module(f"{self.package}.action"), name)

    def event(self, ident: int, stamp: float, sender: str, name: str, data: str) -> Any:
        """An `Event` message; `data` is the JSON text of the event's fields."""
        return self.Event(id=ident, stamp=ros_time(stamp), sender=sender, name=name, data=data)
