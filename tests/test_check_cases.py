"""Check cases as paste-in fixture pairs: `swarmgen validate NAME.xmi` must print NAME.expected.

Each pair in tests/check_cases/ is a model and the exact text `swarmgen validate` prints for it
(format: tests/check_cases/README.md). The command runs in process through click's CliRunner, in
the cases' directory, so the file names printed do not depend on the checkout. On a mismatch the
test shows a unified diff; `pytest tests/test_check_cases.py --update-golden` rewrites the
.expected files from today's output (review `git diff tests/check_cases` before committing).
"""

from __future__ import annotations

import difflib

import pytest
from click.testing import CliRunner

from swarmgen.cli import main
from tests.conftest import ROOT

CASES = ROOT / "tests" / "check_cases"
UPDATE_COMMAND = ".venv/bin/pytest tests/test_check_cases.py --update-golden"
NAMES = sorted(p.stem for p in CASES.glob("*.xmi"))


def render(exit_code: int, stdout: str, stderr: str) -> str:
    """The .expected text: the exit code, then stdout, then stderr (README.md)."""
    return f"# exit: {exit_code}\n{stdout}# stderr:\n{stderr}"


def validate(name: str, monkeypatch: pytest.MonkeyPatch) -> str:
    """What `swarmgen validate NAME.xmi`, run in the cases' directory, prints and returns."""
    monkeypatch.chdir(CASES)  # the model is named as a user types it: no checkout path in output
    result = CliRunner().invoke(main, ["validate", f"{name}.xmi"])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a crash is a bug, not an expected output
    return render(result.exit_code, result.stdout, result.stderr)


@pytest.mark.parametrize("name", NAMES)
def test_check_case(name: str, monkeypatch: pytest.MonkeyPatch, update_golden: bool) -> None:
    produced = validate(name, monkeypatch)
    expected_file = CASES / f"{name}.expected"
    if update_golden:
        expected_file.write_text(produced, encoding="utf-8")
        return
    assert expected_file.is_file(), f"no {expected_file.name}; create it with: {UPDATE_COMMAND}"
    expected = expected_file.read_text(encoding="utf-8")
    if produced != expected:
        diff = "".join(
            difflib.unified_diff(
                expected.splitlines(keepends=True),
                produced.splitlines(keepends=True),
                fromfile=f"check_cases/{name}.expected",
                tofile=f"swarmgen validate {name}.xmi",
            )
        )
        pytest.fail(
            f"{diff}\nThe output differs from {expected_file.name}; if intended: {UPDATE_COMMAND}",
            pytrace=False,  # the diff is the report; the runner's own code is noise
        )


def test_every_case_is_a_pair() -> None:
    models = {p.stem for p in CASES.glob("*.xmi")}
    expected = {p.stem for p in CASES.glob("*.expected")}
    assert not models - expected, f"models without .expected: {sorted(models - expected)}"
    assert not expected - models, f".expected without a model: {sorted(expected - models)}"
    assert len(models) >= 30, f"only {len(models)} check cases"
