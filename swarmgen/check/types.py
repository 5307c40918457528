"""Types in guards, effects and bindings: comparing a pose with a number, assigning a pose to a
real, sending a string where the event carries a number. Only what is certainly wrong is
reported: an operand whose type is not known (an untyped attribute) never causes a diagnostic.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir import expr
from swarmgen.ir.nodes import Model, Property, State, Transition, TriggerKind
from swarmgen.ir.query import ModelIndex, walk
from swarmgen.span import Span

_NUMBER = {"real", "double", "float", "integer", "int", "long", "unlimitednatural", "number"}
_BOOL = {"boolean", "bool"}
_STRING = {"string", "str"}
_ARITHMETIC = {"+", "-", "*", "/", "%"}
_ORDER = {"<", "<=", ">", ">="}
_WORDS = {"number": "a number", "bool": "a boolean", "string": "a string", "null": "null"}


def category(type_name: str | None, datatypes: set[str]) -> str | None:
    """The type class (number, bool, string, a datatype) of a property type; None if unknown."""
    if type_name is None:
        return None
    lowered = type_name.lower()
    if lowered in _NUMBER:
        return "number"
    if lowered in _BOOL:
        return "bool"
    if lowered in _STRING:
        return "string"
    return type_name if type_name in datatypes else None


def _text(e: expr.Expr, limit: int = 80) -> str:
    """The expression for a message, clipped: a long guard with many errors would otherwise
    print each of its ever larger subexpressions whole."""
    text = expr.to_text(e)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _word(kind: str) -> str:
    return _WORDS.get(kind, f"a {kind}")


@dataclass
class _Scope:
    names: dict[str, str | None]
    fields: dict[str, str | None]
    datatype_fields: dict[str, dict[str, str | None]]


class _Typer:
    def __init__(self, scope: _Scope) -> None:
        self.scope = scope
        self.errors: list[str] = []

    def infer(self, e: expr.Expr) -> str | None:
        if isinstance(e, expr.Const):
            return _const(e.value)
        if isinstance(e, expr.Name):
            return self.scope.names.get(e.name)
        if isinstance(e, expr.EventField):
            return self.scope.fields.get(e.field)
        if isinstance(e, expr.Attr):
            return self._attr(e)
        if isinstance(e, expr.Unary):
            operand = self.infer(e.operand)
            if e.op == "not":
                return "bool"
            if operand is not None and operand != "number":
                self.errors.append(f"'{e.op}' needs a number, not {_word(operand)}: `{_text(e)}`")
            return "number"
        if isinstance(e, expr.Binary):
            return self._binary(e)
        return "bool"  # else

    def _attr(self, e: expr.Attr) -> str | None:
        owner = self.infer(e.obj)
        if owner is None:
            return None
        if owner in self.scope.datatype_fields:
            fields = self.scope.datatype_fields[owner]
            if e.name not in fields:
                self.errors.append(f"{_word(owner)} has no field '{e.name}': `{_text(e)}`")
            return fields.get(e.name)
        self.errors.append(f"{_word(owner)} has no field '{e.name}': `{_text(e)}`")
        return None

    def _binary(self, e: expr.Binary) -> str | None:
        left, right = self.infer(e.left), self.infer(e.right)
        if e.op in {"and", "or"}:
            return "bool"
        if e.op in {"==", "!="}:
            if left and right and left != right and "null" not in (left, right):
                self.errors.append(
                    f"comparing {_word(left)} with {_word(right)} is always {e.op == '!='}: `{_text(e)}`"
                )
            return "bool"
        allowed = {"number", "string"} if e.op in _ORDER or e.op == "+" else {"number"}
        for side in (left, right):
            if side is not None and side not in allowed:
                self.errors.append(f"'{e.op}' cannot take {_word(side)}: `{_text(e)}`")
                return None if e.op in _ARITHMETIC else "bool"
        if left and right and left != right:
            self.errors.append(f"'{e.op}' between {_word(left)} and {_word(right)}: `{_text(e)}`")
            return None if e.op in _ARITHMETIC else "bool"
        if e.op in _ORDER:
            return "bool"
        return left or right


def _const(value: object) -> str | None:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int | float):
        return "number"
    return "string"


def _compatible(target: str | None, value: str | None) -> bool:
    return target is None or value is None or value == "null" or target == value


def check_types(model: Model) -> list[Diagnostic]:
    """Report guards, actions and bindings whose operand types certainly do not fit."""
    index = ModelIndex(model)
    datatypes = {d.name for d in model.datatypes}
    datatype_fields = {
        d.name: {f.name: category(f.type, datatypes) for f in d.fields} for d in model.datatypes
    }
    found: list[Diagnostic] = []
    for machine in model.machines:
        names = {n: category(p.type, datatypes) for n, p in index.data_scope[machine.id].items()}
        states = {p.vertex.id: p.vertex for p in walk(machine) if isinstance(p.vertex, State)}
        for transition in machine.transitions:
            fields = _fields(index, transition, states, datatypes)
            typer = _Typer(_Scope(names, fields, datatype_fields))
            found += _transition(index, typer, transition, datatypes)
        empty = _Scope(names, {}, datatype_fields)
        for state in states.values():
            typer = _Typer(empty)
            for action in (*state.entry, *state.exit):
                _action(index, typer, action, datatypes)
            if state.activity is not None:
                behaviour = index.behaviours.get(state.activity.behaviour)
                inputs = {
                    p.name: category(p.type, datatypes)
                    for p in (behaviour.inputs if behaviour else ())
                }
                for binding in state.activity.bindings:
                    value = typer.infer(binding.value)
                    if not _compatible(inputs.get(binding.name), value):
                        typer.errors.append(
                            f"input '{binding.name}' is {_word(inputs[binding.name] or '')}, "
                            f"bound to {_word(value or '')}"
                        )
            found += _report(typer.errors, state.span)
    return found


def _fields(
    index: ModelIndex, transition: Transition, states: dict[str, State], datatypes: set[str]
) -> dict[str, str | None]:
    per_trigger: list[dict[str, str | None]] = []
    for trigger in transition.triggers:
        props: tuple[Property, ...] = ()
        if trigger.kind == TriggerKind.EVENT and trigger.event in index.events:
            props = index.events[trigger.event].fields
        elif trigger.kind == TriggerKind.OUTCOME:
            state = states.get(transition.source)
            call = state.activity if state is not None else None
            behaviour = index.behaviours.get(call.behaviour) if call is not None else None
            props = behaviour.outputs if behaviour is not None else ()
        per_trigger.append({p.name: category(p.type, datatypes) for p in props})
    if not per_trigger:
        return {}
    merged = dict(per_trigger[0])
    for other in per_trigger[1:]:
        for name in list(merged):
            if other.get(name) != merged[name]:
                merged[name] = None
    return merged


def _transition(
    index: ModelIndex, typer: _Typer, transition: Transition, datatypes: set[str]
) -> list[Diagnostic]:
    if transition.guard is not None:
        typer.infer(transition.guard)
    for action in transition.effect:
        _action(index, typer, action, datatypes)
    return _report(typer.errors, transition.span)


def _action(index: ModelIndex, typer: _Typer, action: expr.Action, datatypes: set[str]) -> None:
    if isinstance(action, expr.Assign):
        target = typer.scope.names.get(action.target)
        value = typer.infer(action.value)
        if not _compatible(target, value):
            typer.errors.append(
                f"'{action.target}' is {_word(target or '')}, assigned {_word(value or '')}"
            )
        return
    event = index.events_by_name.get(action.event)
    fields = {f.name: category(f.type, datatypes) for f in (event.fields if event else ())}
    for arg in action.args:
        value = typer.infer(arg.value)
        if not _compatible(fields.get(arg.name), value):
            typer.errors.append(
                f"field '{arg.name}' of '{action.event}' is {_word(fields[arg.name] or '')}, given {_word(value or '')}"
            )


def _report(errors: list[str], span: Span) -> list[Diagnostic]:
    return [dg.TYPE_ERROR.at(span, error=message) for message in _unique(errors)]


def _unique(items: list[str]) -> Iterator[str]:
    yield from dict.fromkeys(items)
