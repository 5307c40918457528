"""One function per command, wiring the stages: load -> build -> check -> emit -> write.

Nothing below this module prints or writes files. The CLI and the tests both call these.
"""

from __future__ import annotations

import difflib
import gc
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from swarmgen import __version__, check, graph
from swarmgen import diagnostics as dg
from swarmgen.backends import registry
from swarmgen.chart.lower import lower
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend import load
from swarmgen.ir.build import build
from swarmgen.ir.nodes import Model
from swarmgen.render import render
from swarmgen.scxml.emit import ScxmlDocument, serialize

MANIFEST = ".swarmgen.json"
Files = dict[PurePosixPath, str]


@dataclass(frozen=True)
class Validation:
    model: Model | None
    diagnostics: list[Diagnostic]

    @property
    def exit_code(self) -> dg.ExitCode:
        return dg.exit_code_for(self.diagnostics)


@dataclass(frozen=True)
class Compilation:
    validation: Validation
    files: Files  # relative path -> text; empty when the model has errors


@contextmanager
def _few_collections() -> Iterator[None]:
    """Run with a rare cyclic GC: a model is millions of long-lived objects and next to no garbage,
    so the default thresholds only re-scan a growing heap (40% of the time at 10,000 states).
    mypy raises its thresholds for the same reason. Restored afterwards."""
    before = gc.get_threshold()
    gc.set_threshold(200_000, 30, 30)
    try:
        yield
    finally:
        gc.set_threshold(*before)


def validate(path: Path) -> Validation:
    """Load, build and check one model; stops after the first stage that reports errors."""
    with _few_collections():
        return _validate(path)


def _validate(path: Path) -> Validation:
    raw, found = load(path)
    if raw is None or dg.has_errors(found):
        return Validation(None, dg.normalise(found))
    model, built = build(raw)
    found += built
    if not dg.has_errors(found):
        found += check.run(model)
    return Validation(model, dg.normalise(found))


def compile_model(path: Path, backends: Sequence[str] | None = None) -> Compilation:
    """Validate, then render SCXML and the backends (all, or those named)."""
    with _few_collections():
        return _compile(path, backends)


def _compile(path: Path, backends: Sequence[str] | None) -> Compilation:
    validation = _validate(path)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        return Compilation(validation, {})
    files: Files = {}
    charts = lower(validation.model)
    documents = tuple(serialize(chart) for chart in charts)
    for document in documents:
        files[PurePosixPath("scxml", f"{document.name}.scxml")] = document.text
    for name, backend in registry().items():
        if backends is None or name in backends:
            for relative, text in backend.render(validation.model, charts).items():
                files[PurePosixPath(name) / relative] = text
    if backends is None or "diagrams" in backends:
        for relative, text in graph.files(validation.model, "mermaid").items():
            files[PurePosixPath("diagrams") / relative] = text
    files[PurePosixPath("README.md")] = _output_readme(validation.model, path, documents)
    files[PurePosixPath(MANIFEST)] = _manifest(path, files)
    return Compilation(validation, files)


def graph_model(path: Path, fmt: str = "mermaid", member: str | None = None) -> Compilation:
    """Validate, then draw every machine and the swarm composition (`swarmgen.graph`) in `fmt`,
    with a manifest so that the next run may replace the directory. Raises graph.GraphError for
    an unknown member type or a missing Graphviz."""
    with _few_collections():
        validation = _validate(path)
        if validation.model is None or dg.has_errors(validation.diagnostics):
            return Compilation(validation, {})
        files = graph.files(validation.model, fmt, member)
        files[PurePosixPath(MANIFEST)] = _manifest(path, files)
        return Compilation(validation, files)


def _md(text: str) -> str:
    """Model names inside a Markdown table: no pipes, backticks or line breaks."""
    return " ".join(text.replace("|", "/").replace("`", "'").split())


