"""Liveness properties (`eventually P`, `P leads to Q`, `P until Q`) on the explored graph,
under the fairness assumption, with lasso counterexamples (docs/verify.md, "Fairness").

**Fairness.** A run is fair when every member step that is enabled infinitely often is taken
infinitely often (strong fairness per step label: member type, kind, event or outcome, state
and outputs): events in an inbox are delivered, running behaviours end and every outcome a
behaviour keeps being able to end with is eventually taken, pending timers fire; the station
eventually sends each of its events it still may send, except the abort, which it may send at
any time or never. A run may also stop in a state where nothing fair is enabled (no member can
move, the station has sent all but the abort): that is a fair run too. **The abort discharges**: once the
station has sent the abort, obligations still pending are dropped (what must happen after the
abort is abort safety, SG402).

**The check** is a product of the graph with the property's obligation bit (pending or not):
a violation is a reachable pending position from which the run can stop (no member step
enabled), or a fair cycle of pending positions. Fair cycles are found by the Emerson-Lei
refinement of strongly connected components (iterative Tarjan): a component that leaves some
label enabled but never takes it loses the states where that label is enabled, and its rest is
decomposed again. The counterexample is the shortest stem (BFS in the product) and a cycle
inside the component through an edge of every label it takes.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator

from swarmgen.graphs import strongly_connected
from swarmgen.props.tree import Property
from swarmgen.records import dataclass
from swarmgen.verify.observe import Graph, Observer
from swarmgen.verify.system import Step


@dataclass
class Lasso:
    """A violation: the steps to it, then the steps of the cycle (empty: the run stops)."""

    stem: list[Step]
    cycle: list[Step]
    how: str


def check(observer: Observer, prop: Property) -> Lasso | None:
    """The shortest violation of a liveness property, or None when it holds."""
    return _Product(observer, prop).violation()


def premise_seen(observer: Observer, prop: Property) -> bool:
    """Whether the left side of `P leads to Q` holds at some position of the explored graph
    before the abort, where it starts an obligation (else the property holds vacuously). The
    reductions keep this: symmetry and the partial-order reduction's visibility keep every
    position's atoms, so P holds somewhere in the reduced graph iff it does in the whole one."""
    left, graph, bits, holds = prop.left, observer.graph, observer.bits, observer.holds
    assert left is not None
    if 0 not in graph.aborted and holds(left, (bits[0], frozenset())):
        return True
    for state in bits:
        for edge in graph.edges(state):
            target = graph.target[edge]
            if target not in graph.aborted and holds(left, (bits[target], graph.events[edge])):
                return True
    return False


class _Product:
    """Nodes are `2 * state + pending`; only pending nodes can violate."""

    def __init__(self, observer: Observer, prop: Property) -> None:
        self.observer, self.prop, self.graph = observer, prop, observer.graph
        self.parent: dict[int, tuple[int, int]] = {}  # node -> (parent node, edge)
        self.order: list[int] = []  # nodes in BFS order
        self.unsafe: int | None = None  # `until`: a position where P and Q both fail
        self.rank: dict[int, int] = {}  # node -> its place in BFS order

    def first(self) -> int:
        start = self.prop.kind != "leads to"  # `eventually`, `until`: pending from the start
        pending = self._next(start, (self.observer.bits[0], frozenset()), 0 in self.graph.aborted)
        return int(pending)

    def _next(self, pending: bool, position: tuple[int, frozenset[str]], aborted: bool) -> bool:
        """The obligation after a position (P starts one, Q ends it, the abort drops it)."""
        holds, prop = self.observer.holds, self.prop
        if aborted:
            return False
        if prop.kind == "leads to":
            assert prop.right is not None
            return (pending or holds(prop.left, position)) and not holds(prop.right, position)
        goal = prop.right if prop.kind == "until" else prop.left
        assert goal is not None
        return pending and not holds(goal, position)

    def successors(self, node: int) -> Iterator[tuple[int, int]]:
        """(successor node, edge index) of a product node."""
        state, pending = divmod(node, 2)
        graph, bits = self.graph, self.observer.bits
        for edge in graph.edges(state):
            target = graph.target[edge]
            position = (bits[target], graph.events[edge])
            after = self._next(bool(pending), position, target in graph.aborted)
            until = pending and self.prop.kind == "until" and after and self.unsafe is None
            if until and not self.observer.holds(self.prop.left, position):
                self.unsafe = 2 * target + 1
            yield 2 * target + int(after), edge

    def violation(self) -> Lasso | None:
        start = self.first()
        initial = (self.observer.bits[0], frozenset[str]())
        if (
            self.prop.kind == "until"
            and start % 2
            and not self.observer.holds(self.prop.left, initial)
        ):
            return Lasso([], [], "the left side fails before the right side holds")
        self.parent[start] = (-1, -1)
        queue = deque([start])
        stop: int | None = None
        while queue:
            node = queue.popleft()
            self.order.append(node)
            state, pending = divmod(node, 2)
            if pending and stop is None and self._stops(state):
                stop = node
            for successor, edge in self.successors(node):
                if successor not in self.parent:
                    self.parent[successor] = (node, edge)
                    queue.append(successor)
        if self.unsafe is not None:
            return Lasso(self.path(self.unsafe), [], "the left side fails before the right side")
        self.rank = {n: i for i, n in enumerate(self.order)}
        cycle = _fair_cycle(self)
        candidates = [c for c in (stop, cycle[0] if cycle else None) if c is not None]
        if not candidates:
            return None
        self.rank = {n: i for i, n in enumerate(self.order)}
        entry = min(candidates, key=self.rank.__getitem__)
        if entry == stop:
            return Lasso(self.path(entry), [], "the swarm can stop with it pending")
        assert cycle is not None
        return Lasso(self.path(entry), cycle[1], "a fair cycle keeps it pending for ever")

    def enabled(self, state: int) -> frozenset[int]:
        """The fairness labels enabled in a state (none for a state never expanded)."""
        known = self.graph.enabled.get(state)
        return self.graph.label_sets[known] if known is not None else frozenset()

    def _stops(self, state: int) -> bool:
        graph = self.graph
        if state not in graph.enabled:
            return False  # never expanded (bounded): no verdict here
        return not graph.label_sets[graph.enabled[state]]

    def path(self, node: int) -> list[Step]:
        """The steps from the product's start to `node`."""
        steps: list[Step] = []
        while True:
            parent, edge = self.parent[node]
            if parent < 0:
                return steps[::-1]
            steps.append(self.graph.steps[self.graph.step[edge]])
            node = parent


