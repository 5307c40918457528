"""One function per command, wiring the stages: load -> build -> check -> emit -> write.

Nothing below this module prints or writes files. The CLI and the tests both call these.
"""

from __future__ import annotations

import gc
import json
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import field, replace
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from swarmgen import __version__, check, outtree
from swarmgen import diagnostics as dg
from swarmgen.chart import checks as chart_checks
from swarmgen.chart.lower import lower
from swarmgen.chart.model import Chart
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend import RawModel, load
from swarmgen.generated import header, markdown_cell
from swarmgen.ir import query
from swarmgen.ir.build import build
from swarmgen.ir.nodes import Model
from swarmgen.records import dataclass
from swarmgen.ros.idl_index import InterfaceIndex, default_roots

if TYPE_CHECKING:
    from swarmgen.scxml.emit import ScxmlDocument

# What only compile and graph use (Jinja2 and the templates, the diagrams) is imported in their
# functions: `validate` loads the stages it runs and no more (docs/performance.md).

MANIFEST = outtree.MANIFEST
OutputError = outtree.OutputError
Files = dict[PurePosixPath, str]


@dataclass(frozen=True)
class Validation:
    """The outcome of validating a model: the IR, its diagnostics and, if clean, its charts."""

    model: Model | None
    diagnostics: list[Diagnostic]
    charts: tuple[Chart, ...] = ()  # the lowered model; empty unless it passed the checks
    # the declared ROS types' definitions the check used (the rclpy backend binds in it)
    interfaces: InterfaceIndex | None = field(default=None, compare=False, repr=False)

    @property
    def exit_code(self) -> dg.ExitCode:
        """The CLI exit status the diagnostics call for."""
        return dg.exit_code_for(self.diagnostics)


@dataclass(frozen=True)
class Compilation:
    """A validation and the files it produced for the selected backends."""

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


def validate(path: Path, interfaces: Sequence[Path] = ()) -> Validation:
    """Load, build, check, lower and check the charts of one model; stops after the first
    stage that reports errors (so compile and validate report the same diagnostics). Declared
    ROS types resolve in the installed packages, `interfaces` (directories), `interfaces/`
    beside the model, then swarmgen's bundled standard definitions (`ros.idl_index`)."""
    with _few_collections():
        return _validate(path, interfaces)


def interface_index(path: Path, interfaces: Sequence[Path] = ()) -> InterfaceIndex:
    """The interface definitions the model at `path` is checked against (read lazily)."""
    return InterfaceIndex(default_roots(interfaces, path))


def _validate(path: Path, interfaces: Sequence[Path] = ()) -> Validation:
    raw, found = load(path)
    return _validate_loaded(path, raw, found, interfaces)


def _validate_loaded(
    path: Path, raw: RawModel | None, found: list[Diagnostic], interfaces: Sequence[Path]
) -> Validation:
    if raw is None or dg.has_errors(found):
        return Validation(None, dg.normalise(found))
    model, built = build(raw)
    found += built
    if dg.has_errors(found):
        return Validation(model, dg.normalise(found))
    index = interface_index(path, interfaces)
    found += check.run(model, index)
    children = query.sessions(model)  # invoked documents: checked as models of their own
    for child in children:
        found += check.run(child, index)
    if not check.may_lower(found):
        return Validation(model, dg.normalise(found), interfaces=index)
    charts = lower(model)
    found += chart_checks.run(model, charts)
    for child in children:
        found += chart_checks.run(child, lower(child))
    return Validation(model, dg.normalise(found), charts, index)


def compile_model(
    path: Path,
    backends: Sequence[str] | None = None,
    templates: Path | None = None,
    interfaces: Sequence[Path] = (),
) -> Compilation:
    """Validate (declared ROS types against `interfaces` too, as `validate`), then render every
    output of the registry (all, or SCXML and those named), with the templates of `templates`
    before the shipped ones (`swarmgen.render`)."""
    from swarmgen.render import templates_from

    with _few_collections(), templates_from(templates):
        return _compile(path, backends, interfaces)


def _compile(
    path: Path, backends: Sequence[str] | None, interfaces: Sequence[Path] = ()
) -> Compilation:
    from swarmgen.backends import SCXML, ScxmlOutput, registry, selection

    validation = _validate(path, interfaces)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        return Compilation(validation, {})
    files: Files = {}
    outputs = registry(validation.interfaces)
    for name in selection(backends):
        for relative, text in outputs[name].render(validation.model, validation.charts).items():
            files[PurePosixPath(name) / relative] = text
    scxml = outputs[SCXML]
    assert isinstance(scxml, ScxmlOutput)  # always rendered: the README lists its documents
    files[PurePosixPath("README.md")] = _output_readme(validation.model, path, scxml.documents)
    files[PurePosixPath(MANIFEST)] = _manifest("compile", path, files)
    return Compilation(validation, files)