def _output_readme(model: Model, source: Path, documents: tuple[ScxmlDocument, ...]) -> str:
    swarms = [
        {
            "name": _md(s.name),
            "members": [{"count": p.count, "type": _md(p.type_name)} for p in s.members],
        }
        for s in model.swarms
    ]
    rows = [
        {
            "path": f"scxml/{d.name}.scxml",
            "member": _md(d.member or "-"),
            "machine": _md(d.machine),
            "states": d.states,
            "transitions": d.transitions,
        }
        for d in documents
    ]
    return render(
        "common/README.md.j2",
        version=__version__,
        source=_md(source.name),
        model=_md(model.name),
        swarms=swarms,
        documents=rows,
    )


def _manifest(source: Path, files: Mapping[PurePosixPath, str]) -> str:
    digests = {str(p): hashlib.sha256(t.encode()).hexdigest() for p, t in sorted(files.items())}
    payload = {
        "generator": "swarmgen",
        "version": __version__,
        "source": source.name,
        "files": digests,
    }
    return json.dumps(payload, indent=2, sort_keys=True) + "\n"


class OutputError(Exception):
    """The output directory cannot be written safely."""


def write_tree(files: Files, out_dir: Path) -> None:
    """Replace `out_dir` with exactly `files`, atomically: a temporary sibling, then renames.

    A directory we did not create (no manifest) is never replaced, so `-o .` cannot wipe a
    project; paths are checked to stay inside the output directory.
    """
    out_dir = out_dir.absolute()
    _check_replaceable(out_dir)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
    try:
        for relative, text in sorted(files.items()):
            target = (staging / relative).resolve()
            if not target.is_relative_to(staging.resolve()):
                raise OutputError(f"refusing to write outside the output directory: {relative}")
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(text.encode("utf-8"))
        _swap(staging, out_dir)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def _check_replaceable(out_dir: Path) -> None:
    if not out_dir.exists():
        return
    if not out_dir.is_dir():
        raise OutputError(f"{out_dir} exists and is not a directory")
    if any(out_dir.iterdir()) and not (out_dir / MANIFEST).is_file():
        raise OutputError(
            f"{out_dir} is not empty and was not written by swarmgen (no {MANIFEST}); "
            "choose an empty or new directory"
        )


def _swap(staging: Path, out_dir: Path) -> None:
    if not out_dir.exists():
        os.replace(staging, out_dir)
        return
    retired = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.old.", dir=out_dir.parent))
    os.replace(out_dir, retired / "tree")
    os.replace(staging, out_dir)
    shutil.rmtree(retired, ignore_errors=True)


def diff_tree(files: Files, out_dir: Path) -> str:
    """Unified diff between what would be generated and what `out_dir` holds ('' if equal)."""
    on_disk: dict[PurePosixPath, str] = {}
    if out_dir.is_dir():
        for path in sorted(out_dir.rglob("*")):
            if path.is_file():
                on_disk[PurePosixPath(path.relative_to(out_dir).as_posix())] = path.read_text(
                    encoding="utf-8", errors="replace"
                )
    chunks: list[str] = []
    for relative in sorted(set(files) | set(on_disk)):
        old, new = on_disk.get(relative), files.get(relative)
        if old == new:
            continue
        chunks.extend(
            difflib.unified_diff(
                (old or "").splitlines(keepends=True),
                (new or "").splitlines(keepends=True),
                fromfile=f"a/{relative}" if old is not None else "/dev/null",
                tofile=f"b/{relative}" if new is not None else "/dev/null",
            )
        )
    return "".join(chunks)


def ir_schema() -> str:
    """The IR's JSON Schema, deterministic (sorted keys)."""
    schema = Model.model_json_schema()
    schema["$id"] = "urn:swarmgen:ir:schema"
    schema["title"] = f"swarmgen IR (swarmgen {__version__.split('.')[0]}.x)"
    return json.dumps(schema, indent=2, sort_keys=True, ensure_ascii=False) + "\n"
