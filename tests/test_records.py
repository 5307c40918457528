"""Dataclasses with precompiled methods (swarmgen/records.py, swarmgen/_records/)."""

from __future__ import annotations

import dataclasses
import importlib
import os
import pickle
import subprocess
import sys
import types
from pathlib import Path

import pytest

from swarmgen import records
from swarmgen.outtree import Manifest
from swarmgen.span import Span
from tests.conftest import ROOT


def test_modules_are_current(tmp_path: Path) -> None:
    """Every module that uses `records.dataclass` has its `_records/` module, holding the
    methods its dataclasses make now (run `make records` when this fails)."""
    subprocess.run(
        [sys.executable, "-m", "swarmgen.records", str(tmp_path)],
        cwd=ROOT,
        check=True,
        capture_output=True,
        timeout=120,
    )
    built = sorted(p.name for p in tmp_path.glob("*.py"))
    assert sorted(p.name for p in records.DIRECTORY.glob("*.py")) == built
    assert len(built) > 50
    for name in built:
        shipped = (records.DIRECTORY / name).read_text(encoding="utf-8")
        assert shipped == (tmp_path / name).read_text(encoding="utf-8"), (
            f"{name} is stale: run `make records`"
        )


def _normalised(code: types.CodeType) -> types.CodeType:
    """`code` without where it was compiled (file, lines), nested code objects too."""
    consts = tuple(_normalised(c) if isinstance(c, types.CodeType) else c for c in code.co_consts)
    return code.replace(
        co_filename="", co_firstlineno=1, co_linetable=b"", co_exceptiontable=b"", co_consts=consts
    )


def _entries() -> list[tuple[str, str, types.CodeType]]:
    found = []
    for path in sorted(records.DIRECTORY.glob("*.py")):
        if path.stem != "__init__":
            module = importlib.import_module(f"{records.PACKAGE}.{path.stem}")
            found += [(path.stem, text, code) for text, code in module.FUNCTIONS.items()]
    return found


def test_each_function_is_its_text_compiled() -> None:
    """A function is found by its text, so it must be what compiling that text gives."""
    entries = _entries()
    assert len(entries) > 500
    for stem, text, code in entries:
        compiled = compile(text, "<string>", "exec", dont_inherit=True)  # as dataclasses
        (made,) = [c for c in compiled.co_consts if isinstance(c, types.CodeType)]
        assert _normalised(code) == _normalised(made), (stem, text)


def check_precompiled() -> None:
    """Span's and Manifest's methods come from `_records/` (run in a fresh process that keeps
    bytecode: `test_precompiled_in_a_process_that_keeps_bytecode`)."""
    for method in ("__init__", "__repr__", "__eq__", "__hash__", "__setattr__", "__delattr__"):
        attribute = getattr(Span, method)
        assert attribute.__qualname__ == f"Span.{method}"
        function = getattr(attribute, "__wrapped__", attribute)  # __repr__: recursion guard
        assert function.__code__.co_filename == str(records.DIRECTORY / "span.py"), method
        assert function.__globals__ is vars(sys.modules["swarmgen.span"]), method
    assert Manifest.__init__.__code__.co_filename == str(records.DIRECTORY / "outtree.py")


def _run(code: str, env: dict[str, str]) -> None:
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr


