"""Livelocks (issue 10): transitions that take each other forever without an input from outside.

Unconditional cycles are refused statically with a located SG160 naming the loop (2- and
3-cycles, self-loops, junction cycles, through and inside composite states, completion of a
composite that reaches its final state at once, internal `raise` loops).
Cycles with a guard somewhere validate, and at run time the step bound (docs/semantics.md,
`STEP_BOUND`) ends the macrostep with error.execution: the same trace (configuration, data,
error count) in the Python engine, asyncio, smach, Qt SCXML and (one case) rclpy. Guarded cycles
that end before the bound raise nothing. Before this, every backend and Qt spun at 100% CPU.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import pytest

from swarmgen import pipeline, replay
from swarmgen.chart.lower import lower
from swarmgen.diagnostics import Severity
from swarmgen.runtime.chart import STEP_BOUND
from swarmgen.runtime.engine import Engine, NullHost
from tests.conftest import ROOT, SAMPLE_MODELS
from tests.hostile import assert_clean, assert_refused, swarmgen
from tests.modelkit import Machine, ModelKit
from tests.scenarios import ScenarioMaker, follow, semantic_chart

Build = Callable[[ModelKit, Machine], None]
BACKENDS = ("asyncio", "smach", "scxml")
LIMIT = 5.0  # seconds: generous for a loaded CI box; each case is well under a second of work


def _model(tmp: Path, name: str, build: Build) -> Path:
    kit = ModelKit(name)
    kit.behaviour("Patrol", outcomes=["succeeded", "aborted"])
    kit.event("go", sender="station")
    kit.event("poke", sender="station")
    kit.event("stop", sender="station")
    kit.event("ping", scope="local")
    kit.event("pong", scope="local")
    kit.event("tick", {"level": "Integer"}, scope="local")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    build(kit, machine)
    kit.member("Bot", machine, data={"n": ("Integer", 0), "m": ("Integer", 0)})
    kit.swarm("Swarm", {"Bot": 1})
    path = tmp / f"{name}.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def _states(m: Machine, *names: str) -> None:
    for name in names:
        m.state(name)


# --- unconditional cycles: refused (SG160)


def _two(_: ModelKit, m: Machine) -> None:
    _states(m, "A", "B")
    m.transition("Idle", "A", "go")
    m.transition("A", "B")
    m.transition("B", "A")


def _three(_: ModelKit, m: Machine) -> None:
    _states(m, "A", "B", "C")
    m.transition("Idle", "A", "go")
    m.transition("A", "B")
    m.transition("B", "C")
    m.transition("C", "A")


def _self(_: ModelKit, m: Machine) -> None:
    m.state("A", entry="n = n + 1")
    m.transition("Idle", "A", "go")
    m.transition("A", "A")


def _junctions(_: ModelKit, m: Machine) -> None:
    m.pseudo("J1", "junction")
    m.pseudo("J2", "junction")
    m.transition("Idle", "J1", "go")
    m.transition("J1", "J2")
    m.transition("J2", "J1")


def _state_junction(_: ModelKit, m: Machine) -> None:
    m.state("A")
    m.pseudo("J", "junction")
    m.transition("Idle", "A", "go")
    m.transition("A", "J")
    m.transition("J", "A", effect="n = n + 1")


def _through_composite(_: ModelKit, m: Machine) -> None:
    m.state("A")
    (inner,) = m.composite("C")
    m.initial("C1", region=inner)
    m.state("C1", region=inner)
    m.transition("Idle", "A", "go")
    m.transition("A", "C")
    m.transition("C1", "A")


def _completion(_: ModelKit, m: Machine) -> None:
    """A composite whose initial state is final completes at once: its completion re-enters."""
    (inner,) = m.composite("C")
    m.initial("Done", region=inner)
    m.final("Done", region=inner)
    m.state("D")
    m.transition("Idle", "C", "go")
    m.transition("C", "D")
    m.transition("D", "C")


def _inside_composite(_: ModelKit, m: Machine) -> None:
    (inner,) = m.composite("Outer")
    m.initial("A", region=inner)
    m.state("A", region=inner)
    m.state("B", region=inner)
    m.transition("Idle", "Outer", "go")
    m.transition("A", "B")
    m.transition("B", "A")
    m.transition("Outer", "Idle", "stop")


def _raise_self(_: ModelKit, m: Machine) -> None:
    m.state("A", entry="raise ping")
    m.transition("Idle", "A", "go")
    m.transition("A", "A", "ping")


def _raise_ping_pong(_: ModelKit, m: Machine) -> None:
    m.state("A", entry="raise ping")
    m.state("B", entry="raise pong")
    m.transition("Idle", "A", "go")
    m.transition("A", "B", "ping")
    m.transition("B", "A", "pong")


def _raise_in_effects(_: ModelKit, m: Machine) -> None:
    _states(m, "A", "B")
    m.transition("Idle", "A", "go", effect="raise ping")
    m.transition("A", "B", "ping", effect="raise ping")
    m.transition("B", "A", "ping", effect="raise ping")


def _raise_with_data(_: ModelKit, m: Machine) -> None:
    """`raise tick(level = n)` goes to the back of the member's own queue, after the inputs
    waiting: one may end the loop, so it is left to the step bound."""
    m.state("A", entry="n = n + 1\nraise tick(level = n)")
    m.transition("Idle", "A", "go")
    m.transition("A", "A", "tick")


STATIC: dict[str, tuple[Build, str]] = {
    "two-cycle": (_two, "A -> B -> A"),
    "three-cycle": (_three, "A -> B -> C -> A"),
    "self-loop": (_self, "A -> A"),
    "junction-cycle": (_junctions, "J1 -> J2 -> J1"),
    "state-junction-cycle": (_state_junction, "A -> J -> A"),
    "through-composite": (_through_composite, "A -> C1 -> A"),
    "composite-completion": (_completion, "C -> D -> C"),
    "inside-composite": (_inside_composite, "A -> B -> A"),
    "raise-self-transition": (_raise_self, "A -> A"),
    "raise-ping-pong": (_raise_ping_pong, "A -> B -> A"),
    "raise-in-effects": (_raise_in_effects, "A -> B -> A"),
}


def _livelocks(path: Path) -> list[Any]:
    validation = pipeline.validate(path)
    return [d for d in validation.diagnostics if d.code.id == "SG160"]


@pytest.mark.parametrize("case", list(STATIC), ids=list(STATIC))
def test_unconditional_cycle_is_an_error(tmp_path: Path, case: str) -> None:
    build, loop = STATIC[case]
    started = time.perf_counter()
    found = _livelocks(_model(tmp_path, case.title().replace("-", ""), build))
    assert time.perf_counter() - started < LIMIT
    assert len(found) == 1, found
    diagnostic = found[0]
    assert diagnostic.level is Severity.ERROR
    assert loop in diagnostic.message, diagnostic.message
    assert diagnostic.span.line > 0 and diagnostic.span.xmi_id, diagnostic.span  # located


def test_the_cli_refuses_a_livelock_and_writes_nothing(tmp_path: Path) -> None:
    model = _model(tmp_path, "Loop", _two)
    outcome = swarmgen("validate", model, cwd=tmp_path, timeout=30)
    assert_refused(outcome, exit=1, says="SG160")
    assert re.search(rf"{re.escape(model.name)}:\d+:\d+: error: A -> B -> A", outcome.stdout)
    out = tmp_path / "out"
    compiled = swarmgen("compile", model, "-o", out, cwd=tmp_path, timeout=30)
    assert_refused(compiled, exit=1, says="SG160")
    assert not out.exists()


# --- cycles that need something: no static error


def _guarded(_: ModelKit, m: Machine) -> None:
    _states(m, "A", "B")
    m.transition("Idle", "A", "go")
    m.transition("A", "B", guard="n < 3", effect="n = n + 1")
    m.transition("B", "A")


def _behaviour_waits(_: ModelKit, m: Machine) -> None:
    m.state("A", do="Patrol")
    m.state("B")
    m.transition("Idle", "A", "go")
    m.transition("A", "B")  # the completion of A waits for Patrol's outcome
    m.transition("B", "A")


def _composite_waits(_: ModelKit, m: Machine) -> None:
    (inner,) = m.composite("C")
    m.initial("W", region=inner)
    m.state("W", do="Patrol", region=inner)
    m.final("Done", region=inner)
    m.transition("W", "Done", "succeeded")
    m.state("D")
    m.transition("Idle", "C", "go")
    m.transition("C", "D")  # waits for C's final state, reached on an outcome
    m.transition("D", "C")


def _external_cycle(_: ModelKit, m: Machine) -> None:
    _states(m, "A", "B")
    m.transition("Idle", "A", "go")
    m.transition("A", "B", "go")
    m.transition("B", "A", "go")


def _raise_dropped(_: ModelKit, m: Machine) -> None:
    m.state("A", entry="raise ping")
    m.state("B", entry="raise ping")
    m.transition("Idle", "A", "go")
    m.transition("A", "B", "ping")
    m.transition("B", "Idle", "stop")  # B drops its ping: the run settles


NO_ERROR: dict[str, Build] = {
    "guarded-cycle": _guarded,
    "completion-waits-for-behaviour": _behaviour_waits,
    "composite-waits-for-final": _composite_waits,
    "external-event-cycle": _external_cycle,
    "raised-event-dropped": _raise_dropped,
    "raise-with-data-loop": _raise_with_data,
}


@pytest.mark.parametrize("case", list(NO_ERROR), ids=list(NO_ERROR))
def test_cycle_that_needs_something_is_no_error(tmp_path: Path, case: str) -> None:
    path = _model(tmp_path, case.title().replace("-", ""), NO_ERROR[case])
    assert _livelocks(path) == []
    validation = pipeline.validate(path)
    assert not [d for d in validation.diagnostics if d.level is Severity.ERROR]


# --- at run time: the step bound, the same trace everywhere


def _loop(limit: str) -> Build:
    def build(_: ModelKit, m: Machine) -> None:
        _states(m, "A", "B")
        m.transition("Idle", "A", "go")
        m.transition("A", "B", guard=f"n < {limit}", effect="n = n + 1")
        m.transition("B", "A")
        m.transition("A", "Idle", "stop")

    return build


def _raise_loop(limit: str) -> Build:
    def build(_: ModelKit, m: Machine) -> None:
        m.state("A", entry="m = m + 1\nraise ping")
        m.transition("Idle", "A", "go")
        m.transition("A", "A", "ping", guard=f"m < {limit}")
        m.transition("A", "Idle", "stop")

    return build


def _junction_escape(_: ModelKit, m: Machine) -> None:
    """At the bound the looping branch is refused: the `else` branch is taken."""
    m.pseudo("J", "junction")
    m.state("Done")
    m.transition("Idle", "J", "go")
    m.transition("J", "J", guard="n < 5000", effect="n = n + 1")
    m.transition("J", "Done", guard="else")


def _parallel_twice(_: ModelKit, m: Machine) -> None:
    """A bounded transition of a state above two regions is considered once per region (W3C's
    selection), so it counts twice per microstep, in Qt as in the engine."""
    left, right = m.composite("C", ["Left", "Right"], entry="m = m + 1\nraise ping")
    m.initial("X", region=left)
    m.state("X", region=left)
    m.initial("Y", region=right)
    m.state("Y", region=right)
    m.transition("Idle", "C", "go")
    m.transition("C", "C", "ping", guard="m < 5000")


def _data_loop(_: ModelKit, m: Machine) -> None:
    m.state("A", entry="n = n + 1\nraise tick(level = n)")
    m.transition("Idle", "A", "go")
    m.transition("A", "A", "tick", guard="event.level < 5000")


GO: dict[str, Any] = {"event": "go"}
POKE: dict[str, Any] = {"event": "poke"}
STOP: dict[str, Any] = {"event": "stop"}
# name -> (build, steps, expected (active, errors, data) after each step)
RUNTIME: dict[
    str, tuple[Build, list[dict[str, Any]], list[tuple[list[str], int, dict[str, int]]]]
] = {
    "eventless-loop-hits-bound": (
        _loop("5000"),
        [GO, POKE, {"burst": [POKE, POKE]}, STOP],
        [
            (["A"], 1, {"n": STEP_BOUND // 2}),
            (["A"], 2, {"n": STEP_BOUND}),  # the next event starts the count again
            (["A"], 4, {"n": 2 * STEP_BOUND}),  # one bound per external event
            (["Idle"], 4, {"n": 2 * STEP_BOUND}),  # the member keeps processing events
        ],
    ),
    "eventless-loop-ends-first": (_loop("10"), [GO, POKE], [(["A"], 0, {"n": 10})] * 2),
    "raise-loop-hits-bound": (
        _raise_loop("5000"),
        [GO, POKE, STOP],
        # entry, then STEP_BOUND re-entries; the refused transition drops its ping: no restart
        [(["A"], 1, {"m": STEP_BOUND + 1})] * 2 + [(["Idle"], 1, {"m": STEP_BOUND + 1})],
    ),
    "raise-loop-ends-first": (_raise_loop("20"), [GO], [(["A"], 0, {"m": 20})]),
    "junction-escapes-by-else": (_junction_escape, [GO], [(["Done"], 1, {"n": STEP_BOUND})]),
    "parallel-counts-per-region": (
        _parallel_twice,
        [GO],
        [(["C", "Left", "Right", "X", "Y"], 1, {"m": STEP_BOUND // 2 + 1})],
    ),
    "raise-with-data-loop-hits-bound": (_data_loop, [GO], [(["A"], 1, {"n": STEP_BOUND + 1})]),
}


def _engine_trace(model: Path, steps: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The bare engine (no asyncio member) fed as the replay feeds it."""
    validation = pipeline.validate(model)
    assert validation.model is not None
    chart = next(c for c in lower(validation.model) if c.member == "Bot")
    host = NullHost()
    engine = Engine(semantic_chart(chart), host)
    engine.start()
    trace = [_record(engine)]
    for step in steps:
        follow(engine, step)
        while host.delivered:  # a `raise` with data: the back of the member's own queue
            engine.send(host.delivered.pop(0))
        trace.append(_record(engine))
    return trace


