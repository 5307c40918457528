"""The `swarmgen` command line: the click group of the commands in `swarmgen.commands` (thin,
over `swarmgen.pipeline`) and the console entry point.

Exit codes: 0 clean (warnings allowed), 1 model errors or `--check` drift, 2 unreadable input or
misuse, 3 an internal error (a bug in swarmgen: please report it).
"""

from __future__ import annotations

import os
import sys

import click

from swarmgen import __version__, console
from swarmgen import diagnostics as dg
from swarmgen.commands.compile import compile_, schema
from swarmgen.commands.graph import graph_
from swarmgen.commands.replay import replay
from swarmgen.commands.simulate import simulate
from swarmgen.commands.timeline import timeline
from swarmgen.commands.validate import validate

COMMANDS = (validate, compile_, schema, replay, graph_, timeline, simulate)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="swarmgen")
def main() -> None:
    """Compile Modelio swarm models (XMI) to validated SCXML and runnable code."""


for _command in COMMANDS:
    main.add_command(_command)


def run() -> None:
    """Console entry point: run the command, then end the process at once. Tearing down a large
    model object by object can take a second after the work is done (mypy's `hard_exit` does the
    same); output is flushed first. The standard streams follow `swarmgen.console`: a reader
    that closes early ends nothing, a stdout that cannot be written is one error line (exit 2)."""
    console.install()
    code: int
    try:
        main(standalone_mode=True)
        code = 0
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    except console.StreamError as err:  # raised outside a command, e.g. by --help
        click.echo(f"swarmgen: error: {err}", err=True)
        code = dg.ExitCode.INPUT_ERROR
    try:
        sys.stdout.flush()
    except console.StreamError as err:
        click.echo(f"swarmgen: error: {err}", err=True)
        code = dg.ExitCode.INPUT_ERROR
    sys.stderr.flush()
    os._exit(code)