def test_precompiled_in_a_process_that_keeps_bytecode(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(tmp_path)
    checks = "check_precompiled(); behaves_as_the_standard_dataclass(); default_factories()"
    for _ in range(2):  # writing the bytecode, then reading it
        _run(f"from tests.test_records import *; {checks}", env)


@pytest.mark.parametrize("unwritable", [False, True])
def test_compiled_where_bytecode_is_neither_kept_nor_there(
    tmp_path: Path, unwritable: bool
) -> None:
    """With PYTHONDONTWRITEBYTECODE, or where `.pyc` cannot be written, and none there, a
    `_records/` module would be compiled from source on every run: the methods are compiled one
    by one as dataclasses does instead."""
    if unwritable:  # the cache prefix lies under a regular file: no directory can be made there
        (tmp_path / "file").write_text("")
        env = dict(os.environ, PYTHONPYCACHEPREFIX=str(tmp_path / "file" / "pyc"))
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    else:
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", PYTHONPYCACHEPREFIX=str(tmp_path))
    code = (
        "import sys; from swarmgen.span import Span; from swarmgen import records\n"
        "assert Span.__init__.__code__.co_filename == '<string>'\n"
        "assert not any(m.startswith(records.PACKAGE + '.') for m in sys.modules)"
    )
    _run(code, env)


@dataclasses.dataclass(frozen=True, slots=True)
class _PlainSpan:
    """Span's fields, made by the standard library alone."""

    file: str
    line: int = 0
    col: int = 0
    xmi_id: str | None = None
    path: str = ""


def behaves_as_the_standard_dataclass() -> None:
    """Span (a `records.dataclass`) against the same class made by `dataclasses` alone."""
    span = Span("m.xmi", 3, 4, "id1", "a/b")
    plain = _PlainSpan("m.xmi", 3, 4, "id1", "a/b")
    assert repr(span) == repr(plain).replace("_PlainSpan", "Span")
    assert [f.name for f in dataclasses.fields(Span)] == [f.name for f in dataclasses.fields(plain)]
    assert Span.__match_args__ == _PlainSpan.__match_args__
    assert Span.__slots__ == _PlainSpan.__slots__
    assert dataclasses.asdict(span) == dataclasses.asdict(plain)
    assert span == Span("m.xmi", 3, 4, "id1", "a/b") and span != Span("m.xmi")
    assert span.__eq__(plain) is NotImplemented
    assert hash(span) == hash(plain) == hash(("m.xmi", 3, 4, "id1", "a/b"))
    assert dataclasses.replace(span, line=9) == Span("m.xmi", 9, 4, "id1", "a/b")
    assert Span("f") == Span("f", 0, 0, None, "")
    assert pickle.loads(pickle.dumps(span)) == span
    with pytest.raises(dataclasses.FrozenInstanceError):
        span.line = 1  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        del span.line  # type: ignore[misc]
    with pytest.raises(TypeError):
        Span()  # type: ignore[call-arg]
    match span:
        case Span(file, line):
            assert (file, line) == ("m.xmi", 3)


def default_factories() -> None:
    """A default factory makes a new value for each instance."""
    first, second = Manifest("compile", "m.xmi", {}), Manifest("compile", "m.xmi", {})
    assert first.pending == second.pending == {} and first.pending is not second.pending
    assert Manifest("graph", "s", {}, {"a": "b"}).pending == {"a": "b"}


def test_it_behaves_as_the_standard_dataclass() -> None:
    """In this process (precompiled or not, as its bytecode settings make it)."""
    behaves_as_the_standard_dataclass()
    default_factories()


def test_a_class_not_in_records_is_compiled_as_before() -> None:
    @records.dataclass(frozen=True)
    class Local:
        """Not in any `_records/` module."""

        name: str
        size: int = 1

    assert Local("x") == Local("x", 1) and repr(Local("x")).endswith(".Local(name='x', size=1)")
    assert Local.__init__.__code__.co_filename == "<string>"


def test_the_standard_library_is_left_as_it_was() -> None:
    with pytest.raises(TypeError, match="non-default argument"):

        @records.dataclass
        class Broken:
            """A field without a default after one with."""

            a: int = 0
            b: str  # type: ignore[misc]

    assert dataclasses._create_fn is records._CREATE_FN  # type: ignore[attr-defined]


def test_the_command_line_process_precompiles_every_covered_dataclass(tmp_path: Path) -> None:
    """`install` (the console entry point's): the vendored runtime's and pydantic's dataclasses,
    whose modules do not use `records.dataclass`, take their methods from `_records/` too."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(tmp_path)
    code = (
        "from swarmgen import records; records.install()\n"
        "import annotated_types, swarmgen.runtime.faults as faults\n"
        "from swarmgen.span import Span\n"
        "for cls in (annotated_types.Gt, faults.Partition, Span):\n"
        "    path = cls.__init__.__code__.co_filename\n"
        "    assert path.startswith(str(records.DIRECTORY)), (cls, path)\n"
        "assert annotated_types.Gt(1) == annotated_types.Gt(1) and repr(annotated_types.Gt(1))"
        " == 'Gt(gt=1)'\n"
    )
    for _ in range(2):  # writing the bytecode, then reading it
        _run(code, env)


def test_only_swarmgen_and_the_pinned_packages_are_covered() -> None:
    assert records.covered("swarmgen.chart.model") and records.covered("pydantic.fields")
    assert records.covered("annotated_types")
    assert not records.covered("jinja2.nodes") and not records.covered("swarmgen")
    assert records.record_module("swarmgen.chart.model") == "swarmgen._records.chart__model"
    assert records.record_module("pydantic.fields") == "swarmgen._records.ext__pydantic__fields"
