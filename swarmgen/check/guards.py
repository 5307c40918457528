"""Guards as logic: whether two guards can hold together, decided without search or by one.

1. Without search (`exclusive`): conjuncts that compare one name with constants and cannot all
   hold together (`x < 20` and `x >= 20`, `level == 1` and `level == 2`).
2. By search (`search`): each name and event field ranges over the constants the guards compare
   it with (and their neighbours), booleans and null; a valuation under which every guard holds
   is the witness. The search spends a shared `Budget` and raises `Undecidable` when it is out.
"""

from __future__ import annotations

import itertools
import operator
from collections.abc import Callable
from typing import Any

from swarmgen import expr
from swarmgen.records import dataclass

MAX_VALUATIONS = 20_000  # per pair: past it, the pair counts as exclusive (as it always did)


@dataclass
class Budget:
    """The work (guard nodes evaluated) a model's searches may still spend."""

    left: int

    def spend(self, units: int) -> bool:
        """Take `units` if that many are left."""
        if units > self.left:
            self.left = 0
            return False
        self.left -= units
        return True


def search(
    guards: list[Compiled], constants: list[dict[str, set[Any]]], cost: int, budget: Budget
) -> dict[str, Any] | None:
    """A valuation under which every guard holds (the witness), or None; each valuation tried
    costs `cost` of the budget, and Undecidable is raised when the budget runs out."""
    merged: dict[str, set[Any]] = {}
    for compared in constants:
        for name, seen in compared.items():
            merged.setdefault(name, set()).update(seen)
    variables = sorted(merged)
    domains = [_domain(merged[v]) for v in variables]
    for values in itertools.islice(itertools.product(*domains), MAX_VALUATIONS):
        if not budget.spend(cost):
            raise Undecidable("the search budget ran out")
        env = dict(zip(variables, values, strict=True))
        if all((v := evaluate(g, env)) is not _UNDEFINED and v for g in guards):
            return {k: v for k, v in env.items() if v is not _UNDEFINED}
    return None


def _domain(constants: set[Any]) -> list[Any]:
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


# --- guards in pieces: size, compared constants, conjunct constraints

_UNDEFINED = object()
_ORDER = {"<", "<=", ">", ">="}
_FLIPPED = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "==", "!=": "!="}
Constraints = dict[str, list[tuple[str, Any]]]  # name -> (op, constant): `name op constant`


class Undecidable(Exception):
    """The search ran out of budget, or a value grew past what the check computes."""


def guard_size(e: expr.Expr) -> int:
    """How many nodes the guard has: what evaluating it once costs."""
    return sum(1 for _ in expr.walk(e))


def _names(e: expr.Expr) -> str | None:
    if isinstance(e, expr.Name):
        return e.name
    if isinstance(e, expr.EventField):
        return f"event.{e.field}"
    return None


def compared_constants(guard: expr.Expr) -> dict[str, set[Any]]:
    """Every name and event field of the guard, with the constants it is compared with (one
    walk: asking per name would be quadratic in the guard's size)."""
    found: dict[str, set[Any]] = {}
    for node in expr.walk(guard):
        name = _names(node)
        if name is not None:
            found.setdefault(name, set())
        elif isinstance(node, expr.Binary):
            for side, other in ((node.left, node.right), (node.right, node.left)):
                name = _names(side)
                if name is not None and isinstance(other, expr.Const):
                    found.setdefault(name, set()).add(other.value)
    return found


def _conjuncts(guard: expr.Expr) -> list[expr.Expr]:
    found, stack = [], [guard]
    while stack:
        node = stack.pop()
        if isinstance(node, expr.Binary) and node.op == "and":
            stack += [node.right, node.left]
        else:
            found.append(node)
    return found


def guard_constraints(guard: expr.Expr) -> Constraints:
    """The conjuncts `name op constant` (or `constant op name`) that the guard requires."""
    found: Constraints = {}
    for node in _conjuncts(guard):
        if not isinstance(node, expr.Binary) or node.op not in _FLIPPED:
            continue
        op: str = node.op
        name, constant = _names(node.left), node.right
        if name is None:
            name, op, constant = _names(node.right), _FLIPPED[op], node.left
        if name is not None and isinstance(constant, expr.Const):
            found.setdefault(name, []).append((op, constant.value))
    return found


def exclusive(first: Constraints, second: Constraints) -> bool:
    """True when some name is constrained by both guards in ways that cannot hold together."""
    return any(
        not _satisfiable(first[name] + second[name]) for name in first.keys() & second.keys()
    )


