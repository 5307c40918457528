"""Types in guards, effects and bindings: comparing a pose with a number, assigning a pose to a
real, sending a string where the event carries a number, an enumeration literal that does not
exist, comparing sequences. Only what is certainly wrong is reported: an operand whose type is
not known (an untyped attribute) never causes a diagnostic.

Type classes: `number`, `bool`, `string`, `null`, a data type's or an enumeration's name, and
`T[]` for a sequence of `T` (a property with multiplicity `*` or above 1).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model, Property, State, Transition, TriggerKind
from swarmgen.ir.primitives import Primitive, primitive
from swarmgen.ir.query import ModelIndex, walk
from swarmgen.records import dataclass
from swarmgen.span import Span

# primitive type -> its type class (Real and Integer are both numbers in every target)
_CLASSES = {
    Primitive.REAL: "number",
    Primitive.INTEGER: "number",
    Primitive.BOOLEAN: "bool",
    Primitive.STRING: "string",
}
_ARITHMETIC = {"+", "-", "*", "/", "%"}
_ORDER = {"<", "<=", ">", ">="}
_WORDS = {"number": "a number", "bool": "a boolean", "string": "a string", "null": "null"}
# the SCXML event processor of `_ioprocessors.scxml.location` (the language's only path into it)
_PROCESSOR = expr.Attr(obj=expr.System(name="_ioprocessors"), name="scxml")


def category(type_name: str | None, datatypes: set[str]) -> str | None:
    """The type class (number, bool, string, a data type or enumeration) of a property type;
    None if unknown (`datatypes` holds the names of both)."""
    if type_name is None:
        return None
    kind = primitive(type_name)
    if kind is not None:
        return _CLASSES[kind]
    return type_name if type_name in datatypes else None


def of(prop: Property, known: set[str]) -> str | None:
    """A property's type class: its type's, as a sequence (`T[]`) when it is multi-valued."""
    kind = category(prop.type, known)
    return f"{kind}[]" if kind is not None and prop.many else kind


def _text(e: expr.Expr, limit: int = 80) -> str:
    """The expression for a message, clipped: a long guard with many errors would otherwise
    print each of its ever larger subexpressions whole."""
    text = expr.to_text(e)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _word(kind: str) -> str:
    if kind.endswith("[]"):
        return f"a sequence of {kind[:-2]}"
    return _WORDS.get(kind, f"a {kind}")


@dataclass
class _Scope:
    names: dict[str, str | None]
    fields: dict[str, str | None]
    datatype_fields: dict[str, dict[str, str | None]]
    enums: Mapping[str, tuple[str, ...]]


class _Typer:
    def __init__(self, scope: _Scope) -> None:
        self.scope = scope
        self.errors: list[str] = []
        self.literals: list[tuple[str, str, str]] = []  # (enumeration, literal, text)

    def infer(self, e: expr.Expr) -> str | None:
        if isinstance(e, expr.Const) and e.enum is not None:
            if e.value not in self.scope.enums.get(e.enum, ()):
                self.literals.append((e.enum, str(e.value), _text(e)))
            return e.enum
        if isinstance(e, expr.Const):
            return _const(e.value)
        if isinstance(e, expr.Name):
            return self.scope.names.get(e.name)
        if isinstance(e, expr.EventField):
            return self.scope.fields.get(e.field)
        if isinstance(e, expr.ListOf):  # a sequence of the items' type, when they agree
            kinds = {self.infer(item) for item in e.items}
            kind = kinds.pop() if len(kinds) == 1 else None
            return f"{kind}[]" if kind is not None and not kind.endswith("[]") else None
        if isinstance(e, expr.InState):
            return "bool"
        if isinstance(e, expr.Invalid):  # no value: it fails when it runs
            return None
        if isinstance(e, expr.StartsWith):
            for side in (e.text, e.prefix):
                found = self.infer(side)
                if found is not None and found != "string":
                    self.errors.append(
                        f"'startswith' takes strings, not {_word(found)}: `{_text(e)}`"
                    )
            return "bool"
        if isinstance(e, expr.System):  # `_event` is read field by field
            return "string" if e.name in ("_sessionid", "_name") else None
        if isinstance(e, expr.Attr) and isinstance(e.obj, expr.System):
            return None if e.name == "data" or e.obj.name != "_event" else "string"
        if isinstance(e, expr.Attr) and e.obj == _PROCESSOR:  # _ioprocessors.scxml.location
            return "string"
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
            if any(side and side.endswith("[]") for side in (left, right)):
                # Python compares lists by value, ECMAScript arrays by identity
                self.errors.append(f"sequences cannot be compared: `{_text(e)}`")
            elif left and right and left != right and "null" not in (left, right):
                self.errors.append(
                    f"comparing {_word(left)} with {_word(right)} is always {e.op == '!='}: `{_text(e)}`"
                )
            elif any(side in self.scope.datatype_fields for side in (left, right)):
                # Python compares dicts by value, ECMAScript objects by identity
                self.errors.append(f"data type values cannot be compared: `{_text(e)}`")
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
    datatypes = {d.name for d in model.datatypes} | {e.name for e in model.enumerations}
    datatype_fields = {
        d.name: {f.name: of(f, datatypes) for f in d.fields} for d in model.datatypes
    }
    enums = {e.name: e.literals for e in model.enumerations}
    found: list[Diagnostic] = []
    for machine in model.machines:
        names = {n: of(p, datatypes) for n, p in index.data_scope[machine.id].items()}
        states = {p.vertex.id: p.vertex for p in walk(machine) if isinstance(p.vertex, State)}
        for transition in machine.transitions:
            fields = _fields(index, transition, states, datatypes)
            typer = _Typer(_Scope(names, fields, datatype_fields, enums))
            found += _transition(index, typer, transition, datatypes)
        empty = _Scope(names, {}, datatype_fields, enums)
        for state in states.values():
            typer = _Typer(empty)
            for action in (*state.entry, *state.exit):
                _action(index, typer, action, datatypes)
            if state.activity is not None:
                behaviour = index.behaviours.get(state.activity.behaviour)
                inputs = {p.name: of(p, datatypes) for p in (behaviour.inputs if behaviour else ())}
                for binding in state.activity.bindings:
                    value = typer.infer(binding.value)
                    if not _compatible(inputs.get(binding.name), value):
                        typer.errors.append(
                            f"input '{binding.name}' is {_word(inputs[binding.name] or '')}, "
                            f"bound to {_word(value or '')}"
                        )
            found += _report(typer, state.span)
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
        per_trigger.append({p.name: of(p, datatypes) for p in props})
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
    return _report(typer, transition.span)


def _action(index: ModelIndex, typer: _Typer, action: expr.Action, datatypes: set[str]) -> None:
    if isinstance(action, expr.Assign):
        value = typer.infer(action.value)
        name = action.target
        if isinstance(name, expr.Invalid):  # assigns nothing: it fails when it runs
            return
        target = typer.scope.names.get(name)
        if name not in expr.SYSTEM_VARIABLES and not _compatible(target, value):
            typer.errors.append(f"'{name}' is {_word(target or '')}, assigned {_word(value or '')}")
        return
    if isinstance(action, expr.Cancel):
        return
    if isinstance(action, expr.ForEach):
        _loop(index, typer, action, datatypes)
        return
    if isinstance(action, expr.Done):  # refused outside a final state (check.expressions)
        return
    if isinstance(action, expr.Log):
        typer.infer(action.value)
        return
    if isinstance(action, expr.Block):
        for inner in action.actions:
            _action(index, typer, inner, datatypes)
        return
    if isinstance(action, expr.If):
        for branch in action.branches:
            if branch.cond is not None:
                typer.infer(branch.cond)
            for inner in branch.actions:
                _action(index, typer, inner, datatypes)
        return
    if isinstance(action, expr.Raise):
        _send_options(typer, action)
    if isinstance(action, expr.Raise) and action.delay is not None:
        amount = typer.infer(action.delay.amount)
        wanted = "string" if not action.delay.unit else "number"
        if amount is not None and amount != wanted:
            needs = "a duration string" if not action.delay.unit else "a number"
            typer.errors.append(
                f"the delay of '{expr.event_text(action)}' is {_word(amount)}, it needs {needs}"
            )
    event = index.events_by_name.get(action.event) if action.event is not None else None
    fields = {f.name: of(f, datatypes) for f in (event.fields if event else ())}
    if isinstance(action, expr.Raise) and action.content is not None:
        typer.infer(action.content)  # any value: the event's whole data
        if fields:  # the value rule: an event declared with fields always carries them
            typer.errors.append(
                f"'{action.event}' has fields ({', '.join(fields)}): it carries them, not a value"
            )
    for arg in action.args:
        value = typer.infer(arg.value)
        if not _compatible(fields.get(arg.name), value):
            typer.errors.append(
                f"field '{arg.name}' of '{action.event}' is {_word(fields[arg.name] or '')}, given {_word(value or '')}"
            )


def _send_options(typer: _Typer, action: expr.Raise) -> None:
    """`to`, `via` and a computed name take strings; `into` writes a string (the send id) to
    its datum."""
    options = (("target", action.target), ("I/O processor", action.via), ("name", action.named))
    for word, value in options:
        found = typer.infer(value) if value is not None else None
        if found is not None and found != "string":
            event = expr.event_text(action)
            typer.errors.append(f"the {word} of '{event}' is {_word(found)}, not a string")
    if action.into is not None and not _compatible(typer.scope.names.get(action.into), "string"):
        datum = typer.scope.names.get(action.into) or ""
        typer.errors.append(f"'{action.into}' is {_word(datum)}, given a send id (a string)")


def _loop(index: ModelIndex, typer: _Typer, action: expr.ForEach, datatypes: set[str]) -> None:
    """`for item, i in xs`: xs a sequence whose items fit `item`, `i` a number."""
    array = typer.infer(action.array)
    if array is not None and not array.endswith("[]"):
        typer.errors.append(f"'for' takes a sequence, not {_word(array)}: `{_text(action.array)}`")
    item = typer.scope.names.get(action.item)
    if array is not None and array.endswith("[]") and not _compatible(item, array[:-2]):
        typer.errors.append(
            f"'{action.item}' is {_word(item or '')}, given items of {_word(array)}"
        )
    if action.index is not None and not _compatible(typer.scope.names.get(action.index), "number"):
        typer.errors.append(f"the index '{action.index}' of a 'for' is a number")
    for inner in action.actions:
        _action(index, typer, inner, datatypes)


def _report(typer: _Typer, span: Span) -> list[Diagnostic]:
    found = [dg.TYPE_ERROR.at(span, error=message) for message in _unique(typer.errors)]
    for enum, literal, text in dict.fromkeys(typer.literals):
        literals = typer.scope.enums.get(enum, ())
        from difflib import get_close_matches  # an unknown literal only

        close = get_close_matches(literal, literals, n=1)
        values = {"enum": enum, "literal": literal, "text": text}
        if close:
            found.append(dg.UNKNOWN_LITERAL.at(span, suggestion=close[0], **values))
        else:
            shown = ", ".join(literals) or "(none)"
            found.append(dg.UNKNOWN_LITERAL.at(span, "none-close", literals=shown, **values))
    return found


def _unique(items: list[str]) -> Iterator[str]:
    yield from dict.fromkeys(items)
