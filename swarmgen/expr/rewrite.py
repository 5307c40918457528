"""Queries and rewrites of expression and action trees (`tree`): the nodes an expression
holds, the names and event fields it reads, the expressions an action evaluates, and the
rewrites the IR build and the lowering make (enumeration literals, event fields as data, state
names as chart ids).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterator

from swarmgen.expr.tree import (
    Action,
    Arg,
    Assign,
    Attr,
    Binary,
    Block,
    Branch,
    Cancel,
    Const,
    Delay,
    Done,
    EventField,
    Expr,
    ForEach,
    If,
    InState,
    ListOf,
    Log,
    Name,
    Raise,
    Send,
    StartsWith,
    Unary,
)


def _children(e: Expr) -> tuple[Expr, ...]:
    if isinstance(e, ListOf):
        return e.items
    if isinstance(e, Attr):
        return (e.obj,)
    if isinstance(e, Unary):
        return (e.operand,)
    if isinstance(e, Binary):
        return (e.left, e.right)
    if isinstance(e, StartsWith):
        return (e.text, e.prefix)
    return ()


def walk(expr: Expr) -> Iterator[Expr]:
    """All nodes of the tree, pre-order, left to right (iterative: no recursion limit)."""
    stack: list[Expr] = [expr]
    while stack:
        node = stack.pop()
        yield node
        stack.extend(reversed(_children(node)))


# The rewrites below return the node itself where nothing under it changes: the result is equal
# either way, and most trees have nothing to rewrite (re-validating every node of every
# expression was a fifth of the IR build at 10,000 states).


def replace_fields(expr: Expr, names: dict[str, str]) -> Expr:
    """`event.<f>` read as the member datum `names[f]` instead (depth is bounded by the parser)."""
    if isinstance(expr, EventField) and expr.field in names:
        return Name(name=names[expr.field])
    return _rebuild(expr, lambda e: replace_fields(e, names))


def resolve_enums(expr: Expr, enums: Collection[str]) -> Expr:
    """`E.lit` read as the literal `lit` of enumeration `E` when `E` is one of `enums` (a
    string constant that remembers its enumeration; depth is bounded by the parser)."""
    if isinstance(expr, Attr) and isinstance(expr.obj, Name) and expr.obj.name in enums:
        return Const(value=expr.name, enum=expr.obj.name)
    return _rebuild(expr, lambda e: resolve_enums(e, enums))


def resolve_action_enums(action: Action, enums: Collection[str]) -> Action:
    """An action with its enumeration literals resolved (`resolve_enums`)."""
    return map_action(action, lambda e: resolve_enums(e, enums))


def map_action(action: Action, rewrite: Callable[[Expr], Expr]) -> Action:
    """The action with `rewrite` applied to each expression it holds (itself when none
    changes)."""
    if isinstance(action, Cancel):
        if action.expr is None:
            return action
        computed = rewrite(action.expr)
        return action if computed is action.expr else Cancel(expr=computed)
    if isinstance(action, Log):
        value = rewrite(action.value)
        return action if value is action.value else Log(label=action.label, value=value)
    if isinstance(action, Done):
        values = [rewrite(a.value) for a in action.args]
        content = rewrite(action.content) if action.content is not None else None
        if content is action.content and all(
            v is a.value for v, a in zip(values, action.args, strict=True)
        ):
            return action
        args = tuple(Arg(name=a.name, value=v) for a, v in zip(action.args, values, strict=True))
        return Done(args=args, content=content)
    if isinstance(action, Block):
        inner_actions = tuple(map_action(a, rewrite) for a in action.actions)
        return action if inner_actions == action.actions else Block(actions=inner_actions)
    if isinstance(action, ForEach):
        array, inner = rewrite(action.array), tuple(map_action(a, rewrite) for a in action.actions)
        if array is action.array and inner == action.actions:
            return action
        return ForEach(array=array, item=action.item, index=action.index, actions=inner)
    if isinstance(action, If):
        branches = tuple(
            Branch(
                cond=rewrite(b.cond) if b.cond is not None else None,
                actions=tuple(map_action(a, rewrite) for a in b.actions),
            )
            for b in action.branches
        )
        return action if branches == action.branches else If(branches=branches)
    if isinstance(action, Assign):
        value = rewrite(action.value)
        return action if value is action.value else Assign(target=action.target, value=value)
    values = [rewrite(a.value) for a in action.args]
    delay = action.delay if isinstance(action, Raise) else None
    amount = rewrite(delay.amount) if delay is not None else None
    given = action.target if isinstance(action, Raise) else None
    target = rewrite(given) if given is not None else None
    given_via = action.via if isinstance(action, Raise) else None
    via = rewrite(given_via) if given_via is not None else None
    recomputed = _computed(action, rewrite)
    if (
        all(v is a.value for v, a in zip(values, action.args, strict=True))
        and (delay is None or amount is delay.amount)
        and target is given
        and via is given_via
        and recomputed is None
    ):
        return action
    args = tuple(Arg(name=a.name, value=v) for a, v in zip(action.args, values, strict=True))
    if isinstance(action, Send):
        return Send(event=action.event, args=args)
    if delay is not None and amount is not None:
        delay = Delay(amount=amount, unit=delay.unit)
    named, content = recomputed if recomputed is not None else (action.named, action.content)
    return Raise(
        event=action.event,
        args=args,
        delay=delay,
        sendid=action.sendid,
        target=target,
        via=via,
        into=action.into,
        named=named,
        content=content,
    )


def _computed(
    action: Raise | Send, rewrite: Callable[[Expr], Expr]
) -> tuple[Expr | None, Expr | None] | None:
    """A raise's computed name and content value rewritten, or None when neither changes."""
    if not isinstance(action, Raise) or (action.named is None and action.content is None):
        return None
    named = rewrite(action.named) if action.named is not None else None
    content = rewrite(action.content) if action.content is not None else None
    if named is action.named and content is action.content:
        return None
    return named, content


