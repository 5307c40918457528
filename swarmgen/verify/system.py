"""The swarm as a transition system over the members' engines (docs/verify.md).

A state is every member's engine (`state.EngineState`) with its inbox of events in flight, and
whether the station has sent the abort. A step is one nondeterministic choice:

- `station`: the station sends one of its events to every member (only while no earlier copy
  of it is still in flight, and never after the abort, so the space stays finite);
- `deliver`: a member takes the first event of its inbox (one macrostep of its engine);
- `outcome`: a running behaviour ends with one of its declared outcomes, its outputs given as
  the zero of their types (the documented bound for behaviour outputs);
- `emit`: a running behaviour sends one of the events its `emits` tag names (at most
  `emit_bound` times per activation);
- `timer`: a pending timer fires.

After its input a member also processes the events it queued to itself (`raise e(f = ...)`),
as the asyncio member and `swarmgen replay` do before their next input; the swarm events it
sent then go to the end of the inboxes of every running member (the sender's too), `local`
ones to the sender only. Each member runs on the engine of the generated code of its type.
"""

from __future__ import annotations

import pickle
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from swarmgen.runtime.chart import Action, Chart, Context
from swarmgen.runtime.engine import FINALIZE_PREFIX, Engine, Event
from swarmgen.verify.state import (
    EngineState,
    Frozen,
    VerifyHost,
    capture,
    check_engine,
    freeze,
    restore,
    thaw,
)

Sent = list[tuple[str, Frozen, str]]  # (event, data, scope) a member sent
# an input's result: the member after, what it sent, the input as a replay step, states entered
Result = tuple[EngineState, Sent, dict[str, Any], frozenset[str]]
MEMO_LIMIT = 500_000  # inputs remembered (`System.run_input`)
MAX_OWN_EVENTS = 100_000  # events a member may queue to itself in one step (the engine's step
# bound stops a loop through them long before; this only keeps a bug from spinning)


@dataclass(frozen=True, slots=True)
class Message:
    """An event in flight to one member: its name, data and who sent it."""

    name: str
    data: Frozen
    source: str  # "station", or the sending member's type


@dataclass(frozen=True, slots=True)
class MemberState:
    """One member: its engine and the events waiting for it, oldest first."""

    engine: EngineState
    inbox: tuple[Message, ...] = ()

    def key(self) -> tuple[Any, ...]:
        """What makes the member's value (see `EngineState.key`)."""
        return (self.engine.key(), tuple((m.name, m.data, m.source) for m in self.inbox))


@dataclass(frozen=True, slots=True)
class SwarmState:
    """Every member (in the system's member order, or canonical order under symmetry) and
    whether the abort was sent."""

    members: tuple[MemberState, ...]
    aborted: bool = False

    def key(self) -> bytes:
        """The state's value as bytes (the visited set hashes it)."""
        members = tuple(m.key() for m in self.members)
        return pickle.dumps((members, self.aborted), pickle.HIGHEST_PROTOCOL)


@dataclass(frozen=True, slots=True)
class Step:
    """One step: its kind, the member (index in the state's order), the event or outcome and
    the state whose behaviour or timer it is."""

    kind: str  # "station", "deliver", "outcome", "emit", "timer", "delayed" (state: its key)
    member: int = -1
    event: str = ""
    state: str = ""


@dataclass(frozen=True, slots=True)
class Effect:
    """What a step did: the member that took an input (-1: none), that input as a replay step,
    and whether its engine changed (the event was received, not ignored)."""

    member: int = -1
    replay: dict[str, Any] | None = None
    event: str = ""
    source: str = ""
    changed: bool = False
    sent: tuple[str, ...] = ()  # names of the events the member sent
    entered: frozenset[str] = frozenset()  # states it entered (some maybe left again)


@dataclass
class MemberKind:
    """A member type: its chart (from the generated module), one engine and host that every
    member of the type is restored into, its event scopes and its behaviours' `emits`."""

    name: str
    chart: Chart
    scopes: Mapping[str, str]
    emits: Mapping[str, tuple[str, ...]]  # behaviour -> events it emits
    engine: Engine
    host: VerifyHost
    initial: EngineState
    entered: set[str]  # states entered since the last input (`watch_entries`)
    started: frozenset[str] = frozenset()  # states starting the machine entered


def make_kind(
    name: str, chart: Chart, scopes: Mapping[str, str], emits: Mapping[str, tuple[str, ...]]
) -> MemberKind:
    """A member type's engine, started once: its initial state. The chart must be the
    verifier's own (`watch_entries` changes it)."""
    entered = watch_entries(chart)
    host = VerifyHost()
    engine = Engine(chart, host, name)
    check_engine(engine)
    engine.clock = lambda: 0.0  # timestamps mean nothing to the search; keep steps alike
    engine.start()
    own_events(engine, host)
    initial = capture(engine, host)
    return MemberKind(
        name, chart, scopes, emits, engine, host, initial, entered, frozenset(entered)
    )


