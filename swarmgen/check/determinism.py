"""Determinism: two transitions from one state on the same trigger whose guards can both hold.

Each transition is reported once, with the first earlier transition that can fire with it (the
model order then silently picks that one); transitions without a guard are reported once per
group. A pair of guards is decided in two steps:

1. without search (`_exclusive`): conjuncts that compare one name with constants and
   cannot all hold together (`x < 20` and `x >= 20`, `level == 1` and `level == 2`);
2. by search: each name and event field ranges over the constants the guards compare it with
   (and their neighbours), booleans and null; a valuation under which both guards hold is
   reported as the witness.

The search is bounded by a work budget per model (node evaluations); pairs left when it runs
out are reported once per group as undecided (a note, SG132), never searched on.
"""

from __future__ import annotations

import itertools
import operator
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir import expr
from swarmgen.ir.nodes import Model, PseudoKind, Pseudostate, Transition, TriggerKind
from swarmgen.ir.query import walk

MAX_VALUATIONS = 20_000  # per pair: past it, the pair counts as exclusive (as it always did)
# Guard nodes evaluated per model, about 0.25 s: a valuation costs the size of both guards, a
# pair test PAIR_COST (measured: it takes as long as evaluating 30 nodes). 40 guarded transitions
# on one trigger used to search for minutes; 2,000 exclusive ones took 4 s of pair tests alone.
WORK_BUDGET = 4_000_000
PAIR_COST = 32
_HINT = "make the guards exclusive (e.g. `[x < 20]` and `[x >= 20]`), or use `else`"


@dataclass
class _Budget:
    left: int = WORK_BUDGET

    def spend(self, units: int) -> bool:
        """Take `units` if that many are left."""
        if units > self.left:
            self.left = 0
            return False
        self.left -= units
        return True


@dataclass(eq=False)
class _Guarded:
    """A transition with what the pair tests need of its guard, computed once."""

    transition: Transition
    guard: expr.Expr | None
    size: int = 0
    constraints: _Constraints = field(default_factory=dict)
    constants: dict[str, set[Any]] = field(default_factory=dict)
    compiled: Compiled | None = None

    @classmethod
    def of(cls, transition: Transition) -> _Guarded:
        guard = transition.guard
        if guard is None:
            return cls(transition, None)
        return cls(
            transition,
            guard,
            _size(guard),
            _constraints(guard),
            _compared_constants(guard),
            compile_guard(guard),
        )


@dataclass
class _Finding:
    """One report in the making; the same pair found on several triggers is reported once."""

    kind: str  # "pair", "unguarded" or "undecided"
    source: str
    transitions: tuple[Transition, ...]  # the pair; every unguarded twin; the first undecided pair
    witness: dict[str, Any] = field(default_factory=dict)
    keys: dict[str, None] = field(default_factory=dict)  # the triggers, in order (a set)
    pairs: set[tuple[int, int]] = field(default_factory=set)  # undecided: which pairs
    untested: int = 0  # undecided: pairs not even tried (the budget ran out before them)


_Undecided = object()  # a pair test's third answer
_PairResult = dict[str, Any] | None | object


class _Analysis:
    """What one model's groups share: the budget, each guard's pieces, each pair's answer."""

    def __init__(self) -> None:
        self.budget = _Budget()
        self.guarded: dict[int, _Guarded] = {}
        self.answers: dict[tuple[int, int], _PairResult] = {}
        self.findings: dict[tuple[object, ...], _Finding] = {}

    def of(self, transition: Transition) -> _Guarded:
        item = self.guarded.get(id(transition))
        if item is None:
            item = self.guarded[id(transition)] = _Guarded.of(transition)
        return item

    def pair(self, first: _Guarded, second: _Guarded) -> _PairResult:
        """A witness, None (exclusive) or _Undecided; memoised across triggers."""
        key = (id(first.transition), id(second.transition) if second.guard is not None else 0)
        if key not in self.answers:
            self.answers[key] = self._decide(first, second)
        return self.answers[key]

    def _decide(self, first: _Guarded, second: _Guarded) -> _PairResult:
        if not self.budget.spend(PAIR_COST):
            return _Undecided
        if _exclusive(first.constraints, second.constraints):
            return None
        try:
            return _search(first, second, self.budget)
        except Undecidable:
            return _Undecided

    def add(self, merge: tuple[object, ...], finding: _Finding, key: str) -> _Finding:
        kept = self.findings.setdefault(merge, finding)
        kept.keys[key] = None
        return kept


