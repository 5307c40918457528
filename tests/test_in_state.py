"""`In("S")` in guards and actions (W3C's `In()` in any cond): a state's name (or chart id)
resolved to its id when lowering, the same configuration test in asyncio, smach and the
emitted SCXML in Qt SCXML; an unknown state is SG112."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, pipeline, replay
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")

DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="p" name="Ins">
  <datamodel><data id="x" expr="0"/></datamodel>
  <parallel id="p">
    <state id="a"><state id="a1"><transition event="go" target="a2"/></state><state id="a2"/></state>
    <state id="b">
      <state id="b1">
        <transition event="go" cond="In('a1') &amp;&amp; !In('a2')" target="b2">
          <if cond="In('a2')"><assign location="x" expr="1"/><else/><assign location="x" expr="2"/></if>
        </transition>
      </state>
      <state id="b2"><transition event="check" cond="In('a2') &amp;&amp; x == 2" target="pass"/></state>
    </state>
  </parallel>
  <final id="pass"/>
</scxml>
"""


def test_the_language_reads_in() -> None:
    guard = expr.parse_expr('In("Searching") and not In("a b")')
    assert expr.in_states(guard) == {"Searching", "a b"}
    assert expr.parse_expr(expr.to_text(guard)) == guard
    for bad in ("In(Searching)", 'In("")', "In()"):
        with pytest.raises(expr.ExprError):
            expr.parse_expr(bad)


def test_in_agrees_in_every_backend(tmp_path: Path, qt_available: None) -> None:
    """Transitions are selected before any is taken: `go` sees a1 active in both regions."""
    source = tmp_path / "ins.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    steps = [{"event": "go"}, {"event": "check"}]
    traces = {b: replay.replay(source, "Ins", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert [r["active"] for r in traces["scxml"]][1:] == [["a", "a2", "b", "b2", "p"], ["pass_"]]
    assert traces["scxml"][-1]["data"] == {"x": 2}


def test_an_unknown_state_is_reported(tmp_path: Path) -> None:
    kit = ModelKit("Unknown")
    kit.event("go", sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Busy")
    machine.transition("Idle", "Busy", "go", guard='In("Bussy")')
    kit.member("Bot", machine)
    kit.swarm("Swarm", {"Bot": 1})
    model = tmp_path / "unknown.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    found = [d for d in pipeline.validate(model).diagnostics if d.code.id == "SG112"]
    assert [d.message for d in found] == [
        "transition tests In('Bussy'), but no state has that name"
    ]
