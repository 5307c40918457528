"""The generated Python is black-stable without black on the compile path: black (pinned, the
project's mode) leaves every generated .py file unchanged, over generated/ and over the trees of
random models, and `pyformat` formatted every statement itself (no fallback to black); its quick
paths (lines copied or read without the tokenizer) print what the tokenized path prints."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import black
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from swarmgen import pipeline
from swarmgen.backends import pyassign, pyformat, pylayout, pyrender
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


# --- pylayout: statements laid out from their parts, against black

_WORDS = st.text("abcXYZ_ .-/'", min_size=0, max_size=24)
_NAMES = st.from_regex(r"[a-z_][a-z0-9_]{0,14}", fullmatch=True).filter(
    lambda n: not n.startswith("__") and n not in {"if", "in", "is", "or", "as", "for", "and"}
)
_ATOMS = st.one_of(
    _WORDS.map(repr),
    _NAMES,
    st.integers(-5000, 10**9).map(repr),
    st.lists(_WORDS, max_size=4).map(lambda items: repr(tuple(items))),
    st.lists(_WORDS, max_size=3).map(repr),
    st.booleans().map(repr),
    st.text("abc d", min_size=50, max_size=110).map(repr),  # one token too long to fit
)


def _args(node: st.SearchStrategy[pylayout.Node]) -> st.SearchStrategy[list[pylayout.Arg]]:
    keyword = st.builds(pylayout.Kw, _NAMES.map(lambda n: f"{n}="), node)
    return st.lists(st.one_of(node, keyword), max_size=5)


def _nodes(inner: st.SearchStrategy[pylayout.Node]) -> st.SearchStrategy[pylayout.Node]:
    callee = st.lists(_NAMES, min_size=1, max_size=2).map(".".join)
    entry = st.builds(pylayout.Kw, _WORDS.map(lambda w: f"{w!r}: "), inner)
    return st.one_of(
        st.builds(lambda c, a: pylayout.Call(c, tuple(a)), callee, _args(inner)),
        st.builds(lambda a: pylayout.Seq("[", tuple(a)), st.lists(inner, max_size=5)),
        st.builds(lambda a: pylayout.Seq("{", tuple(a)), st.lists(entry, min_size=1, max_size=5)),
    )


_NODES = st.recursive(_ATOMS, _nodes, max_leaves=8)
_CALLS = st.builds(
    lambda c, a: pylayout.Call(c, tuple(a)),
    st.lists(_NAMES, min_size=1, max_size=3).map(".".join),
    _args(_NODES),
)


@settings(max_examples=300, deadline=None)
@given(call=_CALLS, depth=st.integers(0, 3))
def test_layout_prints_what_black_prints(call: pylayout.Call, depth: int) -> None:
    # the statement inside `depth` real blocks, so black sees its true indentation
    blocks = "".join(f"{'    ' * level}if x:\n" for level in range(depth))
    source = blocks + "    " * depth + pylayout.flat(call) + "\n"
    expected = black.format_str(source, mode=black_mode())
    lines = pylayout.layout(call, depth)
    if lines is None:  # a form not reproduced (triple quotes, an atom too long): pyformat's
        event("not laid out")
        return
    event(f"{min(len(lines), 6)} lines")
    assert blocks + "\n".join(lines) + "\n" == expected
    # pyformat copies the recorded lines and prints what its tokenized path prints
    text = pylayout.statement(depth, call.callee, call.args)
    laid = blocks + "    " * depth + text + "\n"
    assert laid == expected
    assert pyformat.format_source(laid, pyrender.black_statement) == expected
    assert pyformat.format_source(laid, pyrender.black_statement, quick=False) == expected


# --- pyassign: long one-line assignments and returns read back into nodes, against black

_TUPLES = st.builds(lambda a: pylayout.Seq("(", tuple(a)), st.lists(_NODES, min_size=2, max_size=5))
_VALUES = st.one_of(_CALLS, _TUPLES, _NODES.filter(lambda n: not isinstance(n, str)))
_TARGETS = st.one_of(
    st.just("return "),
    st.builds(
        lambda name, annotation: f"{name}{annotation} = ",
        st.lists(_NAMES, min_size=1, max_size=2).map(".".join),
        st.sampled_from(
            [
                "",
                ": int",
                ": dict[str, Any]",
                ": tuple[Parameter, ...]",
                ": dict[str, tuple[str, x.Y]]",
            ]
        ),
    ),
)


_CALLEE = "_0000000._00000000000000"
# fits in 100 columns only without its trailing comma, which black then reads as magic
_MAGIC = pylayout.Seq(
    "(",
    (
        pylayout.Call(_CALLEE, ("-1000",)),
        pylayout.Call(
            _CALLEE, (pylayout.Kw("_0000=", "'XXXXXX'"), pylayout.Kw("_0000000=", "'XXXX'"))
        ),
    ),
)


@settings(max_examples=300, deadline=None)
@given(target=_TARGETS, value=_VALUES, depth=st.integers(0, 3), trailing=st.booleans())
@example(target="return ", value=_MAGIC, depth=0, trailing=True)
def test_long_assignments_print_what_black_prints(
    target: str, value: pylayout.Node, depth: int, trailing: bool
) -> None:
    blocks = "".join(f"{'    ' * level}if x:\n" for level in range(depth))
    text = pylayout.flat(value)
    if trailing and isinstance(value, pylayout.Seq) and value.items:
        text = text[:-1] + ", " + text[-1]  # as the templates print PARAMETERS
    line = "    " * depth + target + text
    source = blocks + line + "\n"
    lines = pyassign.layout_line(line)
    if lines is None:  # short, or a form not read (pyformat's tokenized path prints it)
        event("not laid out" if len(line) > pylayout.LINE_LENGTH else "fits")
        return
    event(f"{min(len(lines), 6)} lines")
    expected = black.format_str(source, mode=black_mode())
    assert blocks + "\n".join(lines) + "\n" == expected
    assert pyformat.format_source(source, pyrender.black_statement) == expected


@settings(max_examples=300, deadline=None)
@given(text=st.text(st.characters(min_codepoint=32, max_codepoint=126), max_size=90))
def test_one_line_docstrings_copied_as_black_prints_them(text: str) -> None:
    line = f'    """{text}"""'
    copied = pyformat.quick_line(line)
    if copied is None:  # quotes, a backslash or a space at an end: the tokenized path
        event("tokenized")
        return
    event("copied")
    source = f"def f():\n{line}\n"
    assert "def f():\n" + copied + "\n" == black.format_str(source, mode=black_mode())
