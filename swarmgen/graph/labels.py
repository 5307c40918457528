"""The diagrams' texts: transition labels, effects and triggers in the model's own notation,
each one line and clipped to a limit (raw, unescaped: each renderer escapes for its format)."""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence

from swarmgen import expr
from swarmgen.ir import nodes as ir
from swarmgen.names import one_line

GUARD_LIMIT = 40
EFFECT_LIMIT = 60
TRIGGER_LIMIT = 40
ACTIVITY_LIMIT = 48


@functools.lru_cache(maxsize=4096)
def clip(text: str, limit: int) -> str:
    """One line, at most `limit` characters (an ellipsis marks the cut). Memoised: the same
    guard and effect texts label thousands of transitions."""
    flat = " ".join(one_line(text).split())
    return flat if len(flat) <= limit else flat[: limit - 1].rstrip() + "…"


def _args_text(args: Sequence[expr.Arg]) -> str:
    return ", ".join(f"{a.name} = {expr.to_text(a.value)}" for a in args)


def action_text(action: expr.Action) -> str:
    """An effect in the model's action language."""
    match action:
        case expr.Assign():
            target = action.target
            shown = expr.to_text(target) if isinstance(target, expr.Invalid) else target
            return f"{shown} = {expr.to_text(action.value)}"
        case expr.Raise() | expr.Send():
            verb = "raise" if isinstance(action, expr.Raise) else "send"
            args = f"({_args_text(action.args)})" if action.args else ""
            if isinstance(action, expr.Raise) and action.content is not None:
                args = f"({expr.to_text(action.content)})"  # the event's whole data
            return f"{verb} {expr.event_text(action)}{args}{_delay_text(action)}"
        case expr.Cancel() if action.expr is not None:
            return f"cancel ({expr.to_text(action.expr)})"
        case expr.Cancel():
            return f"cancel {action.sendid}"
        case expr.If():
            return _if_text(action)
        case expr.Block():
            return f"block {'; '.join(action_text(a) for a in action.actions)} end"
        case expr.Log():
            label = f"{expr.to_text(expr.Const(value=action.label))}, " if action.label else ""
            return f"log {label}{expr.to_text(action.value)}"
        case expr.Done():
            return f"done({_args_text(action.args)})"
        case expr.ForEach():
            names = action.item + (f", {action.index}" if action.index else "")
            body = "; ".join(action_text(a) for a in action.actions)
            return f"for {names} in {expr.to_text(action.array)} do {body} end"


def _if_text(action: expr.If) -> str:
    parts = []
    for number, branch in enumerate(action.branches):
        body = "; ".join(action_text(a) for a in branch.actions)
        if branch.cond is None:
            parts.append(f"else {body}")
        else:
            keyword = "if" if number == 0 else "elif"
            parts.append(f"{keyword} {expr.to_text(branch.cond)} then {body}")
    return " ".join(parts) + " end"


def _delay_text(action: expr.Raise | expr.Send) -> str:
    if not isinstance(action, expr.Raise):
        return ""
    to = f" to {expr.to_text(action.target)}" if action.target is not None else ""
    to += f" via {expr.to_text(action.via)}" if action.via is not None else ""
    into = f" into {action.into}" if action.into is not None else ""
    if action.delay is None:
        return to + into
    unit = f" {action.delay.unit}" if action.delay.unit else ""
    named = f" as {action.sendid}" if action.sendid else ""
    return f"{to} after {expr.to_text(action.delay.amount)}{unit}{named}{into}"


def actions_text(actions: Iterable[expr.Action], opaque: Iterable[ir.OpaqueCode]) -> str:
    """Actions, then opaque code (as `<language code>`), separated by semicolons."""
    parts = [action_text(a) for a in actions]
    parts += [f"<{o.language} code>" for o in opaque]
    return "; ".join(parts)


def trigger_text(trigger: ir.Trigger) -> str:
    """A trigger as the model writes it: `after N ms`, `*` or the event's name."""
    if trigger.kind == ir.TriggerKind.TIME and trigger.delay_ms is not None:
        return f"after {trigger.delay_ms} ms"
    if trigger.kind == ir.TriggerKind.ANY:
        return "*"
    return trigger.name


def transition_label(transition: ir.Transition) -> tuple[str, ...]:
    """`event`, `[guard]`, `/ effect` (the parts that are there), each one line and clipped."""
    parts: list[str] = []
    triggers = ", ".join(trigger_text(t) for t in transition.triggers)
    if triggers:
        parts.append(clip(triggers, TRIGGER_LIMIT))
    guard = expr.to_text(transition.guard) if transition.guard is not None else None
    guard = guard or transition.guard_text
    if guard:
        parts.append(f"[{clip(guard, GUARD_LIMIT)}]")
    opaque = [o for o in transition.opaque if o.role == "effect"]
    effect = actions_text(transition.effect, opaque)
    if effect:
        parts.append(f"/ {clip(effect, EFFECT_LIMIT)}")
    return tuple(parts)
