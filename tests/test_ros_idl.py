"""The rosidl definition reader and the interface index: every installed definition parses,
syntax errors are located data, search order and shadowing, the bundled copy, hostile files."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from swarmgen.ros.idl import IdlError, InterfaceDef, parse
from swarmgen.ros.idl_index import BUNDLED, InterfaceIndex, Root, default_roots

SHARE = Path(sys.prefix) / "share"
KINDS = ("msg", "srv", "action")


def _definitions(root: Path) -> list[Path]:
    return sorted(
        p for kind in KINDS for p in root.glob(f"*/{kind}/*.{kind}") if p.parent.name == kind
    )


def _parse(path: Path) -> InterfaceDef | IdlError:
    kind = path.suffix[1:]
    return parse(
        path.read_text(), package=path.parent.parent.name, name=path.stem, kind=kind,  # type: ignore[arg-type]
        file=str(path),
    )  # fmt: skip


def test_every_bundled_definition_parses() -> None:
    files = _definitions(BUNDLED)
    assert len(files) == 110  # the 8 standard packages of Kilted
    assert [str(r) for r in map(_parse, files) if isinstance(r, IdlError)] == []


@pytest.mark.skipif(not (SHARE / "std_msgs").is_dir(), reason="ROS 2 wheels not installed")
def test_every_installed_definition_parses_and_the_bundled_copy_is_equal() -> None:
    files = _definitions(SHARE)
    assert len(files) >= 110
    assert [str(r) for r in map(_parse, files) if isinstance(r, IdlError)] == []
    for bundled in _definitions(BUNDLED):
        installed = SHARE / bundled.relative_to(BUNDLED)
        assert installed.read_bytes() == bundled.read_bytes(), installed


def test_sections_fields_constants_defaults_arrays() -> None:
    text = (
        '# file comment\nint8 LOW=-1  # a constant\nstring<=8 NAME="x"\n'
        "float64[3] v\nint32[<=4] few 1\nstring<=10[] names\nHeader h\n"
        "geometry_msgs/Pose p\nbool flag true\n---\nbool success\n"
    )
    d = parse(text, package="pkg", name="Thing", kind="srv", file="T.srv")
    assert isinstance(d, InterfaceDef)
    request, response = d.sections
    assert [c.name for c in request.constants] == ["LOW", "NAME"]
    v, few, names, h, p, flag = request.fields
    assert (v.array, v.bound, v.bounded) == (True, 3, False)
    assert (few.bound, few.bounded, few.default) == (4, True, "1")
    assert names.type.string_bound == 10 and names.array and names.bound is None
    assert h.type.key == "pkg/msg/Header"  # ROS 2: `Header` is the definition's own package
    assert p.type.key == "geometry_msgs/msg/Pose" and p.line == 8
    assert flag.default == "true" and response.field("success") is not None


@pytest.mark.parametrize(
    ("text", "kind", "line", "col", "words"),
    [
        ("floatt x\n", "msg", 1, 1, "unknown type"),
        ("int32 Bad\n", "msg", 1, 7, "lower snake case"),
        ("int32[0] x\n", "msg", 1, 7, "array bound"),
        ("int32[<=x] x\n", "msg", 1, 7, "array bound"),
        ("string<=0 x\n", "msg", 1, 1, "string bound"),
        ("int32 x\n---\nint32 y\n", "msg", 2, 1, "exactly 0"),
        ("a\n---\nb\n", "srv", 1, 1, "TYPE NAME"),
        ("int32 x\n---\n---\n---\n", "action", 4, 1, "exactly 2"),
        ("int32 x\n", "srv", 1, 1, "exactly 1"),
        ("int8 x 300\n", "msg", 1, 8, "out of range"),
        ("int8 lower=1\n", "msg", 1, 6, "UPPER_CASE"),
        ("int32 x\nint32 x\n", "msg", 2, 7, "twice"),
        ("pkg/Bad_Name x\n", "msg", 1, 1, "unknown type"),
    ],
)
def test_syntax_errors_are_located(text: str, kind: str, line: int, col: int, words: str) -> None:
    result = parse(text, package="pkg", name="T", kind=kind, file="T." + kind)  # type: ignore[arg-type]
    assert isinstance(result, IdlError), result
    assert (result.line, result.col) == (line, col) and words in result.error


def _write(root: Path, rel: str, text: str) -> Path:
    path = root / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_search_order_first_wins_and_differences_are_reported(tmp_path: Path) -> None:
    first, second = tmp_path / "a", tmp_path / "b"
    _write(first, "p/msg/M.msg", "int32 x\n")
    _write(second, "p/msg/M.msg", "int64 x\n")
    _write(second, "p/msg/Same.msg", "int32 x\n")
    _write(first, "p/msg/Same.msg", "int32 x   \n")
    index = InterfaceIndex([Root(first, "user"), Root(second, "user")])
    res = index.resolve("p", "msg", "M")
    assert res.root is not None and res.root.sections[0].fields[0].type.name == "int32"
    assert res.shadowed == (
        ("p/msg/M", str(first / "p/msg/M.msg"), (str(second / "p/msg/M.msg"),)),
    )
    assert index.resolve("p", "msg", "Same").shadowed == ()  # equal up to trailing space
    assert index.resolve("p", "msg", "M") is res  # memoised


def test_default_roots_order(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    model = tmp_path / "m.xmi"
    (tmp_path / "interfaces").mkdir()
    monkeypatch.setenv("AMENT_PREFIX_PATH", os.pathsep.join([str(tmp_path / "ws"), ""]))
    roots = default_roots([tmp_path / "user"], model)
    assert [(r.path, r.origin) for r in roots] == [
        (tmp_path / "ws" / "share", "installed"),
        (Path(sys.prefix) / "share", "installed"),
        (tmp_path / "user", "user"),
        (tmp_path / "interfaces", "user"),
        (BUNDLED, "bundled"),
    ]


def test_nested_resolution_unknown_and_recursive(tmp_path: Path) -> None:
    _write(tmp_path, "p/msg/A.msg", "B b\n")
    _write(tmp_path, "p/msg/B.msg", "# c\nA[] back\n")
    _write(tmp_path, "p/msg/C.msg", "int32 x\nq/Missing m\n")
    _write(tmp_path, "p/action/Go.action", "geometry_msgs/PoseStamped target\n---\n---\n")
    index = InterfaceIndex([Root(tmp_path, "user"), Root(BUNDLED, "bundled")])
    recursive = index.resolve("p", "msg", "A").problem
    assert recursive is not None and recursive.kind == "recursive"
    assert (Path(recursive.file).name, recursive.line, recursive.col) == ("B.msg", 2, 1)
    assert recursive.error == "p/msg/A -> p/msg/B -> p/msg/A"
    missing = index.resolve("p", "msg", "C").problem
    assert missing is not None and (missing.kind, missing.type, missing.line) == (
        "missing",
        "q/msg/Missing",
        2,
    )
    go = index.resolve("p", "action", "Go")
    assert go.problem is None
    assert {"geometry_msgs/msg/Pose", "std_msgs/msg/Header", "builtin_interfaces/msg/Time"} <= set(
        go.definitions
    )


def test_hostile_files_are_diagnostics(tmp_path: Path) -> None:
    _write(tmp_path, "p/msg/Huge.msg", "int32 x\n" * 200_000)
    (tmp_path / "p/msg/Bin.msg").write_bytes(b"\xff\xfe\x00int32 x")
    (tmp_path / "p/msg/Nul.msg").write_bytes(b"int32 x\x00\n")
    _write(tmp_path, "p/msg/Many.msg", "# x\n" * 20_000)
    (tmp_path / "p/msg/Loop.msg").symlink_to(tmp_path / "p/msg/Loop.msg")
    os.mkfifo(tmp_path / "p/msg/Fifo.msg")
    for i in range(40):  # deeper than MAX_DEPTH
        _write(tmp_path, f"p/msg/D{i}.msg", f"D{i + 1} next\n")
    _write(tmp_path, "p/msg/D40.msg", "int32 x\n")
    index = InterfaceIndex([Root(tmp_path, "user")])
    kinds = {}
    for name in ("Huge", "Bin", "Nul", "Many", "Loop", "Fifo", "D0"):
        res = index.resolve("p", "msg", name)
        assert res.problem is not None, name
        kinds[name] = res.problem.kind
    assert kinds == {
        "Huge": "syntax", "Bin": "syntax", "Nul": "syntax", "Many": "syntax",
        "Loop": "missing", "Fifo": "missing", "D0": "too-deep",
    }  # fmt: skip
