"""A reader of rosidl interface definitions (`.msg`, `.srv`, `.action` text) into typed data.

It follows rosidl_adapter's grammar: `#` starts a comment anywhere on a line; a line is
`TYPE NAME [DEFAULT]` (a field) or `TYPE NAME=VALUE` (a constant); a `.srv` has two sections
(request `---` response), an `.action` three (goal `---` result `---` feedback). A nested type
is `pkg/Name`, or `Name` in the definition's own package (ROS 2 has no special `Header`: write
`std_msgs/Header`). Errors are data (`IdlError` with line and column), never an exception.
"""

from __future__ import annotations

import re
from typing import Literal

from swarmgen.records import dataclass

Kind = Literal["msg", "srv", "action"]
KINDS: tuple[Kind, ...] = ("msg", "srv", "action")
SECTIONS: dict[Kind, tuple[str, ...]] = {
    "msg": ("message",),
    "srv": ("request", "response"),
    "action": ("goal", "result", "feedback"),
}
INTEGERS = frozenset(
    {"byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
)
FLOATS = frozenset({"float32", "float64"})
STRINGS = frozenset({"string", "wstring"})
PRIMITIVES = INTEGERS | FLOATS | STRINGS | {"bool"}
_RANGES = {
    "byte": (0, 255), "char": (0, 255), "int8": (-(2**7), 2**7 - 1), "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1), "uint16": (0, 2**16 - 1), "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1), "int64": (-(2**63), 2**63 - 1), "uint64": (0, 2**64 - 1),
}  # fmt: skip
# rosidl_adapter's name patterns (the same as swarmgen.ros.idl_names, plus constants).
_PACKAGE = re.compile(r"(?!.*__)(?!.*_$)[a-z][a-z0-9_]*")
_FIELD = _PACKAGE
_TYPE = re.compile(r"[A-Z][A-Za-z0-9]*")
_CONSTANT = re.compile(r"[A-Z]([A-Z0-9_]?[A-Z0-9]+)*")
_BOUND = re.compile(r"<=(\d+)")
MAX_LINES = 10_000  # no real definition comes close; bounds the work a hostile file asks for


@dataclass(frozen=True)
class TypeRef:
    """A field's base type: a primitive (`package` None) or a message `package/name`."""

    name: str
    package: str | None = None
    string_bound: int | None = None  # `string<=N`

    @property
    def primitive(self) -> bool:
        """Whether it is a primitive type (bool, a number, a string)."""
        return self.package is None

    @property
    def key(self) -> str:
        """`pkg/msg/Name` for a message, the primitive's name otherwise."""
        return self.name if self.package is None else f"{self.package}/msg/{self.name}"

    def text(self) -> str:
        """The type as a definition writes it (`string<=8`, `geometry_msgs/Pose`)."""
        if self.package is not None:
            return f"{self.package}/{self.name}"
        return self.name if self.string_bound is None else f"{self.name}<={self.string_bound}"


@dataclass(frozen=True)
class Field:
    """One field: `type name [default]`, possibly an array (`T[]`, `T[N]`, `T[<=N]`)."""

    name: str
    type: TypeRef
    array: bool
    bound: int | None  # the array's size (fixed) or upper bound (`bounded`)
    bounded: bool
    default: str | None
    line: int
    text: str  # the source line, for quoting in diagnostics


@dataclass(frozen=True)
class Constant:
    """One constant: `TYPE NAME=VALUE` (a primitive type)."""

    name: str
    type: TypeRef
    value: str
    line: int
    text: str


@dataclass(frozen=True)
class Section:
    """One part of a definition: a message, a request or response, a goal, result or feedback."""

    name: str
    fields: tuple[Field, ...]
    constants: tuple[Constant, ...]
    line: int  # first line of the section (the line after its `---`)

    def field(self, name: str) -> Field | None:
        """The field called `name`, if any."""
        return next((f for f in self.fields if f.name == name), None)


