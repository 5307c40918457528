"""The model's primitive types, in one table: their aliases, zeros and Python types.

UML tools spell the primitives several ways (`Real`, `Double`, `Float`; `Integer`, `Int`, `Long`,
`UnlimitedNatural`; `Boolean`, `Bool`; `String`), in any case and with stray spaces. Every stage
that asks "is this a primitive, and which?" asks `primitive()`, so they cannot disagree. The
vendored runtimes (`swarmgen/runtime`, `swarmgen/ros/runtime`) do not import it: they see values,
not type names.
"""

from __future__ import annotations

from enum import StrEnum
from types import MappingProxyType


class Primitive(StrEnum):
    """A primitive type of the model, by its UML name."""

    REAL = "Real"
    INTEGER = "Integer"
    BOOLEAN = "Boolean"
    STRING = "String"

    @property
    def zero(self) -> bool | int | float | str:
        """The value an item of this type holds when nothing gave it one."""
        return _ZEROS[self]

    @property
    def python(self) -> str:
        """The Python type's name (`float`, `int`, `bool`, `str`)."""
        return _PYTHON[self]


ALIASES = MappingProxyType(
    {
        "real": Primitive.REAL,
        "double": Primitive.REAL,
        "float": Primitive.REAL,
        "integer": Primitive.INTEGER,
        "int": Primitive.INTEGER,
        "long": Primitive.INTEGER,
        "unlimitednatural": Primitive.INTEGER,
        "boolean": Primitive.BOOLEAN,
        "bool": Primitive.BOOLEAN,
        "string": Primitive.STRING,
    }
)
_ZEROS: dict[Primitive, bool | int | float | str] = {
    Primitive.REAL: 0.0,
    Primitive.INTEGER: 0,
    Primitive.BOOLEAN: False,
    Primitive.STRING: "",
}
_PYTHON = {
    Primitive.REAL: "float",
    Primitive.INTEGER: "int",
    Primitive.BOOLEAN: "bool",
    Primitive.STRING: "str",
}


def primitive(type_name: str | None) -> Primitive | None:
    """The primitive a type name denotes (case and surrounding spaces ignored), else None (no
    type, a data type, an enumeration, an unknown name)."""
    if type_name is None:
        return None
    return ALIASES.get(type_name.strip().lower())


def zero_of(type_name: str | None) -> bool | int | float | str | None:
    """The zero of a primitive type name; None for anything else."""
    found = primitive(type_name)
    return None if found is None else found.zero
