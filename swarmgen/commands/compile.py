"""`swarmgen compile` (a model into its output tree, or `--check` for drift) and
`swarmgen schema` (the IR's JSON Schema)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from swarmgen import console
from swarmgen.commands.common import (
    DISABLE,
    FORMAT,
    INTERFACES,
    MODEL,
    PATH,
    STRICT,
    DeferredHelpOption,
    OutputChoice,
    PathType,
    batch,
    check_codes,
    emit_diagnostics,
    fail,
    guarded,
    outputs,
)

if TYPE_CHECKING:
    from swarmgen import pipeline

# The pipeline and the diagnostics are imported in the command functions: `swarmgen --help` and
# `swarmgen compile --help` must not load the compiler (docs/performance.md).


def _backend_help() -> str:
    """The help of --backend: it names the registry's outputs, so it is made when shown."""
    from swarmgen.backends import SCXML

    return (
        f"Only these outputs besides SCXML (repeatable: {', '.join(outputs(SCXML))}; "
        "`scxml` alone: SCXML only). Default: all."
    )


@click.command(name="compile")
@MODEL
@click.option("-o", "--output", type=PATH, required=True, help="Output directory.")
@click.option("--check", is_flag=True, help="Write nothing; exit 1 with a diff if OUTPUT is stale.")
@click.option(
    "--backend",
    "backends",
    multiple=True,
    metavar="NAME",
    type=OutputChoice(outputs),
    cls=DeferredHelpOption,
    help_text=_backend_help,
)
@click.option(
    "--templates",
    type=PathType(path_type=Path, exists=True, file_okay=False),
    help="A directory of Jinja2 templates used before the shipped ones (same relative paths).",
)
@INTERFACES
@FORMAT
@STRICT
@DISABLE
@batch
@guarded
def compile_(
    model: Path,
    output: Path,
    check: bool,
    backends: tuple[str, ...],
    templates: Path | None,
    interfaces: tuple[Path, ...],
    fmt: str,
    strict: bool,
    disabled: tuple[str, ...],
) -> None:
    """Compile MODEL into OUTPUT (SCXML and every backend), replacing it atomically."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    check_codes(disabled)
    result = pipeline.compile_model(
        model, backends=backends or None, templates=templates, interfaces=interfaces
    )
    diagnostics = dg.apply_options(result.validation.diagnostics, strict=strict, disabled=disabled)
    emit_diagnostics(diagnostics, fmt, to_stdout=False)
    if dg.has_errors(diagnostics) and result.files:
        click.echo(
            f"swarmgen: {console.shown(model)}: {dg.summary_line(diagnostics)} (--strict); "
            "nothing written",
            err=True,
        )
        sys.exit(dg.ExitCode.MODEL_ERRORS)
    if not result.files:
        click.echo(
            f"swarmgen: {console.shown(model)}: {dg.summary_line(diagnostics)}; nothing written",
            err=True,
        )
        sys.exit(result.validation.exit_code or dg.ExitCode.MODEL_ERRORS)
    if check:
        _check_drift(model, output, result.files)
        return
    pipeline.write_tree(result.files, output)
    count = sum(1 for p in result.files if p.suffix == ".scxml")
    click.echo(
        f"swarmgen: {console.shown(model)} -> {console.shown(output)}: {count} SCXML document(s); "
        f"{dg.summary_line(diagnostics)}",
        err=True,
    )


def _check_drift(model: Path, output: Path, files: pipeline.Files) -> None:
    """--check: a diff and exit 1 if OUTPUT differs from what MODEL compiles to; writes nothing."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    difference = pipeline.diff_tree(files, output)
    if difference:
        click.echo(difference, nl=False)
        click.echo(
            f"swarmgen: {console.shown(output)} is stale; run: swarmgen compile "
            f"{console.shown(model)} -o {console.shown(output)}",
            err=True,
        )
        sys.exit(dg.ExitCode.MODEL_ERRORS)
    click.echo(f"swarmgen: {console.shown(output)} is up to date", err=True)


@click.command()
@click.option(
    "-o",
    "--output",
    type=PATH,
    default=Path("schemas"),
    show_default=True,
    help="Directory for ir.schema.json.",
)
@click.option("--check", is_flag=True, help="Exit 1 if the schema on disk is stale.")
@guarded
def schema(output: Path, check: bool) -> None:
    """Write the JSON Schema of swarmgen's IR."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    target = output / "ir.schema.json"
    text = pipeline.ir_schema()
    if check:
        try:
            current = target.read_bytes() if target.is_file() else b""
        except OSError as err:
            fail(f"{console.shown(target)}: cannot read: {err.strerror}")
        if current != text.encode():
            shown = console.shown(output)
            click.echo(
                f"swarmgen: {shown}/ir.schema.json is stale; run: swarmgen schema -o {shown}",
                err=True,
            )
            sys.exit(dg.ExitCode.MODEL_ERRORS)
        return
    made = console.check_directory(output, "-o")
    try:
        console.check_file(target, "-o")
        console.write_file(target, text.encode(), "-o")
    except console.OutputPathError:
        console.remove_made(made)
        raise
    click.echo(f"swarmgen: wrote {console.shown(target)}", err=True)
