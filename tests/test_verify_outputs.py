"""`swarmgen verify`, behaviour outputs from finite domains: the model's defaults, values on each
side of the constants its guards compare the outputs against, and the zero for the rest."""

from __future__ import annotations

from pathlib import Path

from swarmgen.verify import run
from swarmgen.verify.domains import guard_constants
from swarmgen.verify.explore import Budget
from swarmgen.verify.state import thaw
from tests.modelkit import ModelKit
from tests.test_verify import codes, replays_to_the_same_configuration, write
from tests.test_verify_props import finding


def measuring(tmp_path: Path, *properties: str) -> Path:
    """A probe's `level` (Integer) and `ratio` (Real) decide where the member ends: only
    outputs on both sides of the guards' constants reach every final state."""
    kit = ModelKit("Outputs")
    kit.hardware("Probe", "Sensor")
    outputs = {"level": "Integer", "ratio": "Real"}
    kit.behaviour("Measure", "HardwareFunction", requires=["Probe"], outputs=outputs)
    kit.event("launch", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Measuring", do="Measure")
    for name in ("High", "Mid", "Low"):
        m.final(name)
    m.transition("Idle", "Measuring", "launch")
    m.transition("Measuring", "High", "succeeded", guard="level > 3 and ratio < 0.5")
    m.transition("Measuring", "Mid", "succeeded", guard="level > 3 and ratio >= 0.5")
    m.transition("Measuring", "Low", "succeeded", guard="3 >= level")  # the literal on the left
    for outcome in ("aborted", "preempted"):
        m.transition("Measuring", "Measuring", outcome)
    data = {"level": ("Integer", 0), "ratio": ("Real", 0.0)}
    kit.member("UAV", machine=m, parts={"p": "Probe"}, data=data)
    kit.swarm("Swarm", {"UAV": 1})
    for number, text in enumerate(properties, start=1):
        kit.property("Swarm", f"p{number}", text)
    return write(kit, tmp_path, "outputs")


def test_outputs_on_each_side_of_the_guards_reach_every_state(tmp_path: Path) -> None:
    result = run.verify(measuring(tmp_path), Budget())
    # with the zeros alone (phase 2) High and Mid were never entered (SG403)
    assert (result.exit_code, codes(result)) == (run.VERIFIED, [])
    assert result.loaded.system is not None
    ends = result.loaded.system.kinds[0].endings["Measuring"]
    levels = sorted({(thaw(o.outputs) or {}).get("level", 0) for o in ends})
    ratios = sorted({(thaw(o.outputs) or {}).get("ratio", 0.0) for o in ends})
    assert (levels, ratios) == ([0, 2, 3, 4], [-0.5, 0.0, 0.5, 1.5])  # 0, 0.0: the zeros


def test_a_counterexample_gives_the_outputs_it_needs(tmp_path: Path) -> None:
    model = measuring(tmp_path, "never UAV in High")
    result = run.verify(model, Budget())
    assert codes(result) == ["SG407"]
    trace = finding(result, "SG407")
    (end,) = [s for s in trace.scenarios["UAV_1"] if "complete" in s]
    assert end["outcome"] == "succeeded" and end["outputs"]["level"] > 3
    assert end["outputs"].get("ratio", 0.0) < 0.5
    assert result.loaded.system is not None
    replays_to_the_same_configuration(model, result.loaded.system, trace)


def test_constants_are_read_on_either_side_of_a_comparison(tmp_path: Path) -> None:
    result = run.verify(measuring(tmp_path), Budget())
    assert result.loaded.model is not None
    found = guard_constants(result.loaded.model)
    assert found[("data", "level", ())] == {3}
    assert found[("data", "ratio", ())] == {0.5}
