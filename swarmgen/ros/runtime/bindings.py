"""Declared interfaces of behaviours (`spec.Binding`): checked, their types imported, and the
outcome their answers give.

A binding's type triple is checked against rosidl's name rules before anything is imported
(so a spec can only ever import `<package>.msg|srv|action`), and its field paths against the
type's own fields; every failure is a `BindingError` with one line saying what is wrong, which
the member node reports when it starts.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .convert import ConversionError, check_path, filled, get_path, renamed
from .spec import BehaviourSpec, Binding

# rosidl's patterns (as swarmgen.ros.idl_names, which the vendored runtime cannot import).
_PACKAGE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
_TYPE = re.compile(r"^[A-Z][A-Za-z0-9]*$")
_ROS_NAME = re.compile(r"^(?!.*__)[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")
KINDS = {"action": "action", "service": "srv", "topic": "msg"}
DIRECTIONS = ("publish", "subscribe")
# Seconds, when the spec gives none: a service call's limit, the wait of a publisher behaviour
# for a subscriber; an action goal and a subscriber's wait for its message: no limit (0).
DEFAULT_TIMEOUTS = {"action": 0.0, "service": 10.0, "publish": 1.0, "subscribe": 0.0}


class BindingError(ValueError):
    """A declared interface that cannot be used: bad name, unknown type, unknown field."""


@dataclass(frozen=True)
class Resolved:
    """A checked binding with its imported type: the action or service class, or for topics
    the message class; `request` is what the inputs fill, `answer` what the outputs read."""

    behaviour: BehaviourSpec
    binding: Binding
    type: Any
    request: Any
    answer: Any
    parameter: str  # `behaviours.<key>.timeout_s`

    @property
    def label(self) -> str:
        """`pkg/kind/Name` of the type, for messages."""
        return "/".join(self.binding.type)


def resolve(behaviour: BehaviourSpec) -> Resolved:
    """Check `behaviour.binding` and import its type (BindingError, one line, if unusable)."""
    binding = behaviour.binding
    assert binding is not None
    where = f"behaviour {behaviour.name!r}"
    interface = _import(binding, where)
    if binding.kind == "action":
        request, answer = interface.Goal, interface.Result
    elif binding.kind == "service":
        request, answer = interface.Request, interface.Response
    else:
        request = answer = interface
    try:
        for _, path in binding.inputs:
            check_path(request, path)
        for path, _ in binding.outputs:
            check_path(answer, path)
        if binding.outcome:
            check_path(answer, binding.outcome)
    except ConversionError as err:
        raise BindingError(f"{where}: {'/'.join(binding.type)}: {err}") from None
    key = binding.key or _snake(behaviour.name)
    return Resolved(behaviour, binding, interface, request, answer, f"behaviours.{key}.timeout_s")


def _import(binding: Binding, where: str) -> Any:
    expected = KINDS.get(binding.kind)
    if expected is None:
        raise BindingError(f"{where}: unknown ROS kind {binding.kind!r} (action|service|topic)")
    if binding.kind == "topic" and binding.direction not in DIRECTIONS:
        raise BindingError(f"{where}: topic direction {binding.direction!r} (publish|subscribe)")
    if not _ROS_NAME.fullmatch(binding.ros_name):
        raise BindingError(f"{where}: invalid relative ROS name {binding.ros_name!r}")
    triple = binding.type
    if len(triple) != 3:
        raise BindingError(f"{where}: ROS type {triple!r} is not (package, kind, Name)")
    package, kind, name = triple
    label = f"{package}/{kind}/{name}"
    if not (isinstance(package, str) and _PACKAGE.fullmatch(package)):
        raise BindingError(f"{where}: invalid ROS package name in {label!r}")
    if not (isinstance(name, str) and _TYPE.fullmatch(name)):
        raise BindingError(f"{where}: invalid ROS type name in {label!r}")
    if kind != expected:
        raise BindingError(f"{where}: {label} is no {binding.kind} type (want {expected})")
    try:
        module = importlib.import_module(f"{package}.{kind}")
    except ImportError as err:
        raise BindingError(f"{where}: unknown ROS type {label} ({err})") from None
    interface = getattr(module, name, None)
    if interface is None:
        raise BindingError(f"{where}: unknown ROS type {label} (no {name} in {package}.{kind})")
    return interface


def _snake(name: str) -> str:
    """`TakeOff` -> `take_off`, anything but letters and digits -> `_` (a parameter name)."""
    text = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name)
    return re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_") or "behaviour"


def outputs_of(resolved: Resolved, answer: Any) -> dict[str, Any]:
    """The behaviour's outputs read from a result, response or message (data type keys
    renamed back to the model's names, empty enumeration fields as their first literal)."""
    blanks = dict(resolved.binding.enums)
    return {
        output: filled(
            renamed(get_path(answer, path), renames(resolved, "output", output), False),
            blanks.get(output, ()),
        )
        for path, output in resolved.binding.outputs
    }


def renames(resolved: Resolved, side: str, name: str) -> tuple[Any, ...]:
    """The key renames of input or output `name` (`side`), () when its keys are ROS names."""
    return next((t for s, n, t in resolved.binding.renames if (s, n) == (side, name)), ())


def outcome_of(resolved: Resolved, answer: Any, default: str) -> str:
    """The outcome an answer gives: its outcome field (a non-empty string names the outcome; a
    bool is succeeded or aborted), else `default` (from the goal status, or succeeded)."""
    if not resolved.binding.outcome:
        return default
    value = get_path(answer, resolved.binding.outcome)
    if isinstance(value, bool):
        return default if value else "aborted"
    return value if isinstance(value, str) and value else default


def assignments(resolved: Resolved, args: Mapping[str, Any]) -> list[tuple[str, Any]]:
    """(field path, value) for every mapped input the call gives, with ROS field names."""
    return [
        (path, renamed(args.get(name), renames(resolved, "input", name), True))
        for name, path in resolved.binding.inputs
    ]