def _record(engine: Engine) -> dict[str, Any]:
    return {"active": engine.active(), "errors": engine.error_count, "data": dict(engine.data)}


def _essentials(trace: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{k: r[k] for k in ("active", "errors", "data")} for r in trace]


@pytest.mark.parametrize("case", list(RUNTIME), ids=list(RUNTIME))
def test_step_bound_gives_one_trace_everywhere(
    tmp_path: Path, case: str, qt_available: None
) -> None:
    model = _model(tmp_path, case.title().replace("-", ""), RUNTIME[case][0])
    assert _livelocks(model) == []  # guarded: validates, caught at run time
    _, steps, expected = RUNTIME[case]
    started = time.perf_counter()
    traces = {b: _essentials(replay.replay(model, "Bot", steps, b)) for b in BACKENDS}
    traces["engine"] = _essentials(replay.canonical(_engine_trace(model, steps)))
    assert time.perf_counter() - started < 4 * LIMIT
    reference = traces["scxml"]
    for backend, trace in traces.items():
        assert trace == reference, f"{backend} differs from Qt SCXML:\n{trace}\n{reference}"
    for record, (active, errors, data) in zip(reference[1:], expected, strict=True):
        assert record["active"] == active and record["errors"] == errors, record
        assert {k: record["data"][k] for k in data} == data, record


