"""IR and expression nodes made without pydantic when pydantic would take the values as given.

The nodes are frozen pydantic models (`ir.nodes.Node`, `expr.tree`'s `_Model`). Validating one
checks each field's value against its declared form and runs the field's validators; for a
value already of that form (a `str` for `str`, one of a `Literal`'s strings, a tuple of nodes
for `tuple[Node, ...]`, a node of a union's classes, an enumeration member) it keeps the value as
it is. `fill` checks exactly those forms in Python, runs the same validators (`AfterValidator`s
in the annotations, `field_validator`s in `after` mode) and fills the node as pydantic would:
the fields in declaration order, the defaults of the fields not given, the given ones as the
fields set. Anything else, a value of another form (a list for a tuple, a string for an
enumeration, an `int` for a `float`), a missing or unknown field, a validator that raises or
returns another value, a class with a form `fill` does not know, goes through pydantic's
validation as before, which converts it or raises its `ValidationError`. So every node is the
one validation makes; tests/test_fastnode.py builds every fixture model both ways and compares.

Why: the node classes defer building their pydantic validators (`defer_build`), and a
`validate` or `compile` whose nodes all take this path builds none of them, nor does pydantic
look for plugins (an `importlib.metadata` scan of every installed distribution): about a
tenth of `swarmgen validate` on the SAR sample (docs/performance.md).
"""

from __future__ import annotations

import enum
import types
import typing
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from pydantic import AfterValidator, BaseModel
from pydantic.fields import FieldInfo

Check = Callable[[Any], bool]  # True: the value passes validation unchanged
# per class: (field name, check, default or _REQUIRED) in declaration order, the field names;
# None when the class has a form `fill` does not reproduce (always validated then)
_Plan = tuple[tuple[tuple[str, Check, Any], ...], frozenset[str]]
_PLANS: dict[type[BaseModel], _Plan | None] = {}
_REQUIRED = object()
_set = object.__setattr__
_enabled = True


class _Unknown(Exception):
    """A declared form this module does not reproduce."""


def fill(node: BaseModel, data: dict[str, Any]) -> bool:
    """Fill `node` from `data` as pydantic's validation would, when every value passes as it
    is; False (nothing done) otherwise: the caller validates."""
    cls = type(node)
    if cls in _PLANS:
        plan = _PLANS[cls]
    else:
        plan = _PLANS[cls] = _plan_of(cls)
    if plan is None or not _enabled:
        return False
    fields, names = plan
    if not data.keys() <= names:
        return False
    values = {}
    for name, check, default in fields:
        if name in data:
            value = data[name]
            if not check(value):
                return False
        elif default is _REQUIRED:
            return False
        else:
            value = default
        values[name] = value
    _set(node, "__dict__", values)
    _set(node, "__pydantic_fields_set__", set(data))
    _set(node, "__pydantic_extra__", None)
    _set(node, "__pydantic_private__", None)
    return True


@contextmanager
def validating() -> Iterator[None]:
    """Every node made in this block goes through pydantic's validation (the tests' check)."""
    global _enabled
    before, _enabled = _enabled, False
    try:
        yield
    finally:
        _enabled = before


def _plan_of(cls: type[BaseModel]) -> _Plan | None:
    decorators = cls.__pydantic_decorators__
    if (
        decorators.model_validators
        or decorators.root_validators
        or decorators.validators
        or cls.model_post_init is not BaseModel.model_post_init
        or cls.__private_attributes__
        or cls.model_config.get("extra") != "forbid"
        or cls.model_config.get("revalidate_instances", "never") != "never"
    ):
        return None
    after: dict[str, list[Callable[[Any], Any]]] = {}
    for decorator in decorators.field_validators.values():
        if decorator.info.mode != "after":
            return None
        for name in decorator.info.fields:
            after.setdefault(name, []).append(decorator.func)
    try:
        hints = typing.get_type_hints(cls, include_extras=True)
    except Exception:  # a name only a type checker sees: pydantic resolves or reports it
        return None
    fields = []
    try:
        for name, info in cls.model_fields.items():
            if info.default_factory is not None or info.alias or not _known(info.metadata):
                return None  # a form the annotations alone do not give (constraints, aliases)
            check = _check(hints[name], after.get(name, []))
            fields.append((name, check, _REQUIRED if info.is_required() else info.default))
    except _Unknown:
        return None
    return tuple(fields), frozenset(cls.model_fields)


def _check(hint: Any, validators: list[Callable[[Any], Any]]) -> Check:
    """The check of one field: its form, then its validators (each must return the value)."""
    base = _form(hint)
    if not validators:
        return base
    return _validated(base, validators)


def _validated(base: Check, validators: list[Callable[[Any], Any]]) -> Check:
    def check(value: Any) -> bool:
        if not base(value):
            return False
        try:
            return all(validator(value) is value for validator in validators)
        except (ValueError, AssertionError):
            return False  # pydantic reports it: validated again, it raises ValidationError

    return check


def _form(hint: Any) -> Check:
    """A check that `value` is of the declared form exactly as validation keeps it."""
    origin = typing.get_origin(hint)
    if origin is typing.Annotated:
        base, *extras = typing.get_args(hint)
        validators = []
        for extra in extras:
            if isinstance(extra, AfterValidator):
                validators.append(extra.func)
            elif not (isinstance(extra, FieldInfo) and _only_discriminator(extra)):
                raise _Unknown(extra)
        return _check(base, validators)  # type: ignore[arg-type]
    if origin is typing.Literal:
        allowed = frozenset((type(a), a) for a in typing.get_args(hint))
        return lambda value: (type(value), value) in allowed
    if origin in (typing.Union, types.UnionType):
        return _union(typing.get_args(hint))
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) != 2 or args[1] is not Ellipsis:
            raise _Unknown(hint)
        item = _form(args[0])
        return lambda value: type(value) is tuple and all(item(v) for v in value)
    if hint is type(None):
        return lambda value: value is None
    if hint in (str, int, float, bool):
        return lambda value: type(value) is hint
    if isinstance(hint, type) and issubclass(hint, enum.Enum):
        return lambda value: type(value) is hint
    if isinstance(hint, type) and (issubclass(hint, BaseModel) or _is_dataclass(hint)):
        return lambda value: isinstance(value, hint)
    raise _Unknown(hint)


_PLAIN = (str, int, float, bool, type(None))


def _union(members: tuple[Any, ...]) -> Check:
    # A value of one member's exact type is kept as it is by pydantic's smart union; the
    # discriminated unions' members are node classes, told apart by class.
    plain = frozenset(m for m in members if m in _PLAIN)
    nodes = tuple(m for m in members if isinstance(m, type) and issubclass(m, BaseModel))
    others = [_form(m) for m in members if m not in plain and m not in nodes]

    def check(value: Any) -> bool:
        return (
            type(value) in plain
            or (bool(nodes) and isinstance(value, nodes))
            or any(other(value) for other in others)
        )

    return check


def _only_discriminator(info: FieldInfo) -> bool:
    return info.discriminator is not None and not info.metadata


def _known(metadata: list[Any]) -> bool:
    """A field's collected metadata holds only what its annotation shows (`_form` reads it)."""
    return all(isinstance(m, AfterValidator) for m in metadata)


def _is_dataclass(cls: type) -> bool:
    return hasattr(cls, "__dataclass_fields__")
