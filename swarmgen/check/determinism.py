"""Determinism: two transitions from one state on the same trigger whose guards can both hold.

Guards are decided by search: each name and event field ranges over the constants the guards
compare it with (and their neighbours), booleans and null; a valuation under which both
guards hold is reported as the witness. The model order then silently picks one of them.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir import expr
from swarmgen.ir.nodes import Model, PseudoKind, Pseudostate, Transition, TriggerKind
from swarmgen.ir.query import walk

MAX_VALUATIONS = 20_000
_UNDEFINED = object()


def check_determinism(model: Model) -> list[Diagnostic]:
    found: list[Diagnostic] = []
    for machine in model.machines:
        kinds = {p.vertex.id: p.vertex for p in walk(machine)}
        groups: dict[tuple[str, str], list[Transition]] = {}
        for transition in machine.transitions:
            source = kinds.get(transition.source)
            if isinstance(source, Pseudostate) and source.kind not in {
                PseudoKind.CHOICE,
                PseudoKind.JUNCTION,
            }:
                continue  # fork, initial, history: a single or simultaneous transitions
            for key in _trigger_keys(transition):
                groups.setdefault((transition.source, key), []).append(transition)
        for (source_id, key), transitions in groups.items():
            vertex = kinds.get(source_id)  # None for a ConnectionPointReference
            found += _conflicts((vertex.name if vertex else "") or source_id, key, transitions)
    return found


def _trigger_keys(transition: Transition) -> list[str]:
    if not transition.triggers:
        return ["(completion)"]
    keys = []
    for trigger in transition.triggers:
        if trigger.kind == TriggerKind.TIME:
            keys.append(f"after {trigger.delay_ms} ms")
        else:
            keys.append(trigger.name)
    return keys


def _conflicts(source: str, key: str, transitions: list[Transition]) -> list[Diagnostic]:
    found = []
    for first, second in itertools.combinations(transitions, 2):
        if isinstance(first.guard, expr.Else) or isinstance(second.guard, expr.Else):
            continue
        witness = both_hold(first.guard, second.guard)
        if witness is None:
            continue
        what = "(no trigger)" if key == "(completion)" else f"'{key}'"
        notes = [f"the other transition is at {first.span.location()}"]
        if witness:
            notes.append(
                "both guards hold when "
                + ", ".join(f"{k} = {v!r}" for k, v in sorted(witness.items()))
            )
        else:
            notes.append("neither has a guard")
        found.append(
            dg.diag(
                dg.NONDETERMINISTIC,
                f"'{source}' has two transitions on {what} that can both fire; the first in model order wins",
                second.span,
                notes=notes,
                hint="make the guards exclusive (e.g. `[x < 20]` and `[x >= 20]`), or use `else`",
            )
        )
    return found


def both_hold(first: expr.Expr | None, second: expr.Expr | None) -> dict[str, Any] | None:
    """A valuation under which both guards are true ({} when both are unguarded), or None."""
    guards = [g for g in (first, second) if g is not None]
    variables = sorted({v for g in guards for v in _variables(g)})
    domains = [_domain(v, guards) for v in variables]
    for values in itertools.islice(itertools.product(*domains), MAX_VALUATIONS):
        env = dict(zip(variables, values, strict=True))
        if all(_truthy(evaluate(g, env)) for g in guards):
            return {k: v for k, v in env.items() if v is not _UNDEFINED}
    return None


def _variables(e: expr.Expr) -> Iterator[str]:
    for node in expr.walk(e):
        if isinstance(node, expr.Name):
            yield node.name
        elif isinstance(node, expr.EventField):
            yield f"event.{node.field}"


def _domain(variable: str, guards: list[expr.Expr]) -> list[Any]:
    constants: set[Any] = set()
    for guard in guards:
        for node in expr.walk(guard):
            if isinstance(node, expr.Binary):
                for side, other in ((node.left, node.right), (node.right, node.left)):
                    if _names(side) == variable and isinstance(other, expr.Const):
                        constants.add(other.value)
    values: list[Any] = [True, False, None]
    for constant in sorted(constants, key=repr):
        if isinstance(constant, bool) or constant is None:
            continue
        if isinstance(constant, int | float):
            values += [constant - 1, constant, constant + 1, constant + 0.5, constant - 0.5]
        else:
            values += [constant, f"{constant}~"]
    if not constants:
        values += [0, 1, -1]
    return list(dict.fromkeys(values))


def _names(e: expr.Expr) -> str | None:
    if isinstance(e, expr.Name):
        return e.name
    if isinstance(e, expr.EventField):
        return f"event.{e.field}"
    return None


def _truthy(value: Any) -> bool:
    return value is not _UNDEFINED and bool(value)


def evaluate(e: expr.Expr, env: dict[str, Any]) -> Any:
    """A small evaluator with the runtime's meaning; errors make a guard false (undefined)."""
    try:
        return _eval(e, env)
    except (TypeError, ZeroDivisionError, ValueError, AttributeError):
        return _UNDEFINED


def _eval(e: expr.Expr, env: dict[str, Any]) -> Any:
    if isinstance(e, expr.Const):
        return e.value
    if isinstance(e, expr.Name):
        return env.get(e.name)
    if isinstance(e, expr.EventField):
        return env.get(f"event.{e.field}")
    if isinstance(e, expr.Attr):
        raise TypeError("attribute of an unknown value")
    if isinstance(e, expr.Unary):
        value = _eval(e.operand, env)
        if value is _UNDEFINED:
            return value
        return (not value) if e.op == "not" else (-value if e.op == "-" else +value)
    if isinstance(e, expr.Binary):
        return _binary(e, env)
    return True  # Else


def _binary(e: expr.Binary, env: dict[str, Any]) -> Any:
    left = _eval(e.left, env)
    if e.op == "and":
        return _eval(e.right, env) if _truthy(left) else left
    if e.op == "or":
        return left if _truthy(left) else _eval(e.right, env)
    right = _eval(e.right, env)
    if left is _UNDEFINED or right is _UNDEFINED:
        return _UNDEFINED
    operations = {
        "==": lambda a, b: a == b,
        "!=": lambda a, b: a != b,
        "<": lambda a, b: a < b,
        "<=": lambda a, b: a <= b,
        ">": lambda a, b: a > b,
        ">=": lambda a, b: a >= b,
        "+": lambda a, b: a + b,
        "-": lambda a, b: a - b,
        "*": lambda a, b: a * b,
        "/": lambda a, b: a / b,
        "%": lambda a, b: a % b,
    }
    return operations[e.op](left, right)
