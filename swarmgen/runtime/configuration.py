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

from swarmgen.runtime.chart import FINALIZE_PREFIX, Action, Node, Transition
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


@dataclass(eq=False, slots=True)
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
        if len(reactors) == 1:  # most names: one state reacts (a behaviour's outcome)
            for owner, candidates in reactors.items():
                pair = ((owner, candidates),)
                first = candidates[0]
                fixed = first if first.cond is None and not first.bounded else None
                chained = tuple((fixed, pair) for state in atomic if owner in state.lineage)
                if not chained:
                    return NO_SELECTION
                return cls(chained, None if fixed is None else (fixed,))
        chains: list[tuple[Transition | None, Chain]] = []
        keys = reactors.keys()
        for state in atomic:
            if keys.isdisjoint(state.lineage):  # most states: at C speed
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


def _alone(owner: Node, candidates: tuple[Transition, ...]) -> Selection:
    """`Selection.of` in a configuration with one atomic state at or below `owner`, the one
    state whose transitions (`candidates`) react to a name."""
    first = candidates[0]
    fixed = first if first.cond is None and not first.bounded else None
    return Selection(((fixed, ((owner, candidates),)),), None if fixed is None else (fixed,))


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
    # For the engine, worked out once. `cancels`: where no exit action runs, the exited states
    # whose behaviour or timers are cancelled (exit order), the states then leaving the
    # configuration at once (None: an exit action runs, the engine leaves them one by one).
    # `entered`: where no entry runs anything (behaviours start after the macrostep), the
    # entered states, and `calls` those with a behaviour (None: the engine enters them one by
    # one, in entry order). `actions`: the taken transitions' actions with their sources.
    cancels: tuple[Node, ...] | None = None
    entered: tuple[Node, ...] | None = None
    calls: tuple[Node, ...] = ()
    actions: tuple[tuple[Action, Node], ...] = ()
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
    return plan_of(taken, exits, records, entries, target, read, entered_quietly(entries))


def plan_of(
    taken: tuple[Transition, ...],
    exits: tuple[Node, ...],
    records: tuple[tuple[Node, tuple[Node, ...]], ...],
    entries: tuple[Entry, ...],
    target: frozenset[Node],
    read: tuple[tuple[Node, Sequence[Node] | None], ...],
    quiet: Quiet,
) -> Plan:
    """The plan with what the engine reads instead of working it out per microstep; `quiet`
    is `entered_quietly(entries)`."""
    actions = tuple((t.action, t.source) for t in taken if t.action is not None)
    entered, calls = quiet if quiet is not None else (None, ())
    return Plan(
        taken, exits, records, entries, target, read, None, cancels(exits), entered, calls, actions
    )


def cancels(exits: Iterable[Node]) -> tuple[Node, ...] | None:
    """Where no exit action runs as these states are left, those with a behaviour or timers to
    cancel, in exit order (None: an exit action runs)."""
    found = []
    for state in exits:
        if state.onexit is not None or state.invokes:  # (an invoke is cancelled by `_leave`)
            return None
        if state.call is not None or state.timers:
            found.append(state)
    return tuple(found)


Quiet = tuple[tuple[Node, ...], tuple[Node, ...]] | None  # `entered_quietly`'s


def entered_quietly(entries: Iterable[Entry]) -> Quiet:
    """Where entering the states of an entry set runs nothing (a behaviour only starts after
    the macrostep), the states and those with a behaviour (None: something runs)."""
    states = []
    calls = []
    for state, initial, default in entries:
        if (
            state.onentry is not None
            or state.invokes
            or state.timers
            or state.kind == "final"
            or initial is not None
            or default is not None
        ):
            return None
        states.append(state)
        if state.call is not None:
            calls.append(state)
    return tuple(states), tuple(calls)


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


@dataclass(eq=False, slots=True)
class Step:
    """A transition whose domain and entry set read no history node: both are then the same
    in every configuration and under every history, so they are computed once per transition
    and a microstep taking it alone only has its exit set left to compute."""

    transition: Transition
    exits: bool  # whether it exits anything (it has targets)
    scope: Node | None  # its domain: it exits the active states below it (None: all)
    entries: tuple[Entry, ...]
    entered: frozenset[Node]
    quiet: Quiet  # `entered_quietly(entries)`
    # What each of its plans shares: the transitions taken, their actions (`plan_of`'s)
    taken: tuple[Transition, ...] = ()
    actions: tuple[tuple[Action, Node], ...] = ()

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
        taken = (transition,)
        actions = ((transition.action, transition.source),) if transition.action is not None else ()
        quiet = entered_quietly(entries)
        return cls(
            transition, bool(transition.targets), scope, entries, states, quiet, taken, actions
        )

    def plan(
        self, config: frozenset[Node], histories: Mapping[Node, tuple[Node, ...]] | None = None
    ) -> Plan:
        """`make_plan(config, (transition,), history)`, for any history. `histories`: the
        history nodes of each state that has some (`Tables.histories`), if known."""
        scope = self.scope
        exits: tuple[Node, ...] = ()
        if self.exits:
            below = config if scope is None else [s for s in config if scope in s.ancestors]
            exits = tuple(sorted(below, key=document_order, reverse=True))
        if histories is None:
            histories = {s: found for s in exits if (found := history_children(s))}
        records = (
            tuple(
                (child, recorded_history(child, state, config))
                for state in exits
                if state in histories
                for child in histories[state]
            )
            if histories
            else ()
        )
        target = config.difference(exits) | self.entered
        entered, calls = self.quiet if self.quiet is not None else (None, ())
        return Plan(
            self.taken,
            exits,
            records,
            self.entries,
            target,
            (),
            None,
            cancels(exits),
            entered,
            calls,
            self.actions,
        )