def test_rclpy_gives_the_same_trace(tmp_path: Path, qt_available: None) -> None:
    model = _model(tmp_path, "RosLoop", _loop("5000"))
    scenarios: list[list[dict[str, Any]]] = [[GO, POKE, STOP], [GO, {"burst": [POKE, STOP]}]]
    ours = replay.replay_many(model, "Bot", scenarios, "rclpy")
    assert ours == replay.replay_many(model, "Bot", scenarios, "scxml")
    assert [r["errors"] for r in ours[0]] == [0, 1, 2, 2]


# --- the generated code: --duration and the exit code still hold


@pytest.mark.parametrize("backend", ["asyncio", "smach"])
def test_generated_member_honours_duration_after_the_bound(tmp_path: Path, backend: str) -> None:
    model = _model(tmp_path, "Spin", _loop("1000000"))
    out = tmp_path / "out"
    assert_clean(swarmgen("compile", model, "-o", out, cwd=tmp_path, timeout=60), (0,))
    package = out / backend
    started = time.perf_counter()
    arguments = ["--swarm", "--events", "go@0.1,go@0.3", "--duration", "1"]
    completed = subprocess.run(
        [sys.executable, "-m", "spin_swarm", *arguments],
        cwd=package,
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )
    elapsed = time.perf_counter() - started
    assert elapsed < 1 + LIMIT, elapsed  # before: --duration ignored, 100% CPU forever
    assert completed.returncode == 1, completed  # not clean: the bound raised errors
    assert completed.stderr.count("step bound in A") == 2, completed.stderr
    assert completed.stdout.count('"event": "go"') == 2  # the member kept processing events


