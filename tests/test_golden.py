"""Golden files: the emitted SCXML of every sample model and every reference XMI file.

On a mismatch the test prints the unified diff and the command that rewrites the goldens;
review `git diff tests/golden` before committing the result.
"""

from __future__ import annotations

import difflib
from pathlib import Path

import pytest

from swarmgen import pipeline
from tests.conftest import ROOT, SAMPLE_MODELS, requires_shared, xmi_sample_files

GOLDEN = ROOT / "tests" / "golden"
INDEX = "documents.txt"  # the documents a model yields (none for a model without a machine)
UPDATE_COMMAND = "make golden  (or: .venv/bin/pytest tests/test_golden.py --update-golden)"


def _cases() -> list[tuple[str, Path]]:
    cases = [(model.parent.name, model) for model in SAMPLE_MODELS]
    cases += [(path.stem, path) for path in xmi_sample_files()]
    return cases


def _emitted(model: Path) -> dict[str, str]:
    result = pipeline.compile_model(model)
    assert result.files, pipeline.dg.render_text(result.validation.diagnostics)  # no errors
    return {p.name: text for p, text in result.files.items() if p.suffix == ".scxml"}


@pytest.mark.parametrize(("case", "model"), _cases(), ids=[c for c, _ in _cases()])
def test_scxml_matches_golden(case: str, model: Path, update_golden: bool) -> None:
    expected_dir = GOLDEN / case
    produced = _emitted(model)
    if update_golden:
        expected_dir.mkdir(parents=True, exist_ok=True)
        for stale in expected_dir.glob("*.scxml"):
            stale.unlink()
        for name, text in produced.items():
            (expected_dir / name).write_text(text, encoding="utf-8")
        (expected_dir / INDEX).write_text(
            "".join(f"{n}\n" for n in sorted(produced)), encoding="utf-8"
        )
        return
    index = expected_dir / INDEX
    assert index.is_file(), f"no golden files for {case}; create them with: {UPDATE_COMMAND}"
    assert index.read_text(encoding="utf-8").split() == sorted(produced), (
        f"documents differ from {index}; if intended: {UPDATE_COMMAND}"
    )
    expected = {p.name: p.read_text(encoding="utf-8") for p in sorted(expected_dir.glob("*.scxml"))}
    problems = []
    for name in sorted(set(expected) | set(produced)):
        diff = "".join(
            difflib.unified_diff(
                expected.get(name, "").splitlines(keepends=True),
                produced.get(name, "").splitlines(keepends=True),
                fromfile=f"golden/{case}/{name}",
                tofile=f"emitted/{case}/{name}",
            )
        )
        if diff:
            problems.append(diff)
    if problems:
        pytest.fail(
            "\n".join(problems)
            + f"\nThe SCXML differs from the golden files; if intended: {UPDATE_COMMAND}"
        )


@requires_shared  # without ../shared the reference files' golden cases have no model here
def test_every_golden_case_has_a_model() -> None:
    known = {case for case, _ in _cases()}
    orphans = sorted(p.name for p in GOLDEN.iterdir() if p.is_dir() and p.name not in known)
    assert not orphans, f"golden directories without a model: {orphans}"
