"""One root for user errors (swarmgen.errors): the CLI maps it to its message and exit code in
one place; the vendored runtime stays independent of it."""

from __future__ import annotations

import ast

import pytest

from swarmgen import console, errors, inputs, jsonfile, outtree, replay
from swarmgen import ros_harness as harness
from swarmgen.graph import GraphError, GraphvizError
from swarmgen.ros import interfaces
from swarmgen.sim import scenario
from swarmgen.trace.bag import TraceError
from tests.conftest import ROOT

USER_ERRORS = [
    console.StreamError,
    console.OutputPathError,
    inputs.InputRefused,
    jsonfile.JsonError,
    outtree.OutputError,
    replay.ReplayError,
    GraphError,
    GraphvizError,
    scenario.ScenarioError,
    scenario.SimulationError,
    TraceError,
    harness.RosUnavailable,
    harness.RosRunError,
    interfaces.InterfaceBuildError,
]


@pytest.mark.parametrize("kind", USER_ERRORS, ids=[k.__name__ for k in USER_ERRORS])
def test_user_errors_share_the_root(kind: type[errors.SwarmgenError]) -> None:
    assert issubclass(kind, errors.SwarmgenError)
    assert kind.exit_code == 2


def test_ros_errors_are_still_runtime_errors() -> None:
    for kind in (harness.RosUnavailable, harness.RosRunError, interfaces.InterfaceBuildError):
        assert issubclass(kind, RuntimeError)


def test_the_vendored_runtime_does_not_import_swarmgen() -> None:
    """swarmgen/runtime and swarmgen/ros/runtime are copied into generated packages."""
    for folder in ("swarmgen/runtime", "swarmgen/ros/runtime"):
        for path in sorted((ROOT / folder).glob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    assert node.module.split(".")[0] != "swarmgen" or ".runtime" in node.module
                    assert node.module != "swarmgen.errors", path
