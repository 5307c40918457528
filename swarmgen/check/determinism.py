"""Determinism: two transitions from one state on the same trigger whose guards can both hold.

Each transition is reported once, with the first earlier transition that can fire with it (the
model order then silently picks that one); transitions without a guard are reported once per
group. Whether a pair of guards can hold together is decided by `guards` (without search, then
by one, whose witness is reported).

The search is bounded by a work budget per model (node evaluations); pairs left when it runs
out are reported once per group as undecided (a note, SG132), never searched on.
"""

from __future__ import annotations

from dataclasses import field
from typing import Any

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.check.guards import (
    Budget,
    Compiled,
    Constraints,
    Undecidable,
    compared_constants,
    compile_guard,
    exclusive,
    guard_constraints,
    guard_size,
    search,
)
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model, PseudoKind, Pseudostate, Transition, TriggerKind
from swarmgen.ir.query import walk
from swarmgen.records import dataclass

# Guard nodes evaluated per model, about 0.25 s: a valuation costs the size of both guards, a
# pair test PAIR_COST (measured: it takes as long as evaluating 30 nodes). 40 guarded transitions
# on one trigger used to search for minutes; 2,000 exclusive ones took 4 s of pair tests alone.
WORK_BUDGET = 4_000_000
PAIR_COST = 32


@dataclass(eq=False)
class _Guarded:
    """A transition with what the pair tests need of its guard, computed once."""

    transition: Transition
    guard: expr.Expr | None
    size: int = 0
    constraints: Constraints = field(default_factory=dict)
    constants: dict[str, set[Any]] = field(default_factory=dict)
    compiled: Compiled | None = None

    @classmethod
    def of(cls, transition: Transition) -> _Guarded:
        """The pieces of `transition`'s guard (none for a transition without one)."""
        guard = transition.guard
        if guard is None:
            return cls(transition, None)
        return cls(
            transition,
            guard,
            guard_size(guard),
            guard_constraints(guard),
            compared_constants(guard),
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
        self.budget = Budget(WORK_BUDGET)
        self.guarded: dict[int, _Guarded] = {}
        self.answers: dict[tuple[int, int], _PairResult] = {}
        self.findings: dict[tuple[object, ...], _Finding] = {}

    def of(self, transition: Transition) -> _Guarded:
        """The guard pieces of `transition`, computed on first use."""
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
        if exclusive(first.constraints, second.constraints):
            return None
        compiled = [g for g in (first.compiled, second.compiled) if g is not None]
        cost = max(1, first.size + second.size)
        try:
            return search(compiled, [first.constants, second.constants], cost, self.budget)
        except Undecidable:
            return _Undecided

    def add(self, merge: tuple[object, ...], finding: _Finding, key: str) -> _Finding:
        """Record `finding` on trigger `key`, merged with an earlier one of the same `merge`."""
        kept = self.findings.setdefault(merge, finding)
        kept.keys[key] = None
        return kept


def check_determinism(model: Model) -> list[Diagnostic]:
    """Report transitions from one source on one trigger whose guards can hold together."""
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
        return ["(eventless)" if transition.eventless else "(completion)"]
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
        return dg.NONDETERMINISM_UNDECIDED.at(
            second.span,
            notes=[
                dg.NONDETERMINISM_UNDECIDED.note(
                    "first-pair", first=first.span.location(), second=second.span.location()
                )
            ],
            count=len(finding.pairs) + finding.untested,
            source=finding.source,
            what=what,
        )
    if finding.kind == "unguarded" and len(finding.transitions) > 2:
        code = dg.NONDETERMINISTIC
        shown = [t.span.location() for t in finding.transitions[1:4]]
        more = len(finding.transitions) - 1 - len(shown)
        never = (
            code.note("never-taken-more", shown=", ".join(shown), more=more)
            if more
            else code.note("never-taken", shown=", ".join(shown))
        )
        return code.at(
            second.span,
            "unguarded",
            notes=[code.note("first-at", where=first.span.location()), never],
            source=finding.source,
            count=len(finding.transitions),
            what=what,
        )
    return _pair_diagnostic(finding, what)


def _pair_diagnostic(finding: _Finding, what: str) -> Diagnostic:
    first, second = finding.transitions
    code = dg.NONDETERMINISTIC
    notes = [code.note("other-at", where=first.span.location())]
    if finding.witness:
        values = ", ".join(f"{k} = {_shown(v)}" for k, v in sorted(finding.witness.items()))
        notes.append(code.note("witness", values=values))
    elif first.guard is None and second.guard is None:
        notes.append(code.note("no-guards"))
    else:
        notes.append(code.note("one-guard"))
    return code.at(second.span, notes=notes, source=finding.source, what=what)


def _triggers(keys: list[str]) -> str:
    shown = ["(no trigger)" if k in ("(completion)", "(eventless)") else f"'{k}'" for k in keys[:3]]
    if len(keys) > 3:
        return ", ".join(shown) + f" and {len(keys) - 3} more triggers"
    return " and ".join(shown) if len(shown) < 3 else f"{shown[0]}, {shown[1]} and {shown[2]}"


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:59] + "…"
