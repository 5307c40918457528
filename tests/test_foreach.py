"""`for item, index in xs do ... end` (W3C `<foreach>`) and sequence literals `[a, b]`: one
trace in asyncio, smach and the emitted SCXML in Qt SCXML; the loop runs over a copy of the
sequence, an item that is no sequence is error.execution (docs/semantics.md, "Loops")."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from swarmgen import expr, pipeline, replay
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")

DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Loops">
  <datamodel><data id="arr">[1, 2, 3]</data><data id="sum" expr="0"/><data id="u"/></datamodel>
  <state id="s0">
    <onentry>
      <foreach array="arr" item="it" index="ix">
        <assign location="sum" expr="sum + it * 10 + ix"/>
        <if cond="ix == 1"><assign location="arr" expr="[]"/></if>
      </foreach>
      <raise event="next"/>
    </onentry>
    <transition event="next" cond="sum == 63 &amp;&amp; it == 3 &amp;&amp; ix == 2" target="s1"/>
    <transition event="next" target="fail"/>
  </state>
  <state id="s1">
    <onentry>
      <assign location="arr" expr="[4, 5]"/>
      <foreach array="arr" item="it"><assign location="sum" expr="sum + it"/></foreach>
    </onentry>
    <onentry><foreach array="u" item="it"><assign location="sum" expr="-1"/></foreach></onentry>
    <transition cond="sum == 72" target="pass"/>
  </state>
  <final id="pass"/><final id="fail"/>
</scxml>
"""


def test_the_language_reads_loops_and_lists() -> None:
    (loop,) = expr.parse_actions("for x, i in xs do s = s + x; if i > 1 then raise e end end")
    assert isinstance(loop, expr.ForEach) and (loop.item, loop.index) == ("x", "i")
    assert len(list(expr.flat((loop,)))) == 4
    assert expr.to_text(expr.parse_expr("[1, [a], []]")) == "[1, [a], []]"
    for bad in ("for x in [1, 2] do end", "for x in xs end", "for in xs do end", "xs[1] == 2"):
        with pytest.raises(expr.ExprError):
            expr.parse_actions(bad) if bad.startswith("for") else expr.parse_expr(bad)
    with pytest.raises(expr.ExprError, match="guard is not a list"):
        expr.parse_expr("[x > 1]")  # UML's brackets around a guard


def test_a_document_loops_alike_in_every_backend(tmp_path: Path, qt_available: None) -> None:
    """The loop goes on over the copy although the body empties the sequence; item and index,
    which no <data> declares, are declared (W3C creates them); a loop over a number (the
    untyped datum's 0) is error.execution and runs nothing."""
    source = tmp_path / "loops.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    ends = {b: replay.replay(source, "Loops", [], b)[-1] for b in BACKENDS}
    for backend, end in ends.items():
        assert end == ends["scxml"], f"{backend} differs from Qt SCXML: {end}"
    assert ends["scxml"]["active"] == ["pass_"]
    assert ends["scxml"]["data"] == {"arr": [4, 5], "it": 5, "ix": 2, "sum": 72, "u": 0}
    assert ends["scxml"]["errors"] == 1


def test_a_model_loops_over_a_sequence(tmp_path: Path, qt_available: None) -> None:
    kit = ModelKit("Looping")
    kit.event("go", {"n": "Integer"}, sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.transition(
        "Idle",
        "Idle",
        "go",
        effect="route = [1.5, event.n]\nfor x, i in route do total = total + x * i end\ncount = count + 1",
    )
    machine.transition("Idle", "Idle", "error.execution", effect="count = count + 100")
    kit.member(
        "Bot",
        machine,
        data={
            "route": ("Real[*]", None),
            "total": ("Real", None),
            "count": ("Integer", None),
            "x": ("Real", None),
            "i": ("Integer", None),
        },
    )
    kit.swarm("Swarm", {"Bot": 1})
    model = tmp_path / "looping.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    assert not [d for d in pipeline.validate(model).diagnostics if d.level.name == "ERROR"]
    steps: list[dict[str, Any]] = [{"event": "go", "data": {"n": 2}}, {"event": "go"}]
    traces = {b: replay.replay(model, "Bot", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert [(r["data"]["total"], r["data"]["count"]) for r in traces["scxml"]] == [
        (0, 0), (2, 1), (2, 2),
    ]  # fmt: skip
