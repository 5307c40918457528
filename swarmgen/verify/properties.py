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

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import codes_verify as cv
from swarmgen.ir.nodes import Model
from swarmgen.records import dataclass
from swarmgen.span import Span
from swarmgen.verify.counterexample import Trace, active_names, rerun
from swarmgen.verify.decouple import local
from swarmgen.verify.explore import Budget, Search
from swarmgen.verify.load import event_span, state_span, swarm_span
from swarmgen.verify.system import Step, System, canonical


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
    found += _lost(model, system, search, budget)
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
    return [
        i for i in range(len(trace.final.members)) if not system.engine(trace.final, i).finished
    ]


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
        tail: list[tuple[int, Step]] = []
        if number is None and after_abort:
            number, tail = _decoupled_deadlock(system, search)
        if number is None:
            continue
        trace = rerun(system, search.path(number), budget.symmetry, tail)
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


def _decoupled_deadlock(
    system: System, search: Search
) -> tuple[int | None, list[tuple[int, Step]]]:
    """The first decoupled state from which the members can all stop, one not final, and
    each member's own steps there (`decouple`)."""
    for number, members in sorted(search.decoupled.items()):
        graphs = [local(system, v) for v in members]
        if any(not g.terminal for g in graphs):
            continue  # some member can always move: no swarm deadlock from here
        ends = [next((t for t in g.terminal if t not in g.finished), None) for g in graphs]
        if all(e is None for e in ends):
            continue
        tail: list[tuple[int, Step]] = []
        for index, (graph, end) in enumerate(zip(graphs, ends, strict=True)):
            tail.extend(
                (index, s) for s in graph.path(end if end is not None else graph.terminal[0])
            )
        return number, tail
    return None, []


def _abort(model: Model, system: System, search: Search, budget: Budget) -> list[Finding]:
    """The first state after the abort (BFS order: the shortest trace) from which no state
    with every member final is reachable, and in which the members are stuck if there is
    one (the trace then ends where they stay, rather than where their fate is sealed)."""
    if not search.aborted and not search.decoupled:
        return []
    reverse: dict[int, list[int]] = {}
    for source, targets in search.aborted.items():
        for target in targets:
            reverse.setdefault(target, []).append(source)
    bad_locals: dict[int, tuple[int, int]] = {}  # decoupled state -> (member, stuck value)
    for number, members in search.decoupled.items():
        for index, value in enumerate(members):
            stuck = local(system, value).stuck()
            if stuck is not None:
                bad_locals[number] = (index, stuck)
                break
    good = set(search.finished) | search.unexpanded
    good.update(n for n in search.decoupled if n not in bad_locals)
    queue = deque(good)
    while queue:
        for source in reverse.get(queue.popleft(), ()):
            if source not in good:
                good.add(source)
                queue.append(source)
    bad = [n for n in (*search.aborted, *bad_locals) if n not in good]
    if not bad:
        return []
    stuck_states = [n for n in bad if n in search.stuck]
    first = min(stuck_states or bad)
    tail: list[tuple[int, Step]] = []
    if first in bad_locals:
        index, value = bad_locals[first]
        graph = local(system, search.decoupled[first][index])
        tail = [(index, s) for s in graph.path(value)]
    trace = rerun(system, search.path(first), budget.symmetry, tail)
    index = _stuck(system, trace)[0]
    span, state = _located(model, system, trace, index)
    diagnostic = cv.VERIFY_ABORT.at(
        span, event=sorted(system.abort)[0], member=system.ids[index], state=state,
        length=trace.length,
    )  # fmt: skip
    return [Finding(diagnostic, trace)]


def _lost(model: Model, system: System, search: Search, budget: Budget) -> list[Finding]:
    """Each event that some step sends while every member it reaches ignores it (SG406),
    with the shortest trace to that step."""
    found = []
    for name, (number, step) in sorted(search.lost.items()):
        trace = rerun(system, [*search.path(number), step], budget.symmetry)
        sender = system.ids[_real_member(system, search, number, step)]
        diagnostic = cv.VERIFY_LOST.at(
            event_span(model, name), event=name, sender=sender, length=trace.length
        )
        found.append(Finding(diagnostic, trace))
    return found


def _real_member(system: System, search: Search, number: int, step: Step) -> int:
    """The member a step of the search names (a canonical position), in the system's order."""
    if not search.symmetry:
        return step.member
    before = rerun(system, search.path(number), True).final
    return canonical(system, before)[1][step.member]


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
