"""`swarmgen validate A B ...` as linters do: every model's diagnostics, the worst exit code
(2 unreadable > 1 model errors > 0), one JSON document and one SARIF run for all of them; and
the CLI's one user-error handler (a graph error's message printed as it is, others one line)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from swarmgen import diagnostics as dg
from swarmgen import pipeline
from swarmgen.cli import main
from swarmgen.commands import common
from swarmgen.errors import SwarmgenError
from swarmgen.graph import GraphError, GraphvizError
from tests.conftest import ROOT, SAMPLE_MODELS

BAD = ROOT / "tests" / "fixtures" / "bad"
BROKEN = BAD / "guard_syntax.xmi"  # a model error: exit 1
NOT_XML = BAD / "not_xml.xmi"  # an input error: exit 2


def _validate(*args: str | Path) -> Result:
    return CliRunner().invoke(main, ["validate", *map(str, args)])


def _summaries(result: Result) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.startswith("swarmgen: ")]


def test_sample_models_and_a_broken_one_in_one_call() -> None:
    result = _validate(*SAMPLE_MODELS, BROKEN)
    assert result.exit_code == 1, result.output
    findings = [line for line in result.stdout.splitlines() if ": error: " in line]
    assert findings and all(line.startswith(str(BROKEN)) for line in findings)
    assert "[SG107]" in result.stdout
    shown = [*map(str, SAMPLE_MODELS), str(BROKEN)]
    assert _summaries(result) == [
        *(f"swarmgen: {m}: 0 error(s), 0 warning(s)" for m in shown[:-1]),
        f"swarmgen: {BROKEN}: 1 error(s), 0 warning(s)",
        f"swarmgen: {len(shown)} models: 1 error(s), 0 warning(s)",
    ]


def test_text_is_each_model_as_validated_alone() -> None:
    models = [*SAMPLE_MODELS, BROKEN, NOT_XML]
    together = _validate(*models)
    alone = [_validate(m) for m in models]
    assert together.stdout == "".join(r.stdout for r in alone)
    assert _summaries(together)[:-1] == [line for r in alone for line in _summaries(r)]


def test_one_unreadable_path_among_good_ones(tmp_path: Path) -> None:
    missing = tmp_path / "missing.xmi"
    result = _validate(SAMPLE_MODELS[0], missing, SAMPLE_MODELS[-1])
    assert result.exit_code == 2, result.output
    assert f"{missing}: error: no such file [SG001]" in result.stdout
    assert len(_summaries(result)) == 4  # the good models after it are still checked
    assert f"swarmgen: {SAMPLE_MODELS[-1]}: 0 error(s), 0 warning(s)" in _summaries(result)


@pytest.mark.parametrize(
    ("models", "code"),
    [
        ([*SAMPLE_MODELS], 0),
        ([*SAMPLE_MODELS, BROKEN], 1),
        ([BROKEN, *SAMPLE_MODELS], 1),
        ([SAMPLE_MODELS[0], BROKEN, NOT_XML], 2),
        ([NOT_XML, BROKEN, SAMPLE_MODELS[0]], 2),
        ([NOT_XML, NOT_XML], 2),
    ],
    ids=["clean", "errors-last", "errors-first", "unreadable-last", "unreadable-first", "twice"],
)
def test_exit_code_is_the_worst(models: list[Path], code: int) -> None:
    assert _validate(*models).exit_code == code


def test_no_model_is_misuse() -> None:
    result = _validate()
    assert result.exit_code == 2 and "Missing argument 'MODEL...'" in result.stderr


def test_strict_and_disable_apply_to_every_model() -> None:
    assert _validate(*SAMPLE_MODELS, BROKEN, "--disable", "SG107").exit_code == 0
    assert _validate(BROKEN, *SAMPLE_MODELS, "--disable", "SG999").exit_code == 2


def test_json_for_one_model_is_unchanged() -> None:
    result = _validate(BROKEN, "--format", "json")
    assert result.exit_code == 1
    assert result.stdout == dg.render_json(pipeline.validate(BROKEN).diagnostics)
    assert set(json.loads(result.stdout)) == {"diagnostics", "summary"}


def test_json_for_several_models(tmp_path: Path) -> None:
    missing = tmp_path / "missing.xmi"
    models = [*SAMPLE_MODELS, BROKEN, missing]
    result = _validate(*models, "--format", "json")
    assert result.exit_code == 2
    payload = json.loads(result.stdout)
    assert list(payload) == ["diagnostics", "summary", "models"]
    alone = [json.loads(_validate(m, "--format", "json").stdout) for m in models]
    assert payload["diagnostics"] == [d for one in alone for d in one["diagnostics"]]
    assert payload["summary"] == {"errors": 2, "warnings": 0}
    assert payload["models"] == [
        *({"file": str(m), "errors": 0, "warnings": 0, "exit_code": 0} for m in SAMPLE_MODELS),
        {"file": str(BROKEN), "errors": 1, "warnings": 0, "exit_code": 1},
        {"file": str(missing), "errors": 1, "warnings": 0, "exit_code": 2},
    ]
    files = {entry["file"] for entry in payload["models"]}
    assert {d["file"] for d in payload["diagnostics"]} == {str(BROKEN), str(missing)} <= files


def test_sarif_is_one_run_over_every_model(tmp_path: Path) -> None:
    missing = tmp_path / "missing.xmi"
    result = _validate(*SAMPLE_MODELS, BROKEN, missing, "--format", "sarif")
    assert result.exit_code == 2
    log = json.loads(result.stdout)
    (run,) = log["runs"]
    rules = [rule["id"] for rule in run["tool"]["driver"]["rules"]]
    assert rules == ["SG001", "SG107"]
    assert [r["ruleId"] for r in run["results"]] == ["SG107", "SG001"]  # in argument order
    for item in run["results"]:
        assert rules[item["ruleIndex"]] == item["ruleId"]
    uris = [
        r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in run["results"]
    ]
    assert uris[0].endswith("guard_syntax.xmi") and uris[1].endswith("missing.xmi")


def test_graph_errors_pass_the_one_handler_verbatim() -> None:
    """The graph command's errors have no except block of their own: the handler prints their
    message as it is (a line break stays), every other user error as one escaped line."""
    assert issubclass(GraphvizError, GraphError) and GraphError.verbatim
    sar = ROOT / "sample_models" / "sar" / "sar.xmi"
    result = CliRunner().invoke(main, ["graph", str(sar), "--member", "Ro\nver"])
    assert result.exit_code == 2 and result.stdout == ""
    assert result.stderr == "swarmgen: error: no member type 'Ro\nver'; choose one of: UAV, UGV\n"


def test_other_user_errors_are_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    class Refused(SwarmgenError):
        exit_code = 2

    with pytest.raises(SystemExit) as done:
        common.report(Refused("first\nsecond\x1b[31m"))
    assert done.value.code == 2
    assert capsys.readouterr().err == "swarmgen: error: first second\\x1b[31m\n"
