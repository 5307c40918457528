"""Dotted event names and W3C descriptor matching (issue 15 item 1): `raise foo.bar` and
`In-s1` in the action language, events whose model names are W3C event names kept as they are
on every output (`names.event_name`), and a descriptor `a.b` taking `a.b` and `a.b.c` but not
`a.bc`: the same trace in asyncio, smach and the emitted SCXML in Qt SCXML, from an SCXML
document and from an XMI model (docs/semantics.md, "Event names and descriptors")."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, pipeline, replay
from swarmgen.names import event_name
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")


def test_an_event_keeps_a_w3c_name_and_nothing_else() -> None:
    assert event_name("task.done") == "task.done"
    assert event_name("In-s11p112") == "In-s11p112"
    assert event_name("go") == "go"
    assert event_name("Select Rover") == "Select_Rover"
    assert event_name("done") == "done_"
    # the platform's own prefixes stay the platform's: a model event never matches `error.*`
    assert event_name("error.mine") == "error_mine"
    assert event_name("done.state.x") == "done_state_x"
    # anything that is no dotted name of letters, digits, `_` and `-` is made an identifier
    for unsafe in ('a".b', "a.b c", "a..b", "a.", ".a", "é.b", "__a.b", "a.b'); x('"):
        assert event_name(unsafe).isidentifier(), unsafe


def test_the_action_language_reads_dotted_names() -> None:
    raised, sent, delayed = expr.parse_actions(
        "raise foo.zoo(a = 1)\nsend In-s11p112\nraise a.1.b after 1 s as t"
    )
    assert isinstance(raised, expr.Raise) and raised.event == "foo.zoo"
    assert isinstance(sent, expr.Send) and sent.event == "In-s11p112"
    assert isinstance(delayed, expr.Raise) and (delayed.event, delayed.sendid) == ("a.1.b", "t")
    for bad in (
        "raise e-1e+5",
        "raise a. b",
        "raise a .b",
        "raise .a",
        "raise a.b.",
        "raise __a.b",
    ):
        with pytest.raises(expr.ExprError):
            expr.parse_actions(bad)
    with pytest.raises(ValueError):
        expr.Raise(event='a"; x')


DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Desc">
  <datamodel><data id="x" expr="0"/><data id="n" expr="''"/></datamodel>
  <state id="s0">
    <onentry><raise event="task.done.ok"/><raise event="In-s0"/></onentry>
    <transition event="task.failed task.done.bad" target="fail"/>
    <transition event="task.*" target="s1"><assign location="n" expr="_event.name"/></transition>
  </state>
  <state id="s1">
    <transition event="In" target="fail"/>
    <transition event="In-s0" target="s2"><assign location="x" expr="1"/></transition>
  </state>
  <state id="s2">
    <transition event="go.fast" target="fail"/>
    <transition event="go" target="s3"><assign location="x" expr="2"/></transition>
  </state>
  <state id="s3">
    <transition event="go.slow.now" target="pass"/>
    <transition event="go" target="fail"/>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""
STEPS = [{"event": "gone"}, {"event": "go.faster"}, {"event": "go.slow.now.x"}]


def test_descriptors_match_by_token_prefix_in_every_backend(
    tmp_path: Path, qt_available: None
) -> None:
    """`task.*` takes `task.done.ok`, `In` does not take `In-s0`, `go` does not take `gone`
    but takes `go.faster`; the first transition in document order that matches wins."""
    source = tmp_path / "desc.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    traces = {b: replay.replay(source, "Desc", STEPS, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert [r["active"] for r in traces["scxml"]] == [["s2"], ["s2"], ["s3"], ["pass_"]]
    assert traces["scxml"][-1]["data"] == {"n": "task.done.ok", "x": 2}


def _model(tmp_path: Path) -> Path:
    """A station's `mission.start.now` taken by a trigger on `mission`; the member raises
    `task.done` (a signal of its own), taken by a trigger on the signal `task`."""
    kit = ModelKit("Dotted")
    kit.event("mission", sender="station")
    kit.event("mission.start.now", sender="station")
    kit.event("task", {"code": "Integer"}, scope="local")  # what a trigger on `task` reads
    kit.event("task.done", {"code": "Integer"}, scope="local")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Working", entry="raise task.done(code = 7)")
    machine.final("Done")
    machine.transition("Idle", "Working", "mission")
    machine.transition("Working", "Done", "task", effect="code = event.code")
    kit.member("Bot", machine, data={"code": ("Integer", None)})
    kit.swarm("Swarm", {"Bot": 1})
    path = tmp_path / "dotted.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def test_an_xmi_model_carries_dotted_names_end_to_end(tmp_path: Path, qt_available: None) -> None:
    model = _model(tmp_path)
    validation = pipeline.validate(model)
    assert [d.code.id for d in validation.diagnostics if d.code.id in ("SG206", "SG207")] == []
    document = pipeline.compile_model(model, backends=["scxml"]).files[
        pipeline.PurePosixPath("scxml", "Bot.scxml")
    ]
    assert 'event="task.done"' in document and 'event="mission"' in document
    steps = [{"event": "mission.start.now"}]
    traces = {b: replay.replay(model, "Bot", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert traces["scxml"][-1]["active"][-1] == "Done"
    assert traces["scxml"][-1]["data"] == {"code": 7}
