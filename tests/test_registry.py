"""The output registry as the single list of outputs, the template override, and the chart-level
checks as their own stage after one lowering."""

from __future__ import annotations

from pathlib import Path, PurePosixPath

import pytest

from swarmgen import backends, check, pipeline, replay
from swarmgen import diagnostics as dg
from swarmgen.chart import checks as chart_checks
from swarmgen.chart.lower import lower
from swarmgen.resources import data_dir
from swarmgen.span import Span
from tests.conftest import ROOT, run_cli

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
BAD = ROOT / "tests" / "fixtures" / "bad"
MISSION = ROOT / "sample_models" / "sar" / "scenarios" / "uav_mission.json"
README = PurePosixPath("README.md")


# --- the registry


def test_every_output_is_a_registry_entry_named_by_its_key() -> None:
    outputs = backends.registry()
    assert list(outputs) == backends.names()
    assert backends.names() == ["scxml", "asyncio", "smach", "rclpy", "diagrams"]
    assert all(output.name == name for name, output in outputs.items())


def test_lists_of_outputs_are_derived_from_the_registry() -> None:
    assert tuple(backends.runnable()) == replay.BACKENDS
    assert "diagrams" not in backends.runnable()
    assert backends.names("scxml") == backends.names()[1:]


def test_selection_always_has_scxml() -> None:
    assert backends.selection(None) == backends.names()
    assert backends.selection([]) == ["scxml"]
    assert backends.selection(["scxml"]) == ["scxml"]
    assert backends.selection(["diagrams", "asyncio"]) == ["scxml", "asyncio", "diagrams"]


def test_compile_writes_the_selected_folders_only() -> None:
    files = pipeline.compile_model(SAR, ["diagrams"]).files
    assert {p.parts[0] for p in files} == {"scxml", "diagrams", "README.md", pipeline.MANIFEST}


@pytest.mark.parametrize(
    ("command", "wrong", "suggested"),
    [
        (["compile", str(SAR), "-o", "out"], "asyncoi", "asyncio"),
        (["compile", str(SAR), "-o", "out"], "diagram", "diagrams"),
        (["replay", str(SAR), "--member", "UAV", "--script", str(MISSION)], "smash", "smach"),
    ],
)
def test_an_unknown_backend_is_refused_with_a_suggestion(
    tmp_path: Path, command: list[str], wrong: str, suggested: str
) -> None:
    result = run_cli(*command, "--backend", wrong, cwd=tmp_path)
    assert result.returncode == 2
    assert f"unknown backend '{wrong}'" in result.stderr
    assert f"did you mean '{suggested}'?" in result.stderr
    assert not (tmp_path / "out").exists()


def test_replay_does_not_offer_diagrams(tmp_path: Path) -> None:
    args = ["replay", str(SAR), "--member", "UAV", "--script", str(MISSION)]
    result = run_cli(*args, "--backend", "diagrams", cwd=tmp_path)
    assert result.returncode == 2
    assert "choose from scxml, asyncio, smach, rclpy" in result.stderr


# --- the template override


def _override(tmp_path: Path) -> Path:
    """A template directory replacing one shipped template (the output README's)."""
    shipped = data_dir("templates") / "common" / "README.md.j2"
    directory = tmp_path / "templates"
    (directory / "common").mkdir(parents=True)
    text = shipped.read_text(encoding="utf-8") + "Adapted by the user's templates.\n"
    (directory / "common" / "README.md.j2").write_text(text, encoding="utf-8")
    return directory


def test_overriding_one_template_changes_that_file_only(tmp_path: Path) -> None:
    shipped = pipeline.compile_model(SAR).files
    adapted = pipeline.compile_model(SAR, templates=_override(tmp_path)).files
    assert shipped.keys() == adapted.keys()
    changed = {path for path in shipped if shipped[path] != adapted[path]}
    assert changed == {README, PurePosixPath(pipeline.MANIFEST)}  # the manifest lists digests
    assert adapted[README] == shipped[README] + "Adapted by the user's templates.\n"
    assert pipeline.compile_model(SAR).files == shipped  # the override does not outlive its call


def test_cli_templates_option(tmp_path: Path) -> None:
    directory = _override(tmp_path)
    result = run_cli("compile", str(SAR), "-o", "out", "--templates", str(directory), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    readme = (tmp_path / "out" / "README.md").read_text(encoding="utf-8")
    assert readme.endswith("Adapted by the user's templates.\n")
    missing = run_cli("compile", str(SAR), "-o", "o2", "--templates", "nope", cwd=tmp_path)
    assert missing.returncode == 2
    assert "--templates" in missing.stderr


# --- chart-level checks: one lowering, after the model-level checks passed


def test_validation_keeps_the_charts_it_checked() -> None:
    validation = pipeline.validate(SAR)
    assert validation.model is not None
    assert validation.charts == lower(validation.model)
    found = dg.normalise(chart_checks.run(validation.model, validation.charts))
    data_flow = (dg.INPUT_MAYBE_UNSET, dg.OUTPUT_UNUSED)
    assert found == [d for d in validation.diagnostics if d.code in data_flow]


@pytest.mark.parametrize("model", ["submachine_cycle.xmi", "two_initials.xmi"])
def test_a_model_with_errors_is_not_lowered(model: str, monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(_: object) -> None:
        raise AssertionError("lowered a model with errors")

    monkeypatch.setattr(pipeline, "lower", refuse)
    validation = pipeline.validate(BAD / model)
    assert dg.has_errors(validation.diagnostics)
    assert validation.charts == ()


def test_a_model_too_large_to_inline_is_never_lowered() -> None:
    too_large = dg.diag(dg.MODEL_TOO_LARGE, "too large", Span(file="m.xmi"))
    assert not check.may_lower([too_large])
    as_warning = dg.Diagnostic(too_large.code, "x", too_large.span, severity=dg.Severity.WARNING)
    assert not check.may_lower([as_warning])
    assert check.may_lower([])