def graph_model(path: Path, fmt: str = "mermaid", member: str | None = None) -> Compilation:
    """Validate, then draw every machine and the swarm composition (`swarmgen.graph`) in `fmt`,
    with a manifest so that the next run may replace the directory. Raises graph.GraphError for
    an unknown member type or a missing Graphviz."""
    from swarmgen import graph

    with _few_collections():
        validation = _validate(path)
        if validation.model is None or dg.has_errors(validation.diagnostics):
            return Compilation(validation, {})
        files = graph.files(validation.model, fmt, member)
        files[PurePosixPath(MANIFEST)] = _manifest("graph", path, files)
        return Compilation(validation, files)


def _output_readme(model: Model, source: Path, documents: tuple[ScxmlDocument, ...]) -> str:
    from swarmgen.render import render

    swarms = [
        {
            "name": markdown_cell(s.name),
            "members": [{"count": p.count, "type": markdown_cell(p.type_name)} for p in s.members],
        }
        for s in model.swarms
    ]
    rows = [
        {
            "path": f"scxml/{d.name}.scxml",
            "member": markdown_cell(d.member or "-"),
            "machine": markdown_cell(d.machine),
            "states": d.states,
            "transitions": d.transitions,
        }
        for d in documents
    ]
    return render(
        "common/README.md.j2",
        markup_header=header(markdown_cell(source.name), syntax="<!--"),
        source=markdown_cell(source.name),
        model=markdown_cell(model.name),
        swarms=swarms,
        documents=rows,
    )


def _manifest(command: str, source: Path, files: Mapping[PurePosixPath, str]) -> str:
    return outtree.manifest_text(command, source.name, files)


def write_tree(files: Files, out_dir: Path) -> None:
    """Make `out_dir` hold `files` (with their manifest), under the rules of `swarmgen.outtree`:
    only swarmgen's own, unedited files are replaced or removed; the swap is crash-safe."""
    outtree.write(files, out_dir)


def diff_tree(files: Files, out_dir: Path) -> str:
    """Unified diff between what would be generated and what `out_dir` holds of swarmgen's
    ('' if equal); files swarmgen did not write are not compared (a compile keeps them)."""
    from difflib import unified_diff

    chunks: list[str] = []
    for relative, old, new in outtree.diff_pairs(files, out_dir):
        chunks.extend(
            unified_diff(
                _lines(old),
                _lines(new),
                fromfile=f"a/{relative}" if old is not None else "/dev/null",
                tofile=f"b/{relative}" if new is not None else "/dev/null",
            )
        )
    return "".join(chunks)


def _lines(content: bytes | None) -> list[str]:
    return (content or b"").decode("utf-8", errors="replace").splitlines(keepends=True)


def ir_schema() -> str:
    """The IR's JSON Schema, deterministic (sorted keys)."""
    schema = Model.model_json_schema()
    schema["$id"] = "urn:swarmgen:ir:schema"
    schema["title"] = f"swarmgen IR (swarmgen {__version__.split('.')[0]}.x)"
    return json.dumps(schema, indent=2, sort_keys=True, ensure_ascii=False) + "\n"


@dataclass(frozen=True)
class Conversion:
    """A validation and, when it is clean of errors, the model written as EMF XMI."""

    validation: Validation
    xmi: bytes | None  # None when the model has errors


def convert_model(path: Path, interfaces: Sequence[Path] = ()) -> Conversion:
    """Validate the model at `path` (any readable format), then write what was read as EMF XMI
    with the swarm profile applied (`frontend.xmi_write`). A model with errors is not written:
    the XMI would carry them into the supported flow."""
    from swarmgen.frontend.xmi_write import write_xmi

    with _few_collections():
        raw, found = load(path)
        validation = _validate_loaded(path, raw, found, interfaces)
        if raw is None or validation.model is None or dg.has_errors(validation.diagnostics):
            return Conversion(validation, None)
        invokes = [e for e in raw.elements() if e.feature == "invoke" and e.uml_type == "Invoke"]
        if invokes:  # the profile has no invoke: writing the rest would drop the sessions
            refused = dg.SCXML_INVOKE.at(invokes[0].span, "convert")
            found = dg.normalise([*validation.diagnostics, refused])
            return Conversion(replace(validation, diagnostics=found), None)
        return Conversion(validation, write_xmi(raw))
