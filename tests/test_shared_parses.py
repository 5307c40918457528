"""The compile path's memos (docs/performance.md, "10,000 states: texts parsed once"): a text
parsed once per build, queries and rewrites that return what they were given when nothing
changes. They must never change an answer."""

from __future__ import annotations

import pytest

from swarmgen import expr
from swarmgen.chart import instates
from swarmgen.chart import model as c
from swarmgen.frontend.raw import RawModel
from swarmgen.ir.build_context import Builder


def _builder() -> Builder:
    return Builder(RawModel(file="m.xmi", roots=[], index={}, stereotypes=[], exporter="test"))


def test_a_text_is_parsed_once_per_build_and_an_error_every_time() -> None:
    b = _builder()
    first = b.expression("counter < limit")
    assert b.expression("counter < limit") is first
    assert first == expr.parse_expr("counter < limit")
    assert b.actions("x = x + 1") is b.actions("x = x + 1")
    assert b.bindings("speed = 2") is b.bindings("speed = 2")
    for _ in range(2):  # a text that fails is not kept: each occurrence reports
        with pytest.raises(expr.ExprError):
            b.expression("counter <")
    assert "counter <" not in b.parsed_exprs
    assert _builder().expression("counter < limit") is not first  # per build, not per process


def test_queries_answer_per_expression_even_when_equal_texts_differ_in_objects() -> None:
    one, other = expr.parse_expr('a + b > c and In("S")'), expr.parse_expr("d")
    assert expr.free_names(one) == {"a", "b", "c"}
    assert expr.free_names(one) is expr.free_names(one)
    assert expr.in_states(one) == {"S"} and expr.in_states(other) == frozenset()
    assert expr.free_names(other) == {"d"}
    assert expr.event_fields(expr.parse_expr("event.x > y")) == {"x"}


def _chart(cond: expr.Expr | None, event: str) -> c.Chart:
    leaf = c.Node(id="s_1", name="S", kind="state")
    move = c.Transition(events=(event,), targets=("s_1",), cond=cond)
    top = c.Node(id="top", name="Top", kind="state", children=(leaf,), transitions=(move,))
    return c.Chart(
        name="m",
        machine="M",
        member=None,
        role=None,
        source="m.xmi",
        data=(),
        initial=("top",),
        children=(top,),
    )


def test_in_and_done_resolved_and_nothing_else_rebuilt() -> None:
    waits = _chart(expr.parse_expr("x > 1"), "done.state.S")
    resolved = instates.resolve_in_states(waits)
    top = resolved.children[0]
    assert top.transitions[0].events == ("done.state.s_1",)
    assert top.transitions[0].cond is waits.children[0].transitions[0].cond  # no In(): kept
    assert top.children[0] is waits.children[0].children[0]  # nothing to resolve: the same node
    tests_in = _chart(expr.parse_expr('In("S")'), "go")
    assert instates.resolve_in_states(tests_in).children[0].transitions[0].cond == expr.parse_expr(
        'In("s_1")'
    )
    plain = _chart(expr.parse_expr("x > 1"), "go")
    assert instates.resolve_in_states(plain) is plain
