"""The rules of docs/semantics.md, each on a minimal model, in every replay backend (asyncio,
smach and the emitted SCXML in Qt SCXML): outputs written before guards, the value rule, and
errors in guards and effects (error.execution, guard false, counted in the trace)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from swarmgen import replay
from tests.modelkit import ModelKit

BACKENDS = ("asyncio", "smach", "scxml")


def _write(tmp_path: Path, kit: ModelKit) -> Path:
    path = tmp_path / f"{kit.name}.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def _traces(model: Path, steps: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    traces = {b: replay.replay(model, "Bot", steps, b) for b in BACKENDS}
    reference = traces["scxml"]
    for backend, trace in traces.items():
        assert trace == reference, f"{backend} differs from Qt SCXML:\n{trace}\n{reference}"
    return traces


def _guarded_outputs(tmp_path: Path) -> Path:
    kit = ModelKit("Guarded")
    kit.behaviour("Patrol", outputs={"fire_intensity": "Real", "fire_id": "Integer"})
    kit.event("go", sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Patrolling", do="Patrol")
    machine.state("Hot")
    machine.state("Cold")
    machine.transition("Idle", "Patrolling", "go")
    machine.transition("Patrolling", "Hot", "succeeded", guard="fire_intensity > 0.5")
    machine.transition("Patrolling", "Cold", "succeeded", guard="fire_intensity <= 0.5")
    machine.transition("Patrolling", "Idle", "aborted", guard="fire_id > 100")
    machine.transition("Hot", "Idle", "go")
    machine.transition("Cold", "Idle", "go")
    kit.member(
        "Bot", machine, data={"fire_intensity": ("Real", None), "fire_id": ("Integer", None)}
    )
    kit.swarm("Swarm", {"Bot": 1})
    return _write(tmp_path, kit)


@pytest.mark.parametrize(("intensity", "target"), [(0.9, "Hot"), (0.2, "Cold"), (0.5, "Cold")])
def test_guards_see_the_outputs_of_the_outcome(
    tmp_path: Path, intensity: float, target: str, qt_available: None
) -> None:
    model = _guarded_outputs(tmp_path)
    steps: list[dict[str, Any]] = [
        {"event": "go"},
        {"complete": "Patrol", "outputs": {"fire_intensity": intensity, "fire_id": 4}},
    ]
    trace = _traces(model, steps)["asyncio"]
    assert trace[2]["active"] == [target]
    assert trace[2]["data"] == {"fire_id": 4, "fire_intensity": intensity}


def test_outputs_are_written_when_no_transition_takes_the_outcome(
    tmp_path: Path, qt_available: None
) -> None:
    """`aborted` is guarded `fire_id > 100`: not taken, but the outputs are written, and the
    output the behaviour did not give becomes its zero (as a ROS result holds it)."""
    model = _guarded_outputs(tmp_path)
    steps: list[dict[str, Any]] = [
        {"event": "go"},
        {"complete": "Patrol", "outcome": "aborted", "outputs": {"fire_id": 7}},
        {"complete": "Patrol", "outcome": "aborted", "outputs": {"fire_intensity": 0.3}},
        {"complete": "Patrol", "outcome": "aborted", "outputs": {"fire_id": 101}},
    ]
    trace = _traces(model, steps)["asyncio"]
    assert [r["active"] for r in trace] == [["Idle"], ["Patrolling"], ["Patrolling"], ["Patrolling"], ["Idle"]]  # fmt: skip
    assert trace[2]["data"] == {"fire_id": 7, "fire_intensity": 0}
    assert trace[3]["data"] == {"fire_id": 0, "fire_intensity": 0.3}
    assert trace[4]["data"] == {"fire_id": 101, "fire_intensity": 0}


def _values_and_errors(tmp_path: Path) -> Path:
    kit = ModelKit("Values")
    kit.event("go", sender="station")
    kit.event("measure", {"level": "Real", "divisor": "Integer"}, sender="station")
    kit.event("lowBattery", {"level": "Real", "where": "String"}, scope="local")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.state("Low")
    machine.state("Ok")
    machine.state("Broken")
    # never-written data without defaults: their zeros, in every backend
    machine.transition("Idle", "Low", "go", guard='battery < 20.0 and label == "" and not flag')
    machine.transition(
        "Low", "Ok", "measure", guard="10 / event.divisor > 1", effect="count = count + 1"
    )
    machine.transition("Low", "Broken", "measure", guard="event.level >= 50.0")
    machine.transition("Ok", "Ok", "go", effect="raise lowBattery(level = battery)")
    machine.transition(
        "Ok", "Broken", "lowBattery", guard='event.level < 20.0 and event.where == ""'
    )
    machine.transition("Broken", "Idle", "go", effect='count = count / 0\nlabel = "never"')
    kit.member(
        "Bot",
        machine,
        data={
            "battery": ("Real", None),
            "label": ("String", None),
            "flag": ("Boolean", None),
            "count": ("Integer", None),
            "pose": ("Pose", None),
        },
    )
    kit.swarm("Swarm", {"Bot": 1})
    return _write(tmp_path, kit)


def test_unset_data_and_fields_hold_zeros_and_errors_count(
    tmp_path: Path, qt_available: None
) -> None:
    model = _values_and_errors(tmp_path)
    steps: list[dict[str, Any]] = [
        {"event": "go"},  # battery 0.0 < 20, label "", flag false: Low
        {"event": "measure", "data": {"divisor": 0}},  # 10 / 0: error, guard false; level 0.0
        {"event": "measure", "data": {"divisor": 5, "level": 60.0}},  # 10 / 5 > 1: Ok
        {"event": "go"},  # raise lowBattery(level = 0.0), where omitted: "" -> Broken
        {"event": "go"},  # count / 0: error, the rest of the effect is skipped -> Idle
    ]
    trace = _traces(model, steps)["asyncio"]
    assert [r["active"] for r in trace] == [["Idle"], ["Low"], ["Low"], ["Ok"], ["Broken"], ["Idle"]]  # fmt: skip
    assert [r["errors"] for r in trace] == [0, 0, 1, 1, 1, 2]
    assert trace[0]["data"] == {
        "battery": 0,
        "count": 0,
        "flag": False,
        "label": "",
        "pose": {"x": 0, "y": 0},
    }
    assert trace[3]["data"]["count"] == 1
    assert trace[5]["data"]["label"] == ""
