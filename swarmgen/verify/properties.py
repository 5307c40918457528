"""The built-in properties over what the search saw, as located diagnostics with their
counterexamples (docs/verify.md, "Properties").

- no deadlock (SG401): no reachable state in which no member can move, the station cannot
  change any member (or is silent: after the abort) and some member is not final;
- abort safety (SG402): from every state after the abort, a state where every member is final
  stays reachable (with finitely many states and fair choices, every member then gets there);
- every state of every machine is entered in the composed swarm (SG403);
- every swarm event a member sends makes some member take a transition at least once (SG404).

A violation is reported only when certain: states the budget left unexplored are assumed to
reach a final state, and SG403/SG404 need the whole space (after a bounded search: SG405).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import codes_verify as cv
from swarmgen.ir.nodes import Model
from swarmgen.span import Span
from swarmgen.verify.counterexample import Trace, active_names, rerun
from swarmgen.verify.explore import Budget, Search
from swarmgen.verify.load import event_span, state_span, swarm_span
from swarmgen.verify.system import System


@dataclass
class Finding:
    """One property's verdict: its diagnostic and, for a violation reached by a trace, the
    trace."""

    diagnostic: dg.Diagnostic
    trace: Trace | None = None


def evaluate(model: Model, system: System, search: Search, budget: Budget) -> list[Finding]:
    """Every property's violations, then the bounded note when the budget stopped the search."""
    swarm = _composition(system)
    found = _deadlock(model, system, search, budget) + _abort(model, system, search, budget)
    if search.bounded:
        span = swarm_span(model)
        bounded = cv.VERIFY_BOUNDED.at(
            span, states=search.states, depth=search.max_depth,
            max_states=budget.max_states, max_depth=budget.max_depth,
        )  # fmt: skip
        return [*found, Finding(bounded)]
    return found + _unreachable(model, system, search, swarm) + _unreceived(model, search, swarm)


def _composition(system: System) -> str:
    counts: dict[str, int] = {}
    for index in system.types:
        name = system.kinds[index].name
        counts[name] = counts.get(name, 0) + 1
    return ", ".join(f"{n}={c}" for n, c in counts.items())


def _stuck(system: System, trace: Trace) -> list[int]:
    return [i for i, m in enumerate(trace.final.members) if not m.engine.finished]


def _located(model: Model, system: System, trace: Trace, index: int) -> tuple[Span, str]:
    names = active_names(system, trace.final, index)
    state = names[-1] if names else ""
    kind = system.kinds[system.types[index]].name
    return state_span(model, kind, state), state


def _deadlock(model: Model, system: System, search: Search, budget: Budget) -> list[Finding]:
    """The shortest deadlock before the abort, and the shortest after it."""
    found = []
    for after_abort in (False, True):
        number = search.deadlocks.get(after_abort)
        if number is None:
            continue
        trace = rerun(system, search.path(number), budget.symmetry)
        stuck = _stuck(system, trace)
        members = ", ".join(
            f"{system.ids[i]} in {', '.join(active_names(system, trace.final, i))}" for i in stuck
        )
        span, _ = _located(model, system, trace, stuck[0])
        if after_abort:
            event = sorted(system.abort)[0]
            diagnostic = cv.VERIFY_DEADLOCK.at(
                span, "after-abort", event=event, members=members, length=trace.length
            )
        else:
            diagnostic = cv.VERIFY_DEADLOCK.at(span, members=members, length=trace.length)
        found.append(Finding(diagnostic, trace))
    return found


def _abort(model: Model, system: System, search: Search, budget: Budget) -> list[Finding]:
    """The first state after the abort (BFS order: the shortest trace) from which no state
    with every member final is reachable, and in which the members are stuck if there is
    one (the trace then ends where they stay, rather than where their fate is sealed)."""
    if not search.aborted:
        return []
    reverse: dict[int, list[int]] = {}
    for source, targets in search.aborted.items():
        for target in targets:
            reverse.setdefault(target, []).append(source)
    good = set(search.finished) | search.unexpanded
    queue = deque(good)
    while queue:
        for source in reverse.get(queue.popleft(), ()):
            if source not in good:
                good.add(source)
                queue.append(source)
    bad = [n for n in search.aborted if n not in good]
    if not bad:
        return []
    stuck = [n for n in bad if n in search.stuck]
    trace = rerun(system, search.path(min(stuck or bad)), budget.symmetry)
    index = _stuck(system, trace)[0]
    span, state = _located(model, system, trace, index)
    diagnostic = cv.VERIFY_ABORT.at(
        span, event=sorted(system.abort)[0], member=system.ids[index], state=state,
        length=trace.length,
    )  # fmt: skip
    return [Finding(diagnostic, trace)]


def _unreachable(model: Model, system: System, search: Search, swarm: str) -> list[Finding]:
    found = []
    present = {system.kinds[t].name for t in system.types}
    for kind in system.kinds:
        if kind.name not in present:
            continue
        entered = search.entered.get(kind.name, set())
        for node in sorted(kind.chart.nodes.values(), key=lambda n: n.order):
            if node.kind == "history" or node.id in entered:
                continue
            name = kind.chart.names.get(node.id, node.id)
            span = state_span(model, kind.name, name)
            diagnostic = cv.VERIFY_UNREACHABLE.at(span, state=name, member=kind.name, swarm=swarm)
            found.append(Finding(diagnostic))
    return found


def _unreceived(model: Model, search: Search, swarm: str) -> list[Finding]:
    return [
        Finding(cv.VERIFY_UNRECEIVED.at(event_span(model, name), event=name, swarm=swarm))
        for name in sorted(search.sent - search.received)
    ]