# --- the bound is one constant, the marks only where cycles are


def test_the_bound_is_defined_once_and_used_everywhere(tmp_path: Path) -> None:
    from swarmgen.runtime import engine
    from swarmgen.scxml.emit import emit

    assert engine.STEP_BOUND is STEP_BOUND
    model = _model(tmp_path, "Bound", _loop("5000"))
    validation = pipeline.validate(model)
    assert validation.model is not None
    (document,) = emit(validation.model)
    assert f"$sg.bound = {STEP_BOUND};" in document.text
    out = tmp_path / "out"
    assert_clean(swarmgen("compile", model, "-o", out, cwd=tmp_path, timeout=60), (0,))
    vendored = sorted(out.rglob("_runtime/chart.py"))
    assert len(vendored) == 3  # asyncio, smach, rclpy
    assert all(f"STEP_BOUND = {STEP_BOUND}\n" in p.read_text() for p in vendored)
    assert f"`STEP_BOUND` = {STEP_BOUND}" in (ROOT / "docs" / "semantics.md").read_text()
    defining = [
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "swarmgen").rglob("*.py")
        if re.search(r"^\s*STEP_BOUND\s*=|bound\s*=\s*\d", p.read_text(), re.M)
    ]
    assert defining == ["swarmgen/runtime/chart.py"], defining


