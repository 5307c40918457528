"""`swarmgen validate MODEL...`: check one or several models as a linter does, each model's
diagnostics in one report, and exit with the worst model's code."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from swarmgen import __version__, console
from swarmgen.commands.common import (
    DISABLE,
    FORMAT,
    INTERFACES,
    PATH,
    STRICT,
    batch,
    check_codes,
    guarded,
)

if TYPE_CHECKING:
    from swarmgen import diagnostics as dg

# The pipeline and the diagnostics are imported in the command functions: `swarmgen --help` and
# `swarmgen validate --help` must not load the compiler (docs/performance.md).

Found = list[tuple[Path, list["dg.Diagnostic"]]]


@click.command()
@click.argument("models", nargs=-1, required=True, type=PATH, metavar="MODEL...")
@INTERFACES
@FORMAT
@STRICT
@DISABLE
@batch
@guarded
def validate(
    models: tuple[Path, ...],
    interfaces: tuple[Path, ...],
    fmt: str,
    strict: bool,
    disabled: tuple[str, ...],
) -> None:
    """Check each MODEL and print its diagnostics (exit 0 clean, 1 errors, 2 unreadable)."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    check_codes(disabled)
    found: Found = []
    for model in models:
        diagnostics = pipeline.validate(model, interfaces).diagnostics
        found.append((model, dg.apply_options(diagnostics, strict=strict, disabled=disabled)))
        if fmt == "text":  # streamed, model by model, as a linter does
            _print(dg.render_text(found[-1][1]))
            _summary(found[-1:])
    if fmt != "text":  # one document for every model
        _print(_json(found) if fmt == "json" else _sarif(found))
        _summary(found)
    if len(found) > 1:
        every = [d for _, diagnostics in found for d in diagnostics]
        click.echo(f"swarmgen: {len(found)} models: {dg.summary_line(every)}", err=True)
    sys.exit(max(dg.exit_code_for(diagnostics) for _, diagnostics in found))


def _print(text: str) -> None:
    """`text` on stdout as it is, nothing for no findings."""
    if text:
        click.echo(text, nl=False)


def _summary(found: Found) -> None:
    """One line per model on stderr: `swarmgen: MODEL: N error(s), M warning(s)`."""
    from swarmgen import diagnostics as dg

    for model, diagnostics in found:
        click.echo(f"swarmgen: {console.shown(model)}: {dg.summary_line(diagnostics)}", err=True)


def _json(found: Found) -> str:
    """One model: the document of `dg.render_json`. Several: the same document over every
    model's diagnostics (in argument order; each names its file) with the totals as `summary`,
    and `models`, one `{file, errors, warnings, exit_code}` per model, in argument order."""
    from swarmgen import diagnostics as dg

    every = [d for _, diagnostics in found for d in diagnostics]
    if len(found) == 1:
        return dg.render_json(every)
    payload = json.loads(dg.render_json(every))
    payload["models"] = [_model_entry(model, diagnostics) for model, diagnostics in found]
    return json.dumps(payload, indent=2, ensure_ascii=False) + "\n"


def _model_entry(model: Path, diagnostics: list[dg.Diagnostic]) -> dict[str, object]:
    """A model's line in the JSON document's `models`: its file as its diagnostics name it."""
    from swarmgen import diagnostics as dg

    errors = sum(d.level is dg.Severity.ERROR for d in diagnostics)
    warnings = sum(d.level is dg.Severity.WARNING for d in diagnostics)
    exit_code = int(dg.exit_code_for(diagnostics))
    return {"file": str(model), "errors": errors, "warnings": warnings, "exit_code": exit_code}


def _sarif(found: Found) -> str:
    """SARIF 2.1.0: one run (one tool invocation), the results of every model."""
    from swarmgen import diagnostics as dg

    return dg.render_sarif([d for _, diagnostics in found for d in diagnostics], __version__)
