"""Assignments to system variables (`_sessionid = e`, W3C 5.10): read-only, so the assignment
sets nothing, raises error.execution when it runs and ends its block, the same in asyncio,
smach and the emitted SCXML in Qt SCXML (docs/semantics.md, "The event and system
variables")."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, pipeline, replay
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")


def test_the_language_reads_an_assignment_to_a_system_variable() -> None:
    for name in sorted(expr.SYSTEM_VARIABLES):
        (action,) = expr.parse_actions(f"{name} = 27")
        assert action == expr.Assign(target=name, value=expr.Const(value=27))
    for bad in ("_event.name = 1", "_name.x = 1", "__x = 1"):
        with pytest.raises(expr.ExprError):
            expr.parse_actions(bad)


DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Ro">
  <datamodel><data id="n" expr="0"/></datamodel>
  <state id="s0">
    <onentry>
      <assign location="_sessionid" expr="'other'"/>
      <raise event="skipped"/>
    </onentry>
    <onentry><raise event="next"/></onentry>
    <transition event="error.execution" cond="_sessionid != 'other'" target="s1">
      <assign location="n" expr="n + 1"/>
    </transition>
    <transition event="*" target="fail"/>
  </state>
  <state id="s1">
    <onentry><assign location="_event" expr="27"/><assign location="n" expr="n + 10"/></onentry>
    <transition event="next"/>
    <transition event="error.execution" cond="_name == 'Ro' &amp;&amp; _event.type == 'platform'" target="s2"/>
    <transition event="*" target="fail"/>
  </state>
  <state id="s2">
    <transition event="go" target="s3"><assign location="_ioprocessors" expr="1"/></transition>
  </state>
  <state id="s3">
    <transition event="error.execution" target="pass"/>
    <transition event="*" target="fail"/>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""


def test_an_assignment_to_a_system_variable_fails_alike_everywhere(
    tmp_path: Path, qt_available: None
) -> None:
    """The failing assignment ends its `<onentry>` (`skipped` is never raised), the next block
    runs (`next`); the variables keep their values (each backend has its own session id); n counts what ran: 1, not 11."""
    source = tmp_path / "ro.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    traces = {b: replay.replay(source, "Ro", [{"event": "go"}], b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert [r["active"] for r in traces["scxml"]] == [["s2"], ["pass_"]]
    assert traces["scxml"][-1]["data"]["n"] == 1
    assert traces["scxml"][-1]["errors"] == 3


def test_a_model_may_assign_one_and_is_told_nothing_false(tmp_path: Path) -> None:
    """In XMI too: no unknown-data error, no type error, no data-flow note on `_name`."""
    kit = ModelKit("Ro")
    kit.event("go", sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.final("Done")
    machine.transition("Idle", "Done", "go", effect='_name = "x"')
    kit.member("Bot", machine)
    kit.swarm("Swarm", {"Bot": 1})
    model = tmp_path / "ro.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    found = pipeline.validate(model).diagnostics
    assert [d for d in found if "_name" in d.message] == []
