"""Qt SCXML runs the transitions it takes together deepest source first; W3C, and every swarmgen
backend, in document order (docs/semantics.md, "Qt SCXML's order of transitions taken
together"). Found by the generated charts' hunting mode. The emitted SCXML cannot be written so
that Qt follows W3C there, so SG216 says where it happens: these documents check that it warns
exactly when Qt's run of the emitted SCXML differs from the other backends'.

Each region's transition on `e` appends its digit to `x` (x = x * 10 + k), so the final `x`
spells the order the actions ran in."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import pipeline, replay

HEAD = '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" datamodel="ecmascript"'


def _t(digit: int) -> str:
    return f'<transition event="e"><assign location="x" expr="x * 10 + {digit}"/></transition>'


def _doc(name: str, regions: str) -> str:
    return f"""{HEAD} initial="p" name="{name}">
  <datamodel><data id="x" expr="0"/></datamodel>
  <parallel id="p">{regions}</parallel>
</scxml>
"""


SHALLOW_THEN_DEEP = (
    f'<state id="a">{_t(1)}</state><state id="b"><state id="b1">{_t(2)}</state></state>'
)
DEEP_THEN_SHALLOW = (
    f'<state id="a"><state id="a1">{_t(1)}</state></state><state id="b">{_t(2)}</state>'
)
SAME_DEPTH = f'<state id="a">{_t(1)}</state><state id="b">{_t(2)}</state>'
NESTED = (
    f'<state id="a">{_t(1)}</state><parallel id="q"><state id="b">{_t(2)}</state>'
    f'<state id="c"><state id="c1">{_t(3)}</state></state></parallel><state id="d">{_t(4)}</state>'
)
NESTED_PLAIN = (
    f'<state id="a">{_t(1)}</state><parallel id="q"><state id="b"/>'
    f'<state id="c">{_t(2)}</state></parallel>'
)
# the parallel state's own targetless transition, selected by `b` (first), and `c`'s
ANCESTOR = f'{_t(1)}<state id="b"/><state id="c">{_t(2)}</state>'
# the same, but `b` takes `e` itself: the parallel state's transition is not selected
ANCESTOR_SHADOWED = f'{_t(1)}<state id="b">{_t(3)}</state><state id="c">{_t(2)}</state>'
# one transition leaves its region (its exit set is all of p), the other is targetless: both
# are taken (hunting mode, seed 31)
LEAVING = (
    f'<state id="a"><transition event="e" target="p"><assign location="x" expr="x * 10 + 1"/>'
    f'</transition></state><parallel id="q"><state id="b"/><state id="c"><state id="c1">{_t(2)}'
    "</state></state></parallel>"
)
# both leave for p (their exit sets meet: one is taken): W3C takes `a`'s (first), Qt `c1`'s
# (deeper), which has no actions (hunting mode, seed 31)
CONFLICT = (
    '<state id="a"><transition event="e" target="p"><assign location="x" expr="x * 10 + 1"/>'
    '</transition></state><parallel id="q"><state id="b"/><state id="c"><state id="c1">'
    '<transition event="e" target="p"/></state></state></parallel>'
)
# document -> (Qt on the document as written, W3C / every backend)
CASES = {
    "conflict": (CONFLICT, 0, 1),
    "ancestor": (ANCESTOR, 21, 12),
    "ancestor_shadowed": (ANCESTOR_SHADOWED, 32, 32),
    "leaving": (LEAVING, 21, 12),
    "shallow_then_deep": (SHALLOW_THEN_DEEP, 21, 12),
    "deep_then_shallow": (DEEP_THEN_SHALLOW, 12, 12),
    "same_depth": (SAME_DEPTH, 12, 12),
    "nested": (NESTED, 3214, 1234),
    "nested_plain": (NESTED_PLAIN, 21, 12),
}


def _final_x(trace: list[dict[str, object]]) -> object:
    data = trace[-1]["data"]
    assert isinstance(data, dict)
    return data["x"]


@pytest.mark.parametrize("case", sorted(CASES))
def test_qt_takes_the_deepest_source_first(case: str, tmp_path: Path, qt_available: None) -> None:
    regions, qt, w3c = CASES[case]
    document = tmp_path / "Order.scxml"
    document.write_text(_doc("Order", regions), encoding="utf-8")
    assert _final_x(replay.run_qt(document, [{"event": "e"}])) == qt
    for backend in ("asyncio", "smach"):
        (trace,) = replay.replay_many(document, "Order", [[{"event": "e"}]], backend)
        assert _final_x(trace) == w3c


@pytest.mark.parametrize("case", sorted(CASES))
def test_sg216_warns_exactly_where_the_emitted_scxml_differs_in_qt(
    case: str, tmp_path: Path, qt_available: None
) -> None:
    regions, _, w3c = CASES[case]
    document = tmp_path / "Order.scxml"
    document.write_text(_doc("Order", regions), encoding="utf-8")
    (emitted,) = replay.replay_many(document, "Order", [[{"event": "e"}]], "scxml")
    warned = [d for d in pipeline.validate(document).diagnostics if d.code.id == "SG216"]
    assert bool(warned) == (_final_x(emitted) != w3c)
    for diagnostic in warned:
        assert diagnostic.span.line > 0  # on the later region's state, in the document
