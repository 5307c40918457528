"""Final states with entry and exit actions and done data (W3C `<final>` with `<onentry>` and
`<donedata>`; swarmgen's `done(f = expr)` / `done(expr)` in a final state's entry), and
transitions on another state's `done.state.<name>`: one trace in asyncio, smach and the emitted
SCXML in Qt SCXML (docs/semantics.md, "Final states and done data")."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from swarmgen import expr, pipeline, replay
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")


def test_the_language_reads_done() -> None:
    fields, whole = expr.parse_actions("done(level = x + 1, tag = 'a')\ndone(x * 2)")
    assert isinstance(fields, expr.Done) and [a.name for a in fields.args] == ["level", "tag"]
    assert isinstance(whole, expr.Done) and whole.content is not None and not whole.args
    assert expr.parse_actions("done = 1")[0] == expr.Assign(
        target="done", value=expr.Const(value=1)
    )
    with pytest.raises(expr.ExprError):
        expr.parse_actions("done")


def _model(tmp_path: Path) -> Path:
    """Mission (composite): Working --go--> Finished (final; entry: count = count + 1, then
    done(level = count * 10)); Mission's completion transitions read the done data."""
    kit = ModelKit("Finishing")
    kit.event("go", sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Mission")
    (main,) = machine.composite("Mission")
    machine.initial("Working", region=main)
    machine.state("Working", region=main)
    machine.final("Finished", region=main, entry="count = count + 1\ndone(level = count * 10)")
    machine.transition("Working", "Finished", "go")
    machine.state("Reported")
    machine.state("Low")
    machine.transition("Mission", "Reported", guard="event.level > 5", effect="level = event.level")
    machine.transition("Mission", "Low")
    kit.member("Bot", machine, data={"count": ("Integer", None), "level": ("Integer", None)})
    kit.swarm("Swarm", {"Bot": 1})
    path = tmp_path / "finishing.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def test_done_data_agrees_in_every_backend(tmp_path: Path, qt_available: None) -> None:
    model = _model(tmp_path)
    assert not [d for d in pipeline.validate(model).diagnostics if d.level.name == "ERROR"]
    steps: list[dict[str, Any]] = [{"event": "go"}]
    traces = {b: replay.replay(model, "Bot", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert traces["scxml"][-1]["active"] == ["Reported"]
    assert traces["scxml"][-1]["data"] == {"count": 1, "level": 10}


DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="p" name="Done">
  <datamodel><data id="seen" expr="0"/><data id="got" expr="''"/></datamodel>
  <parallel id="p">
    <state id="a" initial="a1">
      <state id="a1"><transition event="go" target="a2"/></state>
      <final id="a2"><onentry><assign location="seen" expr="seen + 1"/></onentry>
        <donedata><content expr="'from a'"/></donedata></final>
    </state>
    <state id="b">
      <state id="b1"><transition event="done.state.a" target="b2">
        <assign location="got" expr="_event.data"/></transition></state>
      <final id="b2"/>
    </state>
    <transition event="done.state.p" cond="seen == 1 &amp;&amp; got == 'from a'" target="pass"/>
  </parallel>
  <final id="pass"/>
</scxml>
"""


def test_a_document_with_done_data_runs_alike(tmp_path: Path, qt_available: None) -> None:
    """done.state.a (its data the <content>) is taken by a sibling region's state; both
    regions final: done.state.p."""
    source = tmp_path / "done.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    traces = {b: replay.replay(source, "Done", [{"event": "go"}], b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert traces["scxml"][-1]["active"] == ["pass_"]