def watch_entries(chart: Chart) -> set[str]:
    """Make every state's entry record its id in the returned set: a state entered and left
    in one macrostep (a region's final state whose completion leaves the parallel state) is
    never in a configuration between steps, yet is reached. Its entry actions run as before."""
    entered: set[str] = set()
    for node in chart.nodes.values():
        node.onentry = _recording(node.id, node.onentry, entered)
    return entered


def _recording(node_id: str, original: Action | None, entered: set[str]) -> Action:
    def entry(ctx: Context) -> None:
        entered.add(node_id)
        if original is not None:
            original(ctx)

    return entry


def own_events(engine: Engine, host: VerifyHost) -> None:
    """Process the events the member queued to itself, as its queue would before any input."""
    for _ in range(MAX_OWN_EVENTS):
        if not host.own or not engine.running:
            break
        engine.send(host.own.pop(0))
    host.own.clear()


class System:
    """The composed swarm: member kinds, which kind each member is, the station's events."""

    def __init__(
        self,
        kinds: Sequence[MemberKind],
        counts: Mapping[str, int],
        station: Sequence[str],
        abort: Sequence[str],
        emit_bound: int = 1,
    ) -> None:
        self.kinds = tuple(kinds)
        by_name = {k.name: i for i, k in enumerate(self.kinds)}
        self.types: tuple[int, ...] = tuple(
            by_name[k.name] for k in self.kinds for _ in range(counts.get(k.name, 0))
        )
        self.ids = tuple(
            f"{k.name}_{n}" for k in self.kinds for n in range(1, counts.get(k.name, 0) + 1)
        )
        self.station = tuple(station)
        self.abort = frozenset(abort)
        self.emit_bound = emit_bound
        # Engines are deterministic: the same input to the same member value gives the same
        # result, whatever the other members do, so each is computed once (bounded memo).
        self._memo: dict[tuple[Any, ...], Result] = {}

    def initial(self) -> SwarmState:
        """Every member started, nothing in flight."""
        return SwarmState(tuple(MemberState(self.kinds[t].initial) for t in self.types))

    def steps(self, state: SwarmState) -> list[Step]:
        """Every step enabled in `state`, in a fixed order (member steps, then the station)."""
        found: list[Step] = []
        for index, member in enumerate(state.members):
            found.extend(self.member_steps(index, member))
        if not state.aborted:
            in_flight = {
                m.name for mem in state.members for m in mem.inbox if m.source == "station"
            }
            found.extend(Step("station", event=e) for e in self.station if e not in in_flight)
        return found

    def member_steps(self, index: int, member: MemberState) -> list[Step]:
        """The steps of one member: its next delivery, its behaviours' ends and emissions,
        its timers."""
        engine = member.engine
        if not engine.running:
            return []
        kind = self.kinds[self.types[index]]
        found = [Step("deliver", index)] if member.inbox else []
        for state_id, emitted in engine.calls:
            call = kind.chart.nodes[state_id].call
            if call is None:
                continue
            found.extend(
                Step("outcome", index, o, state_id) for o in call.outcomes or ("succeeded",)
            )
            if emitted < self.emit_bound:
                found.extend(
                    Step("emit", index, e, state_id) for e in kind.emits.get(call.behaviour, ())
                )
        found.extend(Step("timer", index, event, state_id) for state_id, event in engine.timers)
        arriving = dict.fromkeys((key, name) for key, name, _ in engine.delayed)
        found.extend(Step("delayed", index, name, key) for key, name in arriving)
        return found

    def quiescent(self, state: SwarmState) -> bool:
        """No member can move without the station."""
        return not any(self.member_steps(i, m) for i, m in enumerate(state.members))

    def finished(self, state: SwarmState) -> bool:
        """Every member reached a top-level final state."""
        return all(m.engine.finished for m in state.members)

    def station_moves(self, state: SwarmState) -> bool:
        """Whether some station event would change some running member (the station can
        still get the swarm going); false after the abort."""
        if state.aborted:
            return False
        for index, member in enumerate(state.members):
            if not member.engine.running:
                continue
            for name in self.station:
                after = self.run_input(index, member.engine, "deliver", name, None, "")[0]
                if after != member.engine:
                    return True
        return False

    def apply(self, state: SwarmState, step: Step) -> tuple[SwarmState, Effect]:
        """The state after `step`, and what it did."""
        if step.kind == "station":
            message = Message(step.event, None, "station")
            told = tuple(
                replace(m, inbox=(*m.inbox, message)) if m.engine.running else m
                for m in state.members
            )
            return SwarmState(told, state.aborted or step.event in self.abort), Effect()
        index = step.member
        member = state.members[index]
        inbox = member.inbox
        sent: Sent
        if step.kind == "emit":
            scope = self.kinds[self.types[index]].scopes.get(step.event, "swarm")
            after, sent = self._emitted(member.engine, step), [(step.event, None, scope)]
            effect = Effect(sent=(step.event,))
        else:
            name, data, source = step.event, None, ""
            if step.kind == "deliver":
                head, inbox = inbox[0], inbox[1:]
                name, data, source = head.name, head.data, head.source
            after, sent, replayed, entered = self.run_input(
                index, member.engine, step.kind, name, data, step.state
            )
            names = tuple(n for n, _, _ in sent)
            effect = Effect(index, replayed, name, source, after != member.engine, names, entered)
        members = list(state.members)
        members[index] = MemberState(after, inbox)
        self._post(members, index, sent)
        return SwarmState(tuple(members), state.aborted), effect

    def _post(self, members: list[MemberState], index: int, sent: Sent) -> None:
        """What member `index` sent, to the end of the inboxes of its running receivers."""
        kind_name = self.kinds[self.types[index]].name
        for name, data, scope in sent:
            message = Message(name, data, kind_name)
            targets = [index] if scope == "local" else range(len(members))
            for target in targets:
                receiver = members[target]
                if receiver.engine.running:
                    members[target] = MemberState(receiver.engine, (*receiver.inbox, message))

    def _emitted(self, engine: EngineState, step: Step) -> EngineState:
        calls = tuple((s, n + 1 if s == step.state else n) for s, n in engine.calls)
        return replace(engine, calls=calls)

    def run_input(
        self, index: int, before: EngineState, kind: str, name: str, data: Frozen, state_id: str
    ) -> Result:
        """One input to a member's engine: its state after, what it sent (name, data, scope)
        and the input as a `swarmgen replay` step."""
        memo_key = (self.types[index], before.key(), kind, name, data, state_id)
        known = self._memo.get(memo_key)
        if known is not None:
            return known
        if len(self._memo) >= MEMO_LIMIT:
            self._memo.clear()
        result = self._run_input(index, before, kind, name, data, state_id)
        self._memo[memo_key] = result
        return result

    def _run_input(
        self, index: int, before: EngineState, kind: str, name: str, data: Frozen, state_id: str
    ) -> Result:
        member_kind = self.kinds[self.types[index]]
        engine, host = member_kind.engine, member_kind.host
        restore(engine, host, before)
        replayed: dict[str, Any]
        if kind == "outcome":
            node = member_kind.chart.nodes[state_id]
            behaviour = node.call.behaviour if node.call is not None else ""
            host.calls.pop(state_id, None)  # the behaviour ended
            origin = (state_id, engine.activation(state_id))
            event = engine.make_event(
                f"{FINALIZE_PREFIX}{state_id}.{name}", {}, "verify", origin=origin
            )
            replayed = {"complete": behaviour, "outcome": name, "outputs": {}, "state": state_id}
        else:
            if kind == "timer":
                host.cancel_timer(member_kind.chart.nodes[state_id], name)  # it fired
            if kind == "delayed":
                data = host.arrived(state_id, name)
            value = thaw(data)
            event = Event(name, value, 0, 0.0, "verify")
            replayed = {"event": name} if value is None else {"event": name, "data": value}
        member_kind.entered.clear()
        engine.send(event)
        own_events(engine, host)
        sent = [
            (
                e.name,
                freeze(e.data) if e.data is not None else None,
                member_kind.scopes.get(e.name, "swarm"),
            )
            for e in host.sent
        ]
        return capture(engine, host), sent, replayed, frozenset(member_kind.entered)


def canonical(system: System, state: SwarmState) -> tuple[SwarmState, list[int]]:
    """Symmetry: the members of each type sorted by their value, and the permutation used
    (position in the canonical state -> position in `state`)."""
    order: list[int] = []
    start = 0
    members = state.members
    while start < len(members):
        end = start
        while end < len(members) and system.types[end] == system.types[start]:
            end += 1
        group = sorted(range(start, end), key=lambda i: _sort_key(members[i]))
        order.extend(group)
        start = end
    if order == list(range(len(members))):
        return state, order
    return SwarmState(tuple(members[i] for i in order), state.aborted), order


def _sort_key(member: MemberState) -> bytes:
    return pickle.dumps(member.key(), pickle.HIGHEST_PROTOCOL)
