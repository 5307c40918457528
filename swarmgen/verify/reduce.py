"""Stutter reduction: steps that change nothing anyone can observe are taken at once, so the
states between them and the step before are never stored (docs/verify.md, "Reductions").

Two kinds of step qualify. Both are deterministic, send nothing, leave the member's
configuration and data as they are, and commute with every other step of the swarm (other
members only append to the end of an inbox, and a member's own steps either leave the same
state or make the step moot in the same state), so taking them eagerly merges states that are
stutter-bisimilar for every property `verify` checks:

- **an ignored delivery**: the event at the head of a member's inbox makes its engine take no
  transition and send nothing (the member is in a state that does not handle it): the event is
  dropped from the inbox. The inbox is the member's one FIFO queue (its behaviours' ends,
  timers and delayed raises go to its end too), so nothing the member does can come before
  the head: the member's next input is that event, in the state it is in now, whatever else
  happens first (docs/verify.md, "Why an ignored head may be dropped"). Whether it was *lost*
  (no member at all took it) is what SG406 tracks, on the dropped messages this module
  reports;
- **an inert behaviour end**, when the inbox is empty: a running behaviour that can send no
  more events (no `emits`, or its `--emits` bound reached) and whose every outcome leaves the
  member as it is apart from the behaviour's end (no transition on it, outputs already equal
  to the data they write): it is taken as ended at once. Its end would be the head of the
  inbox, taken next and ignored; with events queued before it, the engine may have changed by
  the time it is taken, so it waits for the inbox to empty.

A third reduction drops **dead messages**: an event that no transition of any state the member
can still reach (from its active states, along any transition, whatever its event or guard: an
over-approximation computed on the chart) can take will be ignored when it reaches the head of
the inbox, so it is dropped wherever it is in the inbox. The set of states a member can reach
only shrinks as it moves, so a dead message stays dead.

Each member value's normal form is computed once (`Reducer`, bounded memo).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from swarmgen.records import dataclass
from swarmgen.runtime.chart import Chart, Node
from swarmgen.verify.state import EngineState

if TYPE_CHECKING:
    from swarmgen.verify.system import MemberState, Message, System

MEMO_LIMIT = 300_000


@dataclass(frozen=True, slots=True)
class Normal:
    """A member's normal form and the messages it dropped on the way (oldest first)."""

    member: MemberState
    dropped: tuple[Message, ...] = ()


class Reducer:
    """Normal forms of member values (see the module docstring)."""

    def __init__(self, system: System) -> None:
        self.system = system
        self._memo: dict[tuple[int, MemberState], Normal] = {}
        self._live_memo: dict[tuple[int, tuple[str, ...], str], bool] = {}
        self._reach: dict[tuple[int, tuple[str, ...]], frozenset[Node]] = {}

    def normal(self, kind: int, member: MemberState) -> Normal:
        """The normal form of a member of type `kind`: ignored heads dropped, inert
        behaviours ended."""
        key = (kind, member)
        known = self._memo.get(key)
        if known is not None:
            return known
        if len(self._memo) >= MEMO_LIMIT:
            self._memo.clear()
        found = self._normal(kind, member)
        self._memo[key] = found
        return found

    def _normal(self, kind: int, member: MemberState) -> Normal:
        from swarmgen.verify.system import MemberState

        engine, inbox = member.engine, member.inbox
        dropped: list[Message] = []
        if inbox and engine.running:  # an outcome queued for an active state is always live
            live = tuple(
                m for m in inbox if m.kind == "outcome" or self.live(kind, engine.config, m.name)
            )
            if len(live) < len(inbox):
                dropped.extend(m for m in inbox if m not in live)
                inbox = live
        while engine.running:
            ended = None if inbox else self._inert_ended(kind, engine)
            if ended is not None:
                engine = ended
                continue
            if inbox and self._ignores(kind, engine, inbox[0]):
                dropped.append(inbox[0])
                inbox = inbox[1:]
                continue
            break
        if not engine.running:  # a finished member receives nothing: its inbox is moot
            dropped.extend(inbox)
            inbox = ()
        return Normal(MemberState(engine, inbox), tuple(dropped))

    def live(self, kind: int, config: tuple[str, ...], name: str) -> bool:
        """Whether some state the member can still reach has a transition on `name`."""
        key = (kind, config, name)
        known = self._live_memo.get(key)
        if known is None:
            chart = self.system.kinds[kind].chart
            reach = self._reach.get((kind, config))
            if reach is None:
                reach = self._reach[(kind, config)] = reachable(chart, config)
            known = self._live_memo[key] = any(
                t.events and t.matches(name) for node in reach for t in node.transitions
            )
        return known

    def _ignores(self, kind: int, engine: EngineState, message: Message) -> bool:
        ran = self.system.take(kind, engine, message)
        return not ran.sent and ran.after == engine

    def _inert_ended(self, kind: int, engine: EngineState) -> EngineState | None:
        """The engine with one inert behaviour ended, or None when none is inert."""
        system = self.system
        member_kind = system.kinds[kind]
        for state_id, emitted in engine.calls:
            call = member_kind.chart.nodes[state_id].call
            if call is None:
                continue
            if emitted < system.emit_bound and member_kind.emits.get(call.behaviour):
                continue
            without = replace(engine, calls=tuple(c for c in engine.calls if c[0] != state_id))
            if all(
                not ran.sent and ran.after == without
                for ran in (
                    system.run_input(kind, engine, "outcome", o.name, o.outputs, state_id)
                    for o in member_kind.endings[state_id]
                )
            ):
                return without
        return None


def reachable(chart: Chart, config: tuple[str, ...]) -> frozenset[Node]:
    """Every state a member in `config` may still be in (with its ancestors): the closure
    along every transition's targets, entering any descendant of a target."""
    found: set[Node] = set()
    todo = [chart.nodes[i] for i in config]
    while todo:
        node = todo.pop()
        if node in found:
            continue
        found.add(node)
        todo.extend(node.ancestors)
        for transition in node.transitions:
            for target in transition.targets:
                todo.append(target)
                todo.extend(_descendants(target))
        if node.kind == "history" and node.parent is not None:
            todo.extend(_descendants(node.parent))
    return frozenset(found)


def _descendants(node: Node) -> list[Node]:
    found: list[Node] = []
    todo = list(node.children)
    while todo:
        child = todo.pop()
        found.append(child)
        todo.extend(child.children)
    return found
