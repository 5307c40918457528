"""Which states a microstep exits and enters: the set computations of the W3C SCXML 1.0
algorithm (Appendix D), pure functions of the transitions, the configuration and the history.
`configuration` runs them once per configuration and event and keeps the results (its
dispatch tables); the engine never calls them per event.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from swarmgen.runtime.chart import Node, Transition

History = Mapping[Node, Sequence[Node]]  # a history node -> the states it recorded


def document_order(node: Node) -> int:
    """The sort key of states in document order."""
    return node.order


def is_descendant(node: Node, ancestor: Node) -> bool:
    """Whether `node` lies strictly below `ancestor`."""
    return ancestor in node.ancestors


def exit_set(
    transitions: Iterable[Transition], config: Collection[Node], history: History
) -> set[Node]:
    """The active states the transitions exit (all that lie below their domains)."""
    to_exit: set[Node] = set()
    for transition in transitions:
        if transition.targets:
            scope = domain(transition, history)
            to_exit.update(s for s in config if scope is None or is_descendant(s, scope))
    return to_exit


def recorded_history(history_node: Node, state: Node, config: Collection[Node]) -> tuple[Node, ...]:
    """What a history node of `state`, which is being exited, records, in document order."""
    if history_node.history == "deep":
        recorded = [s for s in config if s.is_atomic and is_descendant(s, state)]
    else:
        recorded = [s for s in config if s.parent is state]
    return tuple(sorted(recorded, key=document_order))


def in_final(state: Node, config: Collection[Node]) -> bool:
    """Whether a compound or parallel state is in a final configuration."""
    if state.kind == "parallel":
        return all(in_final(c, config) for c in state.children if c.kind != "history")
    if state.is_compound:
        return any(c.kind == "final" and c in config for c in state.children)
    return False


def effective_targets(transition: Transition, history: History) -> list[Node]:
    """A transition's targets with history nodes replaced by what they recorded (or default)."""
    found: list[Node] = []
    for target in transition.targets:
        if target.kind == "history":
            recorded = history.get(target)
            if recorded:
                found.extend(recorded)
            elif target.initial is not None:
                found.extend(effective_targets(target.initial, history))
        else:
            found.append(target)
    return found


def domain(transition: Transition, history: History) -> Node | None:
    """The transition's domain: the state it stays inside (None: it has no targets)."""
    targets = effective_targets(transition, history)
    if not targets:
        return None
    source = transition.source
    if (
        transition.internal
        and source.is_compound
        and all(is_descendant(t, source) for t in targets)
    ):
        return source
    return _lcca([source, *targets])


@dataclass
class EntrySet:
    """The states a microstep enters, those entered by default (their initial transition runs)
    and the history defaults to run, by parent."""

    history: History
    to_enter: set[Node] = field(default_factory=set)
    default_entry: set[Node] = field(default_factory=set)
    history_content: dict[Node, Transition] = field(default_factory=dict)

    def add_descendants(self, state: Node) -> None:
        """Add `state` and what entering it enters below it."""
        if state.kind == "history":
            parent = state.parent
            assert parent is not None
            recorded = self.history.get(state)
            if recorded:
                self._add_targets(recorded, parent)
            elif state.initial is not None:
                self.history_content[parent] = state.initial
                self._add_targets(state.initial.targets, parent)
            return
        self.to_enter.add(state)
        if state.is_compound:
            self.default_entry.add(state)
            targets = state.initial.targets if state.initial is not None else _first_child(state)
            self._add_targets(targets, state)
        elif state.kind == "parallel":
            self._add_regions(state)

    def add_ancestors(self, state: Node, ancestor: Node | None) -> None:
        """Add the ancestors of `state` below `ancestor` (and the other regions they need)."""
        for anc in state.ancestors:
            if anc is ancestor or anc.kind == "scxml":
                break
            self.to_enter.add(anc)
            if anc.kind == "parallel":
                self._add_regions(anc)

    def _add_targets(self, targets: Sequence[Node], parent: Node) -> None:
        for s in targets:
            self.add_descendants(s)
        for s in targets:
            self.add_ancestors(s, parent)

    def _add_regions(self, parallel: Node) -> None:
        """Enter by default every region of a parallel state that nothing enters yet."""
        for child in parallel.children:
            if child.kind != "history" and not any(is_descendant(s, child) for s in self.to_enter):
                self.add_descendants(child)


def entry_set(transitions: Iterable[Transition], history: History) -> EntrySet:
    """What taking the transitions enters (SCXML `computeEntrySet`)."""
    entry = EntrySet(history)
    for transition in transitions:
        for target in transition.targets:
            entry.add_descendants(target)
        ancestor = domain(transition, history)
        for state in effective_targets(transition, history):
            entry.add_ancestors(state, ancestor)
    return entry


def _first_child(state: Node) -> tuple[Node, ...]:
    for child in state.children:
        if child.kind != "history":
            return (child,)
    return ()


def _lcca(states: list[Node]) -> Node | None:
    """Least common compound ancestor (the root counts as compound)."""
    head, rest = states[0], states[1:]
    for anc in head.ancestors:
        if anc.kind in {"state", "scxml"} and all(is_descendant(s, anc) for s in rest):
            return anc
    return None


def remove_conflicts(
    enabled: Sequence[Transition], config: Collection[Node], history: History
) -> tuple[Transition, ...]:
    """The enabled transitions without those preempted by an earlier one whose exit set they
    share (a transition from a descendant state wins over its ancestor's: SCXML 5.9.1)."""
    filtered: list[Transition] = []
    exit_sets: dict[int, set[Node]] = {}
    for t1 in enabled:
        exits1 = exit_sets.setdefault(id(t1), exit_set([t1], config, history))
        preempted = False
        to_remove: list[Transition] = []
        for t2 in filtered:
            if exits1 & exit_sets[id(t2)]:
                if is_descendant(t1.source, t2.source):
                    to_remove.append(t2)
                else:
                    preempted = True
                    break
        if not preempted:
            filtered = [t for t in filtered if t not in to_remove]
            filtered.append(t1)
    return tuple(filtered)
