"""Partial-order reduction: in a state, the steps of one member can stand for all the swarm's
steps when they are independent of everything the others can do (docs/verify.md, "Partial-order
reduction").

Two steps are **independent** when they belong to different members and neither posts to an
inbox: each then reads and writes only its own member's value, the other members only append to
the end of its inbox (which the head it delivers does not see), and neither enables or disables
the other. A member's enabled steps form a **persistent set** (every step outside it, on any
path, is independent of every step in it) when:

- its inbox is not empty: no future append can enable a step of it that is not enabled now (its
  delivery is already enabled; its behaviour ends, emissions and timers change only with its own
  steps);
- none of its steps sends an event (an append to another inbox is dependent on that member's
  delivery and on every other append to it);
- the abort has not been sent (after it every state is expanded in full: abort safety is about
  every member's fate, and that part of the space is small);
- none of its steps is **visible**: it changes nothing a user property observes (the member's
  active states and data the property reads, `Observer.projection`).

A persistent set with these conditions preserves deadlocks (SG401) and, with the cycle proviso
the search adds (`explore._may_close_cycle`: every cycle of the reduced graph but a retried
step's self-loop has a fully expanded state), the
stutter-invariant properties over the visible propositions: the user properties, the states
entered (SG403, each member's own steps are all kept, only their interleaving with other
members' steps is pruned) and the events received (SG404).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from swarmgen.verify.system import Step, SwarmState, System

Projection = Callable[[int], Any]  # member value -> what the properties observe of it


def ample(system: System, state: SwarmState, visible: Projection | None) -> list[Step] | None:
    """The steps of the first member whose steps form a persistent set (see the module
    docstring), or None when no member qualifies (expand in full)."""
    for index, value in enumerate(state.members):
        if _qualifies(system, value, visible):
            return [
                Step(s.kind, index, s.event, s.state, s.data) for s in system.local_steps(value)
            ]
    return None


def _qualifies(system: System, value: int, visible: Projection | None) -> bool:
    known = system.ample_memo.get(value)
    if known is None:
        known = system.ample_memo[value] = _check(system, value, visible)
    return known


def _check(system: System, value: int, visible: Projection | None) -> bool:
    member = system.values[value]
    if not member.inbox or not member.engine.running:
        return False
    steps = system.local_steps(value)
    if not steps:
        return False
    before = visible(value) if visible is not None else None
    for step in steps:
        if step.kind == "emit":
            return False
        move = system.move(value, step)
        if move.posts or move.effect.sent:
            return False
        if visible is not None and visible(move.after) != before:
            return False
    return True