_PROBE = """<?xml version="1.0" encoding="UTF-8"?>
<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" datamodel="ecmascript" initial="A">
  <datamodel><data id="seen" expr="''"/></datamodel>
  <script>var $probe = function (e) {
    seen = seen + e.name + " " + e.type + " " + e.origin + " " + e.sendid + ";"; return true; };
  </script>
  <state id="A"><transition event="go" cond="$probe(_event)" target="B"/></state>
  <state id="B">
    <onentry><send event="f" target="#_internal"><param name="x" expr="1"/></send>
      <send event="g" id="after.B.0" delay="0ms"/></onentry>
    <transition event="f" cond="$probe(_event)"/>
    <transition event="g" cond="$probe(_event)" target="C"/>
  </state>
  <state id="C"/>
</scxml>
"""


def test_qt_tells_the_events_a_document_sends_itself(tmp_path: Path, qt_available: None) -> None:
    """What `$sg.tick` relies on: in Qt SCXML an input submitted from outside has no origin, a
    `<send target="#_internal">` (a `raise` with data) has origin `#_internal` and no sendid,
    and a timer (a delayed `<send>` with an id) has its sendid."""
    document = tmp_path / "probe.scxml"
    document.write_text(_PROBE, encoding="utf-8")
    trace = replay.run_qt(document, [GO])
    assert trace[-1]["active"] == ["C"]
    assert trace[-1]["data"]["seen"] == (
        "go external undefined undefined;"
        "f external #_internal undefined;"
        "g external #_internal after.B.0;"
    )


# found by tests/test_generated_equivalence.py: a bounded document (the `*` self-loop) whose
# start takes an eventless transition (the transient initial state that computes `arr`)
_EVENTLESS_AT_START = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s1"
  name="Start"><datamodel><data id="n" expr="0"/><data id="arr" expr="[1, 2, 3]"/></datamodel>
  <state id="s1"><transition event="*" cond="n &lt; 6"><assign location="n" expr="n + 1"/>
  </transition></state>
