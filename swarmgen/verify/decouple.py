"""Decoupled members: after the abort, once no member can be changed by anything another
member sends, the members no longer interact, and the swarm's future is the product of each
member's own future (docs/verify.md, "Reductions").

The station is silent after the abort, and every running member has the abort in its inbox
(or ignored it). An event a member sends goes to the end of the others' inboxes: behind
everything queued there, the abort among it. A member is **sealed** when, along its own steps
(deliveries of what is already in its inbox, behaviour ends, emissions, timers), every value
it reaches without the abort still queued either finished or can take none of the events
members send (no state it can still reach has a transition on one: `Reducer.live`): whatever
arrives later is taken after the abort, by such a value or one it leads to, and dropped
without touching its engine. When every member is sealed, the reachable swarm
states are, up to those dropped events, the product of the members' reachable values, so:

- a swarm state with every member final stays reachable from every reachable state (abort
  safety) exactly when, for every member, a final value stays reachable from each of its own
  reachable values;
- a reachable swarm deadlock (no member can move) exists exactly when every member can reach
  a value without steps and for some member that value is not final;
- the states entered, events sent and events received are the union of the members' own.

What a sealed member sends there can change no member, so it is not judged lost (SG406).
The search stops at such a state instead of expanding the product (`explore`), and
`properties` reads the members' own graphs (`Local`, computed once per member value).
"""

from __future__ import annotations

from collections import deque
from dataclasses import field

from swarmgen.records import dataclass
from swarmgen.verify.system import Step, System

MAX_LOCAL = 100_000  # values of one member's own graph (beyond it the member is not decoupled)


@dataclass
class Local:
    """One member value's own future when nothing more arrives: its reachable values (BFS,
    with parent and step), which are final, which can reach a final one, which have no step,
    the states it enters, the events it sends and the events that change it."""

    open: bool = False  # not sealed: something another member sends may still change it
    parent: dict[int, tuple[int, Step | None]] = field(default_factory=dict)
    finished: set[int] = field(default_factory=set)
    good: set[int] = field(default_factory=set)  # a finished value stays reachable
    terminal: list[int] = field(default_factory=list)  # no step, in BFS order
    entered: set[str] = field(default_factory=set)
    sent: set[str] = field(default_factory=set)
    received: set[str] = field(default_factory=set)

    def path(self, value: int) -> list[Step]:
        """The member's own steps (member -1) from its first value to `value`."""
        steps: list[Step] = []
        while True:
            parent, step = self.parent[value]
            if step is None:
                return steps[::-1]
            steps.append(step)
            value = parent

    def stuck(self) -> int | None:
        """The first (nearest) value without a step that is not final, else the first value
        from which no final value is reachable, else None."""
        for value in self.terminal:
            if value not in self.finished:
                return value
        return next((v for v in self.parent if v not in self.good), None)


def local(system: System, value: int) -> Local:
    """The member value's own graph (computed once per value)."""
    known = system.local_memo.get(value)
    if known is None:
        known = system.local_memo[value] = _local(system, value)
    return known


def _local(system: System, start: int) -> Local:
    found = Local(parent={start: (-1, None)})
    reverse: dict[int, list[int]] = {}
    queue = deque([start])
    while queue:
        value = queue.popleft()
        member = system.values[value]
        if member.engine.finished:
            found.finished.add(value)
        elif not any(m.name in system.abort and m.source == "station" for m in member.inbox) and (
            system.hears(value)
        ):
            found.open = True
            return found
        steps = system.local_steps(value)
        if not steps:
            found.terminal.append(value)
        for step in steps:
            move = system.move(value, step)
            if len(found.parent) >= MAX_LOCAL:
                found.open = True
                return found
            effect = move.effect
            found.entered.update(effect.entered)
            found.sent.update(effect.sent)
            if effect.changed and effect.source not in ("", "station"):
                found.received.add(effect.event)
            reverse.setdefault(move.after, []).append(value)
            if move.after not in found.parent:
                found.parent[move.after] = (value, step)
                queue.append(move.after)
    good = set(found.finished)
    todo = deque(good)
    while todo:
        for source in reverse.get(todo.popleft(), ()):
            if source not in good:
                good.add(source)
                todo.append(source)
    found.good = good
    return found


def decoupled(system: System, members: tuple[int, ...]) -> list[Local] | None:
    """Every member's own graph when all of them are sealed, else None."""
    graphs = []
    for value in members:
        graph = local(system, value)
        if graph.open:
            return None
        graphs.append(graph)
    return graphs
