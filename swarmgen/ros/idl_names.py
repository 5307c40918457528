"""rosidl's rules for the names of packages, messages, actions and fields: every name that
reaches CMake, XML or a path is checked against them, so text from a model can never inject
CMake commands or XML."""

from __future__ import annotations

import keyword
import re

# rosidl's own patterns (rosidl_adapter.parser): no `__`, no trailing `_` in package and field
# names; message names are CamelCase without underscores.
_PACKAGE_NAME = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
_FIELD_NAME = _PACKAGE_NAME
_TYPE_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*$")
# Field names that rosidl accepts but that break the generated Python, C or C++ code, or the
# IDL that rosidl converts .msg files to.
_RESERVED_FIELDS = frozenset(keyword.kwlist) | {
    "alignas", "alignof", "and_eq", "asm", "auto", "bitand", "bitor", "bool", "case", "catch",
    "char", "class", "compl", "const", "constexpr", "const_cast", "decltype", "default", "delete",
    "do", "double", "dynamic_cast", "enum", "explicit", "export", "extern", "float", "friend",
    "goto", "inline", "int", "long", "mutable", "namespace", "new", "noexcept", "not_eq",
    "nullptr", "operator", "or_eq", "private", "protected", "public", "register",
    "reinterpret_cast", "short", "signed", "sizeof", "static", "static_assert", "static_cast",
    "struct", "switch", "template", "this", "thread_local", "throw", "typedef", "typeid",
    "typename", "union", "unsigned", "using", "virtual", "void", "volatile", "wchar_t", "xor",
    "xor_eq", "and", "not", "or", "any", "bitfield", "bitmask", "bitset", "boolean", "fixed",
    "map", "module", "native", "octet", "sequence", "string", "wchar", "wstring",
}  # fmt: skip


def _check(pattern: re.Pattern[str], name: str, what: str) -> str:
    if not isinstance(name, str) or not pattern.fullmatch(name):
        raise ValueError(f"invalid ROS {what} name {name!r} (must match {pattern.pattern})")
    return name


def check_package_name(name: str) -> str:
    """`name` if it is a valid ROS package name, else ValueError."""
    return _check(_PACKAGE_NAME, name, "package")


def check_type_name(name: str) -> str:
    """`name` if it is a valid ROS message/action name (CamelCase), else ValueError."""
    return _check(_TYPE_NAME, name, "message/action")


def check_field_name(name: str) -> str:
    """`name` if it is a valid, non-reserved ROS field name, else ValueError."""
    _check(_FIELD_NAME, name, "field")
    if name in _RESERVED_FIELDS:
        raise ValueError(f"invalid ROS field name {name!r}: reserved in Python, C++ or IDL")
    return name