@dataclass(frozen=True)
class InterfaceDef:
    """A parsed definition: its kind, package, name, sections (in order) and file."""

    kind: Kind
    package: str
    name: str
    sections: tuple[Section, ...]
    file: str

    @property
    def key(self) -> str:
        """`pkg/kind/Name`."""
        return f"{self.package}/{self.kind}/{self.name}"

    def section(self, name: str) -> Section:
        """The section called `name` (`goal`, `response`, ...); KeyError for another kind's."""
        for section in self.sections:
            if section.name == name:
                return section
        raise KeyError(name)


@dataclass(frozen=True)
class IdlError:
    """Why a definition file could not be read, at 1-based line and column (0: the file)."""

    file: str
    line: int
    col: int
    error: str

    def location(self) -> str:
        """`file:line:col`."""
        return f"{self.file}:{self.line}:{max(self.col, 1)}" if self.line else self.file


class _Bad(Exception):
    """A syntax error at a column of the current line (internal; never leaves this module)."""

    def __init__(self, col: int, error: str) -> None:
        super().__init__(error)
        self.col, self.error = col, error


def parse(text: str, *, package: str, name: str, kind: Kind, file: str) -> InterfaceDef | IdlError:
    """The definition of `package/kind/name` in `text`, or the first error found in it."""
    if not _PACKAGE.fullmatch(package):
        return IdlError(file, 0, 0, f"package name {package!r} is not a valid ROS package name")
    if not _TYPE.fullmatch(name):
        return IdlError(
            file, 0, 0, f"type name {name!r} is not CamelCase (rosidl: [A-Z][A-Za-z0-9]*)"
        )
    lines = text.replace("\t", " ").splitlines()
    if len(lines) > MAX_LINES:
        return IdlError(file, MAX_LINES + 1, 1, f"more than {MAX_LINES:,} lines")
    names = SECTIONS[kind]
    sections: list[Section] = []
    body: list[tuple[int, str]] = []
    start = 1
    for number, line in enumerate(lines, start=1):
        if line.rstrip() == "---":
            if len(sections) + 1 >= len(names):
                return IdlError(file, number, 1, _separators(kind))
            section = _section(names[len(sections)], body, start, package, file)
            if isinstance(section, IdlError):
                return section
            sections.append(section)
            body, start = [], number + 1
            continue
        body.append((number, line))
    last = _section(names[len(sections)], body, start, package, file)
    if isinstance(last, IdlError):
        return last
    sections.append(last)
    if len(sections) != len(names):
        return IdlError(file, len(lines), 1, _separators(kind))
    return InterfaceDef(kind, package, name, tuple(sections), file)


def _separators(kind: Kind) -> str:
    count = len(SECTIONS[kind]) - 1
    parts = " --- ".join(SECTIONS[kind])
    return f"a .{kind} file has exactly {count} `---` separator(s) ({parts})"


def _section(
    name: str, body: list[tuple[int, str]], start: int, package: str, file: str
) -> Section | IdlError:
    fields: list[Field] = []
    constants: list[Constant] = []
    seen: set[str] = set()
    for number, raw in body:
        line = raw.split("#", 1)[0].rstrip()
        if not line.strip():
            continue
        try:
            item = _item(line, number, raw.rstrip(), package)
        except _Bad as bad:
            return IdlError(file, number, bad.col, bad.error)
        if item.name in seen:
            return IdlError(
                file, number, raw.find(item.name) + 1, f"{item.name!r} is defined twice"
            )
        seen.add(item.name)
        (constants if isinstance(item, Constant) else fields).append(item)  # type: ignore[arg-type]
    return Section(name, tuple(fields), tuple(constants), start)


