"""`In("S")` in conds and actions, and `done.state.S` triggers: the state's name resolved to
its id in the lowered chart.

A name is a state's model name (`Node.name`) or its chart id (docs/scxml.md: readable ids).
When several states of one chart have the name (a submachine used twice, equal names in
different regions), the first in document order is meant, and its chart id picks another; a
name no state has stays as it is (`check.expressions` reports it before lowering). Charts
without `In()` are returned as they are.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any, TypeVar

from swarmgen import expr
from swarmgen.chart import model as c

DONE = "done.state."  # a trigger on another state's completion names the state

_T = TypeVar("_T")


def resolve_in_states(chart: c.Chart) -> c.Chart:
    """The chart with every `In(name)` naming its state's id."""
    nodes = chart.walk()
    tests_in = any(_has_in(node) for node in nodes)
    if not tests_in and not any(_waits_for_done(node) for node in nodes):
        return chart
    ids: dict[str, str] = {}
    for node in nodes:  # document order: the first of a name wins
        ids.setdefault(node.name or node.id, node.id)
    for node in nodes:
        ids[node.id] = node.id  # an id always names its own state

    def lookup(name: str) -> str:
        return ids.get(name, name)

    return replace(chart, children=tuple(_node(n, lookup, tests_in) for n in chart.children))


def _waits_for_done(node: c.Node) -> bool:
    return any(e.startswith(DONE) for t in node.transitions for e in t.events)


def _has_in(node: c.Node) -> bool:
    transitions = [*node.transitions, *([node.initial] if node.initial else [])]
    exprs = [t.cond for t in transitions if t.cond is not None]
    for action in c.flat(
        (*node.onentry, *node.onexit, *(a for t in transitions for a in t.actions))
    ):
        exprs += _action_exprs(action)
    return any(expr.in_states(e) for e in exprs)


def _action_exprs(action: c.Action) -> list[expr.Expr]:
    if isinstance(action, c.Assign):
        return [action.value]
    if isinstance(action, c.If):
        return [cond for cond, _ in action.branches if cond is not None]
    if isinstance(action, c.ForEach):
        return [action.array]
    if isinstance(action, c.Log):
        return [action.value]
    if isinstance(action, c.Raise | c.Send):
        found = [p.value for p in action.params if not isinstance(p.value, c.FieldDefault)]
        if isinstance(action, c.Raise) and action.delay is not None:
            found.append(action.delay.amount)
        if isinstance(action, c.Raise) and action.target is not None:
            found.append(action.target)
        if isinstance(action, c.Raise):
            found += [e for e in (action.via, action.named, action.content) if e is not None]
        return found
    return []


def _node(node: c.Node, lookup: Callable[[str], str], tests_in: bool) -> c.Node:
    """The node with its `In()` (when the chart `tests_in` at all) and `done.state` names
    resolved; the node itself when none of them is in it (`_replaced`)."""

    def fix(e: expr.Expr) -> expr.Expr:
        return expr.resolve_states(e, lookup)

    def actions(found: tuple[c.Action, ...]) -> tuple[c.Action, ...]:
        return tuple(_action(a, fix) for a in found) if tests_in else found

    def transition(t: c.Transition) -> c.Transition:
        cond = fix(t.cond) if t.cond is not None and tests_in else t.cond
        events = tuple(DONE + lookup(e[len(DONE) :]) if e.startswith(DONE) else e for e in t.events)
        return _replaced(t, events=events, cond=cond, actions=actions(t.actions))

    return _replaced(
        node,
        children=tuple(_node(child, lookup, tests_in) for child in node.children),
        transitions=tuple(transition(t) for t in node.transitions),
        initial=transition(node.initial) if node.initial is not None else None,
        onentry=actions(node.onentry),
        onexit=actions(node.onexit),
    )


def _action(action: c.Action, fix: Callable[[expr.Expr], expr.Expr]) -> c.Action:
    if isinstance(action, c.Assign):
        return _replaced(action, value=fix(action.value))
    if isinstance(action, c.If):
        branches = tuple(
            (fix(cond) if cond is not None else None, tuple(_action(a, fix) for a in inner))
            for cond, inner in action.branches
        )
        return _replaced(action, branches=branches)
    if isinstance(action, c.Log):
        return _replaced(action, value=fix(action.value))
    if isinstance(action, c.Block):
        return _replaced(action, actions=tuple(_action(a, fix) for a in action.actions))
    if isinstance(action, c.ForEach):
        inner_actions = tuple(_action(a, fix) for a in action.actions)
        return _replaced(action, array=fix(action.array), actions=inner_actions)
    if isinstance(action, c.Raise | c.Send):
        params = tuple(
            p if isinstance(p.value, c.FieldDefault) else _replaced(p, value=fix(p.value))
            for p in action.params
        )
        if isinstance(action, c.Raise):
            delay = (
                _replaced(action.delay, amount=fix(action.delay.amount)) if action.delay else None
            )
            target = fix(action.target) if action.target is not None else None
            via = fix(action.via) if action.via is not None else None
            named = fix(action.named) if action.named is not None else None
            content = fix(action.content) if action.content is not None else None
            return _replaced(
                action,
                params=params,
                delay=delay,
                target=target,
                via=via,
                named=named,
                content=content,
            )
        return _replaced(action, params=params)
    return action


def _replaced(obj: _T, **changes: Any) -> _T:
    """`replace(obj, **changes)`, or `obj` itself when every change is what it holds already:
    a chart with one `In()` or `done.state` would otherwise rebuild every transition and
    action of every state (10,000 states: ~40,000 `replace` calls for nothing)."""
    if all(_same(new, getattr(obj, name)) for name, new in changes.items()):
        return obj
    return replace(obj, **changes)  # type: ignore[type-var]


def _same(new: object, old: object) -> bool:
    """Whether a rewritten value is the one it came from: the same object, equal text, or a
    tuple of such (the rewrites return their input itself when nothing in it changes)."""
    if new is old:
        return True
    if isinstance(new, str):
        return new == old
    if isinstance(new, tuple) and isinstance(old, tuple) and len(new) == len(old):
        return all(a is b or _same(a, b) for a, b in zip(new, old, strict=True))
    return False
