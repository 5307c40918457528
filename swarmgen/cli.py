"""The `swarmgen` command line: thin click commands over `swarmgen.pipeline`.

Exit codes: 0 clean (warnings allowed), 1 model errors or `--check` drift, 2 unreadable input or
misuse, 3 an internal error (a bug in swarmgen: please report it).
"""

from __future__ import annotations

import json
import sys
import traceback
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import ParamSpec, TypeVar

import click

from swarmgen import __version__, pipeline
from swarmgen import diagnostics as dg

P = ParamSpec("P")
R = TypeVar("R")
INTERNAL_ERROR = 3


def _guarded(command: Callable[P, R]) -> Callable[P, R]:
    """Turn unexpected exceptions into one clear line (and the traceback only on request)."""

    @wraps(command)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return command(*args, **kwargs)
        except (click.exceptions.Exit, click.ClickException, click.Abort):
            raise
        except pipeline.OutputError as err:
            click.echo(f"swarmgen: error: {err}", err=True)
            sys.exit(dg.ExitCode.INPUT_ERROR)
        except Exception as err:  # a bug: report it without a traceback wall
            click.echo(f"swarmgen: internal error: {type(err).__name__}: {err}", err=True)
            click.echo(
                "  please report this with the model attached; SWARMGEN_DEBUG=1 shows the traceback",
                err=True,
            )
            if _debug():
                traceback.print_exc()
            sys.exit(INTERNAL_ERROR)

    return wrapper


def _debug() -> bool:
    import os

    return os.environ.get("SWARMGEN_DEBUG", "") not in {"", "0"}


def _emit_diagnostics(diagnostics: list[dg.Diagnostic], fmt: str, *, to_stdout: bool) -> None:
    if fmt == "json":
        text = dg.render_json(diagnostics)
    elif fmt == "sarif":
        text = dg.render_sarif(diagnostics, __version__)
    else:
        text = dg.render_text(diagnostics)
    if text:
        click.echo(text, nl=False, err=not to_stdout)


MODEL = click.argument("model", type=click.Path(path_type=Path))
FORMAT = click.option(
    "--format",
    "fmt",
    type=click.Choice(["text", "json", "sarif"]),
    default="text",
    show_default=True,
    help="How diagnostics are printed (SARIF 2.1.0 for code-scanning tools).",
)
STRICT = click.option("--strict", is_flag=True, help="Treat warnings as errors.")
DISABLE = click.option(
    "--disable",
    "disabled",
    multiple=True,
    metavar="CODE",
    help="Do not report this diagnostic code (repeatable), e.g. --disable SG205.",
)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="swarmgen")
def main() -> None:
    """Compile Modelio swarm models (XMI) to validated SCXML and runnable code."""


@main.command()
@MODEL
@FORMAT
@STRICT
@DISABLE
@_guarded
def validate(model: Path, fmt: str, strict: bool, disabled: tuple[str, ...]) -> None:
    """Check MODEL and print its diagnostics (exit 0 clean, 1 errors, 2 unreadable)."""
    _check_codes(disabled)
    result = pipeline.validate(model)
    diagnostics = dg.apply_options(result.diagnostics, strict=strict, disabled=disabled)
    _emit_diagnostics(diagnostics, fmt, to_stdout=True)
    click.echo(f"swarmgen: {model}: {dg.summary_line(diagnostics)}", err=True)
    sys.exit(dg.exit_code_for(diagnostics))


def _check_codes(codes: tuple[str, ...]) -> None:
    unknown = [c for c in codes if c.upper() not in dg.CODES]
    if unknown:
        raise click.BadParameter(f"unknown code(s) {', '.join(unknown)}", param_hint="--disable")


@main.command(name="compile")
@MODEL
@click.option(
    "-o", "--output", type=click.Path(path_type=Path), required=True, help="Output directory."
)
@click.option("--check", is_flag=True, help="Write nothing; exit 1 with a diff if OUTPUT is stale.")
@click.option(
    "--backend",
    "backends",
    multiple=True,
    metavar="NAME",
    help="Only these backends besides SCXML (repeatable; `scxml` alone: SCXML only). Default: all.",
)
@FORMAT
@STRICT
@DISABLE
@_guarded
def compile_(
    model: Path,
    output: Path,
    check: bool,
    backends: tuple[str, ...],
    fmt: str,
    strict: bool,
    disabled: tuple[str, ...],
) -> None:
    """Compile MODEL into OUTPUT (SCXML and every backend), replacing it atomically."""
    _check_codes(disabled)
    from swarmgen.backends import names as backend_names

    known = ["scxml", *backend_names()]
    unknown = [b for b in backends if b not in known]
    if unknown:
        raise click.BadParameter(
            f"unknown backend(s) {', '.join(unknown)}; choose from {', '.join(known)}",
            param_hint="--backend",
        )
    selected = [b for b in backends if b != "scxml"] if backends else None
    result = pipeline.compile_model(model, backends=selected)
    diagnostics = dg.apply_options(result.validation.diagnostics, strict=strict, disabled=disabled)
    _emit_diagnostics(diagnostics, fmt, to_stdout=False)
    if dg.has_errors(diagnostics) and result.files:
        click.echo(
            f"swarmgen: {model}: {dg.summary_line(diagnostics)} (--strict); nothing written",
            err=True,
        )
        sys.exit(dg.ExitCode.MODEL_ERRORS)
    if not result.files:
        click.echo(f"swarmgen: {model}: {dg.summary_line(diagnostics)}; nothing written", err=True)
        sys.exit(result.validation.exit_code or dg.ExitCode.MODEL_ERRORS)
    if check:
        difference = pipeline.diff_tree(result.files, output)
        if difference:
            click.echo(difference, nl=False)
            click.echo(
                f"swarmgen: {output} is stale; run: swarmgen compile {model} -o {output}", err=True
            )
            sys.exit(dg.ExitCode.MODEL_ERRORS)
        click.echo(f"swarmgen: {output} is up to date", err=True)
        return
    pipeline.write_tree(result.files, output)
    count = sum(1 for p in result.files if p.suffix == ".scxml")
    click.echo(
        f"swarmgen: {model} -> {output}: {count} SCXML document(s); {dg.summary_line(diagnostics)}",
        err=True,
    )