def _fair_cycle(product: _Product) -> tuple[int, list[Step]] | None:
    """A fair strongly connected component of pending nodes (Emerson-Lei): its entry (the
    node reached first) and a cycle from it through an edge of each label it takes."""
    graph = product.graph
    pending = [n for n in product.order if n % 2]
    work = [set(pending)]
    while work:
        nodes = work.pop()
        for component in _components(product, nodes):
            edges = [
                (n, s, e) for n in component for s, e in product.successors(n) if s in component
            ]
            if not edges:
                continue
            taken = {product.observer.label(graph.steps[graph.step[e]]) for _, _, e in edges}
            enabled: set[int] = set()
            for n in component:
                enabled |= product.enabled(n // 2)
            missing = enabled - taken
            if not missing:
                entry = min(component, key=product.rank.__getitem__)
                return entry, _cycle(product, component, entry, edges)
            rest = {n for n in component if not product.enabled(n // 2) & missing}
            if rest:
                work.append(rest)
    return None


def _components(product: _Product, nodes: set[int]) -> list[set[int]]:
    """The strongly connected components of the subgraph on `nodes`."""
    return strongly_connected(
        sorted(nodes), lambda node: (s for s, _ in product.successors(node) if s in nodes)
    )


def _cycle(
    product: _Product, component: set[int], entry: int, edges: list[tuple[int, int, int]]
) -> list[Step]:
    """A cycle from `entry` inside the component through an edge of every label taken."""
    graph = product.graph
    wanted: dict[int, tuple[int, int, int]] = {}
    for found in edges:
        wanted.setdefault(product.observer.label(graph.steps[graph.step[found[2]]]), found)
    steps: list[Step] = []
    here = entry
    label = product.observer.label
    for taken, (source, target, index) in wanted.items():
        if any(label(step) == taken for step in steps):
            continue  # the way to an earlier label's edge took one of this label already
        steps += _inside(product, component, here, source)
        steps.append(graph.steps[graph.step[index]])
        here = target
    steps += _inside(product, component, here, entry)
    return steps


def _inside(product: _Product, component: set[int], start: int, goal: int) -> list[Step]:
    """The steps of a shortest path from `start` to `goal` within the component."""
    graph = product.graph
    parent: dict[int, tuple[int, int]] = {start: (-1, -1)}
    queue = deque([start])
    while queue and goal not in parent:
        node = queue.popleft()
        for successor, edge in product.successors(node):
            if successor in component and successor not in parent:
                parent[successor] = (node, edge)
                queue.append(successor)
    steps: list[Step] = []
    node = goal
    while parent[node][0] >= 0:
        node, edge = parent[node]
        steps.append(graph.steps[graph.step[edge]])
    return steps[::-1]


__all__ = ["Graph", "Lasso", "check"]
