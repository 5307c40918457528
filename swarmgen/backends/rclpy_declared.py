"""Declared ROS interfaces in the rclpy output: which behaviours run on the type their model
declares (`rosKind`/`rosName`/`rosType`, resolved by `ros.idl_bind` in the same index the check
used), the `Binding(...)` literal of their spec, and the interface packages the workspace must
build for types found only in the user's interface directories (docs/ros2.md, "The rclpy
backend on declared interfaces").

A behaviour binds when `idl_bind.bind` gives a binding (every input and output maps to a field
of a converting type) and its data type values can travel as they are (every field name of a
data type it carries is already the ROS field name: the runtime passes the dicts unchanged).
Anything else keeps the generated private action, as before.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from swarmgen.inputs import InputRefused, read_limited
from swarmgen.ir.nodes import Behaviour, DataType, Model
from swarmgen.names import one_line, ros_name
from swarmgen.ros.idl import InterfaceDef
from swarmgen.ros.idl_bind import Binding, bind
from swarmgen.ros.idl_index import MAX_FILE, InterfaceIndex
from swarmgen.ros.interfaces import render_user_package

# The parameter the runtime declares per service and topic binding (`bindings.resolve`).
TIMEOUT_PARAMETER = "behaviours.{key}.timeout_s"


@dataclass(frozen=True)
class Declared:
    """A behaviour bound to its declared type, with the parameter key the runtime uses."""

    binding: Binding
    key: str  # `behaviours.<key>.*` (ros_name of the behaviour's name)
    inputs: tuple[tuple[str, str], ...]  # (input identifier, field path)
    outputs: tuple[tuple[str, str], ...]  # (field path, output identifier)

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
            f"outcome={b.outcome_field or ''!r}, direction={direction!r}, key={self.key!r})"
        )

    @property
    def timeout_parameter(self) -> str | None:
        """The ROS parameter the runtime declares for this binding (None for actions)."""
        if self.binding.kind == "action":
            return None
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
    datatypes = {d.name: d for d in model.datatypes}
    taken = set(reserved)
    found: dict[str, Declared] = {}
    for name in names:
        behaviour = behaviours.get(name)
        if behaviour is None:
            continue
        binding = bind(behaviour, index, model.datatypes, model.enumerations)
        if binding is None or binding.package in taken:
            continue
        if not all(
            _travels(p.type, datatypes, ()) for p in (*behaviour.inputs, *behaviour.outputs)
        ):
            continue
        found[name] = _declared(behaviour, binding)
    return found


def _declared(behaviour: Behaviour, binding: Binding) -> Declared:
    idents = {p.name: p.ident for p in (*behaviour.inputs, *behaviour.outputs)}
    return Declared(
        binding,
        ros_name(behaviour.name),
        tuple((idents[name], path) for name, path in binding.inputs),
        tuple((path, idents[name]) for path, name in binding.outputs),
    )


def _travels(
    type_name: str | None, datatypes: Mapping[str, DataType], seen: tuple[str, ...]
) -> bool:
    """A value of `type_name` reaches the message as it is: a data type's field names (its
    dict keys at run time) are the ROS field names, recursively."""
    datatype = datatypes.get((type_name or "").strip())
    if datatype is None or datatype.name in seen:
        return True
    return all(
        f.name == ros_name(f.name) and _travels(f.type, datatypes, (*seen, datatype.name))
        for f in datatype.fields
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


def _user_file(definition: InterfaceDef, index: InterfaceIndex) -> Path | None:
    relative = Path(definition.package, definition.kind, f"{definition.name}.{definition.kind}")
    for root in index.roots:
        if root.origin == "user" and (root.path / relative).is_file():
            return root.path / relative
    return None


def _in_user_root(definition: InterfaceDef, index: InterfaceIndex) -> bool:
    path = _user_file(definition, index)
    if path is None:
        return False
    loaded = index.load(definition.package, definition.kind, definition.name)
    # the first definition is the user's, or an installed one with the same text (SG309 else)
    return loaded.origin == "user" or str(path) not in loaded.differs


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
    """The user's file as it is (it was read and parsed already: size and encoding hold)."""
    path = _user_file(definition, index)
    assert path is not None
    try:
        return read_limited(path, MAX_FILE).decode("utf-8")
    except (InputRefused, OSError, UnicodeDecodeError) as err:  # changed since it was checked
        raise ValueError(f"{path}: cannot read the definition again: {err}") from None


def exec_depends(declared: Iterable[Declared], own: Iterable[str]) -> list[str]:
    """The interface packages the node package runs against, besides its own ones."""
    packages = {d.package for item in declared for d in item.binding.definitions.values()}
    return sorted(packages - set(own))
