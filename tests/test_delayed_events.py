"""Delayed raises and their cancellation (`raise e after N ms as id`, `cancel id`; W3C's
delayed `<send>` and `<cancel>`): the expression language, the SCXML reader and emitter, and
one trace in every replay backend (asyncio, smach and the emitted SCXML in Qt SCXML), with
`wait` steps that let real time pass (docs/semantics.md, "Delayed events")."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from swarmgen import expr, pipeline, replay
from swarmgen.conformance import irp
from swarmgen.scxml.emit import serialize
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")


def test_the_action_language_reads_and_prints_delays() -> None:
    actions = expr.parse_actions(
        "raise e(f = 1) after 2 s as t\ncancel t\nraise g after n * 10 ms\nraise h after d"
    )
    delayed, cancel, computed, text = actions
    assert isinstance(delayed, expr.Raise) and delayed.delay is not None
    assert (delayed.delay.unit, delayed.sendid) == ("s", "t")
    assert cancel == expr.Cancel(sendid="t")
    assert expr.parse_actions("cancel (a + b)")[0] == expr.Cancel(expr=expr.parse_expr("a + b"))
    assert isinstance(computed, expr.Raise) and computed.delay is not None
    assert expr.free_names(computed.delay.amount) == {"n"}
    assert isinstance(text, expr.Raise) and text.delay is not None and text.delay.unit == ""
    assert expr.parse_actions("cancel = 1") == (
        expr.Assign(target="cancel", value=expr.Const(value=1)),
    )
    for bad in ("send e after 1 s", "cancel", "raise e after 1 s as", "cancel 3"):
        with pytest.raises(expr.ExprError):
            expr.parse_actions(bad)


def _model(tmp_path: Path) -> Path:
    """Armed: `tick` after 80 ms as `tk` (cancelled by `stop`: `cancel (which)`, the send id
    computed, W3C's sendidexpr), `late` after 200 ms as `lt`
    (cancelled when `tick` comes); Ticked re-arms `ping` every 100 ms, counted. Every step
    is 50 ms or more from the due times around it."""
    kit = ModelKit("Delays")
    for name in ("go", "stop"):
        kit.event(name, sender="station")
    for name in ("tick", "late"):
        kit.event(name, scope="local")
    kit.event("ping", {"n": "Integer"}, scope="local")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Armed", entry="raise tick after 80 ms as tk\nraise late after 200 ms as lt")
    machine.state("Ticked", entry="raise ping(n = count) after delay ms as p")
    machine.state("Late")
    machine.transition("Idle", "Armed", "go")
    machine.transition("Armed", "Idle", "stop", effect="cancel (which)")  # which: "tk"
    machine.transition("Armed", "Ticked", "tick", effect="cancel lt")
    machine.transition("Armed", "Late", "late")
    machine.transition("Idle", "Late", "late")
    machine.transition("Ticked", "Ticked", "ping", effect="count = event.n + 1")
    machine.transition("Ticked", "Idle", "stop", effect="cancel p")
    kit.member(
        "Bot",
        machine,
        data={"count": ("Integer", None), "delay": ("Integer", 100), "which": ("String", "tk")},
    )
    kit.swarm("Swarm", {"Bot": 1})
    path = tmp_path / "delays.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


STEPS: list[dict[str, Any]] = [
    {"event": "go"},
    {"event": "stop"},  # `tick` cancelled; `late` (not cancelled) still comes
    {"wait": 300},  # late -> Late
    {"event": "go"},  # Late has no `go`: nothing
]
TICKING: list[dict[str, Any]] = [
    {"event": "go"},
    {"wait": 130},  # tick (80 ms) -> Ticked, late cancelled, ping due at 180 ms
    {"wait": 100},  # ping (n 0): count 1, re-armed for 280 ms
    {"event": "stop"},  # ping cancelled -> Idle
    {"wait": 150},  # neither ping nor late comes
]


def _traces(model: Path, steps: list[dict[str, Any]]) -> list[dict[str, Any]]:
    traces = {b: replay.replay(model, "Bot", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    return traces["scxml"]


def test_a_cancelled_delay_never_arrives_and_others_do(tmp_path: Path, qt_available: None) -> None:
    model = _model(tmp_path)
    trace = _traces(model, STEPS)
    assert [r["active"] for r in trace] == [["Idle"], ["Armed"], ["Idle"], ["Late"], ["Late"]]
    trace = _traces(model, TICKING)
    assert [r["active"] for r in trace] == [
        ["Idle"], ["Armed"], ["Ticked"], ["Ticked"], ["Idle"], ["Idle"],
    ]  # fmt: skip
    assert [r["data"]["count"] for r in trace] == [0, 0, 0, 1, 1, 1]


def test_the_scxml_reader_reads_delays_and_cancels(tmp_path: Path) -> None:
    """A document's delayed sends, targetless sends and cancels run on the engine (IRP-like,
    virtual clock) and come out again as `<send delay>`/`<cancel>`."""
    document = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0">
  <datamodel><data id="d" expr="'300ms'"/></datamodel>
  <state id="s0">
    <onentry>
      <send event="tick" delay="100ms" id="t1"/>
      <send event="late" delay="1s" id="lt"/>
      <send event="dyn" delayexpr="d"/>
      <send event="now"/>
    </onentry>
    <transition event="now" target="s1"/>
  </state>
  <state id="s1">
    <transition event="tick" target="s2"><cancel sendid="lt"/></transition>
    <transition event="*" target="fail"/>
  </state>
  <state id="s2">
    <transition event="dyn" target="s3"/>
    <transition event="*" target="fail"/>
  </state>
  <state id="s3">
    <onentry><send event="end" delay=".5s"/></onentry>
    <transition event="end" target="pass"/>
    <transition event="*" target="fail"/>
  </state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""
    source = tmp_path / "delays.scxml"
    assert irp.run_document(document.encode(), source) == irp.Outcome("pass")
    validation = pipeline.validate(source)
    text = serialize(validation.charts[0]).text
    for piece in (
        '<send event="tick" delay="100ms" id="t1"/>',
        '<send event="late" delay="1000ms" id="lt"/>',
        '<send event="dyn" delayexpr="$sg.duration(d)"/>',
        '<send event="now" delay="0ms"/>',
        '<cancel sendid="lt"/>',
        '<send event="end" delay="500ms"/>',
    ):
        assert piece in text, text


def test_verify_explores_delayed_raises_and_their_cancellation(tmp_path: Path) -> None:
    """`swarmgen verify` takes a pending delayed raise as an input that may come at any later
    step (as a time event, delays not modelled): `ping` and `late` both come first in some
    run, a cancelled one never comes; without Late's way out, Late is a deadlock (SG401)."""
    from swarmgen.verify import run
    from swarmgen.verify.explore import Budget

    kit = ModelKit("Waiting")
    kit.event("launch", sender="station")
    kit.event("ping", {"n": "Integer"}, scope="local")
    kit.event("late", scope="local")
    machine = kit.machine("UAVMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Waiting", entry="raise ping(n = 2) after 1 s as p\nraise late after 2 s as l")
    machine.state("Late")
    machine.final("Done")
    machine.transition("Idle", "Waiting", "launch")
    machine.transition("Waiting", "Done", "ping", guard="event.n == 2", effect="cancel l")
    machine.transition("Waiting", "Late", "late")
    kit.member("UAV", machine)
    kit.swarm("Swarm", {"UAV": 1})
    stuck = kit.xmi()
    machine.transition("Late", "Done")  # the way out: Late ends at once
    model = tmp_path / "waiting.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    result = run.verify(model, Budget())
    assert (result.exit_code, result.findings) == (run.VERIFIED, [])
    model.write_text(stuck, encoding="utf-8")
    result = run.verify(model, Budget())
    found = [f.diagnostic.message for f in result.findings]
    assert found == ["deadlock: UAV_1 in Late can never move again (shortest trace: 5 step(s))"]


