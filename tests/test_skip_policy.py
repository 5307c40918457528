"""The skip policy (tests/skips.py), run on a tiny suite in a subprocess: a bare run skips with
reasons; under SWARMGEN_STRICT_SKIPS=1 (`make test`) only reference-corpus skips are allowed."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, reference_absent
from tests.skips import STRICT_ENV

SUITE = {
    "test_inside.py": """
import pytest

from tests.conftest import reference_absent


def test_corpus():
    pytest.skip(reference_absent())


def test_dependency():
    pytest.importorskip("swarmgen_no_such_module", reason="comes with an extra")


def test_runs():
    assert True
""",
    "test_module_level.py": """
import pytest

pytest.importorskip("swarmgen_no_such_module", reason="comes with an extra")
""",
}


def _run(tmp_path: Path, strict: bool, *selection: str) -> subprocess.CompletedProcess[str]:
    for name, text in SUITE.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    (tmp_path / "pytest.ini").write_text("[pytest]\n", encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k != STRICT_ENV}
    env["PYTHONPATH"] = str(ROOT)
    if strict:
        env[STRICT_ENV] = "1"
    plugins = ["-p", "tests.skips", "-p", "no:cacheprovider", "-c", str(tmp_path / "pytest.ini")]
    return subprocess.run(
        [sys.executable, "-m", "pytest", *plugins, "-rs", *(str(tmp_path / s) for s in selection)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
        check=False,
    )


def test_a_bare_run_skips_and_says_why(tmp_path: Path) -> None:
    done = _run(tmp_path, False, "test_inside.py", "test_module_level.py")
    assert done.returncode == 0, done.stdout
    assert "3 skipped" in done.stdout and "1 passed" in done.stdout
    assert "comes with an extra" in done.stdout and reference_absent() in done.stdout


def test_strict_allows_the_reference_corpus(tmp_path: Path) -> None:
    done = _run(tmp_path, True, "test_inside.py::test_corpus", "test_inside.py::test_runs")
    assert done.returncode == 0, done.stdout


@pytest.mark.parametrize("case", ["test_inside.py::test_dependency", "test_module_level.py"])
def test_strict_fails_a_dependency_skip(tmp_path: Path, case: str) -> None:
    done = _run(tmp_path, True, case, "test_inside.py::test_runs")
    assert done.returncode == 1, done.stdout
    assert f"{STRICT_ENV}=1: skipped for a reason other than the reference corpus" in done.stdout
    assert case in done.stdout and "comes with an extra" in done.stdout