def _item(line: str, number: int, text: str, package: str) -> Field | Constant:
    indent = len(line) - len(line.lstrip())
    type_text, _, rest = line.strip().partition(" ")
    rest_col = indent + len(type_text) + 1 + (len(rest) - len(rest.lstrip())) + 1
    rest = rest.strip()
    if not rest:
        raise _Bad(indent + 1, f"expected `TYPE NAME`, got {line.strip()!r}")
    base, array, bound, bounded = _array(type_text, indent + 1)
    type_ = _base(base, package, indent + 1)
    if "=" in rest:
        cname, _, value = (part.strip() for part in rest.partition("="))
        if not _CONSTANT.fullmatch(cname):
            raise _Bad(rest_col, f"constant name {cname!r} is not UPPER_CASE")
        if not type_.primitive or array:
            raise _Bad(indent + 1, f"a constant has a primitive, non-array type, not {type_text!r}")
        _check_value(type_, value, rest_col)
        return Constant(cname, type_, value, number, text)
    fname, _, default_text = rest.partition(" ")
    if not _FIELD.fullmatch(fname):
        raise _Bad(
            rest_col,
            f"field name {fname!r} is not lower snake case (rosidl: [a-z][a-z0-9_]*, no `__`)",
        )
    default = default_text.strip() or None
    if default is not None:
        if not type_.primitive:
            raise _Bad(rest_col + len(fname) + 1, "only primitive fields have default values")
        if not array:
            _check_value(type_, default, rest_col + len(fname) + 1)
    return Field(fname, type_, array, bound, bounded, default, number, text)


def _array(text: str, col: int) -> tuple[str, bool, int | None, bool]:
    if not text.endswith("]"):
        return text, False, None, False
    opening = text.rfind("[")
    if opening <= 0:
        raise _Bad(col, f"array type {text!r} has no element type or no `[`")
    inside = text[opening + 1 : -1]
    if inside == "":
        return text[:opening], True, None, False
    bounded = inside.startswith("<=")
    digits = inside[2:] if bounded else inside
    if not digits.isdigit() or int(digits) <= 0 or len(digits) > 9:
        raise _Bad(
            col + opening + 1, f"array bound {inside!r} must be a positive integer (or `<=N`)"
        )
    return text[:opening], True, int(digits), bounded


def _base(text: str, package: str, col: int) -> TypeRef:
    if text in PRIMITIVES:
        return TypeRef(text)
    for prefix in ("string", "wstring"):
        if text.startswith(prefix + "<="):
            bound = _BOUND.fullmatch(text[len(prefix) :])
            if bound is None or int(bound.group(1)) <= 0 or len(bound.group(1)) > 9:
                raise _Bad(col, f"string bound in {text!r} must be a positive integer")
            return TypeRef(prefix, string_bound=int(bound.group(1)))
    parts = text.split("/")
    if len(parts) == 1:
        pkg, name = package, parts[0]
    elif len(parts) == 2:
        pkg, name = parts
    else:
        raise _Bad(col, f"unknown type {text!r}")
    if not _PACKAGE.fullmatch(pkg) or not _TYPE.fullmatch(name):
        raise _Bad(
            col, f"unknown type {text!r} (not a primitive type, nor `pkg/Name` of a message)"
        )
    return TypeRef(name, pkg)


def _check_value(type_: TypeRef, value: str, col: int) -> None:
    """A constant's or default's value must be one its type can hold (strings: any text)."""
    if type_.name in STRINGS:
        return
    if not value:
        raise _Bad(col, "missing value")
    if type_.name == "bool":
        if value.lower() not in {"true", "false", "1", "0"}:
            raise _Bad(col, f"{value!r} is not a bool (true, false, 1, 0)")
        return
    try:
        number = float(value) if type_.name in FLOATS else int(value, 0)
    except ValueError:
        raise _Bad(col, f"{value!r} is not a valid {type_.name}") from None
    low, high = _RANGES.get(type_.name, (None, None))
    if low is not None and high is not None and not low <= number <= high:
        raise _Bad(col, f"{value} is out of range for {type_.name} ({low}..{high})")
