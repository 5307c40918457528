"""Every analysis check on a minimal model that has the bug (positive) and on the same model
without it (negative). The sample models must be free of all diagnostics."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from swarmgen import pipeline
from swarmgen.diagnostics import Diagnostic
from tests.conftest import SAMPLE_MODELS
from tests.modelkit import Machine, ModelKit


def base(
    change: Callable[[ModelKit, Machine], None] | None = None,
) -> ModelKit:
    """A small, clean swarm: UAVs cover an area and land on abort."""
    kit = ModelKit("Mini")
    kit.hardware("Camera", "Sensor")
    kit.hardware("DownCam", "Sensor", generals=["Camera"], params={"fov": ("Real", 1.0)})
    kit.hardware("Flight", "Controller")
    kit.behaviour("TakeOff", "HardwareFunction", inputs={"altitude": "Real"}, requires=["Flight"])
    kit.behaviour("Coverage", outputs={"target": "Integer"}, requires=["Camera"])
    kit.behaviour("Land", "HardwareFunction", inputs={"target": "Integer"}, requires=["Flight"])
    kit.event("launch", sender="station")
    kit.event("missionAbort", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Up", do="TakeOff")
    m.state("Cover", do="Coverage")
    m.state("Down", do="Land")
    m.final("Done")
    m.transition("Idle", "Up", "launch")
    m.transition("Up", "Cover", "succeeded")
    m.transition("Up", "Down", "aborted")
    m.transition("Cover", "Down", "missionAbort")
    m.transition("Down", "Done")
    if change is not None:
        change(kit, m)
    kit.member(
        "UAV",
        machine=m,
        parts={"cam": "DownCam", "fc": "Flight"},
        data={"altitude": ("Real", 1.5), "target": ("Integer", 0), "level": ("Integer", 0)}
        | getattr(kit, "extra_data", {}),
    )
    kit.swarm("Swarm", {"UAV": 2})
    return kit


def diagnostics(kit: ModelKit, tmp_path: Path) -> list[Diagnostic]:
    path = tmp_path / "model.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return pipeline.validate(path).diagnostics


def codes(kit: ModelKit, tmp_path: Path) -> list[str]:
    return [d.code.id for d in diagnostics(kit, tmp_path)]


def test_base_model_is_clean(tmp_path: Path) -> None:
    assert diagnostics(base(), tmp_path) == []


@pytest.mark.parametrize("model", SAMPLE_MODELS, ids=[m.parent.name for m in SAMPLE_MODELS])
def test_sample_models_have_no_diagnostics(model: Path) -> None:
    found = pipeline.validate(model).diagnostics
    assert found == [], pipeline.dg.render_text(found)


def t(m: Machine, source: str, target: str) -> Any:
    return next(x for x in m.transitions if x.source == source and x.target == target)


def _unreachable(kit: ModelKit, m: Machine) -> None:
    m.state("Orphan", do="Coverage")
    m.transition("Orphan", "Down", "missionAbort")


def _no_way_out(kit: ModelKit, m: Machine) -> None:
    m.state("Stuck")
    m.transition("Idle", "Stuck", "missionAbort")


def _never_ends(kit: ModelKit, m: Machine) -> None:
    m.transitions[-1] = type(m.transitions[-1])("Down", "Idle", ())


def _unguarded_twins(kit: ModelKit, m: Machine) -> None:
    m.transition("Idle", "Down", "launch")


def _overlapping_guards(kit: ModelKit, m: Machine) -> None:
    t(m, "Idle", "Up").guard = "level < 20"
    m.transition("Idle", "Down", "launch", guard="level > 10")


def _exclusive_guards(kit: ModelKit, m: Machine) -> None:
    t(m, "Idle", "Up").guard = "level < 20"
    m.transition("Idle", "Down", "launch", guard="level >= 20")


def _unhandled_outcome(kit: ModelKit, m: Machine) -> None:
    t(m, "Up", "Down").triggers = ("preempted",)  # Up handles succeeded, no longer aborted


def _never_sent(kit: ModelKit, m: Machine) -> None:
    kit.event("targetFound", {"id": "Integer"})
    m.transition("Cover", "Down", "targetFound")


def _sent_by_behaviour(kit: ModelKit, m: Machine) -> None:
    _never_sent(kit, m)
    kit.behaviours["Coverage"]["emits"] = ["targetFound"]


def _never_handled(kit: ModelKit, m: Machine) -> None:
    kit.event("alarm", {"level": "Integer"})
    t(m, "Up", "Cover").effect = "send alarm(level = 2)"


def _type_error(kit: ModelKit, m: Machine) -> None:
    kit.event("launch", {"pose": "Pose"}, sender="station")
    t(m, "Idle", "Up").guard = "event.pose > altitude"


def _type_error_assign(kit: ModelKit, m: Machine) -> None:
    kit.event("launch", {"pose": "Pose"}, sender="station")
    t(m, "Idle", "Up").effect = "altitude = event.pose"


def _type_ok(kit: ModelKit, m: Machine) -> None:
    kit.event("launch", {"pose": "Pose"}, sender="station")
    t(m, "Idle", "Up").guard = "event.pose.x > altitude and level + 1 >= 2"


def _missing_capability(kit: ModelKit, m: Machine) -> None:
    kit.hardware("Lidar", "Sensor")
    kit.behaviour("Mapping", requires=["Lidar"])
    m.state("Map", do="Mapping")
    m.transition("Cover", "Map", "launch")
    m.transition("Map", "Down", "missionAbort")


def _missing_parameter(kit: ModelKit, m: Machine) -> None:
    kit.behaviours["Coverage"]["inputs"] = {"sweep_width": "Real"}


def _parameter_from_hardware(kit: ModelKit, m: Machine) -> None:
    kit.behaviours["Coverage"]["inputs"] = {"fov": "Real"}


def _input_maybe_unset(kit: ModelKit, m: Machine) -> None:
    # `spot` is member data without a default, set on the way Cover -> Down only
    kit.behaviours["Land"]["inputs"] = {"target": "Integer", "spot": "Integer"}
    kit.extra_data = {"spot": ("Integer", None)}  # type: ignore[attr-defined]
    t(m, "Cover", "Down").effect = "spot = 3"


def _input_always_set(kit: ModelKit, m: Machine) -> None:
    _input_maybe_unset(kit, m)
    t(m, "Up", "Down").effect = "spot = 4"


def _output_unused(kit: ModelKit, m: Machine) -> None:
    kit.behaviours["Land"]["inputs"] = {}


CASES: list[tuple[str, Callable[[ModelKit, Machine], None], str | None]] = [
    ("unreachable", _unreachable, "SG201"),
    ("no-way-out", _no_way_out, "SG202"),
    ("never-ends", _never_ends, "SG203"),
    ("unguarded-twins", _unguarded_twins, "SG204"),
    ("overlapping-guards", _overlapping_guards, "SG204"),
    ("exclusive-guards", _exclusive_guards, None),
    ("unhandled-outcome", _unhandled_outcome, "SG205"),
    ("never-sent", _never_sent, "SG206"),
    ("sent-by-behaviour", _sent_by_behaviour, None),
    ("never-handled", _never_handled, "SG207"),
    ("type-error-compare", _type_error, "SG208"),
    ("type-error-assign", _type_error_assign, "SG208"),
    ("types-ok", _type_ok, None),
    ("missing-capability", _missing_capability, "SG211"),
    ("missing-parameter", _missing_parameter, "SG212"),
    ("parameter-from-hardware", _parameter_from_hardware, None),
    ("input-maybe-unset", _input_maybe_unset, "SG209"),
    ("input-always-set", _input_always_set, None),
    ("output-unused", _output_unused, "SG210"),
]


def test_unset_input_path(tmp_path: Path) -> None:
    (diag,) = [d for d in diagnostics(base(_input_maybe_unset), tmp_path) if d.code.id == "SG209"]
    assert "'spot'" in diag.message
    assert diag.notes == (
        "a path that never assigns it: Idle -> [launch] -> Up -> [outcome.Up.aborted] -> Down",
    )


@pytest.mark.parametrize(("change", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_check(
    change: Callable[[ModelKit, Machine], None], expected: str | None, tmp_path: Path
) -> None:
    found = codes(base(change), tmp_path)
    if expected is None:
        assert found == []
    else:
        assert expected in found, found


def test_capability_message_names_state_member_and_hardware(tmp_path: Path) -> None:
    (diag,) = [d for d in diagnostics(base(_missing_capability), tmp_path) if d.code.id == "SG211"]
    assert (
        diag.message
        == "state 'Map' of 'UAV' runs 'Mapping', which requires Lidar; 'UAV' has no Lidar"
    )
    assert diag.span.line > 0 and diag.hint


def test_generalisation_satisfies_requirement(tmp_path: Path) -> None:
    """DownCam specialises Camera: Coverage (requires Camera) runs on the UAV."""
    kit = base()
    assert "Camera" not in kit.members["UAV"][1].values()
    assert codes(kit, tmp_path) == []


def test_nondeterminism_witness(tmp_path: Path) -> None:
    (diag,) = [d for d in diagnostics(base(_overlapping_guards), tmp_path) if d.code.id == "SG204"]
    witness = next(n for n in diag.notes if n.startswith("both guards hold when"))
    value = float(witness.split("level = ")[1])
    assert 10 < value < 20


def test_swarm_count_below_one(tmp_path: Path) -> None:
    kit = base()
    kit.swarm("Swarm", {"UAV": 0})
    assert "SG214" in codes(kit, tmp_path)


def test_ros_name_collision(tmp_path: Path) -> None:
    kit = base()
    kit.behaviour("take_off", "HardwareFunction", requires=["Flight"])
    assert "SG215" in codes(kit, tmp_path)
