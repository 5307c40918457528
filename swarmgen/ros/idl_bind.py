"""The binding of a behaviour to its declared ROS interface type: which input fills which goal,
request or message field, which result, response or message field becomes which output, and
what stops it (`analyse` gives the issues as data; `bind` the binding alone). Pure: the
definitions come from an `InterfaceIndex`; shared by the check and the rclpy backend.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import field
from typing import Any, Literal

from swarmgen.ir.nodes import Behaviour, DataType, Enumeration, Property
from swarmgen.ir.primitives import Primitive, primitive
from swarmgen.names import ros_name
from swarmgen.records import dataclass
from swarmgen.ros.idl import (
    FLOATS,
    INTEGERS,
    KINDS,
    STRINGS,
    Constant,
    Field,
    InterfaceDef,
    Kind,
    Section,
)
from swarmgen.ros.idl_index import InterfaceIndex, Problem

RosKind = Literal["action", "service", "topic"]
INTERFACE_KIND: dict[str, Kind] = {"action": "action", "service": "srv", "topic": "msg"}
# Which sections the inputs fill and the outputs come from, per interface kind.
_SIDES: dict[Kind, tuple[str, str]] = {
    "action": ("goal", "result"),
    "srv": ("request", "response"),
    "msg": ("message", "message"),
}
_INTO = {  # model type -> the primitive field types an input of it may fill
    Primitive.REAL: FLOATS,
    Primitive.INTEGER: INTEGERS | FLOATS,
    Primitive.BOOLEAN: frozenset({"bool"}),
    Primitive.STRING: STRINGS,
}
_FROM = {  # model type -> the primitive field types an output of it may be read from
    Primitive.REAL: FLOATS | INTEGERS,
    Primitive.INTEGER: INTEGERS,
    Primitive.BOOLEAN: frozenset({"bool"}),
    Primitive.STRING: STRINGS,
}
# the section types of an action and a service, as rosidl names them (`Go_Goal`)
_SECTION_SUFFIX = {
    "goal": "_Goal", "result": "_Result", "feedback": "_Feedback",
    "request": "_Request", "response": "_Response", "message": "",
}  # fmt: skip
WHOLE = ""  # the field path of a parameter that is the whole goal, request or message
# Key renames of a data type's values: (model key, ROS field name, renames inside that field).
Renames = tuple[tuple[str, str, "Renames"], ...]
MAX_QUOTE = 8  # definition lines quoted in one note


@dataclass(frozen=True)
class Binding:
    """How a behaviour runs over its declared type (docs/ros2.md, "Declared interface types")."""

    kind: RosKind
    package: str
    interface: Kind
    name: str
    direction: Literal["call", "publish", "subscribe"]
    inputs: tuple[tuple[str, str], ...]  # (behaviour input, field path)
    outputs: tuple[tuple[str, str], ...]  # (field path, behaviour output)
    outcome_field: str | None  # result `string outcome` (action), response `bool success` (srv)
    definitions: Mapping[str, InterfaceDef] = field(default_factory=dict)
    # (input|output, behaviour parameter, renames) for data type values whose keys are not
    # already the ROS field names (`posX` -> `pos_x`); the runtime renames them both ways
    renames: tuple[tuple[str, str, Renames], ...] = ()

    @property
    def type(self) -> str:
        """`pkg/kind/Name`."""
        return f"{self.package}/{self.interface}/{self.name}"


@dataclass(frozen=True)
class Issue:
    """Why a behaviour does not bind: a key (the diagnostic it becomes), its values, the
    definition lines to quote as `(file, line, text)`, and a definition-file problem."""

    key: str
    values: Mapping[str, Any]
    quote: tuple[tuple[str, int, str], ...] = ()
    problem: Problem | None = None


def split_type(text: str, ros_kind: str) -> tuple[str, Kind, str] | None:
    """`pkg/kind/Name`, or `pkg/Name` with the kind read from rosKind; None if neither."""
    parts = text.strip().split("/")
    if len(parts) == 3 and parts[1] in KINDS:
        kind: Kind = "action" if parts[1] == "action" else "srv" if parts[1] == "srv" else "msg"
        return parts[0], kind, parts[2]
    if len(parts) == 2 and ros_kind in INTERFACE_KIND:
        return parts[0], INTERFACE_KIND[ros_kind], parts[1]
    return None


def bind(
    behaviour: Behaviour,
    index: InterfaceIndex,
    datatypes: Sequence[DataType] = (),
    enums: Sequence[Enumeration] = (),
) -> Binding | None:
    """The binding of `behaviour` to its declared type, or None (undeclared, or an issue)."""
    binding, _ = analyse(behaviour, index, datatypes, enums)
    return binding


def analyse(
    behaviour: Behaviour,
    index: InterfaceIndex,
    datatypes: Sequence[DataType] = (),
    enums: Sequence[Enumeration] = (),
) -> tuple[Binding | None, list[Issue]]:
    """The binding and the issues that prevent it or come with it (shadowed definitions)."""
    ros = behaviour.ros
    if ros is None or not ros.type:
        return None, []
    triple = split_type(ros.type, ros.kind)
    if triple is None:
        return None, [Issue("bad-form", {"text": ros.type})]
    package, kind, name = triple
    resolution = index.resolve(package, kind, name)
    issues = [
        Issue("shadowed", {"type": key, "used": used, "others": ", ".join(others)})
        for key, used, others in resolution.shadowed
    ]
    if resolution.problem is not None or resolution.root is None:
        assert resolution.problem is not None
        return None, [*issues, Issue(resolution.problem.kind, {}, problem=resolution.problem)]
    root = resolution.root
    if INTERFACE_KIND[ros.kind] != kind:
        values = {"type": root.key, "kind": kind, "ros_kind": ros.kind}
        return None, [*issues, Issue("kind", values, _lines(root.sections[0], root))]
    known = {d.name: d for d in datatypes}
    mapper = _Mapper(resolution.definitions, known, root, {e.name for e in enums})
    binding = mapper.bind(behaviour, ros.kind)
    return (binding if not mapper.issues else None), issues + mapper.issues


def message_key(ros_type: str) -> str:
    """A «RosMessage» data type's rosType as a field's type key (`pkg/msg/Name`): `pkg/Name`
    is read as a message; the section types of actions and services keep their kind."""
    parts = ros_type.strip().split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else "/".join(parts)


class _Mapper:
    """Matches a behaviour's inputs and outputs with a definition's sections."""

    def __init__(
        self,
        definitions: Mapping[str, InterfaceDef],
        datatypes: dict[str, DataType],
        root: InterfaceDef,
        enums: set[str] | frozenset[str] = frozenset(),
    ) -> None:
        self.definitions, self.datatypes, self.root = definitions, datatypes, root
        self.enums = enums
        self.issues: list[Issue] = []

    def bind(self, behaviour: Behaviour, ros_kind: RosKind) -> Binding:
        into, out = _SIDES[self.root.kind]
        direction: Literal["call", "publish", "subscribe"] = "call"
        if self.root.kind == "msg":
            if behaviour.inputs and behaviour.outputs:
                self.issues.append(Issue("direction", {"type": self.root.key}))
            direction = "publish" if behaviour.inputs else "subscribe"
        inputs = [self._match(p, self.root.section(into), "input") for p in behaviour.inputs]
        outcome = _outcome_field(self.root)
        outputs = [self._match(p, self.root.section(out), "output") for p in behaviour.outputs]
        return Binding(
            ros_kind,
            self.root.package,
            self.root.kind,
            self.root.name,
            direction,
            tuple(
                (p.name, f) for p, f in zip(behaviour.inputs, inputs, strict=True) if f is not None
            ),
            tuple(
                (f, p.name)
                for p, f in zip(behaviour.outputs, outputs, strict=True)
                if f is not None
            ),
            outcome,
            dict(self.definitions),
            self._renames(behaviour, inputs, outputs),
        )

    def _renames(
        self, behaviour: Behaviour, inputs: list[str | None], outputs: list[str | None]
    ) -> tuple[tuple[str, str, Renames], ...]:
        """The key renames of every mapped parameter that has some."""
        found: list[tuple[str, str, Renames]] = []
        for side, params, paths in (
            ("input", behaviour.inputs, inputs),
            ("output", behaviour.outputs, outputs),
        ):
            for param, path in zip(params, paths, strict=True):
                tree = renames_of(param.type, self.datatypes, ())
                if path is not None and tree:
                    found.append((side, param.name, tree))
        return tuple(found)

    def _whole(self, param: Property, section: Section) -> bool:
        """Whether `param` is a «RosMessage» data type of exactly this section's type (the
        message of a topic, `Name_Goal` of an action, ...): it then fills the whole section."""
        datatype = self.datatypes.get((param.type or "").strip())
        if datatype is None or datatype.ros_type is None or param.many:
            return False
        root = self.root
        wanted = f"{root.package}/{root.kind}/{root.name}{_SECTION_SUFFIX.get(section.name, '')}"
        return message_key(datatype.ros_type) == wanted

    def _match(self, param: Property, section: Section, side: str) -> str | None:
        if self._whole(param, section):
            datatype = self.datatypes[(param.type or "").strip()]
            reason = self._fields(datatype, section, f"the {section.name}", side, ())
            if reason is None:
                return WHOLE
            values = {
                "side": side, "name": param.name, "model_type": param.type, "field": section.name,
                "field_type": f"the whole {section.name}", "type": self.root.key,
                "detail": reason[1],
            }  # fmt: skip
            self.issues.append(Issue("type", values, _lines(section, self.root)))
            return None
        wanted = ros_name(param.name)
        found = section.field(wanted)
        if found is None:
            names = [f.name for f in section.fields]
            from difflib import get_close_matches  # a misspelling only

            close = get_close_matches(wanted, names, n=1)
            values = {
                "side": side, "name": param.name, "field": wanted, "section": section.name,
                "type": self.root.key, "suggestion": f"`{close[0]}`" if close else None,
            }  # fmt: skip
            self.issues.append(Issue("unknown-field", values, _lines(section, self.root)))
            return None
        reason = self._compatible(param, found, side, ())
        if reason is None:
            return found.name
        key, detail = reason
        values = {
            "side": side, "name": param.name, "model_type": _model_type(param),
            "field": found.name, "field_type": _field_type(found), "type": self.root.key,
            "detail": detail,
        }  # fmt: skip
        quote = ((self._file_of(found), found.line, found.text),)
        self.issues.append(Issue(key, values, quote))
        return None

    def _file_of(self, item: Field) -> str:
        for definition in self.definitions.values():
            for section in definition.sections:
                if item in section.fields:
                    return definition.file
        return self.root.file

    def _compatible(
        self, param: Property, item: Field, side: str, seen: tuple[str, ...]
    ) -> tuple[str, str] | None:
        """None if a value of `param`'s type fits the field (`side`: into it or out of it),
        else the issue key (`type`, or `shape` for a data type) and why. A sequence maps to an
        array field (`T[]`, `T[N]`, `T[<=N]`) whose element type fits by the same rules."""
        if item.array and not param.many:
            return "type", "the field is an array; the model's value is a single one"
        if param.many and not item.array:
            return "type", "the model's value is a sequence; the field is a single one"
        model_type = (param.type or "").strip()
        if not model_type:
            ok = item.type.primitive  # untyped: any primitive, converted at run time
            return None if ok else ("type", "an untyped value cannot fill a message field")
        kind = Primitive.STRING if model_type in self.enums else primitive(model_type)
        if kind is not None:
            allowed = (_INTO if side == "input" else _FROM)[kind]
            if item.type.primitive and item.type.name in allowed:
                return None
            return "type", f"{model_type} {'into' if side == 'input' else 'from'} {_element(item)}"
        datatype = self.datatypes.get(model_type)
        if datatype is None or item.type.primitive:
            return "type", f"{model_type} is not a {_element(item)}"
        if datatype.ros_type is not None:
            if message_key(datatype.ros_type) != item.type.key:
                return "type", f"{model_type} is {datatype.ros_type}, not {item.type.text()}"
            reason = self._shape(datatype, item, side, seen)
            return None if reason is None else ("type", reason[1])
        return self._shape(datatype, item, side, seen)

    def _shape(
        self, datatype: DataType, item: Field, side: str, seen: tuple[str, ...]
    ) -> tuple[str, str] | None:
        message = self.definitions.get(item.type.key)
        if message is None or datatype.name in seen:
            return "shape", f"{datatype.name} cannot map to {item.type.text()}"
        return self._fields(datatype, message.sections[0], item.type.text(), side, seen)

    def _fields(
        self, datatype: DataType, section: Section, where: str, side: str, seen: tuple[str, ...]
    ) -> tuple[str, str] | None:
        """Each field of `datatype` names a field of `section` of a type it converts to."""
        for sub in datatype.fields:
            target = section.field(ros_name(sub.name))
            if target is None:
                return "shape", f"{where} has no field `{ros_name(sub.name)}`"
            reason = self._compatible(sub, target, side, (*seen, datatype.name))
            if reason is not None:
                return "shape", f"{datatype.name}.{sub.name}: {reason[1]}"
        return None


def renames_of(
    type_name: str | None, datatypes: Mapping[str, DataType], seen: tuple[str, ...]
) -> Renames:
    """The key renames of a value of `type_name` (a data type's field names through
    `ros_name`, the rule the mapping checks with), recursively; () when none differ."""
    datatype = datatypes.get((type_name or "").strip())
    if datatype is None or datatype.name in seen:
        return ()
    found: list[tuple[str, str, Renames]] = []
    for sub in datatype.fields:
        inner = renames_of(sub.type, datatypes, (*seen, datatype.name))
        if inner or sub.name != ros_name(sub.name):
            found.append((sub.name, ros_name(sub.name), inner))
    return tuple(found)


def _outcome_field(root: InterfaceDef) -> str | None:
    """`string outcome` in an action's result, `bool success` in a service's response."""
    wanted = {"action": ("result", "outcome", "string"), "srv": ("response", "success", "bool")}
    if root.kind not in wanted:
        return None
    section, name, type_ = wanted[root.kind]
    item = root.section(section).field(name)
    ok = item is not None and not item.array and item.type.name == type_ and item.type.primitive
    return name if ok else None


def _model_type(param: Property) -> str:
    """A parameter's type as the model writes it (`Real[*]` for a sequence)."""
    text = param.type or "untyped"
    return f"{text}[*]" if param.many else text


def _element(item: Field) -> str:
    """The field's type, of its elements for an array."""
    return f"{item.type.text()} elements" if item.array else item.type.text()


def _field_type(item: Field) -> str:
    if not item.array:
        return item.type.text()
    size = "" if item.bound is None else ("<=" if item.bounded else "") + str(item.bound)
    return f"{item.type.text()}[{size}]"


def _lines(section: Section, root: InterfaceDef) -> tuple[tuple[str, int, str], ...]:
    items: list[Field | Constant] = [*section.fields, *section.constants]
    items.sort(key=lambda i: i.line)
    return tuple((root.file, i.line, i.text) for i in items[:MAX_QUOTE])
