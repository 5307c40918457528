"""The typed behaviour module of the Python packages (`behaviour_types.py`, docs/plugins.md): per
behaviour a frozen request dataclass (inputs), a result dataclass (outcome, then outputs) and a
Protocol, the model's data types as dataclasses, and the package's plug-in table."""

from __future__ import annotations

import keyword
from collections.abc import Iterable
from typing import Any

from swarmgen.chart.model import BehaviourInfo, Chart
from swarmgen.ir.nodes import DataType, Enumeration, Model
from swarmgen.ir.primitives import primitive
from swarmgen.names import IdAllocator, doc_text, identifier
from swarmgen.render import render

MODULE = "behaviour_types"  # the module's name in every generated Python package
UNTYPED = "object"
NESTED_CYCLE = "Mapping[str, object]"  # a data type that contains itself cannot be a dataclass
# names the module itself defines or imports: no class may take them
_TAKEN = (
    "Context",
    "GROUP",
    "Implementations",
    "Library",
    "Literal",
    "Mapping",
    "PLUGINS",
    "Plugins",
    "Protocol",
    "Request",
    "TypedDict",
    "dataclass",
    "library",
)


def _is_name(text: str) -> bool:
    return text.isidentifier() and text.isascii() and not keyword.iskeyword(text)


def camel(ident: str) -> str:
    """`take_off` -> `TakeOff`, `TakeOff` stays."""
    return "".join(part[:1].upper() + part[1:] for part in ident.split("_")) or "Unnamed"


class TypeNames:
    """Python types for model types: primitives, the model's data types (as dataclasses, in
    dependency order), enumerations as `Literal[...]` of their literals' names (the values
    they hold at run time), sequences as `tuple[T, ...]`, `object` for untyped or unknown ones."""

    def __init__(
        self,
        datatypes: Iterable[DataType],
        classes: IdAllocator,
        enums: Iterable[Enumeration] = (),
    ) -> None:
        self.enums = {e.name: e for e in enums if e.literals}
        self.uses_literal = False
        self.by_name: dict[str, DataType] = {}
        for key in ("name", "ident"):  # by name first, then by identifier
            for datatype in datatypes:
                self.by_name.setdefault(getattr(datatype, key), datatype)
        self.classes = classes
        self.names: dict[str, str] = {}  # data type id -> class name
        self.ordered: list[dict[str, Any]] = []  # class views, dependencies first
        self._visiting: set[str] = set()
        self.uses_mapping = False

    def of(self, type_name: str | None, many: bool = False) -> str:
        """The Python type of a model type (`many`: a sequence of it), rendering the data
        type's class when needed."""
        if many:
            return f"tuple[{self.of(type_name)}, ...]"
        if type_name is None:
            return UNTYPED
        enumeration = self.enums.get(type_name)
        if enumeration is not None:
            self.uses_literal = True
            return f"Literal[{', '.join(repr(lit) for lit in enumeration.literals)}]"
        kind = primitive(type_name)  # case-insensitive, as the ROS mapping
        if kind is not None:
            return kind.python
        datatype = self.by_name.get(type_name)
        if datatype is None:
            return UNTYPED
        if datatype.id in self._visiting:
            self.uses_mapping = True
            return NESTED_CYCLE
        if datatype.id not in self.names:
            self._visiting.add(datatype.id)
            fields = [(f.ident, self.of(f.type, f.many)) for f in datatype.fields]
            self._visiting.discard(datatype.id)
            self.names[datatype.id] = self.classes.claim(camel(datatype.ident))
            doc = doc_text(f"Data type {datatype.name}.")
            self.ordered.append({"name": self.names[datatype.id], "doc": doc, "fields": fields})
        return self.names[datatype.id]


def behaviour_view(info: BehaviourInfo, types: TypeNames, classes: IdAllocator) -> dict[str, Any]:
    """What the template prints for one behaviour: its three classes and their fields."""
    base = camel(info.ident)
    many = info.sequences
    outputs = [(name, types.of(type_, name in many)) for name, type_ in info.outputs]
    outcomes = ", ".join(repr(o) for o in info.outcomes)
    return {
        "key": repr(info.name),
        "name": doc_text(info.name),
        "request": classes.claim(f"{base}Request"),
        "result": classes.claim(f"{base}Result"),
        "protocol": classes.claim(f"{base}Behaviour"),
        "inputs": [(name, types.of(type_, name in many)) for name, type_ in info.inputs],
        "outcome_field": IdAllocator(identifier(n) for n, _ in outputs).claim("outcome"),
        "outcome_type": f"Literal[{outcomes}]" if outcomes else "str",
        "outputs": [(n, t if t == UNTYPED else f"{t} | None") for n, t in outputs],
    }


def _imports(types: TypeNames, behaviours: list[dict[str, Any]]) -> list[str]:
    """The standard-library imports the module uses (ruff refuses unused ones)."""
    lines = ["from collections.abc import Mapping"] if types.uses_mapping else []
    if types.ordered or behaviours:
        lines.append("from dataclasses import dataclass")
    literal = types.uses_literal or any(b["outcome_type"] != "str" for b in behaviours)
    typing = ["Literal"] if literal else []
    typing += ["Protocol", "TypedDict"] if behaviours else ["TypedDict"]
    lines.append(f"from typing import {', '.join(typing)}")
    return lines


def render_types(
    model: Model, charts: tuple[Chart, ...], package: str, common: dict[str, str]
) -> str:
    """`behaviour_types.py` of a package; its plug-ins are the group `<package>.behaviours`."""
    classes = IdAllocator(_TAKEN)
    types = TypeNames(model.datatypes, classes, model.enumerations)
    for datatype in model.datatypes:  # every data type, used by a behaviour or not
        types.of(datatype.name)
    seen = {b.name: b for chart in charts for b in chart.behaviours}
    behaviours = [behaviour_view(info, types, classes) for _, info in sorted(seen.items())]
    return render(
        "common/behaviour_types.py.j2",
        **common,
        model=doc_text(model.name or "swarm"),
        group=repr(f"{package}.behaviours"),
        datatypes=types.ordered,
        behaviours=behaviours,
        imports=_imports(types, behaviours),
        # class syntax when it can name every behaviour (ruff's UP013), else the functional form
        keys_are_names=all(_is_name(name) for name in seen),
    )
