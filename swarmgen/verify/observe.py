"""User properties as observers of the search: each state's atoms, each edge's events, the
first violation of a safety property (BFS: the shortest), and the graph the liveness check
(`liveness`) needs (docs/verify.md, "User properties").

A run is a sequence of states joined by steps; its **positions** are the initial state and the
state after each step, and the atoms of a position are those of its state plus the events the
step sent (a member's send or emission, or the station's event). `always P` holds when P holds
at every position, `never P` when it holds at none; the other operators are checked on the
recorded graph under the fairness assumption (`liveness`).
"""

from __future__ import annotations

import operator
from array import array
from collections.abc import Callable, Sequence
from dataclasses import field
from typing import Any

from swarmgen.props.tree import (
    Atom,
    Bool,
    Both,
    Count,
    Datum,
    Formula,
    InState,
    Not,
    Occurs,
    Property,
    property_atoms,
)
from swarmgen.records import dataclass
from swarmgen.span import Span
from swarmgen.verify.state import thaw
from swarmgen.verify.system import Effect, Step, SwarmState, System

_OPS: dict[str, Callable[[Any, Any], bool]] = {
    "==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le,
    ">": operator.gt, ">=": operator.ge,
}  # fmt: skip
Position = tuple[int, frozenset[str]]  # a state's atom bits and the events of the step


@dataclass(frozen=True)
class Checked:
    """A user property ready to check: its name, text, where it was written, its tree."""

    name: str
    text: str
    span: Span
    tree: Property


@dataclass
class Graph:
    """The explored graph as flat arrays: per expanded state its first edge (`start`), per edge
    its target, step id and event bits; per state its enabled fairness labels (`enabled`, an
    interned set) and whether the abort was sent."""

    start: dict[int, tuple[int, int]] = field(default_factory=dict)  # state -> (first, end)
    target: array[int] = field(default_factory=lambda: array("l"))
    step: array[int] = field(default_factory=lambda: array("l"))
    events: list[frozenset[str]] = field(default_factory=list)
    enabled: dict[int, int] = field(default_factory=dict)  # state -> label set id
    label_sets: list[frozenset[int]] = field(default_factory=list)
    aborted: set[int] = field(default_factory=set)
    steps: list[Step] = field(default_factory=list)  # step ids -> steps
    labels: dict[tuple[Any, ...], int] = field(default_factory=dict)  # fairness labels

    def edges(self, state: int) -> range:
        """The indices of a state's edges (empty for a state never expanded)."""
        first, end = self.start.get(state, (0, 0))
        return range(first, end)


