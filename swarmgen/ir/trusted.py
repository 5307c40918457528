"""IR nodes made by `ir.build` without pydantic's validation, which it makes redundant.

Validating a node checks that each field holds its declared type: strings, integers, tuples of
nodes, one of a `Literal`'s strings, an enumeration member, a node of the discriminated union.
The IR nodes declare no validator of their own, so validation adds nothing else, and it
converts nothing either when every value already has its type: no list passed for a tuple, no
string for an enumeration, no integral float for an integer. `ir.build` passes values of the
declared types (tuples built from generators, `StrEnum` members from its tables, `Literal`
strings from `Builder.tag_choice`'s fixed choices or constants, nodes it just built), so a
validated node equals the node built as it is. tests/test_ir_trusted.py builds every model under
tests/ and sample_models/ (and a synthetic one) both ways and compares `model_dump_json`,
`repr` and equality.

Skipping it matters twice: each node costs about half as much (there are tens of thousands at
10,000 states), and the IR classes defer building their validators (`defer_build`), so a
`validate` that builds every node here never builds them: about 15 ms of start-up that
`swarmgen validate` paid for nothing (docs/performance.md). A node made anywhere else (a test,
a library user, `model_validate`) is validated as before.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

from pydantic import BaseModel

# None: not decided (validate); True inside `ir.build`; False when a caller asks for validation.
_TRUSTED: ContextVar[bool | None] = ContextVar("swarmgen_ir_trusted", default=None)
_MISSING = object()
# per class: its fields in declaration order, each with its default (or _MISSING)
_FIELDS: dict[type[BaseModel], tuple[tuple[str, Any], ...]] = {}


def active() -> bool:
    """Whether nodes made now skip validation (inside `by_builder`, not under `validated`)."""
    return _TRUSTED.get() is True


@contextmanager
def by_builder() -> Iterator[None]:
    """Nodes made in this block are built as they are (`ir.build`), unless `validated` is on."""
    token = _TRUSTED.set(_TRUSTED.get() is not False)
    try:
        yield
    finally:
        _TRUSTED.reset(token)


@contextmanager
def validated() -> Iterator[None]:
    """Every node made in this block is validated, `ir.build`'s included (the tests' check)."""
    token = _TRUSTED.set(False)
    try:
        yield
    finally:
        _TRUSTED.reset(token)


def construct(node: BaseModel, data: dict[str, Any]) -> None:
    """Fill `node` with `data` as `model_construct` would (defaults for the fields not given,
    the given ones as the fields set), refusing unknown and missing fields as validation does."""
    cls = type(node)
    fields = _FIELDS.get(cls)
    if fields is None:
        fields = _FIELDS[cls] = _fields_of(cls)
    values = {}
    for name, default in fields:
        value = data.get(name, default)
        if value is _MISSING:
            raise TypeError(f"{cls.__name__}: missing field {name!r}")
        values[name] = value
    if not data.keys() <= values.keys():
        unknown = sorted(data.keys() - values.keys())
        raise TypeError(f"{cls.__name__}: unknown fields {unknown}")
    object.__setattr__(node, "__dict__", values)
    object.__setattr__(node, "__pydantic_fields_set__", set(data))
    object.__setattr__(node, "__pydantic_extra__", None)
    object.__setattr__(node, "__pydantic_private__", None)


def _fields_of(cls: type[BaseModel]) -> tuple[tuple[str, Any], ...]:
    found = []
    for name, info in cls.model_fields.items():
        if info.default_factory is not None:
            raise TypeError(f"{cls.__name__}.{name}: a default factory is not built here")
        found.append((name, _MISSING if info.is_required() else info.default))
    return tuple(found)
