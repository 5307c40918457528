"""The transitions of a lowered chart that lie on a potential microstep cycle: those the step
bound counts (docs/semantics.md, "The step bound"; `Transition.bounded`).

A transition is *spontaneous* when it needs no external event: it is eventless, or its event can
be raised by the member itself (a `raise`, `done.state.<id>` of a state with a final child,
`error.execution`). A spontaneous transition t1 may enable a spontaneous t2 when t2's
source can be active together with one of t1's targets (one is an ancestor of the other, or they
lie in orthogonal regions) and so can t2's join sources. A transition is bounded when it lies on
a cycle of that graph whose events are raised by the cycle itself (its effects, and the entry
and exit actions around its sources and targets).

This over-approximates on purpose: bounding a transition that never loops changes nothing (the
bound is never reached), missing one would let a livelock spin. A chart without such cycles is
returned unchanged, so valid models keep their output byte for byte.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import replace

from swarmgen.chart.model import Action, Chart, Node, Raise, Transition, flat
from swarmgen.graphs import strongly_connected
from swarmgen.names import dot_prefixes

ERROR_EVENT = "error.execution"  # any expression may fail: always counted as raised
# Past this many spontaneous transitions the pairwise graph would be slow on a hostile chart:
# then every spontaneous transition is bounded (safe, see above).
MAX_SPONTANEOUS = 1000
MAX_EDGES = 100_000

Key = tuple[str, int]  # (source node id, index among its transitions)


def bound_cycles(chart: Chart) -> Chart:
    """`chart` with `bounded` set on the transitions of its potential microstep cycles."""
    marked = _Graph(chart).bounded()
    if not marked:
        return chart
    return replace(chart, children=tuple(_mark(n, marked) for n in chart.children))


def _mark(node: Node, marked: set[Key]) -> Node:
    transitions = tuple(
        replace(t, bounded=True) if (node.id, i) in marked else t
        for i, t in enumerate(node.transitions)
    )
    return replace(
        node, transitions=transitions, children=tuple(_mark(c, marked) for c in node.children)
    )


def raised(actions: Iterable[Action]) -> set[str]:
    """Events these actions put on the member's own queues: `raise e` on the internal queue,
    `raise e(f = ...)` at the back of its external queue (the step bound counts through those
    too: docs/semantics.md)."""
    return {
        a.event
        for a in flat(tuple(actions))
        if isinstance(a, Raise) and a.delay is None and a.target is None and a.event
    }  # (a computed name, `raise (expr)`, is "": unknown here)


def matches(descriptor: str, prefixes: set[str]) -> bool:
    """SCXML descriptor matching (`a.b` matches `a.b` and `a.b.c`; `*` matches anything)
    against `dot_prefixes(names)`."""
    if descriptor == "*":
        return True
    return (descriptor[:-2] if descriptor.endswith(".*") else descriptor) in prefixes


class _Graph:
    def __init__(self, chart: Chart) -> None:
        self.parent: dict[str, str | None] = {}
        self.kind: dict[str, str] = {}
        self.chains: dict[str, tuple[str, ...]] = {}  # ancestors-or-self, innermost first
        self.nodes: dict[str, Node] = {}
        self._entering: dict[tuple[str, str], bool] = {}
        order: list[Node] = []
        stack: list[tuple[Node, str | None]] = [(n, None) for n in reversed(chart.children)]
        while stack:
            node, parent = stack.pop()
            order.append(node)
            self.nodes[node.id] = node
            self.parent[node.id], self.kind[node.id] = parent, node.kind
            above = self.chains[parent] if parent is not None else ()
            self.chains[node.id] = (node.id, *above)
            stack.extend((child, node.id) for child in reversed(node.children))
        self._raises(order)
        self.all: list[tuple[Key, Node, Transition]] = [
            ((n.id, i), n, t) for n in order for i, t in enumerate(n.transitions)
        ]
        everything = {ERROR_EVENT}
        for node in order:
            everything |= self.entry[node.id] | self.anc[node.id]
        for _, _, transition in self.all:
            everything |= raised(transition.actions)
        prefixes = dot_prefixes(everything)
        self.spontaneous = [
            item
            for item in self.all
            if not item[2].events or any(matches(d, prefixes) for d in item[2].events)
        ]

    def _raises(self, order: Sequence[Node]) -> None:
        """Per node, the events raised around it: `anc`, by the actions of it and its ancestors
        (entered or exited with it); `exits`, by the exit actions of its subtree; `entry`, when
        it is entered by default (its initial states, down to a final's `done.state.<id>`)."""
        self.anc: dict[str, set[str]] = {}
        self.exits = {node.id: raised(node.onexit) for node in order}
        for node in order:
            names = raised((*node.onentry, *node.onexit))
            if node.initial is not None:
                names |= raised(node.initial.actions)
            parent = self.parent[node.id]
            self.anc[node.id] = names | (self.anc[parent] if parent is not None else set())
        for node in reversed(order):
            parent = self.parent[node.id]
            if parent is not None:
                self.exits[parent] |= self.exits[node.id]
        self.entry: dict[str, set[str]] = {}
        for node in reversed(order):  # children first: their default entry is known
            self.entry[node.id] = self._entered(node)

    def _entered(self, node: Node) -> set[str]:
        names = raised(node.onentry)
        parent = self.parent[node.id]
        if node.kind == "final" and parent is not None:
            names.add(f"done.state.{parent}")
            grandparent = self.parent[parent]
            if grandparent is not None and self.kind[grandparent] == "parallel":
                names.add(f"done.state.{grandparent}")
        children = [c.id for c in node.children if c.kind != "history"]
        if node.kind == "parallel":
            targets = children
        elif node.initial is not None:
            names |= raised(node.initial.actions)
            targets = list(node.initial.targets)
        else:
            targets = children[:1]
        for target in targets:
            names |= self.entry.get(target, set())
            for between in self.chains.get(target, ())[1:]:  # states on the way down
                if between == node.id:
                    break
                names |= self.anc[between]
        return names

    def _ends(self, source: Node, transition: Transition) -> list[str]:
        """The states whose configuration follows the transition (a history: its parent)."""
        if not transition.targets:
            return [source.id]
        found = []
        for target in transition.targets:
            parent = self.parent.get(target)
            found.append(parent if self.kind.get(target) == "history" and parent else target)
        return found

    def _compatible(self, a: str, b: str) -> bool:
        """Whether states `a` and `b` can be active together."""
        chain_a, chain_b = self.chains.get(a, (a,)), self.chains.get(b, (b,))
        if a in chain_b or b in chain_a:
            return True
        common = next((s for s in chain_b if s in set(chain_a)), None)
        return common is not None and self.kind[common] == "parallel"

    def _produced(self, source: Node, transition: Transition) -> set[str]:
        names = raised(transition.actions) | self.anc[source.id] | self.exits[source.id]
        names.add(ERROR_EVENT)
        if not transition.targets:
            return names
        for target in transition.targets:
            parent = self.parent.get(target)
            if self.kind.get(target) == "history" and parent is not None:
                # a history restores any descendants of its parent: all their actions count
                names |= self.anc[parent] | self._subtree_raises(parent)
            else:
                names |= self.anc.get(target, set()) | self.entry.get(target, set())
        return names

    def _subtree_raises(self, node_id: str) -> set[str]:
        return set().union(
            *(self.entry[n] | self.anc[n] for n, chain in self.chains.items() if node_id in chain)
        )

    def _domain(self, source: Node, transition: Transition) -> str | None:
        """W3C's transition domain: the source for an internal transition into it, else the
        least common compound ancestor (None: the document root)."""
        targets = [self.chains.get(t, (t,)) for t in transition.targets]
        if transition.internal and all(source.id in chain[1:] for chain in targets):
            return source.id
        for ancestor in self.chains[source.id][1:]:
            if self.kind[ancestor] == "state" and all(ancestor in c[1:] for c in targets):
                return ancestor
        return None

    def _leaves_source(self, source: Node, transition: Transition) -> bool:
        return bool(transition.targets) and self._domain(source, transition) != source.id

    def _enters(self, source: Node, transition: Transition, state: str) -> bool:
        """Whether taking the transition may enter `state` (a target, an ancestor of one below
        the domain, a state entered by default under one, anything under a history's parent)."""
        domain = self._domain(source, transition)
        chain = self.chains.get(state, (state,))
        if domain is not None and domain not in chain[1:]:
            return False
        for target in transition.targets:
            parent = self.parent.get(target)
            if self.kind.get(target) == "history" and parent is not None:
                if parent in chain:
                    return True
            elif state in self.chains.get(target, (target,)) or self._by_default(target, state):
                return True
        return False

    def _by_default(self, entered: str, state: str) -> bool:
        """Whether entering `entered` enters `state` (a descendant) by default entry."""
        key = (entered, state)
        if key not in self._entering:
            self._entering[key] = self._walk_default(entered, state)
        return self._entering[key]

    def _walk_default(self, current: str, state: str) -> bool:
        chain = self.chains.get(state, (state,))
        while current in chain:
            if current == state:
                return True
            node = self.nodes[current]
            if node.kind == "parallel":
                current = chain[chain.index(current) - 1]  # every region is entered
                continue
            children = [c.id for c in node.children if c.kind != "history"]
            targets = node.initial.targets if node.initial is not None else tuple(children[:1])
            below = [t for t in targets if current in self.chains.get(t, (t,))[1:]]
            if any(state in self.chains.get(t, (t,)) for t in below):
                return True  # on the way down to an initial target
            nxt = [t for t in below if t in chain]
            if not nxt:
                return False
            current = nxt[0]
        return False

    def _edges(self) -> list[set[int]] | None:
        items = self.spontaneous
        if len(items) > MAX_SPONTANEOUS:
            return None
        memo: dict[tuple[str, str], bool] = {}

        def compatible(a: str, b: str) -> bool:
            if (a, b) not in memo:
                memo[(a, b)] = self._compatible(a, b)
            return memo[(a, b)]

        edges: list[set[int]] = [set() for _ in items]
        count = 0
        for i, (_, source, transition) in enumerate(items):
            ends = self._ends(source, transition)
            for j, (_, other, candidate) in enumerate(items):
                if any(compatible(other.id, e) for e in ends) and all(
                    any(compatible(s, e) for e in ends) for s in candidate.in_states
                ):
                    edges[i].add(j)
                    count += 1
            if count > MAX_EDGES:
                return None
        return edges

    def bounded(self) -> set[Key]:
        items = self.spontaneous
        edges = self._edges()
        if edges is None:
            return {key for key, _, _ in items}
        produced = [self._produced(source, t) for _, source, t in items]
        found: set[int] = set()
        work = [set(range(len(items)))]
        while work:
            for component in _components(work.pop(), edges):
                if len(component) == 1 and not any(i in edges[i] for i in component):
                    continue
                names = dot_prefixes(set().union(*(produced[i] for i in component)))
                fed = {i for i in component if self._fed(items, i, component, names)}
                if fed == component:
                    found |= component
                elif fed:
                    work.append(fed)  # an event the cycle does not raise: cut, look again
        return {items[i][0] for i in found}

    def _fed(
        self, items: list[tuple[Key, Node, Transition]], i: int, cycle: set[int], prefixes: set[str]
    ) -> bool:
        """Whether transition `i` can fire again and again within `cycle`: the cycle raises its
        events (`prefixes`: their `dot_prefixes`), and re-enters its source if taking it leaves
        the source."""
        _, source, transition = items[i]
        if transition.events and not any(matches(d, prefixes) for d in transition.events):
            return False
        if not self._leaves_source(source, transition):
            return True
        return any(self._enters(items[j][1], items[j][2], source.id) for j in cycle)


def _components(group: set[int], edges: list[set[int]]) -> list[set[int]]:
    """Strongly connected components of the graph restricted to `group`: roots in ascending
    order, each node's successors in descending order (the order these analyses report in)."""
    return strongly_connected(sorted(group), lambda node: sorted(edges[node] & group, reverse=True))
