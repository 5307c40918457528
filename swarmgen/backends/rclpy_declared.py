"""Declared ROS interfaces in the rclpy output: which behaviours run on the type their model
declares (`rosKind`/`rosName`/`rosType`, resolved by `ros.idl_bind` in the same index the check
used), the `Binding(...)` literal of their spec, and the interface packages the workspace must
build for types found only in the user's interface directories (docs/ros2.md, "The rclpy
backend on declared interfaces").

A behaviour binds exactly when `idl_bind.bind` gives a binding, the decision the check reports
on (every input and output maps to a field of a converting type); data type keys that are not
ROS field names (`posX`) travel renamed (`Binding.renames`, applied by the runtime both ways).
Anything else keeps the generated private action, as before.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import PurePosixPath

from swarmgen.ir.nodes import Behaviour, Model
from swarmgen.names import one_line, ros_name
from swarmgen.records import dataclass
from swarmgen.ros.idl import InterfaceDef
from swarmgen.ros.idl_bind import Binding, Renames, bind
from swarmgen.ros.idl_index import InterfaceIndex
from swarmgen.ros.interfaces import render_user_package

# The parameter the runtime declares per binding (`bindings.resolve`, `goals.py` for actions).
TIMEOUT_PARAMETER = "behaviours.{key}.timeout_s"
_MAX_DEPTH = 32
# `enum_blanks`: a first literal, or (model key, blanks) pairs of a data type's fields
Blanks = str | tuple[tuple[str, "Blanks"], ...]


@dataclass(frozen=True)
class Declared:
    """A behaviour bound to its declared type, with the parameter key the runtime uses."""

    binding: Binding
    key: str  # `behaviours.<key>.*` (ros_name of the behaviour's name)
    inputs: tuple[tuple[str, str], ...]  # (input identifier, field path)
    outputs: tuple[tuple[str, str], ...]  # (field path, output identifier)
    renames: tuple[tuple[str, str, Renames], ...] = ()  # (input|output, identifier, renames)
    enums: tuple[tuple[str, Blanks], ...] = ()  # (output identifier, `enum_blanks`)

    @property
    def triple(self) -> tuple[str, str, str]:
        """(package, msg|srv|action, Name)."""
        return (self.binding.package, self.binding.interface, self.binding.name)

    def literal(self, ros_name_: str) -> str:
        """The `Binding(...)` literal of generated code (model text only as repr())."""
        b = self.binding
        direction = "" if b.direction == "call" else b.direction
        return (
            f"Binding(kind={b.kind!r}, type={self.triple!r}, ros_name={ros_name_!r}, "
            f"inputs={self.inputs!r}, outputs={self.outputs!r}, "
            f"outcome={b.outcome_field or ''!r}, direction={direction!r}, key={self.key!r}"
            f"{f', renames={self.renames!r}' if self.renames else ''}"
            f"{f', enums={self.enums!r}' if self.enums else ''})"
        )

    @property
    def timeout_parameter(self) -> str | None:
        """The ROS parameter the runtime declares for this binding (every kind)."""
        return TIMEOUT_PARAMETER.format(key=self.key)


def declared_bindings(
    model: Model, names: Iterable[str], index: InterfaceIndex | None, reserved: Iterable[str]
) -> dict[str, Declared]:
    """The behaviours of `names` (model names) that run on their declared type; none without
    an index. A type in a package named like one of `reserved` (the workspace's own packages)
    is not bound."""
    if index is None:
        return {}
    behaviours = {b.name: b for b in model.behaviours}
    taken = set(reserved)
    found: dict[str, Declared] = {}
    for name in names:
        behaviour = behaviours.get(name)
        if behaviour is None:
            continue
        binding = bind(behaviour, index, model.datatypes, model.enumerations)
        if binding is None or binding.package in taken:
            continue
        found[name] = _declared(behaviour, binding, model)
    return found


def _declared(behaviour: Behaviour, binding: Binding, model: Model) -> Declared:
    idents = {p.name: p.ident for p in (*behaviour.inputs, *behaviour.outputs)}
    enums = tuple(
        (p.ident, blanks)
        for p in behaviour.outputs
        if (blanks := enum_blanks(p.type, model)) and p.name in dict(binding.outputs).values()
    )
    return Declared(
        binding,
        ros_name(behaviour.name),
        tuple((idents[name], path) for name, path in binding.inputs),
        tuple((path, idents[name]) for path, name in binding.outputs),
        tuple((side, idents[name], tree) for side, name, tree in binding.renames),
        enums,
    )


def enum_blanks(type_name: str | None, model: Model, depth: int = 0) -> Blanks:
    """Where a value of `type_name` holds enumeration values, for the runtime's
    `convert.filled`: an enumeration's first literal, or (model key, blanks) pairs of the
    data type fields that hold some (recursively); () for none (the value rule: an empty
    string read from ROS is the enumeration's zero, its first literal)."""
    enumeration = next((e for e in model.enumerations if e.name == type_name), None)
    if enumeration is not None:
        return enumeration.literals[0] if enumeration.literals else ()
    datatype = next((d for d in model.datatypes if d.name == type_name), None)
    if datatype is None or depth >= _MAX_DEPTH:  # SG150 refuses a type containing itself
        return ()
    return tuple(
        (f.name, inner) for f in datatype.fields if (inner := enum_blanks(f.type, model, depth + 1))
    )


def user_definitions(
    declared: Iterable[Declared], index: InterfaceIndex
) -> dict[str, dict[PurePosixPath, InterfaceDef]]:
    """package -> its definitions the bindings use that a user directory defines (the same
    text as the one resolved), so the workspace builds them. Decided by the user directories,
    not by what happens to be installed, so the output does not depend on earlier builds."""
    found: dict[str, dict[PurePosixPath, InterfaceDef]] = {}
    for item in declared:
        for definition in item.binding.definitions.values():
            if _in_user_root(definition, index):
                path = PurePosixPath(definition.kind, f"{definition.name}.{definition.kind}")
                found.setdefault(definition.package, {})[path] = definition
    return {package: dict(sorted(found[package].items())) for package in sorted(found)}


def _in_user_root(definition: InterfaceDef, index: InterfaceIndex) -> bool:
    """Whether a user directory defines it, as the index read it for the check (no new look
    at the disk): the first definition is the user's, or an installed one with its text."""
    loaded = index.load(definition.package, definition.kind, definition.name)
    return loaded.origin == "user" or loaded.user_copy


def user_packages(
    declared: Iterable[Declared], index: InterfaceIndex
) -> dict[str, dict[PurePosixPath, str]]:
    """The files of every user interface package the bindings need, by package name."""
    packages: dict[str, dict[PurePosixPath, str]] = {}
    for package, definitions in user_definitions(declared, index).items():
        texts = {path: _text(d, index) for path, d in definitions.items()}
        dependencies = {
            item.type.package
            for d in definitions.values()
            for section in d.sections
            for item in section.fields
            if not item.type.primitive and item.type.package
        }
        description = one_line(f"ROS 2 interfaces {package} (user definitions, built by swarmgen)")
        packages[package] = render_user_package(package, texts, dependencies, description)
    return packages


def _text(definition: InterfaceDef, index: InterfaceIndex) -> str:
    """The definition's text as the index read it for the check (memoised there): a file that
    changed or vanished since then cannot make the workspace differ from what was checked."""
    return index.load(definition.package, definition.kind, definition.name).text


def exec_depends(declared: Iterable[Declared], own: Iterable[str]) -> list[str]:
    """The interface packages the node package runs against, besides its own ones."""
    packages = {d.package for item in declared for d in item.binding.definitions.values()}
    return sorted(packages - set(own))
