"""The engine's dispatch tables: `Tables` interns each configuration it reaches, and a
`Configuration` keeps, per event name, the transitions that could react (`Selection`) and, per
set of enabled transitions, the whole microstep (`Plan`, made in `plans` by the set functions of
`microstep`, W3C SCXML 1.0, Appendix D). What a configuration seen for the first time costs is
kept small: `Tables` indexes the chart's transitions by descriptor (what reacts to a name is a
few look-ups), keeps what is the same in every configuration once (the selections of names one
state reacts to, by that state; names nothing reacts to), and a transition whose domain and
entry set read no history has them computed once (`Step`), leaving the exit set.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from swarmgen.runtime.chart import FINALIZE_PREFIX, Node, Transition
from swarmgen.runtime.microstep import History, document_order
from swarmgen.runtime.plans import Plan, Step, history_children, make_plan
from swarmgen.runtime.values import Record, fields_filler

# `Plan`, `Step` and `make_plan` live in `plans`; the tests and older callers import them here.
__all__ = [
    "CONFIGURATION_LIMIT",
    "ENTRY_LIMIT",
    "NAME_LIMIT",
    "NO_SELECTION",
    "Configuration",
    "Plan",
    "Selection",
    "Step",
    "Tables",
    "make_plan",
]

# Bounds on what the tables keep (a stream of distinct event names, or a chart whose parallel
# regions reach very many configurations, must not fill memory): past them a table starts over,
# which costs recomputation, never a different result.
CONFIGURATION_LIMIT = 4096
ENTRY_LIMIT = 1024
NAME_LIMIT = 4096  # event names whose reacting transitions a chart keeps

Chain = tuple[tuple[Node, tuple[Transition, ...]], ...]  # (owner, candidates), innermost first
# Of one event name: the nodes with transitions that match it, each with those (document order).
Reactors = Mapping[Node, tuple[Transition, ...]]


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


class Configuration:
    """A configuration the engine reached, with its selections and plans as they are needed."""

    __slots__ = ("atomic", "eventless", "plans", "selections", "states", "steps", "tables")

    def __init__(self, states: frozenset[Node], tables: Tables) -> None:
        self.states = states
        self.tables = tables
        self.steps = tables.steps
        atomic = [n for n in states if n.is_atomic]
        self.atomic = tuple(sorted(atomic, key=document_order) if len(atomic) > 1 else atomic)
        # looked at after every microstep
        eventless = tables.eventless
        self.eventless = Selection.of(self.atomic, eventless) if eventless else NO_SELECTION
        # What the names one state reacts to select here, at once: a dictionary merge per
        # atomic state rather than a miss per name (`Tables.alone_below`).
        self.selections: dict[str | None, Selection] = {}
        for state in self.atomic:
            self.selections.update(tables.alone_below(state))
        self.plans: dict[tuple[Transition, ...], Plan] = {}

    def selection(self, name: str) -> Selection:
        """What could react to the event `name`."""
        found = self.selections.get(name)
        if found is None:
            if len(self.selections) >= ENTRY_LIMIT:
                self.selections.clear()
            tables = self.tables
            alone = tables.alone.get(name)
            if alone is not None:  # the same in every configuration where its state is active
                found = alone[1] if alone[0] in self.states else NO_SELECTION
            else:
                reactors = tables.reactors(name)
                if not reactors:  # the same in every configuration: kept once, by the chart
                    return tables.inert(name)
                found = Selection.of(self.atomic, reactors)
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
                made = step.plan_in(self)
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
        "alone_at",
        "below",
        "bounded",
        "by_descriptor",
        "by_name",
        "configurations",
        "eventless",
        "fillers",
        "histories",
        "inert_names",
        "invokes",
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
        self.bounded = False  # whether a transition counts for the step bound
        self.invokes = False  # whether a state invokes sessions
        for node in nodes:
            self.invokes = self.invokes or bool(node.invokes)
            if node.kind == "parallel":
                above_parallel.update(node.lineage)
            if node.kind == "history" and node.parent is not None:
                self.histories[node.parent] = history_children(node.parent)
            if node.eventless:
                self.eventless[node] = node.eventless
            for transition in node.transitions:
                self.bounded = self.bounded or transition.bounded
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
        self.alone_at: dict[Node, dict[str, Selection]] = {}  # those names, by their state
        for name in names:
            reactors = self._reactors(name)
            if len(reactors) == 1:
                for owner, candidates in reactors.items():
                    if owner not in above_parallel:
                        self.alone[name] = (owner, _alone(owner, candidates))
                        self.alone_at.setdefault(owner, {})[name] = self.alone[name][1]
            if name not in self.alone:
                self.known[name] = reactors
        # Per atomic state, the selections of the names in `alone` whose state is it or one
        # of its ancestors, as configurations that have it need them; as many as the chart
        # has states.
        self.below: dict[Node, dict[str, Selection]] = {}
        # The names nothing reacts to (they select nothing in any configuration), as they
        # come (NAME_LIMIT): `Engine._step` looks here where its configuration has no entry.
        self.inert_names: dict[str, Selection] = {}
        self.fillers: dict[str, Callable[[Mapping[str, Any] | None], Record]] = {}

    def filler(
        self, name: str, template: Mapping[str, Any]
    ) -> Callable[[Mapping[str, Any] | None], Record]:
        """`fill_fields` for the event `name` (whose declared fields `template` has)."""
        found = self.fillers.get(name)
        if found is None:
            found = self.fillers[name] = fields_filler(template)
        return found

    def alone_below(self, state: Node) -> dict[str, Selection]:
        """The selections of the names in `alone` whose state is `state` or an ancestor."""
        found = self.below.get(state)
        if found is None:
            found = {}
            for owner in reversed(state.lineage):
                some = self.alone_at.get(owner)
                if some is not None:
                    found.update(some)
            self.below[state] = found
        return found

    def inert(self, name: str) -> Selection:
        """NO_SELECTION, for a name nothing in the chart reacts to (kept in `inert_names`)."""
        if len(self.inert_names) >= NAME_LIMIT:
            self.inert_names.clear()
        self.inert_names[name] = NO_SELECTION
        return NO_SELECTION

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
            if len(some) == 1:  # most names: one transition of the node could match
                matching: tuple[Transition, ...] = (some[0],) if some[0].matches(name) else ()
            else:
                matching = tuple(t for t in node.transitions if t in some and t.matches(name))
            if matching:
                found[node] = matching
        return found