def check_determinism(model: Model) -> list[Diagnostic]:
    analysis = _Analysis()
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
            if len(transitions) < 2:
                continue
            vertex = kinds.get(source_id)  # None for a ConnectionPointReference
            name = (vertex.name if vertex else "") or source_id
            _group(analysis, name, source_id, key, transitions)
    return [_diagnostic(f) for f in analysis.findings.values()]


def _trigger_keys(transition: Transition) -> list[str]:
    if not transition.triggers:
        return ["(completion)"]
    keys = []
    for trigger in transition.triggers:
        if trigger.kind == TriggerKind.TIME:
            keys.append(f"after {trigger.delay_ms} ms")
        else:
            keys.append(trigger.name)
    return list(dict.fromkeys(keys))  # two triggers on one event are one key


def _group(
    analysis: _Analysis, source: str, source_id: str, key: str, transitions: list[Transition]
) -> None:
    """Each transition of one source on one trigger (in model order) against the earlier ones:
    the first that can fire with it is reported; unguarded twins once for the group."""
    items = [analysis.of(t) for t in transitions if not isinstance(t.guard, expr.Else)]
    unguarded = [g.transition for g in items if g.guard is None]
    if len(unguarded) > 1:
        merge = ("unguarded", *map(id, unguarded))
        analysis.add(merge, _Finding("unguarded", source, tuple(unguarded)), key)
    first_unguarded: _Guarded | None = None
    earlier: list[_Guarded] = []
    for at, item in enumerate(items):
        if item.guard is None and first_unguarded is not None:
            continue  # reported above, once for the group
        candidates = [first_unguarded] if first_unguarded is not None else earlier
        if analysis.budget.left == 0 and candidates:  # count the rest, test none of them
            rest = _untested(items[at:], len(earlier), first_unguarded is not None)
            pair = (candidates[0].transition, item.transition)
            analysis.add(("undecided", source_id), _Finding("undecided", source, pair), key)
            analysis.findings["undecided", source_id].untested += rest
            return
        for other in candidates:
            if _against(analysis, source, source_id, key, other, item):
                break
        if item.guard is None:
            first_unguarded = item
        else:
            earlier.append(item)


def _against(
    analysis: _Analysis, source: str, source_id: str, key: str, other: _Guarded, item: _Guarded
) -> bool:
    """Test `item` against the earlier `other`; True when they conflict (and it is recorded)."""
    guarded, plain = (other, item) if item.guard is None else (item, other)
    answer = analysis.pair(guarded, plain) if guarded.guard is not None else {}
    pair = (other.transition, item.transition)
    if answer is _Undecided:
        kept = analysis.add(("undecided", source_id), _Finding("undecided", source, pair), key)
        kept.pairs.add((id(pair[0]), id(pair[1])))
        return False
    if isinstance(answer, dict):
        analysis.add(("pair", *map(id, pair)), _Finding("pair", source, pair, answer), key)
        return True
    return False


def _untested(rest: list[_Guarded], guarded: int, after_unguarded: bool) -> int:
    """How many pair tests the items of `rest` would need (the budget ran out before them)."""
    count = 0
    for item in rest:
        if after_unguarded:
            count += 1 if item.guard is not None else 0
        else:
            count += guarded
            guarded += item.guard is not None
            after_unguarded = item.guard is None
    return count


