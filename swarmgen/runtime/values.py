"""The value rule's runtime half (docs/semantics.md): Records, typed zeros, filling values
with their type's fields, and durations (standard library only)."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from typing import Any


class Record(dict[str, Any]):
    """Event and member data: a dict whose keys also read as attributes (`pose.x`), like the
    SCXML ECMAScript datamodel."""

    __slots__ = ()

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


PLAIN = frozenset({str, int, float, bool, type(None)})  # the types `record` returns as they are


def record(value: Any) -> Any:
    """Deep-convert mappings to Records (lists are kept as lists of converted items)."""
    if type(value) in PLAIN:  # the common case, without the slow ABC checks below
        return value
    if isinstance(value, Mapping):
        return Record({str(k): record(v) for k, v in value.items()})
    if isinstance(value, list | tuple):
        return [record(v) for v in value]
    return value


def zero_like(value: Any) -> Any:
    """The zero of a value's type (every datum starts typed: docs/semantics.md, value rule)."""
    if isinstance(value, bool):
        return False
    if isinstance(value, int):
        return 0
    if isinstance(value, float):
        return 0.0
    if isinstance(value, str):
        return ""
    if isinstance(value, Mapping):
        return Record({str(k): zero_like(v) for k, v in value.items()})
    if isinstance(value, list | tuple):
        return []
    return None


def fill(value: Any, template: Any) -> Any:
    """`value` as a value of `template`'s type (the value rule, docs/semantics.md): every field
    the template has, what is missing (or null) taking the template's value, recursively; a
    field the type does not have is dropped (a ROS message's `header.stamp` where the model's
    type has none, a sender's extra key), so a datum holds exactly its type's fields."""
    if type(template) in PLAIN:
        return template if value is None else record(value)
    if isinstance(template, Mapping):
        given = value if isinstance(value, Mapping) else {}
        return Record({str(k): fill(given.get(k), default) for k, default in template.items()})
    return record(template) if value is None else record(value)


def fill_fields(data: Mapping[str, Any] | None, template: Mapping[str, Any]) -> Record:
    """An event's data on arrival: each declared field as `fill` makes it; fields the event
    does not declare are kept as they came (no expression can read them: the check)."""
    data = data if isinstance(data, Mapping) else {}
    filled = Record({str(k): record(v) for k, v in data.items()})
    for key, default in template.items():
        filled[key] = fill(data.get(key), default)
    return filled


Filler = Callable[[Any], Any]


def filler(template: Any) -> Filler:
    """`fill(value, template)` as a function of `value`, the template's walk done once (an
    event's fields are filled on every arrival of the event)."""
    if type(template) in PLAIN:
        return lambda value: template if value is None else record(value)
    if not isinstance(template, Mapping):
        return lambda value: record(template) if value is None else record(value)
    parts = tuple((str(k), k, filler(default)) for k, default in template.items())
    fresh = defaults_maker(template)

    def fill_mapping(value: Any) -> Record:
        if value is None:
            return fresh()
        given = value if isinstance(value, Mapping) else {}
        return Record({key: part(given.get(k)) for key, k, part in parts})

    return fill_mapping


def defaults_maker(
    template: Mapping[Any, Any], outer_key: Callable[[Any], Any] = str
) -> Callable[[], Record]:
    """A function making `fill(None, template)`: a new Record tree of the template's values.

    Where every leaf is a plain value (the usual message type), it is a function compiled from
    the template's shape: each Record of the tree is a copy of a prototype dict holding the
    level's plain values (the nested ones' places kept, in order, by None), and the nested
    Records are then put in their places; a copy of a dict costs less than a field at a time
    (an event's defaults are made on every arrival). Only indices into `constants` appear in
    its text, never a key or a value of the model."""
    constants: list[Any] = []
    lines: list[str] = []

    def level(value: Mapping[Any, Any], key_of: Callable[[Any], Any]) -> str | None:
        """The variable the level's Record is made in (None: not a tree of plain values)."""
        prototype: dict[Any, Any] = {}
        nested = []
        for k, v in value.items():
            key = key_of(k)
            if type(v) in PLAIN:
                prototype[key] = v
            elif isinstance(v, Mapping):
                prototype[key] = None
                nested.append((key, v))
            else:
                return None  # a list: made by `fill` itself
        if len(prototype) < len(value):
            return None  # keys equal as strings: `fill` decides which one wins
        made = f"r{len(lines)}"
        constants.append(prototype)
        lines.append(f"{made} = R(C[{len(constants) - 1}])")
        for key, v in nested:
            inner = level(v, str)
            if inner is None:
                return None
            constants.append(key)
            lines.append(f"{made}[C[{len(constants) - 1}]] = {inner}")
        return made

    top = level(template, outer_key)
    if top is None:
        return lambda: Record({outer_key(k): fill(None, v) for k, v in template.items()})
    text = "def make():\n" + "".join(f"    {line}\n" for line in lines) + f"    return {top}\n"
    namespace: dict[str, Any] = {"__builtins__": {}, "R": Record, "C": tuple(constants)}
    exec(text, namespace)
    made: Callable[[], Record] = namespace["make"]
    return made


def fields_filler(template: Mapping[str, Any]) -> Callable[[Mapping[str, Any] | None], Record]:
    """`fill_fields(data, template)` as a function of `data`, made once per event name."""
    # per field: its default where that is a plain value (`filler`'s, inlined), else its filler
    parts = tuple(
        (key, default, None if type(default) in PLAIN else filler(default))
        for key, default in template.items()
    )
    fresh = defaults_maker(template, lambda key: key)  # `fill_fields` keeps the keys as they are

    def fill_event(data: Mapping[str, Any] | None) -> Record:
        if not data or (type(data) is not Record and not isinstance(data, Mapping)):
            return fresh()  # (None and Records first: no ABC check)
        # `record` of each value, called only for what is not a plain value
        filled = Record(
            {
                k if type(k) is str else str(k): v if type(v) in PLAIN else record(v)
                for k, v in data.items()
            }
        )
        for key, default, part in parts:
            value = data.get(key)
            if part is not None:
                filled[key] = part(value)
            elif value is None:
                filled[key] = default
            else:
                filled[key] = value if type(value) in PLAIN else record(value)
        return filled

    return fill_event


_DURATION = re.compile(r"\s*(\d+(?:\.\d*)?|\.\d+)(ms|s)\s*", re.ASCII)


def duration_ms(value: Any) -> float:
    """A CSS2 time (`"1.5s"`, `"200ms"`, `".5s"`: SCXML's `delay`) in milliseconds; anything
    else is an error (error.execution where an action computes it; `$sg.duration` in SCXML)."""
    found = _DURATION.fullmatch(value) if isinstance(value, str) else None
    if found is None:
        raise ValueError(f"{value!r} is not a duration such as '2s' or '500ms'")
    return float(found.group(1)) * (1.0 if found.group(2) == "ms" else 1000.0)
