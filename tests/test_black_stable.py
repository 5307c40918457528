"""The generated Python is black-stable without black on the compile path: black (pinned, the
project's mode) leaves every generated .py file unchanged, over generated/ and over the trees of
random models, and `pyformat` formatted every statement itself (no fallback to black); its quick
paths (lines copied or read without the tokenizer) print what the tokenized path prints."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import black
import pytest
from hypothesis import HealthCheck, given, settings

from swarmgen import pipeline
from swarmgen.backends import pyformat, pyrender
from swarmgen.backends.pyrender import black_mode
from tests.conftest import ROOT
from tests.modelkit import ModelKit
from tests.test_robustness import models

RUNTIME_DIRS = {"_runtime", "_ros"}  # copied runtime sources, not rendered by format_python


def _unstable(files: dict[str, str]) -> list[str]:
    mode = black_mode()
    return [name for name, text in files.items() if black.format_str(text, mode=mode) != text]


def test_generated_tree_is_black_stable() -> None:
    files = {
        str(path): path.read_text(encoding="utf-8")
        for path in sorted((ROOT / "generated").rglob("*.py"))
        if not RUNTIME_DIRS & set(path.parts)
    }
    assert len(files) > 20
    assert _unstable(files) == []


def test_sample_models_need_no_fallback() -> None:
    before = pyformat.STATS.fallbacks
    for model in sorted((ROOT / "sample_models").glob("*/*.xmi")):
        compiled = pipeline.compile_model(model)
        assert any(p.suffix == ".py" for p in compiled.files)
    assert pyformat.STATS.fallbacks == before, pyformat.STATS.samples[-5:]


@settings(
    max_examples=6,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(kit=models())
def test_random_models_are_black_stable(kit: ModelKit, tmp_path: Path) -> None:
    path = tmp_path / "random.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    before = pyformat.STATS.fallbacks
    compiled = pipeline.compile_model(path)
    files = {
        str(p): text
        for p, text in compiled.files.items()
        if p.suffix == ".py" and not RUNTIME_DIRS & set(p.parts)
    }
    assert files
    assert _unstable(files) == []
    assert pyformat.STATS.fallbacks == before, pyformat.STATS.samples[-5:]


def test_quick_paths_print_what_the_tokenizer_path_prints(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    # every source a compile formats (the real formatter runs; its inputs are kept), formatted
    # again with every statement through one tokenizer
    sources: list[str] = []
    real = pyformat.format_source

    def keep(source: str, fallback: Callable[[str, int], str], quick: bool = True) -> str:
        sources.append(source)
        return real(source, fallback, quick)

    monkeypatch.setattr(pyformat, "format_source", keep)
    pyrender.format_python.cache_clear()
    for model in sorted((ROOT / "sample_models").glob("*/*.xmi")):
        pipeline.compile_model(model)
    pyrender.format_python.cache_clear()
    assert len(sources) > 20
    for source in sources:
        expected = real(source, pyrender.black_statement, quick=False)
        assert real(source, pyrender.black_statement) == expected
