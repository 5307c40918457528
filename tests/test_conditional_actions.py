"""`if c then ... elif c then ... else ... end` in actions (W3C `<if>`/`<elseif>`/`<else>`):
the first branch whose condition holds runs; a condition that fails is false, raises
error.execution, and the block goes on. One trace in asyncio, smach and the emitted SCXML in
Qt SCXML (docs/semantics.md, "Conditional actions"), with a transition on error.execution;
the SCXML reader reads `<if>` back."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from swarmgen import expr, pipeline, replay
from swarmgen.conformance import irp
from swarmgen.runtime.engine import Engine
from swarmgen.scxml.emit import serialize
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")


def test_the_action_language_reads_if_blocks() -> None:
    (block, after) = expr.parse_actions(
        "if x > 1 then y = 1; raise e\nelif event.n < 0 then y = 2\nelse\n  y = 3\nend\nz = 1"
    )
    assert isinstance(block, expr.If) and isinstance(after, expr.Assign)
    assert [b.cond is None for b in block.branches] == [False, False, True]
    assert len(list(expr.flat((block,)))) == 5
    assert expr.parse_actions("end = 1") == (expr.Assign(target="end", value=expr.Const(value=1)),)
    for bad in ("if a then x = 1", "if a x = 1 end", "if a then else y = 1 elif b then end"):
        with pytest.raises(expr.ExprError):
            expr.parse_actions(bad)


def _model(tmp_path: Path) -> Path:
    """`go` runs an if whose first condition reads an event field and an unset datum, whose
    second divides by the event's divisor (0: error.execution, false), and an else."""
    kit = ModelKit("Conditional")
    kit.event("go", {"level": "Real", "divisor": "Integer"}, sender="station")
    kit.event("low", scope="local")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Alarm")
    effect = (
        'if event.level < 20.0 and label == "" then mode = 1; raise low\n'
        "elif 10 / event.divisor > 1 then mode = 2\n"
        "else mode = 3\nend\ncount = count + 1"
    )
    machine.transition("Idle", "Idle", "go", effect=effect)
    machine.state("Faulty")
    machine.transition("Idle", "Alarm", "low")
    machine.transition("Alarm", "Alarm", "go", effect="count = 10 / event.divisor")
    machine.transition("Alarm", "Faulty", "error.execution")
    kit.member(
        "Bot",
        machine,
        data={"mode": ("Integer", None), "count": ("Integer", None), "label": ("String", None)},
    )
    kit.swarm("Swarm", {"Bot": 1})
    path = tmp_path / "conditional.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def test_branches_errors_and_later_actions_agree(tmp_path: Path, qt_available: None) -> None:
    model = _model(tmp_path)
    steps: list[dict[str, Any]] = [
        {"event": "go", "data": {"level": 50.0, "divisor": 0}},  # error: false -> else
        {"event": "go", "data": {"level": 50.0, "divisor": 2}},  # 10 / 2 > 1 -> elif
        {"event": "go", "data": {"level": 5.0}},  # if, raise low -> Alarm
        {"event": "go", "data": {"divisor": 5}},  # count 2
        {"event": "go", "data": {"divisor": 0}},  # error.execution -> Faulty
    ]
    traces = {b: replay.replay(model, "Bot", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    trace = traces["scxml"]
    assert [(r["data"]["mode"], r["data"]["count"]) for r in trace] == [
        (0, 0), (3, 1), (2, 2), (1, 3), (1, 2), (1, 2),
    ]  # fmt: skip
    assert [r["errors"] for r in trace] == [0, 1, 1, 1, 1, 2]
    assert [r["active"] for r in trace[3:]] == [["Alarm"], ["Alarm"], ["Faulty"]]


def test_the_scxml_reader_reads_if_and_the_emitter_writes_it(tmp_path: Path) -> None:
    document = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0">
  <datamodel><data id="x" expr="1"/><data id="y" expr="0"/></datamodel>
  <state id="s0">
    <onentry>
      <if cond="x / 0 &gt; 1"><assign location="y" expr="10"/>
      <elseif cond="x == 1"/><assign location="y" expr="20"/><raise event="bump"/>
      <else/><assign location="y" expr="30"/></if>
    </onentry>
    <transition event="bump" cond="y == 20" target="pass"/>
    <transition event="other" target="fail"/>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""
    source = tmp_path / "if.scxml"
    assert irp.run_document(document.encode(), source) == irp.Outcome("pass")
    text = serialize(pipeline.validate(source).charts[0]).text
    assert '<elseif cond="(x == 1)"/>' in text and "<else/>" in text, text


ERRORS = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Errs">
  <datamodel><data id="x" expr="1"/></datamodel>
  <state id="s0">
    <onentry><assign location="x" expr="x / 0"/><raise event="foo"/></onentry>
    <transition event="foo" target="fail"/>
    <transition event="error.execution" target="s1"/>
  </state>
  <state id="s1">
    <onentry><raise event="bar"/><if cond="x % 0 == 1"><raise event="baz"/></if></onentry>
    <transition event="bar" target="s2"/>
    <transition event="*" target="fail"/>
  </state>
  <state id="s2">
    <transition event="error" target="pass"/>
    <transition event="*" target="fail"/>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""


def test_error_events_in_a_document_take_transitions(tmp_path: Path, qt_available: None) -> None:
    """A failing assign ends its block (no `foo`); error.execution is internal, after the `bar`
    raised before the failing `<if>` cond; `error` takes every error event."""
    source = tmp_path / "errors.scxml"
    source.write_text(ERRORS, encoding="utf-8")
    ends = {b: replay.replay(source, "Errs", [], b)[-1]["active"] for b in BACKENDS}
    assert ends == {b: ["pass_"] for b in BACKENDS}


LOGGING = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Logs">
  <datamodel><data id="x" expr="2"/></datamodel>
  <state id="s0">
    <onentry><log label="only a label"/><log label="x is" expr="x * 10"/><log expr="x / 0"/>
      <assign location="x" expr="3"/></onentry>
  </state>
</scxml>
"""


def test_log_goes_to_the_log_and_changes_nothing(tmp_path: Path, qt_available: None) -> None:
    """`log "label", expr` (W3C <log>): the value to the engine's `on_log`; one that fails is
    error.execution and ends its block; the traces (no log in them) agree everywhere."""
    source = tmp_path / "logs.scxml"
    source.write_text(LOGGING, encoding="utf-8")
    (log,) = expr.parse_actions('log "x is", x * 10')
    assert isinstance(log, expr.Log) and log.label == "x is"
    ends = {b: replay.replay(source, "Logs", [], b)[-1] for b in BACKENDS}
    assert ends["asyncio"] == ends["smach"] == ends["scxml"]
    assert (ends["scxml"]["data"], ends["scxml"]["errors"]) == ({"x": 2}, 1)
    chart = irp.build(pipeline.validate(source).charts[0])
    logged: list[tuple[str, object]] = []
    engine = Engine(chart, on_log=lambda label, value: logged.append((label, value)))
    engine.start()
    assert logged == [("only a label", ""), ("x is", 20)]


BLOCKS = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Blocks">
  <datamodel><data id="n" expr="0"/></datamodel>
  <state id="s0">
    <onentry><assign location="n" expr="n + 1"/><assign location="n" expr="n / 0"/>
      <assign location="n" expr="100"/></onentry>
    <onentry><assign location="n" expr="n + 10"/></onentry>
    <onexit><assign location="n" expr="n % 0"/></onexit>
    <onexit><assign location="n" expr="n + 1000"/></onexit>
    <transition event="go" target="s1"/>
  </state>
  <state id="s1"/>
</scxml>
"""


def test_each_onentry_is_a_block_of_its_own(tmp_path: Path, qt_available: None) -> None:
    """Several <onentry>/<onexit> are `block ... end`s: an error ends only its block."""
    source = tmp_path / "blocks.scxml"
    source.write_text(BLOCKS, encoding="utf-8")
    traces = {b: replay.replay(source, "Blocks", [{"event": "go"}], b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert [(r["data"]["n"], r["errors"]) for r in traces["scxml"]] == [(11, 1), (1011, 2)]
    (block,) = expr.parse_actions("block x = 1 / 0; y = 2 end")
    assert isinstance(block, expr.Block) and len(block.actions) == 2
    kit = ModelKit("Misplaced")
    kit.event("go", sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle", entry="block x = 1 end")
    machine.transition("Idle", "Idle", "go", effect="block x = 2 end")
    kit.member("Bot", machine, data={"x": ("Integer", None)})
    kit.swarm("Swarm", {"Bot": 1})
    model = tmp_path / "misplaced.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    found = [d.message for d in pipeline.validate(model).diagnostics if d.code.id == "SG108"]
    assert found == ["effect has a block where none may stand"]
