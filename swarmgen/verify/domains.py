"""Behaviour outputs from finite domains: the values a behaviour's outputs take when it ends
(docs/verify.md, "Behaviour outputs").

An output is written into a member datum (`Call.results`). Its domain is

- **the model's default**: the value the datum starts with, when the model declares a default
  for the datum or for the output parameter (as the value rule fills it);
- **the constants guards compare it against**, read from every guard of the model that compares
  the datum (`target_id > 3`), a field of it (`target_pose.pose.position.x < 2.5`) or the
  outcome's field (`event.target_id == 7`) with a literal, on either side: for an integer
  `c - 1`, `c` and `c + 1`; for a real each constant, one below the least, one above the
  greatest and the midpoint between neighbours (a value in every interval the constants cut);
  each string or enumeration literal; both booleans;
- **the zero** (the output not given, as a ROS result holds it) when neither gives a value.

A structured output takes its base value (default, else zero) with one compared field changed
at a time. Every outcome of the behaviour ends with every combination of its outputs' values,
at most `MAX_ENDINGS` per behaviour state (beyond that, one output varies at a time, the others
at their first value).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from swarmgen.expr.rewrite import walk as walk_expr
from swarmgen.expr.tree import COMPARISONS, Attr, Binary, Const, EventField, Expr, Name, Unary
from swarmgen.ir.nodes import Model
from swarmgen.runtime.chart import Chart, record, zero_like
from swarmgen.verify.kinds import Outcome
from swarmgen.verify.state import freeze

MAX_ENDINGS = 64  # outcome and output combinations of one behaviour state
Path = tuple[str, str, tuple[str, ...]]  # ("data" or "event", datum or field, fields under it)


def endings(
    model: Model, chart: Chart, member_type: str, initial: Mapping[str, Any]
) -> dict[str, tuple[Outcome, ...]]:
    """Per state with a behaviour: every outcome with every combination of output values."""
    constants = guard_constants(model)
    defaults = _declared(model, member_type)
    found: dict[str, tuple[Outcome, ...]] = {}
    for node in chart.nodes.values():
        call = node.call
        if call is None:
            continue
        outcomes = call.outcomes or ("succeeded",)
        choices = [
            [(output, v) for v in _domain(output, key, initial, defaults, constants)]
            for output, key in call.results
        ]
        found[node.id] = tuple(
            Outcome(name, freeze(outputs) if outputs else None)
            for outputs in _combinations(choices, MAX_ENDINGS // len(outcomes))
            for name in outcomes
        )
    return found


def guard_constants(model: Model) -> dict[Path, set[Any]]:
    """Every literal a guard of the model compares a datum, a field of one or an event field
    with, by what it compares."""
    found: dict[Path, set[Any]] = {}
    for machine in model.machines:
        for transition in machine.transitions:
            if transition.guard is None:
                continue
            for node in walk_expr(transition.guard):
                if not isinstance(node, Binary) or node.op not in COMPARISONS:
                    continue
                for side, other in ((node.left, node.right), (node.right, node.left)):
                    path, value = _path(side), _literal(other)
                    if path is not None and value is not None:
                        found.setdefault(path, set()).add(value)
    return found


def _path(expr: Expr) -> Path | None:
    fields: list[str] = []
    while isinstance(expr, Attr):
        fields.append(expr.name)
        expr = expr.obj
    if isinstance(expr, Name):
        return ("data", expr.name, tuple(reversed(fields)))
    if isinstance(expr, EventField):
        return ("event", expr.field, tuple(reversed(fields)))
    return None


def _literal(expr: Expr) -> Any:
    if isinstance(expr, Unary) and expr.op == "-" and isinstance(expr.operand, Const):
        value = expr.operand.value
        return -value if isinstance(value, int | float) and not isinstance(value, bool) else None
    return expr.value if isinstance(expr, Const) else None


def _declared(model: Model, member_type: str) -> set[str]:
    """The data of the member type, and the outputs, that have a default in the model."""
    declared = {
        p.name
        for t in model.member_types
        if t.name == member_type
        for p in t.data
        if p.default is not None
    }
    declared |= {
        f"output:{p.name}" for b in model.behaviours for p in b.outputs if p.default is not None
    }
    return declared


def _domain(
    output: str,
    key: str,
    initial: Mapping[str, Any],
    declared: set[str],
    constants: Mapping[Path, set[Any]],
) -> list[Any]:
    """An output's values (None: not given, the zero), base value first."""
    start = initial.get(key)
    has_default = key in declared or f"output:{output}" in declared
    # a default equal to the zero is the output not given (the same write, a shorter replay)
    base = start if has_default and start != zero_like(start) else None
    values: list[Any] = [base]
    compared = {
        fields: consts
        for (where, name, fields), consts in constants.items()
        if (where, name) in (("data", key), ("event", output))
    }
    for fields in sorted(compared):
        template = _at(start, fields)
        for value in _around(template, sorted(compared[fields], key=repr)):
            changed = _with(base if base is not None else zero_like(start), fields, value)
            if changed not in values and (base is not None or changed != zero_like(start)):
                values.append(changed)
    return values


def _around(template: Any, constants: Sequence[Any]) -> Iterator[Any]:
    """The values of the template's type that fall on each side of each constant."""
    if isinstance(template, bool):
        yield from (False, True)
    elif isinstance(template, int):
        ints = {int(c) for c in constants if _number(c)}
        ints |= {math.ceil(c) for c in constants if _number(c)}
        yield from sorted({n + d for n in ints for d in (-1, 0, 1)})
    elif isinstance(template, float):
        reals = sorted({float(c) for c in constants if _number(c)})
        if reals:
            yield reals[0] - 1.0
            for low, high in itertools.pairwise(reals):
                yield from (low, (low + high) / 2)
            yield from (reals[-1], reals[-1] + 1.0)
    elif isinstance(template, str):
        yield from (c for c in constants if isinstance(c, str))


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _at(value: Any, fields: tuple[str, ...]) -> Any:
    for name in fields:
        value = value.get(name) if isinstance(value, Mapping) else None
    return value


def _with(value: Any, fields: tuple[str, ...], new: Any) -> Any:
    """A copy of `value` with the field at `fields` set to `new` (the value itself if empty)."""
    if not fields:
        return new
    copy = record(dict(value)) if isinstance(value, Mapping) else record({})
    copy[fields[0]] = _with(copy.get(fields[0]), fields[1:], new)
    return copy


def _combinations(choices: list[list[tuple[str, Any]]], limit: int) -> list[dict[str, Any]]:
    """Output dicts (an output whose value is None is left out: its zero), every combination
    when there are at most `limit`, else one output varied at a time."""
    if not choices:
        return [{}]
    size = math.prod(len(c) for c in choices)
    if size <= max(limit, 1):
        combos = [dict(p) for p in itertools.product(*choices)]
    else:
        first = dict(c[0] for c in choices)
        combos = [first] + [{**first, o: v} for c in choices for o, v in c[1:]]
    return [{o: v for o, v in combo.items() if v is not None} for combo in combos]
