"""`swarmgen convert IN -o model.xmi`: any readable model (XMI, SCXML, the CPSwarm dialect)
written as EMF XMI with the swarm profile, for Modelio and for swarmgen."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from swarmgen import console
from swarmgen.commands.common import FORMAT, INTERFACES, MODEL, PATH, emit_diagnostics, guarded

# The pipeline and the diagnostics are imported in the command function: `swarmgen --help` and
# `swarmgen convert --help` must not load the compiler (docs/performance.md).


@click.command(name="convert")
@MODEL
@click.option(
    "-o", "--output", type=PATH, required=True,
    help="The XMI file to write (replaced atomically; nothing is written if MODEL has errors).",
)  # fmt: skip
@INTERFACES
@FORMAT
@guarded
def convert(model: Path, output: Path, interfaces: tuple[Path, ...], fmt: str) -> None:
    """Write MODEL (any format swarmgen reads) as EMF XMI with the swarm profile applied."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline

    made = console.check_file(output, "-o")  # directories made for it, removed on failure
    result = pipeline.convert_model(model, interfaces)
    diagnostics = result.validation.diagnostics
    emit_diagnostics(diagnostics, fmt, to_stdout=False)
    if result.xmi is None:
        console.remove_made(made)
        click.echo(
            f"swarmgen: {console.shown(model)}: {dg.summary_line(diagnostics)}; nothing written",
            err=True,
        )
        sys.exit(result.validation.exit_code or dg.ExitCode.MODEL_ERRORS)
    console.write_file(output, result.xmi, "-o")
    click.echo(
        f"swarmgen: {console.shown(model)} -> {console.shown(output)}: "
        f"{dg.summary_line(diagnostics)}",
        err=True,
    )
