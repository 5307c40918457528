"""SG216: two transitions that Qt SCXML takes together in another order than W3C.

W3C takes the transitions of one microstep in the document order of the atomic states that
selected them, and runs their executable content in that order (`selectTransitions`,
`executeTransitionContent`); every swarmgen backend does. Qt SCXML 5.15 sorts them first
(`removeConflictingTransitions`): a descendant's source before its ancestor's, else the source
deeper below their common ancestor, and only then document order (measured:
`tests/test_qt_order.py`). Two transitions are taken together when one event enables both and
their exit sets do not meet: in two regions of one parallel state, both staying inside their
regions, or one of them targetless (its exit set is empty). The orders then differ, and the
emitted SCXML run in Qt may end with other data or queue other events than every other backend,
when both have actions and

- the two are in regions R_i before R_k of a parallel state and the one in R_k is deeper, or
- one is on the parallel state or above it, selected by an earlier region that handles the event
  nowhere (W3C: first), and the other inside a later region (Qt: first, the descendant).

When their exit sets meet (both have targets and one leaves its region), only one is taken:
W3C keeps the first in its order, Qt the first in its own, so in the first case Qt takes the
other transition altogether (found by the hunting mode, seed 31: a transition from a deeper
region to the parallel state itself won over the earlier region's).

No rewriting of the document puts them in W3C's order in Qt (depth is the structure itself), so
the rule says where the promise of one trace cannot hold for Qt: docs/semantics.md, "Qt SCXML's
order of transitions taken together".
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from swarmgen import diagnostics as dg
from swarmgen.chart import model as c
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model, State
from swarmgen.ir.query import walk
from swarmgen.span import Span

_Sourced = tuple[int, c.Node, c.Transition]  # (depth of the source, source, transition)


_Pair = tuple[_Sourced, _Sourced]  # (the transition W3C takes first, the one Qt takes first)


def check_qt_order(model: Model, charts: Sequence[c.Chart]) -> list[Diagnostic]:
    """SG216 for every pair of transitions Qt would take in another order, once per pair of
    source states."""
    found = [
        (chart, pair)
        for chart in charts
        for top in chart.children  # the document's children: depth 1 under <scxml>
        for pair in _search(top, 1, [])
    ]
    if not found:
        return []  # (the model's spans are looked up only for a finding)
    spans = state_spans(model)
    return [_diagnostic(chart, first, second, spans) for chart, (first, second) in found]


def _search(node: c.Node, depth: int, above: list[_Sourced]) -> list[_Pair]:
    """Every parallel state under `node`, with the transitions of its ancestors."""
    own = [(depth, node, t) for t in node.transitions if t.actions]
    here = [*above, *own] if own else above
    found = _parallel(node, depth, here) if node.kind == "parallel" else []
    for child in node.children:
        found += _search(child, depth + 1, here)
    return found


def _walk(node: c.Node, depth: int) -> Iterator[tuple[int, c.Node]]:
    yield depth, node
    for child in node.children:
        yield from _walk(child, depth + 1)


def _parallel(node: c.Node, depth: int, above: list[_Sourced]) -> list[_Pair]:
    """The reordered pairs among `node`'s regions, and between them and `above` (the
    transitions of `node` and its ancestors), once per pair of sources."""
    regions = [_Region(child, depth + 1) for child in node.children]
    # the first region whose atomic states select each transition above (W3C's place for it)
    selected = [
        next((k for k, region in enumerate(regions) if region.silent(first)), len(regions))
        for first in above
    ]
    pairs: dict[tuple[str, str], _Pair] = {}
    for k, later in enumerate(regions):
        for second in later.transitions:
            for first in _before(regions, k, second, above, selected):
                pairs.setdefault((first[1].id, second[1].id), (first, second))
    return list(pairs.values())


class _Region:
    """A region of a parallel state: its transitions (with their depths) and its nodes."""

    def __init__(self, node: c.Node, depth: int) -> None:
        walked = list(_walk(node, depth))
        self.transitions: list[_Sourced] = [(d, n, t) for d, n in walked for t in n.transitions]
        self.ids = frozenset(n.id for _, n in walked)

    def silent(self, above: _Sourced) -> bool:
        """Whether the region takes none of the events of a transition above it (with actions
        or not): its atomic states then select that one."""
        return not any(_overlap(t.events, above[2].events) for _, _, t in self.transitions)

    def holds(self, transition: c.Transition) -> bool:
        """Whether every target of the transition is inside the region."""
        return all(t in self.ids for t in transition.targets)


def _before(
    regions: list[_Region],
    k: int,
    second: _Sourced,
    above: list[_Sourced],
    selected: list[int],
) -> Iterator[_Sourced]:
    """The transitions W3C runs before `second` (in region k) and Qt after it."""
    for region in regions[:k]:
        for first in region.transitions:
            if second[0] > first[0] and _together(first, second, (region, regions[k])):
                yield first
    for first, place in zip(above, selected, strict=True):
        if place < k and _together(first, second, None):
            yield first


def _together(first: _Sourced, second: _Sourced, regions: tuple[_Region, _Region] | None) -> bool:
    """Whether Qt's order changes what one event does with both transitions: `first` is the one
    W3C takes first, `regions` the regions holding them (None: `first` is above the parallel
    state). Taken together (one is targetless, or both stay inside their regions), their actions
    run in the other order; when their exit sets meet, W3C keeps the first and Qt the deeper
    (the descendant, for a transition above: the same in both)."""
    one, two = first[2], second[2]
    if not _overlap(one.events, two.events):
        return False
    apart = not one.targets or not two.targets
    if regions is not None and not apart:
        apart = regions[0].holds(one) and regions[1].holds(two)
    if apart:
        return bool(one.actions and two.actions)
    return regions is not None and (one.targets != two.targets or bool(one.actions or two.actions))


def _overlap(left: tuple[str, ...], right: tuple[str, ...]) -> bool:
    """Whether some event matches a descriptor of each (both eventless: both are taken in the
    same microstep when their conditions hold)."""
    if not left or not right:
        return not left and not right
    return any(_prefix(a, b) or _prefix(b, a) for a in left for b in right)


def _prefix(descriptor: str, other: str) -> bool:
    """SCXML's token prefix match: `e` matches `e` and `e.x`; `*` matches everything."""
    descriptor = descriptor.removesuffix(".*")
    return descriptor == "*" or other == descriptor or other.startswith(descriptor + ".")


def _diagnostic(
    chart: c.Chart, first: _Sourced, second: _Sourced, spans: dict[str, Span]
) -> Diagnostic:
    def name(node: c.Node) -> str:
        return node.name or node.id

    span = spans.get(second[1].name or "", Span(file=chart.source))
    return dg.QT_ORDER.at(span, chart=chart.name, first=name(first[1]), second=name(second[1]))


def state_spans(model: Model) -> dict[str, Span]:
    """Where each state of the model is written, by its name (the chart keeps the names)."""
    return {
        p.vertex.name: p.vertex.span
        for m in model.machines
        for p in walk(m)
        if isinstance(p.vertex, State)
    }
