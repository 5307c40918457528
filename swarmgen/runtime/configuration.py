"""The engine's dispatch tables: `Tables` interns each configuration it reaches, and a
`Configuration` keeps, per event name, the transitions that could react (`Selection`) and, per
set of enabled transitions, the whole microstep (`Plan`), computed once by the set functions of
`microstep` (W3C SCXML 1.0, Appendix D). What a configuration seen for the first time costs is
kept small: `Tables` indexes the chart's transitions by descriptor (what reacts to a name is a
few look-ups), and a transition whose domain and entry set read no history has them computed
once (`Step`), leaving the exit set.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from swarmgen.runtime.chart import Action, Node, Transition
from swarmgen.runtime.microstep import (
    EntrySet,
    History,
    document_order,
    domain,
    effective_targets,
    entry_set,
    exit_set,
    recorded_history,
    remove_conflicts,
)
from swarmgen.runtime.values import Record, fields_filler

# Bounds on what the tables keep (a stream of distinct event names, or a chart whose parallel
# regions reach very many configurations, must not fill memory): past them a table starts over,
# which costs recomputation, never a different result.
CONFIGURATION_LIMIT = 4096
ENTRY_LIMIT = 1024
NAME_LIMIT = 4096  # event names whose reacting transitions a chart keeps

Chain = tuple[tuple[Node, tuple[Transition, ...]], ...]  # (owner, candidates), innermost first
# Of one event name: the nodes with transitions that match it, each with those (document order).
Reactors = Mapping[Node, tuple[Transition, ...]]
# An entered state with the initial transition's and the history default's action it runs.
Entry = tuple[Node, Action | None, Action | None]


@dataclass(frozen=True, slots=True)
class Selection:
    """The transitions that could react to one event name in one configuration.

    `chains`: per atomic state (document order) with candidates, the transition taken without
    evaluating anything (its first candidate has no guard and is not bounded) or None, and its
    candidates along the ancestors. `static`: the enabled transitions when every chain has one."""

    chains: tuple[tuple[Transition | None, Chain], ...]
    static: tuple[Transition, ...] | None

    @classmethod
    def of(cls, atomic: Sequence[Node], reactors: Reactors) -> Selection:
        """The selection over these atomic states of an event whose candidates are `reactors`."""
        if not reactors:
            return NO_SELECTION
        chains: list[tuple[Transition | None, Chain]] = []
        for state in atomic:
            if reactors.keys().isdisjoint(state.lineage):  # most states: at C speed
                continue
            pairs = tuple((o, reactors[o]) for o in state.lineage if o in reactors)
            if pairs:
                first = pairs[0][1][0]
                chains.append((first if first.cond is None and not first.bounded else None, pairs))
        static: list[Transition] | None = []
        for fixed, _ in chains:
            if fixed is None:
                static = None
                break
            if static is not None and fixed not in static:
                static.append(fixed)
        return cls(tuple(chains), tuple(static) if static is not None else None)


NO_SELECTION = Selection((), ())  # nothing in the configuration reacts


def descriptor_keys(name: str) -> list[str]:
    """Every descriptor that can match the event `name` (`Transition.matches`): `*`, the name,
    and each prefix that ends before a dot, alone (`a` matches `a.b`) or with `.*`."""
    keys = ["*", name]
    dot = name.find(".")
    while dot >= 0:
        keys += (name[:dot], name[:dot] + ".*")
        dot = name.find(".", dot + 1)
    return keys


@dataclass(eq=False, slots=True)
class Plan:
    """One microstep, computed once: from a configuration, for the enabled transitions, under
    the history values in `read` (the only ones its entry and exit sets depend on)."""

    transitions: tuple[Transition, ...]  # taken (conflicts removed), in selection order
    exits: tuple[Node, ...]  # exit order: reverse document order
    records: tuple[tuple[Node, tuple[Node, ...]], ...]  # what exiting records in history nodes
    entries: tuple[Entry, ...]  # entry order: document order
    target: frozenset[Node]  # the configuration after the microstep
    read: tuple[tuple[Node, Sequence[Node] | None], ...]
    other: Plan | None = None  # the plan of the same transitions under other history values
    # For the engine: whether no exit runs anything (a behaviour, a timer, exit actions), so
    # the states can leave the configuration at once; the entered states, where no entry runs
    # anything either (None: the engine enters them one by one, in entry order).
    quiet_exits: bool = False
    entered: tuple[Node, ...] | None = None
    after: Configuration | None = None  # the target's interned configuration, once looked up

    def holds(self, history: History) -> bool:
        """Whether the history has the values this plan was computed under."""
        return all(history.get(node) == value for node, value in self.read)


class _Reads(Mapping[Node, Sequence[Node]]):
    """The history as a plan sees it: what the microstep's exits record, else the history
    before it; remembers which history nodes were read there (the plan's key)."""

    def __init__(self, history: History) -> None:
        self.history = history
        self.written: dict[Node, tuple[Node, ...]] = {}
        self.read: dict[Node, Sequence[Node] | None] = {}

    def __getitem__(self, node: Node) -> Sequence[Node]:
        if node in self.written:
            return self.written[node]
        value = self.history.get(node)
        self.read.setdefault(node, value)
        if value is None:
            raise KeyError(node)
        return value

    def __iter__(self) -> Iterator[Node]:
        return iter({**self.history, **self.written})

    def __len__(self) -> int:
        return len({**self.history, **self.written})


def make_plan(config: frozenset[Node], enabled: Sequence[Transition], history: History) -> Plan:
    """The microstep that takes `enabled` from `config` (the W3C algorithm's `microstep`)."""
    reads = _Reads(history)
    taken = remove_conflicts(enabled, config, reads) if len(enabled) > 1 else tuple(enabled)
    exits = tuple(sorted(exit_set(taken, config, reads), key=document_order, reverse=True))
    for state in exits:  # recorded before any state is left, as `exitStates` does
        for child in state.children:
            if child.kind == "history":
                reads.written[child] = recorded_history(child, state, config)
    records = tuple(reads.written.items())
    entry = entry_set(taken, reads)  # sees the history the exits just recorded
    target = config.difference(exits) | entry.to_enter
    entries = _entries(entry)
    read = tuple(reads.read.items())
    return Plan(
        taken,
        exits,
        records,
        entries,
        target,
        read,
        None,
        leaves_quietly(exits),
        entered_quietly(entries),
    )


def leaves_quietly(exits: Iterable[Node]) -> bool:
    """Whether leaving these states runs nothing: no behaviour, timer or exit action."""
    for state in exits:
        if state.call is not None or state.timers or state.onexit is not None or state.invokes:
            return False
    return True


def entered_quietly(entries: Iterable[Entry]) -> tuple[Node, ...] | None:
    """The states of an entry set where entering them runs nothing (None: something runs)."""
    states = []
    for state, initial, default in entries:
        if (
            state.call is not None
            or state.invokes
            or state.onentry is not None
            or state.timers
            or state.kind == "final"
            or initial is not None
            or default is not None
        ):
            return None
        states.append(state)
    return tuple(states)


def _entries(entry: EntrySet) -> tuple[Entry, ...]:
    """The entry set in entry order, each state with the initial and history default it runs."""
    entries: list[Entry] = []
    for state in sorted(entry.to_enter, key=document_order):
        initial = state.initial if state in entry.default_entry else None
        default = entry.history_content.get(state)
        entries.append(
            (
                state,
                initial.action if initial is not None else None,
                default.action if default is not None else None,
            )
        )
    return tuple(entries)


@dataclass(frozen=True, slots=True)
class Step:
    """A transition whose domain and entry set read no history node: both are then the same
    in every configuration and under every history, so they are computed once per transition
    and a microstep taking it alone only has its exit set left to compute."""

    transition: Transition
    exits: bool  # whether it exits anything (it has targets)
    scope: Node | None  # its domain: it exits the active states below it (None: all)
    entries: tuple[Entry, ...]
    entered: frozenset[Node]
    quiet_entries: tuple[Node, ...] | None  # `Plan.entered`

    @classmethod
    def of(cls, transition: Transition) -> Step | None:
        """The step of the transition, or None where history decides what it exits or enters."""
        probe = _Reads({})  # records every history node looked up, whatever its value
        entry = EntrySet(probe)  # `entry_set((transition,), probe)`, its domain computed once
        for target in transition.targets:
            entry.add_descendants(target)
        scope = domain(transition, probe)
        for state in effective_targets(transition, probe):
            entry.add_ancestors(state, scope)
        if probe.read:
            return None
        entries = _entries(entry)
        states = frozenset(entry.to_enter)
        return cls(
            transition, bool(transition.targets), scope, entries, states, entered_quietly(entries)
        )

    def plan(self, config: frozenset[Node]) -> Plan:
        """`make_plan(config, (transition,), history)`, for any history."""
        scope = self.scope
        exits: tuple[Node, ...] = ()
        if self.exits:
            below = (s for s in config if scope is None or scope in s.ancestors)
            exits = tuple(sorted(below, key=document_order, reverse=True))
        records = tuple(
            (child, recorded_history(child, state, config))
            for state in exits
            for child in state.children
            if child.kind == "history"
        )
        target = config.difference(exits) | self.entered
        return Plan(
            (self.transition,),
            exits,
            records,
            self.entries,
            target,
            (),
            None,
            leaves_quietly(exits),
            self.quiet_entries,
        )


class Configuration:
    """A configuration the engine reached, with its selections and plans as they are needed."""

    __slots__ = ("atomic", "eventless", "plans", "selections", "states", "steps", "tables")

    def __init__(self, states: frozenset[Node], tables: Tables) -> None:
        self.states = states
        self.tables = tables
        self.steps = tables.steps
        self.atomic = tuple(sorted((n for n in states if n.is_atomic), key=document_order))
        # looked at after every microstep
        self.eventless = Selection.of(self.atomic, tables.eventless)
        self.selections: dict[str | None, Selection] = {}
        self.plans: dict[tuple[Transition, ...], Plan] = {}

    def selection(self, name: str) -> Selection:
        """What could react to the event `name`."""
        found = self.selections.get(name)
        if found is None:
            if len(self.selections) >= ENTRY_LIMIT:
                self.selections.clear()
            found = self.selections[name] = Selection.of(self.atomic, self.tables.reactors(name))
        return found

    def plan(self, enabled: tuple[Transition, ...], history: History) -> Plan:
        """The microstep taking `enabled` under the current history."""
        first = self.plans.get(enabled)
        plan = first
        while plan is not None:
            if not plan.read or plan.holds(history):
                return plan
            plan = plan.other
        if len(self.plans) >= ENTRY_LIMIT:
            self.plans.clear()
            first = None
        made = None
        if len(enabled) == 1:
            transition = enabled[0]
            if transition in self.steps:
                step = self.steps[transition]
            else:
                step = self.steps[transition] = Step.of(transition)
            if step is not None:
                made = step.plan(self.states)
        if made is None:
            made = make_plan(self.states, enabled, history)
        made.other = first
        self.plans[enabled] = made
        return made


class Tables:
    """A chart's dispatch tables: the configurations reached so far, interned (engines of the
    same chart share them: a plan depends on nothing an engine has of its own)."""

    __slots__ = ("by_descriptor", "by_name", "configurations", "eventless", "fillers", "steps")

    def __init__(self, nodes: Iterable[Node]) -> None:
        self.configurations: dict[frozenset[Node], Configuration] = {}
        # The chart's evented transitions by descriptor, its eventless ones by source: linear in
        # the chart, so that what reacts to a name is a few look-ups, not a walk of the states.
        self.by_descriptor: dict[str, list[Transition]] = {}
        self.eventless: dict[Node, tuple[Transition, ...]] = {}
        for node in nodes:
            if node.eventless:
                self.eventless[node] = node.eventless
            for transition in node.transitions:
                for descriptor in transition.events:
                    self.by_descriptor.setdefault(descriptor, []).append(transition)
        self.by_name: dict[str, Reactors] = {}
        # Per transition taken alone, its Step (None: it reads history); as many as the chart
        # has transitions, so unbounded.
        self.steps: dict[Transition, Step | None] = {}
        self.fillers: dict[str, Callable[[Mapping[str, Any] | None], Record]] = {}

    def filler(
        self, name: str, template: Mapping[str, Any]
    ) -> Callable[[Mapping[str, Any] | None], Record]:
        """`fill_fields` for the event `name` (whose declared fields `template` has)."""
        found = self.fillers.get(name)
        if found is None:
            found = self.fillers[name] = fields_filler(template)
        return found

    def configuration(self, states: frozenset[Node]) -> Configuration:
        """The interned configuration of these states."""
        found = self.configurations.get(states)
        if found is None:
            if len(self.configurations) >= CONFIGURATION_LIMIT:
                self.configurations.clear()
            found = self.configurations[states] = Configuration(states, self)
        return found

    def after(self, plan: Plan) -> Configuration:
        """The configuration the plan leads to. The plan then keeps the interned set of states:
        the next look-ups find it by identity rather than comparing the sets, and the plan
        keeps it (a configuration is valid for ever: past the bound, the plans of the tables
        started anew lead only to their own, so what the old ones reach is dropped as the
        engines move on)."""
        found = self.configuration(plan.target)
        plan.target = found.states
        plan.after = found
        return found

    def reactors(self, name: str) -> Reactors:
        """The nodes with transitions that match the event `name`, with those transitions."""
        found = self.by_name.get(name)
        if found is None:
            if len(self.by_name) >= NAME_LIMIT:
                self.by_name.clear()
            hits: dict[Node, list[Transition]] = {}
            for key in descriptor_keys(name):
                for transition in self.by_descriptor.get(key, ()):
                    hits.setdefault(transition.source, []).append(transition)
            found = self.by_name[name] = {}
            for node, some in hits.items():
                matching = tuple(t for t in node.transitions if t in some and t.matches(name))
                if matching:
                    found[node] = matching
        return found