def _diagnostic(finding: _Finding) -> Diagnostic:
    what = _triggers(list(finding.keys))
    first, second = finding.transitions[0], finding.transitions[1]
    if finding.kind == "undecided":
        return dg.diag(
            dg.NONDETERMINISM_UNDECIDED,
            f"could not decide whether {len(finding.pairs) + finding.untested} pair(s) of "
            f"transitions from '{finding.source}' on {what} exclude each other: the check's "
            "search budget ran out",
            second.span,
            notes=[f"the first such pair: {first.span.location()} and {second.span.location()}"],
            hint="simpler guards (comparisons of one name with constants) are decided at once",
        )
    if finding.kind == "unguarded" and len(finding.transitions) > 2:
        shown = [t.span.location() for t in finding.transitions[1:4]]
        more = len(finding.transitions) - 1 - len(shown)
        return dg.diag(
            dg.NONDETERMINISTIC,
            f"'{finding.source}' has {len(finding.transitions)} transitions on {what} without "
            "a guard; the first in model order always wins",
            second.span,
            notes=[
                f"the first is at {first.span.location()}",
                "never taken: " + ", ".join(shown) + (f" and {more} more" if more else ""),
            ],
            hint=_HINT,
        )
    return _pair_diagnostic(finding, what)


def _pair_diagnostic(finding: _Finding, what: str) -> Diagnostic:
    first, second = finding.transitions
    notes = [f"the other transition is at {first.span.location()}"]
    if finding.witness:
        notes.append(
            "both guards hold when "
            + ", ".join(f"{k} = {_shown(v)}" for k, v in sorted(finding.witness.items()))
        )
    elif first.guard is None and second.guard is None:
        notes.append("neither has a guard")
    else:
        notes.append("one has no guard, and the other's guard can hold")
    return dg.diag(
        dg.NONDETERMINISTIC,
        f"'{finding.source}' has two transitions on {what} that can both fire; "
        "the first in model order wins",
        second.span,
        notes=notes,
        hint=_HINT,
    )


def _triggers(keys: list[str]) -> str:
    shown = ["(no trigger)" if k == "(completion)" else f"'{k}'" for k in keys[:3]]
    if len(keys) > 3:
        return ", ".join(shown) + f" and {len(keys) - 3} more triggers"
    return " and ".join(shown) if len(shown) < 3 else f"{shown[0]}, {shown[1]} and {shown[2]}"


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:59] + "…"


def _search(first: _Guarded, second: _Guarded, budget: _Budget) -> dict[str, Any] | None:
    guards = [g for g in (first.compiled, second.compiled) if g is not None]
    constants: dict[str, set[Any]] = {}
    for item in (first, second):
        for name, compared in item.constants.items():
            constants.setdefault(name, set()).update(compared)
    variables = sorted(constants)
    domains = [_domain(constants[v]) for v in variables]
    cost = max(1, first.size + second.size)
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
_Constraints = dict[str, list[tuple[str, Any]]]  # name -> (op, constant): `name op constant`


class Undecidable(Exception):
    """The search ran out of budget, or a value grew past what the check computes."""


def _size(e: expr.Expr) -> int:
    return sum(1 for _ in expr.walk(e))


def _names(e: expr.Expr) -> str | None:
    if isinstance(e, expr.Name):
        return e.name
    if isinstance(e, expr.EventField):
        return f"event.{e.field}"
    return None


def _compared_constants(guard: expr.Expr) -> dict[str, set[Any]]:
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


def _constraints(guard: expr.Expr) -> _Constraints:
    """The conjuncts `name op constant` (or `constant op name`) that the guard requires."""
    found: _Constraints = {}
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


def _exclusive(first: _Constraints, second: _Constraints) -> bool:
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
    if isinstance(e, expr.Attr):
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
    return lambda env: True  # Else


def _attribute(env: dict[str, Any]) -> Any:
    raise TypeError("attribute of an unknown value")


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
