"""SG216: two transitions that Qt SCXML takes together in another order than W3C.

W3C takes the transitions of one microstep in the document order of the atomic states that
selected them, and runs their executable content in that order (`selectTransitions`,
`executeTransitionContent`); every swarmgen backend does. Qt SCXML 5.15 runs them deepest
source first, in document order only among sources at the same depth (measured on documents
with two to four parallel regions: `tests/test_qt_order.py`). The two orders differ, and the
emitted SCXML run in Qt may end with other data or queue other events than every other backend,
when two transitions in different regions of one `<parallel>` can be taken by one event, both
have actions, and the later region's source is deeper in the emitted document. No rewriting of
the document puts them in W3C's order in Qt (depth is the structure itself), so the rule says
where the promise of one trace cannot hold for Qt: docs/semantics.md, "Qt SCXML's order of
transitions taken together".
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


def check_qt_order(model: Model, charts: Sequence[c.Chart]) -> list[Diagnostic]:
    """SG216 for every pair of transitions Qt would take in another order, once per pair of
    source states."""
    spans = state_spans(model)
    found: list[Diagnostic] = []
    for chart in charts:
        for top in chart.children:  # the document's children: depth 1 under <scxml>
            for depth, node in _walk(top, 1):
                if node.kind == "parallel":
                    found += _parallel(chart, node, depth, spans)
    return found


def _walk(node: c.Node, depth: int) -> Iterator[tuple[int, c.Node]]:
    yield depth, node
    for child in node.children:
        yield from _walk(child, depth + 1)


def _parallel(chart: c.Chart, node: c.Node, depth: int, spans: dict[str, Span]) -> list[Diagnostic]:
    regions = [list(_staying(region, depth + 1)) for region in node.children]
    found: list[Diagnostic] = []
    reported: set[tuple[str, str]] = set()
    for index, earlier in enumerate(regions):
        for later in regions[index + 1 :]:
            for first in earlier:
                for second in later:
                    pair = (first[1].id, second[1].id)
                    if pair not in reported and _reordered(first, second):
                        reported.add(pair)
                        found.append(_diagnostic(chart, first, second, spans))
    return found


def _staying(region: c.Node, depth: int) -> Iterator[_Sourced]:
    """The transitions in `region` that have actions and stay inside it (one that leaves it
    conflicts with every transition of the other regions: W3C and Qt take one of them)."""
    inside = {n.id for _, n in _walk(region, 0)}
    for offset, node in _walk(region, 0):
        for transition in node.transitions:
            if transition.actions and all(t in inside for t in transition.targets):
                yield depth + offset, node, transition


def _reordered(first: _Sourced, second: _Sourced) -> bool:
    """Whether Qt runs `second` (in a later region) before `first`: one event can take both,
    and `second`'s source is deeper."""
    return second[0] > first[0] and _overlap(first[2].events, second[2].events)


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
