"""Type-checking properties against the model, like guards: every member type, state, datum and
event a property names must exist, and a datum compares with a constant of its type.

`check_properties` is a check family (`swarmgen.check`): the properties of every swarm class
(docs/profile.md, "Properties") are parsed and resolved at validation, each error a located SG408
with a hint (the closest name). `verify --property TEXT` checks its text the same way.
"""

from __future__ import annotations

from dataclasses import field, replace

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import codes_verify as cv
from swarmgen.expr.errors import ExprError
from swarmgen.ir.nodes import FinalState, Model, State, SwarmProperty
from swarmgen.ir.query import walk
from swarmgen.props.parse import parse_property
from swarmgen.props.tree import Count, Datum, InState, Occurs, Property, property_atoms
from swarmgen.records import dataclass
from swarmgen.span import Span

_NUMBERS = frozenset({"Integer", "Real", "UnlimitedNatural"})


@dataclass
class Vocabulary:
    """What a property may name: each member type's states and data (name -> type), and the
    events."""

    states: dict[str, set[str]] = field(default_factory=dict)
    data: dict[str, dict[str, str | None]] = field(default_factory=dict)
    events: set[str] = field(default_factory=set)
    enumerations: set[str] = field(default_factory=set)


def vocabulary(model: Model) -> Vocabulary:
    """The names a property of this model may use."""
    found = Vocabulary(events={e.name for e in model.events})
    found.enumerations = {e.name for e in model.enumerations}
    machines = {m.id: m for m in model.machines}
    for member in model.member_types:
        names: set[str] = set()
        todo, done = [member.machine] if member.machine else [], set()
        while todo:
            machine_id = todo.pop()
            if machine_id in done or machine_id not in machines:
                continue
            done.add(machine_id)
            for placed in walk(machines[machine_id]):
                vertex = placed.vertex
                if isinstance(vertex, State | FinalState) and vertex.name:
                    names.add(vertex.name)
                if isinstance(vertex, State) and vertex.submachine:
                    todo.append(vertex.submachine)
        found.states[member.name] = names
        found.data[member.name] = {d.name: d.type for d in member.data}
    return found


def parse_checked(text: str, vocab: Vocabulary) -> tuple[Property | None, list[Problem]]:
    """The property and its problems (a syntax error, or every unknown name)."""
    try:
        prop = parse_property(text)
    except ExprError as err:
        return None, [Problem(err.offset, err.message, err.hint)]
    return prop, resolve(prop, vocab)


@dataclass(frozen=True)
class Problem:
    """One error in a property: where in its text, what, and a hint."""

    offset: int
    message: str
    hint: str | None = None


def resolve(prop: Property, vocab: Vocabulary) -> list[Problem]:
    """Every name the property uses that the model does not have, and mistyped comparisons."""
    problems: list[Problem] = []
    for atom in property_atoms(prop):
        if isinstance(atom, Occurs):
            if atom.event not in vocab.events:
                problems.append(_unknown("event", atom.event, vocab.events, atom.offset))
            continue
        if not isinstance(atom, InState | Datum | Count):
            continue
        if atom.member not in vocab.states:
            problems.append(_unknown("member type", atom.member, vocab.states, atom.offset))
            continue
        if isinstance(atom, InState | Count):
            states = vocab.states[atom.member]
            if atom.state not in states:
                what = f"state of {atom.member}"
                problems.append(_unknown(what, atom.state, states, atom.state_offset))
        else:
            problems.extend(_datum(atom, vocab))
    return problems


def _datum(atom: Datum, vocab: Vocabulary) -> list[Problem]:
    data = vocab.data[atom.member]
    if atom.datum not in data:
        return [_unknown(f"datum of {atom.member}", atom.datum, data, atom.datum_offset)]
    kind, value = data[atom.datum], atom.value
    if kind in _NUMBERS:
        fits = isinstance(value, int | float) and not isinstance(value, bool)
    elif kind == "Boolean":
        fits = isinstance(value, bool) and atom.op in ("==", "!=")
    elif kind == "String" or kind in vocab.enumerations:
        fits = isinstance(value, str)
    else:
        return [
            Problem(
                atom.datum_offset,
                f"{atom.member}.{atom.datum} is a {kind or 'untyped'} datum: a property compares "
                "numbers, strings, enumerations and booleans",
            )
        ]
    if fits:
        return []
    return [
        Problem(
            atom.datum_offset,
            f"{atom.member}.{atom.datum} ({kind}) cannot be compared with {value!r} by {atom.op}",
        )
    ]


def _unknown(what: str, name: str, known: object, offset: int) -> Problem:
    names = sorted(str(n) for n in known)  # type: ignore[attr-defined]
    from difflib import get_close_matches  # an unknown name only

    close = get_close_matches(name, names, n=1, cutoff=0.6)
    hint = f"did you mean '{close[0]}'?" if close else f"choose from: {', '.join(names) or 'none'}"
    return Problem(offset, f"no {what} '{name}'", hint)


def diagnostics(name: str, text: str, span: Span, problems: list[Problem]) -> list[dg.Diagnostic]:
    """Each problem as a located SG408 (the column of the property's text in the message)."""
    found = []
    for problem in problems:
        error = f"{problem.message} (column {problem.offset + 1} of '{_clip(text)}')"
        diagnostic = cv.VERIFY_PROPERTY_INVALID.at(span, name=name, error=error)
        if problem.hint:
            diagnostic = replace(diagnostic, hint=problem.hint)
        found.append(diagnostic)
    return found


def _clip(text: str, limit: int = 60) -> str:
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[: limit - 1] + "…"


def model_properties(model: Model) -> list[SwarmProperty]:
    """The properties of every swarm class, in model order."""
    return [p for swarm in model.swarms for p in swarm.properties]


def check_properties(model: Model) -> list[dg.Diagnostic]:
    """The check family: every property of the model's swarms parsed and resolved."""
    found: list[dg.Diagnostic] = []
    props = model_properties(model)
    if not props:
        return found
    vocab = vocabulary(model)
    for prop in props:
        _, problems = parse_checked(prop.text, vocab)
        found.extend(diagnostics(prop.name, prop.text, prop.span, problems))
    return found
