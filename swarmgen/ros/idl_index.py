"""Where interface definitions are found, and the resolution of a type with its nested types.

Search order (docs/ros2.md, "Declared interface types"): the packages installed in the
environment (`share/` of every `AMENT_PREFIX_PATH` entry, then of `sys.prefix`), then the user's
directories (`--interfaces DIR`, in order, then `interfaces/` beside the model), then the copy
of the Kilted standard definitions bundled with swarmgen. Every root has the layout
`<root>/<pkg>/<msg|srv|action>/<Name>.<kind>`. The first definition found wins; one that differs
in a later root is reported. Only the exact path of a wanted type is ever looked at (no
directory walks), so symlink loops and huge trees elsewhere cost nothing.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Sequence
from dataclasses import field
from pathlib import Path
from typing import Literal

from swarmgen.inputs import InputRefused, read_limited
from swarmgen.records import dataclass
from swarmgen.ros.idl import Field, IdlError, InterfaceDef, Kind, parse

Origin = Literal["installed", "user", "bundled"]
BUNDLED = Path(__file__).resolve().parent / "standard_interfaces"
MAX_FILE = 1 << 20  # 1 MiB: the largest standard definition is under 20 KiB
MAX_DEPTH = 32  # nesting of message types; the standard ones nest at most 6 deep


@dataclass(frozen=True)
class Root:
    """A directory holding `<pkg>/<kind>/<Name>.<kind>` files, and where it comes from."""

    path: Path
    origin: Origin


@dataclass(frozen=True)
class Loaded:
    """The definition of one type as found first, and the later files that define it otherwise."""

    definition: InterfaceDef | IdlError | None  # None: found nowhere
    origin: Origin | None = None
    differs: tuple[str, ...] = ()  # later definitions with another text
    text: str = ""  # the definition's text as read (what a generated interface package copies)
    user_copy: bool = False  # a later user directory has the same text (it is built there)


@dataclass(frozen=True)
class Problem:
    """Why a type does not resolve: `missing`, `syntax`, `recursive` or `too-deep`, located at
    the definition line that refers to the failing type (or at the broken file)."""

    kind: Literal["missing", "syntax", "recursive", "too-deep"]
    type: str  # `pkg/kind/Name` of the type that failed
    file: str = ""
    line: int = 0
    col: int = 0
    error: str = ""
    quote: str = ""  # the definition line that refers to it


@dataclass(frozen=True)
class Resolution:
    """A type and every message it nests (by `pkg/msg/Name`), or why it does not resolve."""

    root: InterfaceDef | None
    definitions: dict[str, InterfaceDef] = field(default_factory=dict)
    problem: Problem | None = None
    shadowed: tuple[tuple[str, str, tuple[str, ...]], ...] = ()  # (type, used file, others)


def environment_roots(environ: dict[str, str] | None = None) -> list[Root]:
    """The `share/` directories of the installed interface packages, in search order."""
    env = os.environ if environ is None else environ
    prefixes = [p for p in env.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    prefixes.append(sys.prefix)
    roots: list[Root] = []
    for prefix in prefixes:
        share = Path(prefix) / "share"
        if share not in [r.path for r in roots]:
            roots.append(Root(share, "installed"))
    return roots


def default_roots(user: Iterable[Path] = (), model: Path | None = None) -> list[Root]:
    """Installed, then `user` directories, then `interfaces/` beside `model`, then bundled."""
    roots = environment_roots()
    roots += [Root(Path(d), "user") for d in user]
    if model is not None and (model.parent / "interfaces").is_dir():
        roots.append(Root(model.parent / "interfaces", "user"))
    roots.append(Root(BUNDLED, "bundled"))
    return roots


class InterfaceIndex:
    """Definitions by type over an ordered list of roots; reads and parses lazily, memoised."""

    def __init__(self, roots: Sequence[Root]) -> None:
        self.roots = tuple(roots)
        self._loaded: dict[tuple[str, Kind, str], Loaded] = {}
        self._resolved: dict[str, Resolution] = {}

    def load(self, package: str, kind: Kind, name: str) -> Loaded:
        """The first definition of `package/kind/name` in the roots (memoised)."""
        key = (package, kind, name)
        if key not in self._loaded:
            self._loaded[key] = self._find(package, kind, name)
        return self._loaded[key]

    def _find(self, package: str, kind: Kind, name: str) -> Loaded:
        found: list[tuple[Root, Path, bytes | str]] = []
        for root in self.roots:
            path = root.path / package / kind / f"{name}.{kind}"
            try:
                if not path.is_file():
                    continue
                found.append((root, path, read_limited(path, MAX_FILE)))
            except (InputRefused, OSError) as err:
                found.append((root, path, str(err)))
        if not found:
            return Loaded(None)
        root, path, content = found[0]
        definition = _parse(content, package, kind, name, path)
        differs = tuple(str(p) for _, p, other in found[1:] if _normal(other) != _normal(content))
        parsed = isinstance(content, bytes) and not isinstance(definition, IdlError)
        text = content.decode("utf-8") if parsed and isinstance(content, bytes) else ""
        copy = any(r.origin == "user" and _normal(o) == _normal(content) for r, _, o in found[1:])
        return Loaded(definition, root.origin, differs, text, copy)

    def resolve(self, package: str, kind: Kind, name: str) -> Resolution:
        """`package/kind/name` with every nested message, depth first (memoised)."""
        key = f"{package}/{kind}/{name}"
        if key not in self._resolved:
            self._resolved[key] = self._resolve(package, kind, name)
        return self._resolved[key]

    def _resolve(self, package: str, kind: Kind, name: str) -> Resolution:
        key = f"{package}/{kind}/{name}"
        loaded = self.load(package, kind, name)
        if loaded.definition is None:
            return Resolution(None, problem=Problem("missing", key))
        if isinstance(loaded.definition, IdlError):
            return Resolution(None, problem=_syntax(key, loaded.definition))
        walk = _Walk(self)
        walk.shadow(key, loaded)
        walk.visit(loaded.definition, (key,))
        return Resolution(loaded.definition, walk.definitions, walk.problem, tuple(walk.shadowed))


class _Walk:
    """A depth-first walk over nested message types, stopping at the first problem."""

    def __init__(self, index: InterfaceIndex) -> None:
        self.index = index
        self.definitions: dict[str, InterfaceDef] = {}
        self.problem: Problem | None = None
        self.shadowed: list[tuple[str, str, tuple[str, ...]]] = []

    def shadow(self, key: str, loaded: Loaded) -> None:
        if loaded.differs and isinstance(loaded.definition, InterfaceDef):
            self.shadowed.append((key, loaded.definition.file, loaded.differs))

    def visit(self, definition: InterfaceDef, stack: tuple[str, ...]) -> None:
        self.definitions[definition.key] = definition
        for section in definition.sections:
            for item in section.fields:
                if self.problem is not None:
                    return
                if not item.type.primitive:
                    self._nested(definition, item, stack)

    def _nested(self, parent: InterfaceDef, item: Field, stack: tuple[str, ...]) -> None:
        key = item.type.key
        where = {"file": parent.file, "line": item.line, "quote": item.text}
        col = len(item.text) - len(item.text.lstrip()) + 1  # the type starts the line
        if key in stack:
            chain = " -> ".join((*stack[stack.index(key) :], key))
            self.problem = Problem("recursive", key, col=col, error=chain, **where)  # type: ignore[arg-type]
            return
        if len(stack) >= MAX_DEPTH:
            error = f"more than {MAX_DEPTH} levels"
            self.problem = Problem("too-deep", key, col=col, error=error, **where)  # type: ignore[arg-type]
            return
        if key in self.definitions:
            return
        assert item.type.package is not None
        loaded = self.index.load(item.type.package, "msg", item.type.name)
        if loaded.definition is None:
            self.problem = Problem("missing", key, col=col, **where)  # type: ignore[arg-type]
        elif isinstance(loaded.definition, IdlError):
            self.problem = _syntax(key, loaded.definition)
        else:
            self.shadow(key, loaded)
            self.visit(loaded.definition, (*stack, key))


def _syntax(key: str, error: IdlError) -> Problem:
    return Problem("syntax", key, error.file, error.line, error.col, error.error)


def _parse(
    content: bytes | str, package: str, kind: Kind, name: str, path: Path
) -> InterfaceDef | IdlError:
    if isinstance(content, str):  # could not be read: the reason
        return IdlError(str(path), 0, 0, f"cannot read the definition: {content}")
    try:
        text = content.decode("utf-8")
    except UnicodeDecodeError as err:
        return IdlError(str(path), 0, 0, f"not UTF-8 text (byte {err.start})")
    if "\x00" in text:
        return IdlError(str(path), 0, 0, "not a text file (it contains NUL bytes)")
    return parse(text, package=package, name=name, kind=kind, file=str(path))


def _normal(content: bytes | str) -> bytes | str:
    """Definitions compare equal when they differ only in line endings and trailing space."""
    if isinstance(content, str):
        return content
    return b"\n".join(line.rstrip() for line in content.replace(b"\r\n", b"\n").split(b"\n"))
