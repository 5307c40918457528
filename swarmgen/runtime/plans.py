"""A microstep's plan (`Plan`), computed once by the set functions of `microstep` (W3C SCXML
1.0, Appendix D) and kept by the dispatch tables (`configuration`): what it exits, records,
enters and runs. A transition whose domain and entry set read no history has them computed
once (`Step`), leaving the exit set, which depends on the configuration.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

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

if TYPE_CHECKING:
    from swarmgen.runtime.configuration import Configuration

# An entered state with the initial transition's and the history default's action it runs.
Entry = tuple[Node, Action | None, Action | None]


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
        simple = _simple_entry(transition)
        if simple is not None:
            scope, chain = simple
            entries: tuple[Entry, ...] = tuple([(state, None, None) for state in chain])
            states = frozenset(chain)
        else:
            probe = _Reads({})  # records every history node looked up, whatever its value
            entry = EntrySet(probe)  # `entry_set((transition,), probe)`, its domain once
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

    def plan_in(self, cfg: Configuration) -> Plan:
        """`plan(cfg.states)`, with its target's interned configuration (`after`)."""
        states = cfg.states
        if self.exits:
            exits, records = self._exits(states, cfg.tables.histories)
            cancelled = cancels(exits)
            after = cfg.tables.configuration(states.difference(exits) | self.entered)
        else:  # no targets: the configuration stays
            exits, records, cancelled, after = (), (), (), cfg
        entered, calls = self.quiet if self.quiet is not None else (None, ())
        return Plan(
            self.taken,
            exits,
            records,
            self.entries,
            after.states,
            (),
            None,
            cancelled,
            entered,
            calls,
            self.actions,
            after,
        )

    def plan(
        self, config: frozenset[Node], histories: Mapping[Node, tuple[Node, ...]] | None = None
    ) -> Plan:
        """`make_plan(config, (transition,), history)`, for any history. `histories`: the
        history nodes of each state that has some (`Tables.histories`), if known."""
        exits: tuple[Node, ...] = ()
        records: tuple[tuple[Node, tuple[Node, ...]], ...] = ()
        if self.exits:
            if histories is None:
                below = self._below(config)
                histories = {s: found for s in below if (found := history_children(s))}
            exits, records = self._exits(config, histories)
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

    def _below(self, config: frozenset[Node]) -> Collection[Node]:
        """The states of the configuration the step exits (those below its domain)."""
        scope = self.scope
        return config if scope is None else [s for s in config if scope in s.ancestors]

    def _exits(
        self, config: frozenset[Node], histories: Mapping[Node, tuple[Node, ...]]
    ) -> tuple[tuple[Node, ...], tuple[tuple[Node, tuple[Node, ...]], ...]]:
        """The exit set in exit order, and what exiting it records in history nodes."""
        below = self._below(config)
        exits = tuple(sorted(below, key=document_order, reverse=True) if len(below) > 1 else below)
        if not histories:
            return exits, ()
        records = tuple(
            (child, recorded_history(child, state, config))
            for state in exits
            if state in histories
            for child in histories[state]
        )
        return exits, records


def _simple_entry(transition: Transition) -> tuple[Node | None, tuple[Node, ...]] | None:
    """The domain and entry set (in entry order) of a transition without targets or with one
    atomic target whose ancestors up to its domain include no parallel state: what `domain`
    and `EntrySet` find, without their search (most transitions; None for the others)."""
    targets = transition.targets
    if not targets:
        return None, ()
    target = targets[0]
    if len(targets) > 1 or not target.is_atomic:  # (a history node is not atomic)
        return None
    source, above = transition.source, target.ancestors
    scope: Node | None = None
    if transition.internal and source.is_compound and source in above:
        scope = source
    else:  # `_lcca((source, target))`
        for ancestor in source.ancestors:
            if (ancestor.kind == "state" or ancestor.kind == "scxml") and ancestor in above:
                scope = ancestor
                break
    chain = [target]
    for ancestor in above:  # `EntrySet.add_ancestors`, which the parallel avoids
        if ancestor is scope or ancestor.kind == "scxml":
            break
        if ancestor.kind == "parallel":
            return None
        chain.append(ancestor)
    chain.reverse()  # ancestors come first in document order
    return scope, tuple(chain)


def history_children(state: Node) -> tuple[Node, ...]:
    """The history nodes of a state (they record what it had active when it is left)."""
    return tuple(child for child in state.children if child.kind == "history")
