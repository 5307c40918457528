"""Chart-level checks: rules over the lowered statecharts, `(Model, [Chart]) -> [Diagnostic]`.

They run as their own stage after `lower` (the pipeline calls `run`), on models the model-level
checks (`swarmgen.check`) passed. Today one family, data flow over each member's chart
(submachines inlined):

- SG209: a behaviour reads member data (a bound expression, or an input read by name) that has no
  default and that some path from the start reaches the state without assigning; one such path
  is reported.
- SG210: a behaviour output is written to member data that nothing reads (note).

The graph goes from atomic state to atomic state: a transition of a state applies in all its
descendants; entering a target enters its default descendants. Assignments are effects, entry
actions, initial transitions and behaviour outputs written back on outcomes.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.chart import model as c
from swarmgen.chart.qtorder import check_qt_order, state_spans
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model
from swarmgen.records import dataclass
from swarmgen.span import Span


@dataclass(frozen=True)
class _Edge:
    target: str
    assigns: frozenset[str]
    label: str


ChartRule = Callable[[Model, Sequence[c.Chart]], list[Diagnostic]]


def check_dataflow(model: Model, charts: Sequence[c.Chart]) -> list[Diagnostic]:
    """SG209 and SG210 over every lowered chart of the model."""
    found: list[Diagnostic] = []
    for chart in charts:
        found += _chart(model, chart)
    return found


CHART_RULES: tuple[ChartRule, ...] = (check_dataflow, check_qt_order)


def run(model: Model, charts: Sequence[c.Chart]) -> list[Diagnostic]:
    """Every chart-level rule's findings, in rule order (the pipeline sorts them by position).

    Only a model the model-level checks passed is lowered (`swarmgen.check.may_lower`), so these
    rules see well-formed charts."""
    found: list[Diagnostic] = []
    for rule in CHART_RULES:
        found += rule(model, charts)
    return found


def _chart(model: Model, chart: c.Chart) -> list[Diagnostic]:
    nodes = {n.id: n for n in chart.walk()}
    parents = {child.id: node.id for node in nodes.values() for child in node.children}
    graph = _Graph(nodes, parents)
    start = [leaf for target in chart.initial for leaf in graph.entry_leaves(target)]
    undefined = {d.id for d in chart.data if d.default is None}
    spans = state_spans(model)
    ids = _data_ids(chart)
    found = []
    for node in nodes.values():
        if node.call is None:
            continue
        read = sorted({n for arg in node.call.args for n in _names(arg.value, ids)} & undefined)
        for name in read:
            path = graph.path_without(start, node.id, name)
            if path is not None:
                found.append(
                    dg.INPUT_MAYBE_UNSET.at(
                        spans.get(node.name or "", Span(file=model.source)),
                        notes=[dg.INPUT_MAYBE_UNSET.note("path", path=" -> ".join(path))],
                        behaviour=node.call.behaviour,
                        state=node.name or node.id,
                        name=name,
                    )
                )
    return found + _unused_outputs(model, chart, nodes, spans, ids)


def _unused_outputs(
    model: Model,
    chart: c.Chart,
    nodes: dict[str, c.Node],
    spans: dict[str, Span],
    ids: dict[str, str],
) -> list[Diagnostic]:
    read: set[str] = set()
    for node in nodes.values():
        for transition in (*node.transitions, *([node.initial] if node.initial else [])):
            if transition.cond is not None:
                read |= _names(transition.cond, ids)
            read |= _action_reads(transition.actions, ids)
        read |= _action_reads((*node.onentry, *node.onexit), ids)
        if node.call is not None:
            read |= {n for arg in node.call.args for n in _names(arg.value, ids)}
    found = []
    reported: set[tuple[str, str]] = set()
    for node in nodes.values():
        if node.call is None:
            continue
        for output, location in node.call.results:
            if location in read or (node.call.behaviour, output) in reported:
                continue
            reported.add((node.call.behaviour, output))
            found.append(
                dg.OUTPUT_UNUSED.at(
                    spans.get(node.name or "", Span(file=model.source)),
                    output=output,
                    behaviour=node.call.behaviour,
                    location=location,
                    member=chart.member or chart.name,
                )
            )
    return found


def _data_ids(chart: c.Chart) -> dict[str, str]:
    """Member data id by name (made once per chart, not once per expression)."""
    return {d.name: d.id for d in chart.data}


def _names(e: expr.Expr, ids: dict[str, str]) -> set[str]:
    return {ids.get(n, n) for n in expr.free_names(e)}


def _action_reads(actions: tuple[c.Action, ...], ids: dict[str, str]) -> set[str]:
    read: set[str] = set()
    for action in c.flat(actions):
        if isinstance(action, c.Assign):
            read |= _names(action.value, ids)
        elif isinstance(action, c.If):
            for cond, _ in action.branches:
                read |= _names(cond, ids) if cond is not None else set()
        elif isinstance(action, c.ForEach):
            read |= _names(action.array, ids)
        elif isinstance(action, c.Raise | c.Send):
            if isinstance(action, c.Raise):
                computed = (
                    action.delay.amount if action.delay else None,
                    action.target,
                    action.via,
                    action.named,
                    action.content,
                )
                for value in computed:
                    read |= _names(value, ids) if value is not None else set()
            for param in action.params:
                if not isinstance(param.value, c.FieldDefault):
                    read |= _names(param.value, ids)
    return read


def _assigned(actions: tuple[c.Action, ...]) -> set[str]:
    found = {a.location for a in c.flat(actions) if isinstance(a, c.Assign) and not a.invalid}
    found -= expr.SYSTEM_VARIABLES  # read-only: assigning one writes nothing
    for loop in c.flat(actions):
        if isinstance(loop, c.ForEach):
            found |= {loop.item, *([loop.index] if loop.index else [])}
        if isinstance(loop, c.Raise) and loop.into is not None:
            found.add(loop.into)
    return found


def _outputs_written(owner: c.Node, transition: c.Transition) -> set[str]:
    """A transition on the outcome of the owner's behaviour leaves with its outputs written
    (they are written when the behaviour ends, before the outcome is matched)."""
    if owner.call is None or not c.takes_outcome(transition.events, owner.id):
        return set()
    return {location for _, location in owner.call.results}


class _Graph:
    def __init__(self, nodes: dict[str, c.Node], parents: dict[str, str]) -> None:
        self.nodes = nodes
        self.parents = parents
        # what entering a node gives, by node id: made once, not once per leaf below an
        # ancestor's transition (read only: callers make new sets and lists from them)
        self._leaves: dict[str, list[str]] = {}
        self._assigns: dict[str, set[str]] = {}
        # per node: (assigns, label, targets) of each transition; a compound state's are read
        # for every leaf below it
        self._exits: dict[str, list[tuple[set[str], str, tuple[str, ...]]]] = {}
        self.edges: dict[str, list[_Edge]] = {}
        for leaf in (n for n in nodes.values() if not n.children or n.kind == "final"):
            self.edges[leaf.id] = self._leaf_edges(leaf)

    def _ancestors(self, node_id: str) -> list[str]:
        chain = [node_id]
        while chain[-1] in self.parents:
            chain.append(self.parents[chain[-1]])
        return chain

    def entry_leaves(self, node_id: str) -> list[str]:
        found = self._leaves.get(node_id)
        if found is None:
            found = self._leaves[node_id] = self._entry_leaves(node_id)
        return found

    def _entry_leaves(self, node_id: str) -> list[str]:
        node = self.nodes.get(node_id)
        if node is None:
            return []
        if node.kind == "history" or node.kind == "parallel" or node.children:
            if node.kind == "parallel":
                return [leaf for child in node.children for leaf in self.entry_leaves(child.id)]
            targets = (
                node.initial.targets if node.initial else tuple(ch.id for ch in node.children[:1])
            )
            return [leaf for t in targets for leaf in self.entry_leaves(t)]
        return [node_id]

    def _entry_assigns(self, node_id: str) -> set[str]:
        found = self._assigns.get(node_id)
        if found is None:
            found = self._assigns[node_id] = self._entry_assigns_of(node_id)
        return found

    def _entry_assigns_of(self, node_id: str) -> set[str]:
        assigned: set[str] = set()
        node = self.nodes.get(node_id)
        if node is None:
            return assigned
        assigned |= _assigned(node.onentry)
        if node.initial is not None:
            assigned |= _assigned(node.initial.actions)
            for target in node.initial.targets:
                assigned |= self._entry_assigns(target)
        return assigned

    def _transitions_of(self, owner_id: str) -> list[tuple[set[str], str, tuple[str, ...]]]:
        found = self._exits.get(owner_id)
        if found is None:
            owner = self.nodes[owner_id]
            found = self._exits[owner_id] = [
                (
                    _assigned(transition.actions) | _outputs_written(owner, transition),
                    " ".join(transition.events) or "(completion)",
                    transition.targets,
                )
                for transition in owner.transitions
            ]
        return found

    def _leaf_edges(self, leaf: c.Node) -> list[_Edge]:
        edges = []
        for owner_id in self._ancestors(leaf.id):
            for assigns, label, targets in self._transitions_of(owner_id):
                for target in targets or (leaf.id,):
                    entered = assigns | self._entry_assigns(target)
                    for next_leaf in self.entry_leaves(target):
                        edges.append(_Edge(next_leaf, frozenset(entered), label))
        return edges

    def path_without(self, start: list[str], goal: str, name: str) -> list[str] | None:
        """A path from a start leaf to `goal` along which `name` is never assigned."""
        previous: dict[str, tuple[str, str] | None] = {s: None for s in start}
        queue = deque(start)
        while queue:
            current = queue.popleft()
            if current == goal:
                return self._unwind(previous, current)
            for edge in self.edges.get(current, []):
                if name in edge.assigns or edge.target in previous:
                    continue
                previous[edge.target] = (current, edge.label)
                queue.append(edge.target)
        return None

    def _unwind(self, previous: dict[str, tuple[str, str] | None], current: str) -> list[str]:
        path = [self.nodes[current].name or current]
        step = previous[current]
        while step is not None:
            path.append(f"[{step[1]}]")
            path.append(self.nodes[step[0]].name or step[0])
            step = previous[step[0]]
        return list(reversed(path))
