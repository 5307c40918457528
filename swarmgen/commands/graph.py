"""`swarmgen graph`: a model's state machines and swarm composition as Mermaid, DOT or SVG."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from swarmgen import console
from swarmgen.commands.common import MODEL, PATH, batch, emit_diagnostics, guarded

# The pipeline and the diagnostics are imported in the command functions: `swarmgen --help` and
# `swarmgen graph --help` must not load the compiler (docs/performance.md).


@click.command(name="graph")
@MODEL
@click.option("--member", help="Only this member type: its machine, submachines and hardware.")
@click.option(
    "--format", "diagram_format", type=click.Choice(["mermaid", "dot", "svg"]), default="mermaid",
    show_default=True, help="Mermaid text, Graphviz DOT, or SVG (laid out by Graphviz `dot`).",
)  # fmt: skip
@click.option(
    "-o", "--output", type=PATH,
    help="Write one file per diagram into this directory (replaced atomically); else stdout.",
)  # fmt: skip
@batch
@guarded
def graph_(model: Path, member: str | None, diagram_format: str, output: Path | None) -> None:
    """Draw MODEL's state machines (one diagram each) and its swarm composition."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    if diagram_format == "svg" and output is None:
        raise click.UsageError("--format svg writes files: give -o DIR")
    result = pipeline.graph_model(model, diagram_format, member)  # GraphError: common.report
    diagnostics = result.validation.diagnostics
    if not result.files:
        emit_diagnostics(diagnostics, "text", to_stdout=False)
        click.echo(
            f"swarmgen: {console.shown(model)}: {dg.summary_line(diagnostics)}; nothing drawn",
            err=True,
        )
        sys.exit(result.validation.exit_code or dg.ExitCode.MODEL_ERRORS)
    diagrams = {p: t for p, t in result.files.items() if p.name != pipeline.MANIFEST}
    if output is None:
        click.echo("\n".join(diagrams.values()), nl=False)
        return
    pipeline.write_tree(result.files, output)
    click.echo(
        f"swarmgen: {console.shown(model)} -> {console.shown(output)}: {len(diagrams)} "
        f"{diagram_format} diagram(s)",
        err=True,
    )