def history_children(state: Node) -> tuple[Node, ...]:
    """The history nodes of a state (they record what it had active when it is left)."""
    return tuple(child for child in state.children if child.kind == "history")


class Configuration:
    """A configuration the engine reached, with its selections and plans as they are needed."""

    __slots__ = ("atomic", "eventless", "plans", "selections", "states", "steps", "tables")

    def __init__(self, states: frozenset[Node], tables: Tables) -> None:
        self.states = states
        self.tables = tables
        self.steps = tables.steps
        self.atomic = tuple(sorted([n for n in states if n.is_atomic], key=document_order))
        # looked at after every microstep
        eventless = tables.eventless
        self.eventless = Selection.of(self.atomic, eventless) if eventless else NO_SELECTION
        self.selections: dict[str | None, Selection] = {}
        self.plans: dict[tuple[Transition, ...], Plan] = {}

    def selection(self, name: str) -> Selection:
        """What could react to the event `name`."""
        found = self.selections.get(name)
        if found is None:
            if len(self.selections) >= ENTRY_LIMIT:
                self.selections.clear()
            alone = self.tables.alone.get(name)
            if alone is not None:  # the same in every configuration where its state is active
                found = alone[1] if alone[0] in self.states else NO_SELECTION
            else:
                found = Selection.of(self.atomic, self.tables.reactors(name))
            self.selections[name] = found
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
                made = step.plan(self.states, self.tables.histories)
        if made is None:
            made = make_plan(self.states, enabled, history)
        made.other = first
        self.plans[enabled] = made
        return made


class Tables:
    """A chart's dispatch tables: the configurations reached so far, interned (engines of the
    same chart share them: a plan depends on nothing an engine has of its own)."""

    __slots__ = (
        "alone",
        "by_descriptor",
        "by_name",
        "configurations",
        "eventless",
        "fillers",
        "histories",
        "known",
        "steps",
    )

    def __init__(self, nodes: Iterable[Node]) -> None:
        self.configurations: dict[frozenset[Node], Configuration] = {}
        # The chart's evented transitions by descriptor, its eventless ones by source: linear in
        # the chart, so that what reacts to a name is a few look-ups, not a walk of the states.
        self.by_descriptor: dict[str, list[Transition]] = {}
        self.eventless: dict[Node, tuple[Transition, ...]] = {}
        # Per transition taken alone, its Step (None: it reads history), made as it is first
        # taken (a chart's first engine need not pay for transitions no run takes); as many
        # as the chart has transitions, so unbounded.
        self.steps: dict[Transition, Step | None] = {}
        names: dict[str, None] = {}  # the names the chart itself gives, in document order
        self.histories: dict[Node, tuple[Node, ...]] = {}  # the states with history nodes
        above_parallel: set[Node] = set()  # the parallel states and their ancestors
        for node in nodes:
            if node.kind == "parallel":
                above_parallel.update(node.lineage)
            if node.kind == "history" and node.parent is not None:
                self.histories[node.parent] = history_children(node.parent)
            if node.eventless:
                self.eventless[node] = node.eventless
            for transition in node.transitions:
                for descriptor in transition.events:
                    self.by_descriptor.setdefault(descriptor, []).append(transition)
                    if "*" not in descriptor:
                        names[descriptor] = None
            if node.call is not None:  # its outcomes arrive as `done.invoke.<id>.<outcome>`
                for outcome in node.call.outcomes:
                    names[f"{FINALIZE_PREFIX}{node.id}.{outcome}"] = None
        self.by_name: dict[str, Reactors] = {}  # other names, as they come (NAME_LIMIT)
        # Per name the chart gives (a descriptor, a behaviour's outcome), made here, linear in
        # the chart: where only one state reacts to it and no parallel state lies below that
        # one (so an active one has one active atomic state below it), `alone` has the state
        # and the name's selection in any configuration that has the state active; else
        # `known` has what reacts to it.
        self.known: dict[str, Reactors] = {}
        self.alone: dict[str, tuple[Node, Selection]] = {}
        for name in names:
            reactors = self._reactors(name)
            if len(reactors) == 1:
                for owner, candidates in reactors.items():
                    if owner not in above_parallel:
                        self.alone[name] = (owner, _alone(owner, candidates))
            if name not in self.alone:
                self.known[name] = reactors
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
        found = self.known.get(name)  # (a name in `alone` is looked up as any other here)
        if found is None:
            found = self.by_name.get(name)
            if found is None:
                if len(self.by_name) >= NAME_LIMIT:
                    self.by_name.clear()
                found = self.by_name[name] = self._reactors(name)
        return found

    def _reactors(self, name: str) -> dict[Node, tuple[Transition, ...]]:
        hits: dict[Node, list[Transition]] = {}
        for key in descriptor_keys(name):
            for transition in self.by_descriptor.get(key, ()):
                hits.setdefault(transition.source, []).append(transition)
        found = {}
        for node, some in hits.items():
            matching = tuple(t for t in node.transitions if t in some and t.matches(name))
            if matching:
                found[node] = matching
        return found
