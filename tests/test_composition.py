"""The swarm composition is computed once (`swarmgen.ir.query.composition`): several parts of one
member type (`uavs1: UAV[2]`, `uavs2: UAV[3]`) add up, to 5 UAVs, in every backend, the ROS 2
launch file, `swarmgen simulate` and the composition diagram alike (issue 9, item 3)."""

from __future__ import annotations

import ast
import importlib
import re
import sys
from collections.abc import Iterator
from pathlib import Path, PurePosixPath

import pytest

from swarmgen import diagnostics as dg
from swarmgen import graph, pipeline
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import composition
from swarmgen.sim import scenario as sc
from swarmgen.sim.machines import compile_machines
from swarmgen.sim.sweep import configurations
from tests.modelkit import ModelKit

TWO_PARTS = [("uavs1", "UAV", 2), ("uavs2", "UAV", 3)]


def kit_with(*swarms: list[tuple[str, str, int]]) -> ModelKit:
    """A clean model (no diagnostics): UAVs take off and land; one Swarm class per argument."""
    kit = ModelKit("Twin")
    kit.hardware("Flight", "Controller")
    kit.behaviour("TakeOff", "HardwareFunction", requires=["Flight"])
    kit.event("launch", sender="station")
    for member in ("UAV", "UGV"):
        m = kit.machine(f"{member}Mission")
        m.initial("Idle")
        m.state("Idle")
        m.state("Up", do="TakeOff")
        m.final("Done")
        m.transition("Idle", "Up", "launch")
        m.transition("Up", "Done", "succeeded")
        m.transition("Up", "Done", "aborted")
        kit.member(member, machine=m, parts={"fc": "Flight"})
    for index, parts in enumerate(swarms):
        kit.swarm(f"Swarm{index or ''}", parts)
    return kit


def write(kit: ModelKit, tmp_path: Path) -> Path:
    path = tmp_path / "twin.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def model_of(path: Path) -> Model:
    validation = pipeline.validate(path)
    assert validation.model is not None and validation.diagnostics == []
    return validation.model


@pytest.fixture
def two_parts(tmp_path: Path) -> Path:
    """`uavs1: UAV[2]`, `uavs2: UAV[3]` and `ugvs: UGV[1]` in one Swarm class."""
    return write(kit_with([*TWO_PARTS, ("ugvs", "UGV", 1)]), tmp_path)


@pytest.fixture
def compiled(two_parts: Path) -> dict[PurePosixPath, str]:
    result = pipeline.compile_model(two_parts)
    assert result.files, dg.render_text(result.validation.diagnostics)
    return dict(result.files)


def literal(text: str, name: str) -> object:
    """The value of the module-level assignment to `name` (annotated or not) in `text`."""
    for node in ast.parse(text).body:
        if isinstance(node, ast.AnnAssign | ast.Assign):
            targets = [node.target] if isinstance(node, ast.AnnAssign) else node.targets
            if any(isinstance(t, ast.Name) and t.id == name for t in targets):
                assert node.value is not None
                return ast.literal_eval(node.value)
    raise AssertionError(f"no {name} = ... in the module")


def file_named(files: dict[PurePosixPath, str], pattern: str) -> str:
    (found,) = [text for path, text in files.items() if path.match(pattern)]
    return found


# --- the query


def test_parts_of_one_type_are_summed(two_parts: Path) -> None:
    assert composition(model_of(two_parts)) == {"UAV": 5, "UGV": 1}


def test_several_swarm_classes_are_summed_too(tmp_path: Path) -> None:
    kit = kit_with(TWO_PARTS, [("more", "UAV", 1), ("ugvs", "UGV", 2)])
    assert composition(model_of(write(kit, tmp_path))) == {"UAV": 6, "UGV": 2}


def test_one_part_per_type_is_unchanged(tmp_path: Path) -> None:
    kit = kit_with([("uavs", "UAV", 4), ("ugvs", "UGV", 2)])
    assert list(composition(model_of(write(kit, tmp_path))).items()) == [("UAV", 4), ("UGV", 2)]


# --- the consumers


def test_python_backends_compose_the_sum(compiled: dict[PurePosixPath, str]) -> None:
    for backend in ("asyncio", "smach"):
        init = file_named(compiled, f"{backend}/*/__init__.py")
        assert literal(init, "COMPOSITION") == {"UAV": 5, "UGV": 1}, backend


@pytest.fixture
def asyncio_package(compiled: dict[PurePosixPath, str], tmp_path: Path) -> Iterator[object]:
    """The written asyncio package, imported (and forgotten afterwards)."""
    out = tmp_path / "out"
    pipeline.write_tree(compiled, out)
    (init,) = (out / "asyncio").glob("*/__init__.py")
    name = init.parent.name
    sys.path.insert(0, str(init.parent.parent))
    try:
        yield importlib.import_module(name)
    finally:
        sys.path.remove(str(init.parent.parent))
        for module in [m for m in sys.modules if m == name or m.startswith(f"{name}.")]:
            del sys.modules[module]


def test_asyncio_package_imports_with_the_sum(asyncio_package: object) -> None:
    assert getattr(asyncio_package, "COMPOSITION") == {"UAV": 5, "UGV": 1}  # noqa: B009


def test_rclpy_launch_file_starts_every_member(compiled: dict[PurePosixPath, str]) -> None:
    init = file_named(compiled, "rclpy/*_nodes/*_nodes/__init__.py")
    assert literal(init, "COMPOSITION") == {"UAV": 5, "UGV": 1}  # the launcher's defaults
    launch = file_named(compiled, "rclpy/*/launch/*.launch.py")
    assert literal(launch, "COMPOSITION") == {"UAV": 5, "UGV": 1}
    assert literal(launch, "SWARM") == '{"UAV": 5, "UGV": 1}'
    members = re.findall(r'executable="(\w+)",\s*namespace="(\w+)",\s*name="\1"', launch)
    nodes = [ns for exe, ns in members if exe != "simulated_behaviours"]
    assert nodes == [f"uav_{i}" for i in range(1, 6)] + ["ugv_1"]


def test_simulate_defaults_to_the_sum(two_parts: Path) -> None:
    machines = compile_machines(two_parts)
    assert machines.composition == {"UAV": 5, "UGV": 1}
    configs = configurations(machines, sc.parse({"name": "default counts"}))
    assert [dict(c.counts) for c in configs] == [{"UAV": 5, "UGV": 1}]


def test_diagram_shows_each_part_and_the_total(two_parts: Path) -> None:
    swarm = graph.files(model_of(two_parts), "mermaid")[PurePosixPath("swarm.mmd")]
    assert '|"uavs1 #91;2#93;"|' in swarm and '|"uavs2 #91;3#93;"|' in swarm
    assert "members#58; 5 (2 parts)" in swarm
    assert "members#58; 1" not in swarm  # UGV has one part: its arrow says it all


# --- the checks


def test_an_empty_part_is_still_an_error_beside_others(tmp_path: Path) -> None:
    kit = kit_with([*TWO_PARTS, ("spare", "UAV", 0)])
    found = pipeline.validate(write(kit, tmp_path)).diagnostics
    assert [d.code.id for d in found] == ["SG214"]
    assert found[0].message.startswith("part 'spare' of swarm 'Swarm' has 0 member(s)")