def test_simulate_delivers_delayed_raises_in_ticks(tmp_path: Path) -> None:
    """In `swarmgen simulate` a delayed raise arrives after its delay in ticks: Work starts
    Coverage only through `start` (after 500 ms), `never` (cancelled) does not come."""
    from swarmgen.sim import scenario as sc
    from swarmgen.sim.machines import compile_machines
    from swarmgen.sim.sweep import simulate

    kit = ModelKit("Delayed")
    kit.hardware("Camera", "Sensor")
    kit.behaviour("Coverage", requires=["Camera"])
    kit.event("launch", sender="station")
    kit.event("start", scope="local")
    kit.event("never", scope="local")
    machine = kit.machine("Mission")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state(
        "Waiting", entry="raise start after 500 ms\nraise never after 100 ms as n\ncancel n"
    )
    machine.state("Work", do="Coverage")
    machine.state("Wrong")
    machine.transition("Idle", "Waiting", "launch")
    machine.transition("Waiting", "Work", "start")
    machine.transition("Waiting", "Wrong", "never")
    kit.member("UAV", machine=machine, parts={"cam": "Camera"})
    kit.swarm("Swarm", {"UAV": 1})
    model = tmp_path / "delayed.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    chosen = sc.parse(
        {
            "name": "test",
            "world": {"width": 11, "height": 11},
            "station": [{"tick": 0, "event": "launch"}],
            "clock_origin": "launch",
            "max_ticks": 20_000,
            "reps": 1,
        }
    )
    (run,) = simulate(compile_machines(model), chosen).runs
    assert run.reason == "coverage" and run.coverage_final == 1.0


def test_a_zero_delay_keeps_document_order(tmp_path: Path, qt_available: None) -> None:
    """`raise a after 0 ms` then `raise b(n = 1)`: both go to the back of the external queue
    when the action runs (W3C dispatches an undelayed `<send>` at once), `a` first; before, `a`
    went through a timer and came after `b` in every Python backend but not in Qt SCXML."""
    kit = ModelKit("Order")
    kit.event("go", sender="station")
    kit.event("a", scope="local")
    kit.event("b", {"n": "Integer"}, scope="local")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("A", entry="raise a after 0 ms\nraise b(n = 1)")
    for state in ("AfterA", "AfterB", "AB", "BA"):
        machine.state(state)
    machine.transition("Idle", "A", "go")
    machine.transition("A", "AfterA", "a")
    machine.transition("A", "AfterB", "b")
    machine.transition("AfterA", "AB", "b")
    machine.transition("AfterB", "BA", "a")
    kit.member("Bot", machine, data={})
    kit.swarm("Swarm", {"Bot": 1})
    model = tmp_path / "order.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    trace = _traces(model, [{"event": "go"}, {"wait": 50}])
    assert [r["active"] for r in trace] == [["Idle"], ["AB"], ["AB"]]
