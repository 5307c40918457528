"""Model data types as messages of the private interface package (docs/ros2.md, "Data types
as messages of the private interface package"): the `.msg` of each data type a private action
carries, its field type (`swarm_interfaces/Pose`, or a «RosMessage»'s own `geometry_msgs/Pose`),
the renames of its model keys that the message's field names spell otherwise, and where its
values hold enumerations (`Field.enums`: empty strings read back as the first literal)."""

from __future__ import annotations

import re
from collections.abc import Collection, Iterable
from dataclasses import field

from swarmgen.backends.rclpy_declared import Blanks, enum_blanks
from swarmgen.ir.nodes import DataType, Model
from swarmgen.names import identifier, one_line, ros_name
from swarmgen.records import dataclass
from swarmgen.ros.idl_bind import Renames, renames_of
from swarmgen.ros.interfaces import (
    check_field_name,
    check_package_name,
    check_type_name,
    interface_type,
)


def field_name(name: str, taken: set[str]) -> str:
    """A model name as a ROS field name not in `taken` (added to it): `ros_name`, then with
    `_value` (a keyword such as `class`) or a number appended."""
    base = ros_name(name)
    for candidate in (base, f"{base}_value", *(f"{base}_{n}" for n in range(2, 100))):
        try:
            check_field_name(candidate)
        except ValueError:
            continue
        if candidate not in taken:
            taken.add(candidate)
            return candidate
    raise ValueError(f"no ROS field name for {name!r}")


def camel(name: str) -> str:
    """A CamelCase ROS type name for a model name (`go to` -> `GoTo`; `B...` if no letter)."""
    parts = re.split(r"[^0-9A-Za-z]+", identifier(name))
    text = "".join(p[:1].upper() + p[1:] for p in parts if p)
    return text if text[:1].isalpha() else f"B{text}"


@dataclass(frozen=True)
class DataMessages:
    """The data types the private actions carry, as messages."""

    types: dict[str, str] = field(default_factory=dict)  # data type name -> field type
    texts: dict[str, str] = field(default_factory=dict)  # message name -> its .msg text
    renames: dict[str, Renames] = field(default_factory=dict)  # data type name -> renames
    # data type name -> its enumeration fields (`enum_blanks`), only those that have some
    enums: dict[str, Blanks] = field(default_factory=dict)

    def packages(self, own: Collection[str]) -> set[str]:
        """The packages of «RosMessage» types used, besides `own`."""
        return {t.split("/")[0] for t in self.types.values()} - set(own)


def declared_message(ros_type: str | None) -> str | None:
    """A «RosMessage» rosType (`pkg/msg/Name` or `pkg/Name`) as a field type `pkg/Name`; None
    when it is no valid message name (the data type then gets a message of its own)."""
    parts = (ros_type or "").strip().split("/")
    if len(parts) == 3 and parts[1] == "msg":
        parts = [parts[0], parts[2]]
    if len(parts) != 2:
        return None
    try:
        return f"{check_package_name(parts[0])}/{check_type_name(parts[1])}"
    except ValueError:
        return None


def _reachable(datatypes: dict[str, DataType], used: Iterable[str | None]) -> list[str]:
    """The data types `used` names and those their generated messages nest, sorted."""
    pending = sorted({t for t in used if t is not None and t in datatypes})
    seen: set[str] = set()
    while pending:
        name = pending.pop()
        if name in seen:
            continue
        seen.add(name)
        if declared_message(datatypes[name].ros_type) is None:  # a «RosMessage» nests its own
            pending += [s.type for s in datatypes[name].fields if s.type in datatypes]
    return sorted(seen)


def data_messages(
    model: Model, package: str, used: Iterable[str | None], taken: Collection[str]
) -> DataMessages:
    """The messages of the data types `used` (private action fields' types), named clear of
    `taken` (Event, ActiveStates, the actions) with a number (`Pose2`) on collision."""
    datatypes = {d.name: d for d in model.datatypes}
    enums = {e.name for e in model.enumerations}
    names = set(taken)
    found = DataMessages()
    order = _reachable(datatypes, used)
    for name in order:
        declared = declared_message(datatypes[name].ros_type)
        if declared is None:
            base = camel(datatypes[name].ident or name)
            candidate, n = base, 2
            while candidate in names:
                candidate, n = f"{base}{n}", n + 1
            names.add(candidate)
            declared = f"{package}/{candidate}"
        found.types[name] = declared
    for name in order:
        _render(datatypes, name, found, enums)
        blanks = enum_blanks(name, model)
        if blanks:  # a message field left empty decodes as the first literal, not as ""
            found.enums[name] = blanks
    return found


def _render(
    datatypes: dict[str, DataType],
    name: str,
    found: DataMessages,
    enums: Collection[str],
) -> Renames:
    """The renames of data type `name`, rendering its .msg first when it is a generated one."""
    if name in found.renames:
        return found.renames[name]
    message = found.types[name].split("/")[1]
    datatype = datatypes[name]
    if declared_message(datatype.ros_type) is not None:
        found.renames[name] = renames_of(name, datatypes, ())
        return found.renames[name]
    taken: set[str] = set()
    lines = [f"# The model's data type {one_line(datatype.name)}."]
    renames: list[tuple[str, str, Renames]] = []
    for sub in datatype.fields:
        ros = field_name(sub.name, taken)
        nested = sub.type is not None and sub.type in found.types
        inner = _render(datatypes, sub.type or "", found, enums) if nested else ()
        if inner or ros != sub.name:
            renames.append((sub.name, ros, inner))
        model_type = f"{sub.type or ''}[]" if sub.many else sub.type
        lines.append(f"{interface_type(model_type, enums, found.types)} {ros}")
    found.texts[message] = "\n".join(lines) + "\n"
    found.renames[name] = tuple(renames)
    return found.renames[name]
