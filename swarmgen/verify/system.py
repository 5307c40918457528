"""The swarm as a transition system over the members' engines (docs/verify.md).

A state is every member's value (its engine, `state.EngineState`, with its inbox of events in
flight), whether the station has sent the abort, and how many times it sent each of its events.
Member values are interned: a swarm state holds one small integer per member, so hashing,
symmetry and the visited set work on tuples of integers, and what a member's step does is
computed once per member value (`Move`), whatever the other members do. A step is one
nondeterministic choice:

- `station`: the station sends one of its events to every running member (each at most
  `station_bound` times, never after the abort, so the space stays finite);
- `deliver`: a member takes the first event of its inbox (one macrostep of its engine);
- `outcome`: a running behaviour ends with one of its declared outcomes and outputs from the
  finite domains `domains` computes: its `done.invoke` event goes to the end of the member's
  inbox (the asyncio member's queue: docs/verify.md, "The transition system");
- `emit`: a running behaviour sends one of the events its `emits` tag names (at most
  `emit_bound` times per activation);
- `timer`: a pending timer fires: its event goes to the end of the member's inbox;
- `delayed`: a pending `raise e after ...` arrives (any time before it is cancelled): to the
  end of the member's inbox.

A member's inbox is its one FIFO queue: what the station and members send it and what its own
behaviours, timers and delayed raises put there, in the order it happened. The swarm events a
member sent go to the end of the inbox of every running member (the sender's too), `local`
ones to the sender only. An outcome still queued when its state is left is stale: it is
dropped (the engine discards it by its activation number). Every member value is kept in its
normal form (`reduce`): ignored deliveries and inert behaviour ends are taken at once.
"""

from __future__ import annotations

from array import array
from collections.abc import Mapping, Sequence
from dataclasses import field, replace
from typing import Any

from swarmgen.records import dataclass
from swarmgen.verify.kinds import MemberKind
from swarmgen.verify.reduce import Reducer
from swarmgen.verify.state import EngineState, Frozen


@dataclass(frozen=True, slots=True)
class Message:
    """An event in a member's inbox: its name, data and who sent it; for an input the member
    queued itself, what it is (`outcome`: a behaviour's end, `name` the outcome, `data` the
    outputs; `timer`; `delayed`) and its state (the send id's key for a delayed raise)."""

    name: str
    data: Frozen
    source: str  # "station", the sending member's type, or "" (the member's own input)
    kind: str = ""  # "" (an event sent to it), "outcome", "timer" or "delayed"
    state: str = ""


@dataclass(frozen=True, slots=True)
class MemberState:
    """One member: its engine and the events waiting for it, oldest first."""

    engine: EngineState
    inbox: tuple[Message, ...] = ()


@dataclass(frozen=True, slots=True)
class SwarmState:
    """Every member's interned value (in the system's member order, or canonical order under
    symmetry), whether the abort was sent, and the station's sends per event."""

    members: tuple[int, ...]
    aborted: bool = False
    station: tuple[int, ...] = ()

    def key(self) -> bytes:
        """The state's value as bytes (the visited set's key)."""
        return array("l", (*self.members, -1, int(self.aborted), *self.station)).tobytes()


@dataclass(frozen=True, slots=True)
class Step:
    """One step: its kind, the member (index in the state's order), the event or outcome, the
    state whose behaviour or timer it is and, for an outcome, the outputs."""

    kind: str  # "station", "deliver", "outcome", "emit", "timer", "delayed" (state: its key)
    member: int = -1
    event: str = ""
    state: str = ""
    data: Frozen = None
    # the hash, computed once: steps key the search's memos, and data may be deep
    _hash: int = field(init=False, repr=False, compare=False, default=0)

    def __post_init__(self) -> None:
        key = (self.kind, self.member, self.event, self.state, self.data)
        object.__setattr__(self, "_hash", hash(key))

    def __hash__(self) -> int:
        return self._hash


@dataclass(frozen=True, slots=True)
class Effect:
    """What a step did: the member that took an input (-1: none), that input as a replay step,
    the event and its source, whether the engine changed (the event was received, not
    ignored), the events sent, the states entered and the ignored deliveries taken at once."""

    member: int = -1
    replay: Mapping[str, Any] | None = None
    event: str = ""
    source: str = ""
    changed: bool = False
    sent: tuple[str, ...] = ()
    entered: frozenset[str] = frozenset()
    dropped: tuple[tuple[int, Message], ...] = ()  # (member index, message)
    lost: tuple[str, ...] = ()  # events the member sent that every receiver dropped at once