</scxml>
"""


def test_the_step_bound_raises_nothing_before_the_first_event(
    tmp_path: Path, qt_available: None
) -> None:
    """W3C 5.10: `_event` is bound only when the first event is processed, so an eventless
    cond at the start must not name it (Qt: a ReferenceError, error.execution); `$sg.tick()`
    reads it after `typeof`, and every backend counts no error."""
    document = tmp_path / "start.scxml"
    document.write_text(_EVENTLESS_AT_START, encoding="utf-8")
    steps = [{"event": "a"}]
    traces = {b: replay.replay(document, "Start", steps, b) for b in ("asyncio", "scxml")}
    assert traces["asyncio"] == traces["scxml"]
    assert [r["errors"] for r in traces["scxml"]] == [0, 0]
    assert [r["data"]["n"] for r in traces["scxml"]] == [0, 1]


def test_bounded_document_is_valid_scxml(tmp_path: Path, scxml_schema: Any) -> None:
    from swarmgen.scxml.emit import emit

    validation = pipeline.validate(_model(tmp_path, "Valid", _parallel_twice))
    assert validation.model is not None
    (document,) = emit(validation.model)
    assert "$sg.spin()" in document.text
    root = ElementTree.fromstring(document.text.encode())
    initials = root.findall(".//{http://www.w3.org/2005/07/scxml}initial/*")
    assert initials and all("cond" not in t.attrib for t in initials)  # SCXML allows none
    scxml_schema.validate(document.text)


def test_only_cycle_transitions_are_bounded(tmp_path: Path) -> None:
    validation = pipeline.validate(_model(tmp_path, "Marks", _loop("5000")))
    assert validation.model is not None
    (chart,) = lower(validation.model)
    bounded = {(n.id, t.targets, t.bounded) for n in chart.walk() for t in n.transitions}
    assert bounded == {
        ("Idle", ("A",), False),  # the way into the loop is not counted
        ("A", ("B",), True),
        ("B", ("A",), True),
        ("A", ("Idle",), False),
    }


def _orthogonal_progress(_: ModelKit, m: Machine) -> None:
    """Two regions each moving on eventlessly: a cycle only in a graph that forgets that a
    state must be entered again to take its transition again."""
    left, right = m.composite("P", ["Left", "Right"])
    for region, names in ((left, ("L1", "L2")), (right, ("R1", "R2"))):
        m.initial(names[0], region=region)
        for name in names:
            m.state(name, region=region)
        m.transition(names[0], names[1])
    m.transition("Idle", "P", "go")
    m.transition("P", "Idle", "stop")


def test_valid_models_keep_their_output(tmp_path: Path) -> None:
    """No bounded transition, so no `$sg.spin` and byte-identical output (tests/test_golden.py
    compares the bytes), in the samples and in orthogonal regions that only move forward."""
    models = [*SAMPLE_MODELS, _model(tmp_path, "Forward", _orthogonal_progress)]
    for model in models:
        validation = pipeline.validate(model)
        assert validation.model is not None
        for chart in lower(validation.model):
            assert not [t for n in chart.walk() for t in n.transitions if t.bounded], model
    from swarmgen.scxml.emit import emit

    for model in SAMPLE_MODELS:
        validation = pipeline.validate(model)
        assert validation.model is not None
        assert all("$sg.spin" not in d.text for d in emit(validation.model))


def test_near_livelock_family_runs_alike_in_every_backend(
    tmp_path: Path, qt_available: None
) -> None:
    model = _model(tmp_path, "Near", _loop("5000"))
    validation = pipeline.validate(model)
    assert validation.model is not None
    (chart,) = lower(validation.model)
    scenarios = ScenarioMaker(chart, seed=10).near_livelocks()
    assert scenarios, "the family reaches the loop"
    reference = replay.replay_many(model, "Bot", scenarios, "scxml")
    assert any(r["errors"] > 0 for trace in reference for r in trace)
    for backend in ("asyncio", "smach"):
        assert replay.replay_many(model, "Bot", scenarios, backend) == reference, backend


def test_a_long_junction_chain_is_checked_quickly(tmp_path: Path) -> None:
    """A hostile chart: 1,500 junctions in a guarded ring (no static error, all bounded)."""

    def ring(_: ModelKit, m: Machine) -> None:
        names = [f"J{i}" for i in range(1500)]
        for name in names:
            m.pseudo(name, "junction")
        m.state("Out")
        m.transition("Idle", names[0], "go")
        for here, there in zip(names, [*names[1:], names[0]], strict=True):
            m.transition(here, there, guard="n < 5")
            m.transition(here, "Out", guard="else")

    model = _model(tmp_path, "Ring", ring)
    started = time.perf_counter()
    validation = pipeline.validate(model)
    assert validation.model is not None
    (chart,) = lower(validation.model)
    elapsed = time.perf_counter() - started
    assert elapsed < 2 * LIMIT, elapsed
    assert _livelocks(model) == []
    assert sum(t.bounded for n in chart.walk() for t in n.transitions) >= 1500