class Observer:
    """The atoms of every state and the events of every edge, for the properties given."""

    def __init__(self, system: System, props: Sequence[Checked], record: bool) -> None:
        self.system = system
        self.props = list(props)
        self.record = record  # keep the graph (liveness properties)
        self.atoms: list[Atom] = []
        for prop in self.props:
            for atom in property_atoms(prop.tree):
                if not isinstance(atom, Occurs | Bool) and atom not in self.atoms:
                    self.atoms.append(atom)
        self.bits: dict[int, int] = {}  # state number -> its atoms' truth, one bit each
        self.graph = Graph()
        self.safety: dict[int, tuple[int, Step | None]] = {}  # property -> (state, last step)
        self._facts: dict[int, tuple[frozenset[str], dict[str, Any]]] = {}
        self._step_ids: dict[Step, int] = {}
        self._sets: dict[frozenset[int], int] = {}
        # per member type, the state names and data its atoms read: all a step may change
        # without the properties seeing it is the rest (`projection`)
        named = [a for a in self.atoms if isinstance(a, InState | Count)]
        read = [a for a in self.atoms if isinstance(a, Datum)]
        self._watched: dict[str, tuple[frozenset[str], tuple[str, ...]]] = {
            kind: (
                frozenset(a.state for a in named if a.member == kind),
                tuple(sorted({a.datum for a in read if a.member == kind})),
            )
            for kind in {a.member for a in [*named, *read]}
        }
        self._value_labels: dict[int, frozenset[int]] = {}  # member value -> its steps' labels
        self._safety_props = sum(p.tree.kind in ("always", "never") for p in self.props)

    # --- the search's hooks -------------------------------------------------------------

    def projection(self, value: int) -> Any:
        """What the properties observe of a member value (partial-order reduction keeps
        steps that change it)."""
        if not self.atoms:
            return None
        kind = self.system.kinds[self.system.value_type[value]].name
        watched = self._watched.get(kind)
        if watched is None:
            return None
        states, read = watched
        names, data = self.facts(value)
        return names & states, tuple(data.get(name) for name in read)

    def discovered(self, number: int, state: SwarmState) -> None:
        """A new state: its atoms."""
        self.bits[number] = self._bits(state)
        if state.aborted:
            self.graph.aborted.add(number)
        if number == 0:
            self._check_safety(0, None, (self.bits[0], frozenset()))

    def edges(
        self,
        number: int,
        state: SwarmState,
        successors: Sequence[tuple[int, Effect]],
        taken: Sequence[Step],
    ) -> None:
        """An expanded state: its enabled steps' labels, and its successors by the steps
        taken."""
        graph = self.graph
        if self.record:
            graph.enabled[number] = self._set(self.enabled_labels(state))
            graph.start[number] = (len(graph.target), len(graph.target) + len(successors))
            targets, step_ids, events = graph.target, graph.step, graph.events
            for step, (target, effect) in zip(taken, successors, strict=True):
                targets.append(target)
                step_ids.append(self._step(step))
                events.append(_events(effect))
        if len(self.safety) == self._safety_props:
            return  # every safety property is already decided (or there is none)
        for step, (target, effect) in zip(taken, successors, strict=True):
            self._check_safety(number, step, (self.bits[target], _events(effect)), target)

    def enabled_labels(self, state: SwarmState) -> frozenset[int]:
        """The fairness labels of every step enabled in `state` (the station's abort aside):
        each member value's labels are computed once (a label names the member's type, not
        its position), the station's from the events it may still send."""
        memo, system = self._value_labels, self.system
        found: set[int] = set()
        for value in state.members:
            labels = memo.get(value)
            if labels is None:
                kind = system.value_type[value]
                labels = memo[value] = frozenset(
                    self._labelled((kind, s.kind, s.event, s.state, s.data))
                    for s in system.local_steps(value)
                )
            found |= labels
        for event in system.station_events(state):
            if event not in system.abort:
                found.add(self._labelled(("station", event)))
        return frozenset(found)

    # --- evaluation -----------------------------------------------------------------------

    def holds(self, formula: Formula, position: Position) -> bool:
        """The formula's truth at a position (its state's atom bits, its step's events)."""
        bits, events = position
        if isinstance(formula, Not):
            return not self.holds(formula.operand, position)
        if isinstance(formula, Both):
            left = self.holds(formula.left, position)
            if formula.kind == "and":
                return left and self.holds(formula.right, position)
            return left or self.holds(formula.right, position)
        if isinstance(formula, Bool):
            return formula.value
        if isinstance(formula, Occurs):
            return formula.event in events
        return bool(bits >> self.atoms.index(formula) & 1)

    def facts(self, value: int) -> tuple[frozenset[str], dict[str, Any]]:
        """A member value's active state names and data (computed once per value)."""
        known = self._facts.get(value)
        if known is None:
            member = self.system.values[value]
            chart = self.system.kinds[self.system.value_type[value]].chart
            names = frozenset(chart.names.get(n, n) for n in member.engine.config)
            data = thaw(member.engine.data) or {}
            known = self._facts[value] = (names, dict(data))
        return known

    def _bits(self, state: SwarmState) -> int:
        found = 0
        for bit, atom in enumerate(self.atoms):
            if self._atom(atom, state):
                found |= 1 << bit
        return found

    def _atom(self, atom: Atom, state: SwarmState) -> bool:
        system = self.system
        values = [
            v
            for i, v in enumerate(state.members)
            if system.kinds[system.types[i]].name == getattr(atom, "member", "")
        ]
        if isinstance(atom, Count):
            count = sum(atom.state in self.facts(v)[0] for v in values)
            return _OPS[atom.op](count, atom.value)
        if isinstance(atom, InState):
            inside = (atom.state in self.facts(v)[0] for v in values)
            return all(inside) if atom.quantifier == "every" else any(inside)
        if isinstance(atom, Datum):
            results = (_compare(self.facts(v)[1].get(atom.datum), atom) for v in values)
            return all(results) if atom.quantifier == "every" else any(results)
        return False

    def _check_safety(
        self, number: int, step: Step | None, position: Position, target: int = 0
    ) -> None:
        for index, prop in enumerate(self.props):
            if index in self.safety or prop.tree.kind not in ("always", "never"):
                continue
            value = self.holds(prop.tree.left, position)
            if value != (prop.tree.kind == "always"):
                self.safety[index] = (number, step) if step is not None else (0, None)

    def _label(self, step: Step) -> int:
        if step.kind == "station":
            return self._labelled(("station", step.event))
        member_type = self.system.types[step.member]
        return self._labelled((member_type, step.kind, step.event, step.state, step.data))

    def _labelled(self, key: tuple[Any, ...]) -> int:
        known = self.graph.labels.get(key)
        if known is None:
            known = self.graph.labels[key] = len(self.graph.labels)
        return known

    def label(self, step: Step) -> int:
        """The fairness label of a step (-1 for the station's abort, which is never forced)."""
        if step.kind == "station" and step.event in self.system.abort:
            return -1
        return self._label(step)

    def _set(self, labels: frozenset[int]) -> int:
        known = self._sets.get(labels)
        if known is None:
            known = self._sets[labels] = len(self.graph.label_sets)
            self.graph.label_sets.append(labels)
        return known

    def _step(self, step: Step) -> int:
        known = self._step_ids.get(step)
        if known is None:
            known = self._step_ids[step] = len(self.graph.steps)
            self.graph.steps.append(step)
        return known


def _events(effect: Effect) -> frozenset[str]:
    if effect.source == "station":
        return frozenset((effect.event,))
    return frozenset(effect.sent)


def _compare(value: Any, atom: Datum) -> bool:
    try:
        return bool(_OPS[atom.op](value, atom.value))
    except TypeError:
        return False