@dataclass(frozen=True, slots=True)
class Move:
    """A member-local step's result, computed once per member value: the member's value after
    (its own sends to itself appended, in normal form), what it posts to the others, and its
    effect (member and dropped indices are filled in by `System.apply`)."""

    after: int
    posts: tuple[Message, ...]  # swarm-scoped messages for every other running member
    effect: Effect
    dropped: tuple[Message, ...]
    kept: frozenset[Message] = frozenset()  # sent messages the sender's own inbox kept


class System:
    """The composed swarm: member kinds, which kind each member is, the station's events, and
    the interned member values."""

    def __init__(
        self,
        kinds: Sequence[MemberKind],
        counts: Mapping[str, int],
        station: Sequence[str],
        abort: Sequence[str],
        emit_bound: int = 1,
        station_bound: int = 1,
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
        self.station_bound = station_bound
        self.values: list[MemberState] = []  # interned member values: id -> value
        self.value_type: list[int] = []
        self.inbox_length: list[int] = []  # interned value id -> its inbox's length
        self._ids: dict[tuple[int, MemberState], int] = {}
        self._runs: dict[tuple[Any, ...], Any] = {}
        self._moves: dict[tuple[Any, ...], Move] = {}
        self._steps: dict[int, tuple[Step, ...]] = {}
        self._appends: dict[tuple[int, Message], tuple[int, tuple[Message, ...]]] = {}
        self._indexed: dict[tuple[int, int], tuple[Step, ...]] = {}
        self._quiet: dict[tuple[int, Step], tuple[int, Effect]] = {}  # `apply`, posting nothing
        # the positions of each type's members (contiguous: `ids` lists them type by type)
        self.groups: tuple[tuple[int, int], ...] = tuple(
            (self.types.index(t), len(self.types) - self.types[::-1].index(t))
            for t in sorted(set(self.types))
        )
        # the events a member may send (every swarm-scoped event its type knows)
        self.member_events = sorted(
            {name for k in self.kinds for name, scope in k.scopes.items() if scope != "local"}
        )
        self.reducer = Reducer(self)
        self.ample_memo: dict[int, bool] = {}  # member value -> its steps are persistent
        self.local_memo: dict[int, Any] = {}  # member value -> its own graph (`decouple`)

    # --- member values ------------------------------------------------------------------

    def intern(self, kind: int, member: MemberState) -> int:
        """The id of a member value of type `kind` (a new one the first time)."""
        key = (kind, member)
        known = self._ids.get(key)
        if known is None:
            known = self._ids[key] = len(self.values)
            self.values.append(member)
            self.value_type.append(kind)
            self.inbox_length.append(len(member.inbox))
        return known

    def hears(self, value: int) -> bool:
        """Whether a running member value with an empty inbox could still take some event a
        member may send (some state it can still reach has a transition on it: `decouple`)."""
        kind = self.value_type[value]
        config = self.values[value].engine.config
        return any(self.reducer.live(kind, config, name) for name in self.member_events)

    def weight(self, state: SwarmState) -> int:
        """The events in flight in `state` (every inbox's length): ample steps never raise it
        (the cycle proviso, `explore`)."""
        return sum(map(self.inbox_length.__getitem__, state.members))

    def member(self, state: SwarmState, index: int) -> MemberState:
        """The value of the member at `index` of `state`."""
        return self.values[state.members[index]]

    def engine(self, state: SwarmState, index: int) -> EngineState:
        """The engine of the member at `index` of `state`."""
        return self.values[state.members[index]].engine

    def _normal_id(self, kind: int, member: MemberState) -> tuple[int, tuple[Message, ...]]:
        normal = self.reducer.normal(kind, member)
        return self.intern(kind, normal.member), normal.dropped

    def run_input(
        self, kind: int, before: EngineState, step: str, name: str, data: Frozen, state_id: str
    ) -> Any:
        """One input to an engine of type `kind` (`MemberKind.run`), computed once."""
        key = (kind, before, step, name, data, state_id)
        known = self._runs.get(key)
        if known is None:
            known = self._runs[key] = self.kinds[kind].run(before, step, name, data, state_id)
        return known

    # --- the initial state and the steps --------------------------------------------------

    def initial(self) -> SwarmState:
        """Every member started, nothing in flight (in normal form: `reduce`)."""
        members = tuple(
            self._normal_id(t, MemberState(self.kinds[t].initial))[0] for t in self.types
        )
        return SwarmState(members, False, (0,) * len(self.station))

    def steps(self, state: SwarmState) -> list[Step]:
        """Every step enabled in `state`, in a fixed order (member steps, then the station)."""
        found: list[Step] = []
        for index, value in enumerate(state.members):
            found.extend(self.member_steps(value, index))
        found.extend(Step("station", event=e) for e in self.station_events(state))
        return found

    def member_steps(self, value: int, index: int) -> tuple[Step, ...]:
        """The steps of a member value at position `index` (computed once)."""
        key = (value, index)
        known = self._indexed.get(key)
        if known is None:
            known = self._indexed[key] = tuple(
                Step(s.kind, index, s.event, s.state, s.data) for s in self.local_steps(value)
            )
        return known

    def local_steps(self, value: int) -> tuple[Step, ...]:
        """The steps of one member value (member -1): its next delivery, its behaviours'
        ends and emissions, its timers."""
        known = self._steps.get(value)
        if known is None:
            known = self._steps[value] = tuple(self._local_steps(value))
        return known

    def _local_steps(self, value: int) -> list[Step]:
        member = self.values[value]
        engine = member.engine
        if not engine.running:
            return []
        kind = self.kinds[self.value_type[value]]
        found = [Step("deliver")] if member.inbox else []
        for state_id, emitted in engine.calls:
            call = kind.chart.nodes[state_id].call
            if call is None:
                continue
            found.extend(
                Step("outcome", -1, o.name, state_id, o.outputs) for o in kind.endings[state_id]
            )
            if emitted < self.emit_bound:
                found.extend(
                    Step("emit", -1, e, state_id) for e in kind.emits.get(call.behaviour, ())
                )
        found.extend(Step("timer", -1, event, state_id) for state_id, event in engine.timers)
        arriving = dict.fromkeys((key, name) for key, name, _ in engine.delayed)
        found.extend(Step("delayed", -1, name, key) for key, name in arriving)
        return found

    def station_events(self, state: SwarmState) -> list[str]:
        """The events the station may still send: none after the abort, each at most
        `station_bound` times."""
        if state.aborted:
            return []
        return [
            e for e, n in zip(self.station, state.station, strict=True) if n < self.station_bound
        ]

    def quiescent(self, state: SwarmState) -> bool:
        """No member can move without the station."""
        return not any(self.local_steps(v) for v in state.members)

    def finished(self, state: SwarmState) -> bool:
        """Every member reached a top-level final state."""
        return all(self.values[v].engine.finished for v in state.members)

    def station_moves(self, state: SwarmState) -> bool:
        """Whether some station event the station may still send would change some running
        member (the station can still get the swarm going)."""
        events = self.station_events(state)
        for value in state.members:
            engine = self.values[value].engine
            if not engine.running:
                continue
            kind = self.value_type[value]
            for name in events:
                ran = self.run_input(kind, engine, "deliver", name, None, "")
                if ran.sent or ran.after != engine:
                    return True
        return False

    # --- applying a step ------------------------------------------------------------------

    def apply(self, state: SwarmState, step: Step) -> tuple[SwarmState, Effect]:
        """The state after `step`, and what it did."""
        if step.kind == "station":
            return self._station(state, step)
        index = step.member
        value = state.members[index]
        quiet = self._quiet.get((value, step))
        if quiet is not None:  # a step that posts nothing: only its member changes
            after, effect = quiet
            now = state.members
            changed = (*now[:index], after, *now[index + 1 :])
            return SwarmState(changed, state.aborted, state.station), effect
        move = self.move(value, step)
        members = list(state.members)
        members[index] = move.after
        dropped = [(index, m) for m in move.dropped]
        lost: list[str] = []
        for message in move.posts:
            kept = message in move.kept
            for target, value in enumerate(members):
                if target != index and self.values[value].engine.running:
                    members[target], gone = self.append(value, message)
                    dropped.extend((target, m) for m in gone)
                    inbox = self.values[members[target]].inbox
                    kept = kept or (bool(inbox) and inbox[-1] == message)
            if not kept:
                lost.append(message.name)
        e = move.effect
        member = index if e.replay is not None else -1
        effect = Effect(
            member, e.replay, e.event, e.source, e.changed, e.sent, e.entered, tuple(dropped),
            tuple(lost),
        )  # fmt: skip
        if not move.posts:
            self._quiet[(value, step)] = (move.after, effect)
        return SwarmState(tuple(members), state.aborted, state.station), effect

    def _station(self, state: SwarmState, step: Step) -> tuple[SwarmState, Effect]:
        message = Message(step.event, None, "station")
        members = list(state.members)
        dropped: list[tuple[int, Message]] = []
        for target, value in enumerate(members):
            if self.values[value].engine.running:
                members[target], lost = self.append(value, message)
                dropped.extend((target, m) for m in lost)
        counts = tuple(
            n + (e == step.event) for e, n in zip(self.station, state.station, strict=True)
        )
        aborted = state.aborted or step.event in self.abort
        effect = Effect(event=step.event, source="station", dropped=tuple(dropped))
        return SwarmState(tuple(members), aborted, counts), effect

    def append(self, value: int, message: Message) -> tuple[int, tuple[Message, ...]]:
        """A member value with `message` at the end of its inbox, in normal form, and the
        messages that dropped."""
        key = (value, message)
        known = self._appends.get(key)
        if known is None:
            member = self.values[value]
            grown = MemberState(member.engine, (*member.inbox, message))
            known = self._appends[key] = self._normal_id(self.value_type[value], grown)
        return known

    def move(self, value: int, step: Step) -> Move:
        """What a member-local step does to a member value (computed once; the step's member
        is not read)."""
        key = (value, step.kind, step.event, step.state, step.data)
        known = self._moves.get(key)
        if known is None:
            known = self._moves[key] = self._move(value, step)
        return known

    def _move(self, value: int, step: Step) -> Move:
        member, kind = self.values[value], self.value_type[value]
        if step.kind != "deliver" and step.kind != "emit":
            return self._queue_own(value, step)
        inbox = member.inbox
        if step.kind == "emit":
            calls = tuple((s, n + 1 if s == step.state else n) for s, n in member.engine.calls)
            after = replace(member.engine, calls=calls)
            scope = self.kinds[kind].scopes.get(step.event, "swarm")
            sent: tuple[tuple[str, Frozen, str], ...] = ((step.event, None, scope),)
            effect = Effect(sent=(step.event,))
        else:
            head, inbox = inbox[0], inbox[1:]
            ran = self.take(kind, member.engine, head)
            after, sent = ran.after, ran.sent
            if ran.left:  # outcomes of the behaviours it cancelled are stale
                inbox = tuple(m for m in inbox if not (m.kind == "outcome" and m.state in ran.left))
            changed = ran.after != member.engine or bool(ran.sent)
            names = tuple(n for n, _, _ in sent)
            effect = Effect(-1, ran.replay, head.name, head.source, changed, names, ran.entered)
        source_type = self.kinds[kind].name
        messages = [Message(n, d, source_type) for n, d, _ in sent]
        own = tuple(messages) if after.running else ()
        after_id, dropped = self._normal_id(kind, MemberState(after, (*inbox, *own)))
        posts = tuple(
            m for m, (_, _, scope) in zip(messages, sent, strict=True) if scope != "local"
        )
        left = self.values[after_id].inbox
        kept = frozenset(m for m in own if m in left[len(left) - len(own) :])
        return Move(after_id, posts, effect, dropped, kept)

    def _queue_own(self, value: int, step: Step) -> Move:
        """A behaviour's end, a timer or a delayed raise: the member's own input goes to the
        end of its inbox (the behaviour has ended, the timer or delayed raise is no longer
        pending); the engine takes it when it reaches the head."""
        member, kind = self.values[value], self.value_type[value]
        engine = member.engine
        data: Frozen = step.data
        if step.kind == "outcome":
            engine = replace(engine, calls=tuple(c for c in engine.calls if c[0] != step.state))
        elif step.kind == "timer":
            fired = (step.state, step.event)
            engine = replace(engine, timers=tuple(t for t in engine.timers if t != fired))
        else:  # delayed: the first pending one of its key and name arrives
            pending = list(engine.delayed)
            at = next(
                i for i, (k, n, _) in enumerate(pending) if (k, n) == (step.state, step.event)
            )
            data = pending.pop(at)[2]
            engine = replace(engine, delayed=tuple(pending))
        message = Message(step.event, data, "", step.kind, step.state)
        after_id, dropped = self._normal_id(kind, MemberState(engine, (*member.inbox, message)))
        return Move(after_id, (), Effect(event=step.event), dropped)

    def take(self, kind: int, engine: EngineState, message: Message) -> Any:
        """What taking `message` from the head of its inbox does to a member's engine
        (`MemberKind.run`'s `Ran`, computed once)."""
        if message.kind == "outcome":
            return self.run_input(
                kind, engine, "outcome", message.name, message.data, message.state
            )
        return self.run_input(kind, engine, "deliver", message.name, message.data, "")


def canonical_state(system: System, state: SwarmState) -> SwarmState:
    """`canonical`'s state alone (the search's key under symmetry), without the permutation."""
    members = state.members
    ordered: list[int] = []
    for start, end in system.groups:
        ordered.extend(sorted(members[start:end]))
    if tuple(ordered) == members:
        return state
    return SwarmState(tuple(ordered), state.aborted, state.station)


def canonical(system: System, state: SwarmState) -> tuple[SwarmState, list[int]]:
    """Symmetry: the members of each type sorted by their interned value, and the permutation
    used (position in the canonical state -> position in `state`)."""
    members = state.members
    order: list[int] = []
    start = 0
    while start < len(members):
        end = start
        kind = system.types[start]
        while end < len(members) and system.types[end] == kind:
            end += 1
        order.extend(sorted(range(start, end), key=members.__getitem__))
        start = end
    if order == list(range(len(members))):
        return state, order
    return SwarmState(tuple(members[i] for i in order), state.aborted, state.station), order