@main.command()
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path),
    default=Path("schemas"),
    show_default=True,
    help="Directory for ir.schema.json.",
)
@click.option("--check", is_flag=True, help="Exit 1 if the schema on disk is stale.")
@_guarded
def schema(output: Path, check: bool) -> None:
    """Write the JSON Schema of swarmgen's IR."""
    target = output / "ir.schema.json"
    text = pipeline.ir_schema()
    if check:
        current = target.read_text(encoding="utf-8") if target.is_file() else ""
        if current != text:
            click.echo(f"swarmgen: {target} is stale; run: swarmgen schema -o {output}", err=True)
            sys.exit(dg.ExitCode.MODEL_ERRORS)
        return
    output.mkdir(parents=True, exist_ok=True)
    target.write_text(text, encoding="utf-8")
    click.echo(f"swarmgen: wrote {target}", err=True)


@main.command()
@MODEL
@click.option("--member", required=True, help="Member type to run.")
@click.option(
    "--script", "scenario", type=click.Path(path_type=Path), required=True, help="Scenario (JSON)."
)
@click.option(
    "--backend", type=click.Choice(["asyncio", "smach", "scxml", "rclpy"]), default="asyncio", show_default=True,
    help="Where to run: the generated asyncio, smach or rclpy code, or the SCXML in Qt SCXML.",
)  # fmt: skip
@_guarded
def replay(model: Path, member: str, scenario: Path, backend: str) -> None:
    """Run one member of MODEL against a scenario; print its trace as JSON lines."""
    from swarmgen import replay as replaying

    try:
        _, steps = replaying.load_scenario(scenario)
        trace = replaying.replay(model, member, steps, backend)
    except replaying.ReplayError as err:
        click.echo(f"swarmgen: error: {err}", err=True)
        sys.exit(dg.ExitCode.INPUT_ERROR)
    for record in trace:
        click.echo(json.dumps(record, sort_keys=True))


@main.command(name="graph")
@MODEL
@click.option("--member", help="Only this member type: its machine, submachines and hardware.")
@click.option(
    "--format", "diagram_format", type=click.Choice(["mermaid", "dot", "svg"]), default="mermaid",
    show_default=True, help="Mermaid text, Graphviz DOT, or SVG (laid out by Graphviz `dot`).",
)  # fmt: skip
@click.option(
    "-o", "--output", type=click.Path(path_type=Path),
    help="Write one file per diagram into this directory (replaced atomically); else stdout.",
)  # fmt: skip
@_guarded
def graph_(model: Path, member: str | None, diagram_format: str, output: Path | None) -> None:
    """Draw MODEL's state machines (one diagram each) and its swarm composition."""
    from swarmgen.graph import GraphError

    if diagram_format == "svg" and output is None:
        raise click.UsageError("--format svg writes files: give -o DIR")
    try:
        result = pipeline.graph_model(model, diagram_format, member)
    except GraphError as err:
        click.echo(f"swarmgen: error: {err}", err=True)
        sys.exit(dg.ExitCode.INPUT_ERROR)
    diagnostics = result.validation.diagnostics
    if not result.files:
        _emit_diagnostics(diagnostics, "text", to_stdout=False)
        click.echo(f"swarmgen: {model}: {dg.summary_line(diagnostics)}; nothing drawn", err=True)
        sys.exit(result.validation.exit_code or dg.ExitCode.MODEL_ERRORS)
    diagrams = {p: t for p, t in result.files.items() if p.name != pipeline.MANIFEST}
    if output is None:
        click.echo("\n".join(diagrams.values()), nl=False)
        return
    pipeline.write_tree(result.files, output)
    click.echo(
        f"swarmgen: {model} -> {output}: {len(diagrams)} {diagram_format} diagram(s)", err=True
    )
