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
# `Node.__init__` reads it directly (one look-up per node).
ACTIVE: ContextVar[bool | None] = ContextVar("swarmgen_ir_trusted", default=None)
# per class: its field names in declaration order, the set of them, the optional ones' defaults
_Spec = tuple[tuple[str, ...], frozenset[str], dict[str, Any]]
_SPECS: dict[type[BaseModel], _Spec] = {}
_set = object.__setattr__


def active() -> bool:
    """Whether nodes made now skip validation (inside `by_builder`, not under `validated`)."""
    return ACTIVE.get() is True


@contextmanager
def by_builder() -> Iterator[None]:
    """Nodes made in this block are built as they are (`ir.build`), unless `validated` is on."""
    token = ACTIVE.set(ACTIVE.get() is not False)
    try:
        yield
    finally:
        ACTIVE.reset(token)


@contextmanager
def validated() -> Iterator[None]:
    """Every node made in this block is validated, `ir.build`'s included (the tests' check)."""
    token = ACTIVE.set(False)
    try:
        yield
    finally:
        ACTIVE.reset(token)


def construct(node: BaseModel, data: dict[str, Any]) -> None:
    """Fill `node` with `data` as `model_construct` would (defaults for the fields not given,
    the given ones as the fields set), refusing unknown and missing fields as validation does."""
    cls = type(node)
    spec = _SPECS.get(cls)
    if spec is None:
        spec = _SPECS[cls] = _spec_of(cls)
    names, known, defaults = spec
    if not data.keys() <= known:
        raise TypeError(f"{cls.__name__}: unknown fields {sorted(data.keys() - known)}")
    try:
        values = {name: data[name] if name in data else defaults[name] for name in names}
    except KeyError as missing:
        raise TypeError(f"{cls.__name__}: missing field {missing}") from None
    _set(node, "__dict__", values)
    _set(node, "__pydantic_fields_set__", set(data))
    _set(node, "__pydantic_extra__", None)
    _set(node, "__pydantic_private__", None)


def _spec_of(cls: type[BaseModel]) -> _Spec:
    defaults = {}
    for name, info in cls.model_fields.items():
        if info.default_factory is not None:
            raise TypeError(f"{cls.__name__}.{name}: a default factory is not built here")
        if not info.is_required():
            defaults[name] = info.default
    names = tuple(cls.model_fields)
    return names, frozenset(names), defaults
