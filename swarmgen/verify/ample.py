"""Partial-order reduction: in a state, one member's delivery can stand for all the swarm's
steps when it is independent of everything the others and the member itself can do
(docs/verify.md, "Reductions").

A member's inbox is its one FIFO queue (`system`): its behaviours' ends, timers and delayed
raises go to its end, as everything other members and the station send does. So the event at
the head is the member's next input whatever else happens first, and taking it is
**independent** of every other step when:

- its inbox is not empty (the head is there: appends behind it change nothing of it);
- taking it sends nothing (to others: their inboxes' order would depend on it; to itself);
- it cancels no timer or delayed raise of the member and no behaviour that may still emit (a
  timer that fired first would stay queued, an emission made first would stay sent);
- it changes nothing a user property observes of the member (*visibility*: whether it is in
  each state the properties' atoms name for its type, and the data they read,
  `Observer.projection`; a step between two states no atom names is invisible).

Then `{deliver}` is a **persistent set**: a step of another member only reads and writes that
member and appends behind the head; a behaviour end, timer or delayed raise of the member
itself appends behind the head too, and an end whose state the delivery leaves is stale when
it is reached (dropped: the same state as the delivery alone). The delivery sends nothing, so
the events in flight (the state's weight) fall along it: no cycle of reduced states exists,
and the search's cycle proviso (`explore._may_close_cycle`) never has to expand such a state
in full. A persistent set keeps every reachable deadlock (SG401) and every state from which no
terminal state is reachable (SG402); with the visibility condition and no cycle left
unexpanded, the stutter-invariant properties over the visible propositions (the user
properties, the states entered, SG403, the events received, SG404): each member's own steps
are all kept, only their interleaving with the others' is pruned.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from swarmgen.verify.system import Step, SwarmState, System

Projection = Callable[[int], Any]  # member value -> what the properties observe of it

DELIVER = Step("deliver")


def ample(system: System, state: SwarmState, visible: Projection | None) -> list[Step] | None:
    """The delivery of the first member whose delivery forms a persistent set (see the module
    docstring), or None when no member's does (expand in full)."""
    for index, value in enumerate(state.members):
        if _qualifies(system, value, visible):
            return [Step("deliver", index)]
    return None


def _qualifies(system: System, value: int, visible: Projection | None) -> bool:
    known = system.ample_memo.get(value)
    if known is None:
        known = system.ample_memo[value] = _check(system, value, visible)
    return known


def _check(system: System, value: int, visible: Projection | None) -> bool:
    member = system.values[value]
    engine = member.engine
    if not member.inbox or not engine.running:
        return False
    move = system.move(value, DELIVER)
    if move.posts or move.effect.sent:
        return False
    kind = system.value_type[value]
    ran = system.take(kind, engine, member.inbox[0])
    if ran.stopped or not _kept(engine.delayed, ran.after.delayed):
        return False
    emitting = system.kinds[kind].emits
    chart = system.kinds[kind].chart
    for state_id, emitted in engine.calls:
        if state_id in ran.left and emitted < system.emit_bound:
            call = chart.nodes[state_id].call
            if call is not None and emitting.get(call.behaviour):
                return False
    return visible is None or visible(move.after) == visible(value)


def _kept(before: tuple[Any, ...], after: tuple[Any, ...]) -> bool:
    """Every delayed raise pending before is still pending, in the same order, after."""
    return after[: len(before)] == before