def _satisfiable(constraints: list[tuple[str, Any]]) -> bool:
    """Whether one value can meet every `op constant` (False only when that is certain).

    With an equality the value is that constant, up to `==` (1, 1.0 and True are one value), so
    the constant itself is tested. Otherwise the orderings bound an interval of numbers or of
    strings (a value cannot be both); `!=` only removes points."""
    for op, constant in constraints:
        if op == "==":
            return all(_holds(constant, o, c) for o, c in constraints)
    ordered = [(op, c) for op, c in constraints if op in _ORDER]
    if not ordered:
        return True
    if len({isinstance(c, str) for _, c in ordered}) > 1 or any(c is None for _, c in ordered):
        return False  # nothing compares with both a string and a number, nor with null
    # the tightest bounds: the largest lower one (strict first), the smallest upper one
    low = max(((c, op == ">") for op, c in ordered if op in {">", ">="}), default=None)
    high = min(((c, op != "<") for op, c in ordered if op in {"<", "<="}), default=None)
    if low is None or high is None:
        return True
    if low[0] != high[0]:
        return bool(low[0] < high[0])  # strings: maybe nothing lies between; the search decides
    point = low[0]
    return not low[1] and high[1] and all(c != point for op, c in constraints if op == "!=")


def _holds(value: Any, op: str, constant: Any) -> bool:
    try:
        return bool(_OPERATIONS[op](value, constant))
    except TypeError:
        return False  # the evaluator's meaning: an error makes the comparison false


# --- the evaluator

# Values the search computes stay small: a string of a guard repeated (`event.note * 2**53`) or
# doubled by nesting would exhaust memory. Past these sizes the pair is undecided.
MAX_STRING = 10_000
MAX_INT_BITS = 1_100  # beyond a double's range: ECMAScript could not hold the value anyway


Compiled = Callable[[dict[str, Any]], Any]


def evaluate(guard: Compiled, env: dict[str, Any]) -> Any:
    """Run a compiled guard; an error makes it undefined (false), as at run time. Raises
    Undecidable when a value outgrows MAX_STRING or MAX_INT_BITS."""
    try:
        return guard(env)
    except (TypeError, ZeroDivisionError, ValueError, AttributeError, OverflowError):
        return _UNDEFINED


def compile_guard(e: expr.Expr) -> Compiled:
    """The expression as nested closures, built once per guard: the search runs each guard
    thousands of times, and walking the tree each time cost most of it."""
    if isinstance(e, expr.Const):
        value = e.value
        return lambda env: value
    name = _names(e)
    if name is not None:
        return lambda env: env.get(name)
    if isinstance(e, expr.Attr | expr.System | expr.InState | expr.Invalid | expr.ListOf):
        return _attribute
    if isinstance(e, expr.Unary):
        operand = compile_guard(e.operand)
        if e.op == "not":
            return lambda env: not operand(env)
        if e.op == "-":
            return lambda env: -_number(operand(env))
        return lambda env: +_number(operand(env))
    if isinstance(e, expr.Binary):
        return _compile_binary(e.op, compile_guard(e.left), compile_guard(e.right))
    if isinstance(e, expr.StartsWith):
        text, prefix = compile_guard(e.text), compile_guard(e.prefix)
        return lambda env: _starts(text(env), prefix(env))
    return lambda env: True  # Else


def _attribute(env: dict[str, Any]) -> Any:
    raise TypeError("attribute of an unknown value")


def _starts(text: Any, prefix: Any) -> bool:
    if not isinstance(text, str) or not isinstance(prefix, str):
        raise TypeError("startswith takes strings")
    return text.startswith(prefix)


def _number(value: Any) -> int | float:
    if isinstance(value, str) or value is None:
        raise TypeError("arithmetic takes numbers")
    return value  # type: ignore[no-any-return]


def _compile_binary(op: str, left: Compiled, right: Compiled) -> Compiled:
    if op == "and":
        return lambda env: right(env) if (value := left(env)) else value
    if op == "or":
        return lambda env: value if (value := left(env)) else right(env)
    operation = _OPERATIONS[op]
    if op not in _ARITHMETIC:
        return lambda env: operation(left(env), right(env))

    def arithmetic(env: dict[str, Any]) -> Any:
        a, b = left(env), right(env)
        # the language's arithmetic: numbers, and `+` of two strings; never Python's string
        # repetition (`"a" * 3` is NaN in ECMAScript, a type error for the checks)
        if not (op == "+" and isinstance(a, str) and isinstance(b, str)):
            a, b = _number(a), _number(b)
        return _bounded(operation(a, b))

    return arithmetic


def _bounded(value: Any) -> Any:
    if isinstance(value, str) and len(value) > MAX_STRING:
        raise Undecidable(f"a string longer than {MAX_STRING} characters")
    if isinstance(value, int) and value.bit_length() > MAX_INT_BITS:
        raise Undecidable(f"an integer of more than {MAX_INT_BITS} bits")
    return value


_ARITHMETIC = {"+", "-", "*", "/", "%"}
_OPERATIONS: dict[str, Callable[[Any, Any], Any]] = {
    "==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le, ">": operator.gt,
    ">=": operator.ge, "+": operator.add, "-": operator.sub, "*": operator.mul,
    "/": operator.truediv, "%": operator.mod,
}  # fmt: skip