def action_exprs(action: Action) -> tuple[Expr, ...]:
    """The expressions an action evaluates itself (an `if`: its conditions, not its
    branches' actions: `flat` gives those), in evaluation order."""
    if isinstance(action, Cancel):
        return (action.expr,) if action.expr is not None else ()
    if isinstance(action, Block):
        return ()
    if isinstance(action, If):
        return tuple(b.cond for b in action.branches if b.cond is not None)
    if isinstance(action, ForEach):
        return (action.array,)
    if isinstance(action, Done):
        return (*(a.value for a in action.args), *([action.content] if action.content else []))
    if isinstance(action, Log):
        return (action.value,)
    if isinstance(action, Assign):
        return (action.value,)
    found = tuple(a.value for a in action.args)
    if isinstance(action, Raise) and action.delay is not None:
        found = (action.delay.amount, *found)
    if isinstance(action, Raise) and action.target is not None:
        found = (action.target, *found)
    if isinstance(action, Raise) and action.content is not None:
        found = (*found, action.content)
    if isinstance(action, Raise) and action.named is not None:
        found = (action.named, *found)
    if isinstance(action, Raise) and action.via is not None:
        found = (action.via, *found)
    return found


# The three queries below, by the expression's identity: one parsed text is one object on every
# transition that has it (ir.build parses each distinct text once), and the checks, the
# lowering and the SCXML writer ask about each transition. Each entry holds its expression, so
# no id is reused while it is kept; the answers are frozen. Bounded: cleared when full.
_ASKED: dict[tuple[str, int], tuple[Expr, frozenset[str]]] = {}
_ASKED_LIMIT = 1 << 16


def _asked(query: str, expr: Expr, answer: Callable[[Expr], frozenset[str]]) -> frozenset[str]:
    key = (query, id(expr))
    held = _ASKED.get(key)
    if held is not None and held[0] is expr:
        return held[1]
    found = answer(expr)
    if len(_ASKED) >= _ASKED_LIMIT:
        _ASKED.clear()
    _ASKED[key] = (expr, found)
    return found


def free_names(expr: Expr) -> frozenset[str]:
    """Member data names read by the expression (the root of `a.b` is `a`; no event fields)."""
    return _asked(
        "names", expr, lambda e: frozenset(n.name for n in walk(e) if isinstance(n, Name))
    )


def event_fields(expr: Expr) -> frozenset[str]:
    """Fields of the triggering event read by the expression."""
    return _asked(
        "fields", expr, lambda e: frozenset(n.field for n in walk(e) if isinstance(n, EventField))
    )


def in_states(expr: Expr) -> frozenset[str]:
    """The states `In(...)` tests in the expression."""
    return _asked(
        "states", expr, lambda e: frozenset(n.state for n in walk(e) if isinstance(n, InState))
    )


def resolve_states(expr: Expr, ids: Callable[[str], str]) -> Expr:
    """`In(name)` with its name replaced by `ids(name)` (lowering: names to chart ids)."""
    if isinstance(expr, InState):
        state = ids(expr.state)
        return expr if state == expr.state else InState(state=state)
    return _rebuild(expr, lambda e: resolve_states(e, ids))


def _rebuild(expr: Expr, rewrite: Callable[[Expr], Expr]) -> Expr:
    """The node with `rewrite` applied to its operands (itself when none changes)."""
    if isinstance(expr, ListOf):
        return _items(expr, rewrite)
    if isinstance(expr, Attr):
        obj = rewrite(expr.obj)
        return expr if obj is expr.obj else Attr(obj=obj, name=expr.name)
    if isinstance(expr, Unary):
        operand = rewrite(expr.operand)
        return expr if operand is expr.operand else Unary(op=expr.op, operand=operand)
    if isinstance(expr, Binary):
        left, right = rewrite(expr.left), rewrite(expr.right)
        if left is expr.left and right is expr.right:
            return expr
        return Binary(op=expr.op, left=left, right=right)
    if isinstance(expr, StartsWith):
        return _operands(expr, rewrite)
    return expr


def _operands(expr: StartsWith, rewrite: Callable[[Expr], Expr]) -> StartsWith:
    """`startswith` with `rewrite` applied to its operands (itself when neither changes)."""
    text, prefix = rewrite(expr.text), rewrite(expr.prefix)
    if text is expr.text and prefix is expr.prefix:
        return expr
    return StartsWith(text=text, prefix=prefix)


def _items(expr: ListOf, rewrite: Callable[[Expr], Expr]) -> ListOf:
    """The list with `rewrite` applied to its items (itself when none changes)."""
    items = tuple(rewrite(item) for item in expr.items)
    if all(new is old for new, old in zip(items, expr.items, strict=True)):
        return expr
    return ListOf(items=items)
