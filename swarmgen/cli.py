"""The `swarmgen` command line: the click group of the commands in `swarmgen.commands` (thin,
over `swarmgen.pipeline`) and the console entry point.

Exit codes: 0 clean (warnings allowed), 1 model errors or `--check` drift, 2 unreadable input or
misuse, 3 an internal error (a bug in swarmgen: please report it).

The group knows its commands by name and one-line summary (`COMMANDS`) and imports a command's
module only when that command runs or shows its help, so `swarmgen --version` and
`swarmgen --help` load no part of the compiler (docs/performance.md). A test checks the
summaries against the commands' own help.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator, MutableMapping
from importlib import import_module

import click

from swarmgen import __version__, collector, console, records
from swarmgen.records import dataclass


@dataclass(frozen=True)
class Entry:
    """A command of the group: where it is defined and the first paragraph of its help."""

    module: str  # in swarmgen.commands
    attribute: str  # the click command in that module
    summary: str  # its docstring's first paragraph: what `swarmgen --help` shortens

    def load(self) -> click.Command:
        """The command itself (its module imported now)."""
        command = getattr(import_module(f"swarmgen.commands.{self.module}"), self.attribute)
        assert isinstance(command, click.Command), (self.module, self.attribute)
        return command


COMMANDS: dict[str, Entry] = {
    "validate": Entry(
        "validate",
        "validate",
        "Check each MODEL and print its diagnostics (exit 0 clean, 1 errors, 2 unreadable).",
    ),
    "compile": Entry(
        "compile",
        "compile_",
        "Compile MODEL into OUTPUT (SCXML and every backend), replacing it atomically.",
    ),
    "schema": Entry("compile", "schema", "Write the JSON Schema of swarmgen's IR."),
    "convert": Entry(
        "convert",
        "convert",
        "Write MODEL (any format swarmgen reads) as EMF XMI with the swarm profile applied.",
    ),
    "replay": Entry(
        "replay",
        "replay",
        "Run one member of MODEL against a scenario; print its trace as JSON lines.",
    ),
    "graph": Entry(
        "graph",
        "graph_",
        "Draw MODEL's state machines (one diagram each) and its swarm composition.",
    ),
    "timeline": Entry(
        "timeline",
        "timeline",
        "Each event's time since launch over many runs (one run per bag; a directory holds bags).",
    ),
    "simulate": Entry(
        "simulate",
        "simulate",
        "Run MODEL's compiled behaviours in the paper's abstract world (or, with `--level "
        "detailed`, the generated ROS 2 swarm in the continuous world) and report the statistics.",
    ),
    "optimize": Entry(
        "optimize",
        "optimize",
        "Search MODEL's parameters for the best value of the objectives over simulated runs.",
    ),
    "verify": Entry(
        "verify",
        "verify",
        "Verify MODEL's swarm exhaustively (exit 0 verified, 1 violated, 4 bounded).",
    ),
}


class _Commands(MutableMapping[str, click.Command]):
    """The group's commands by name: every name of `COMMANDS` is there from the start, its
    command is imported on first access; commands added later are kept as given."""

    def __init__(self) -> None:
        self.loaded: dict[str, click.Command] = {}

    def __getitem__(self, name: str) -> click.Command:
        if name not in self.loaded:
            self.loaded[name] = COMMANDS[name].load()  # KeyError: no such command
        return self.loaded[name]

    def __setitem__(self, name: str, command: click.Command) -> None:
        self.loaded[name] = command

    def __delitem__(self, name: str) -> None:
        raise TypeError(f"swarmgen's commands are fixed; cannot remove {name!r}")

    def __iter__(self) -> Iterator[str]:
        return iter(dict.fromkeys([*COMMANDS, *self.loaded]))

    def __len__(self) -> int:
        return len(set(COMMANDS) | set(self.loaded))

    def __contains__(self, name: object) -> bool:
        return name in COMMANDS or name in self.loaded


class _Group(click.Group):
    """A click group whose command list (`--help`) is made from the summaries, importing no
    command; everything else is click's own."""

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The "Commands" section exactly as click writes it (click.Group.format_commands),
        with each not yet imported command stood in for by its summary."""
        names = self.list_commands(ctx)
        loaded = self.commands.loaded if isinstance(self.commands, _Commands) else {}
        shown = [
            (name, loaded.get(name) or click.Command(name, help=COMMANDS[name].summary))
            for name in names
        ]
        shown = [(name, command) for name, command in shown if not command.hidden]
        if shown:
            limit = formatter.width - 6 - max(len(name) for name, _ in shown)
            with formatter.section("Commands"):
                formatter.write_dl([(name, cmd.get_short_help_str(limit)) for name, cmd in shown])


@click.group(
    cls=_Group, commands=_Commands(), context_settings={"help_option_names": ["-h", "--help"]}
)
@click.version_option(__version__, prog_name="swarmgen")
def main() -> None:
    """Compile Modelio swarm models (XMI) to validated SCXML and runnable code."""


def run() -> None:
    """Console entry point: run the command, then end the process at once. Tearing down a large
    model object by object can take a second after the work is done (mypy's `hard_exit` does the
    same); output is flushed first. The standard streams follow `swarmgen.console`: a reader
    that closes early ends nothing, a stdout that cannot be written is one error line (exit 2)."""
    console.install()
    collector.process_ends_after_command()
    records.install()  # the process is the command's: every dataclass's methods precompiled
    code: int
    try:
        main(standalone_mode=True)
        code = 0
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    except console.StreamError as err:  # raised outside a command, e.g. by --help
        code = _stream_error(err)
    try:
        sys.stdout.flush()
    except console.StreamError as err:
        code = _stream_error(err)
    sys.stderr.flush()
    os._exit(code)


def _stream_error(err: console.StreamError) -> int:
    """Report an unwritable stdout in one line; the exit code for it (2)."""
    from swarmgen import diagnostics as dg  # only on this path: it imports the IR's spans

    click.echo(f"swarmgen: error: {err}", err=True)
    return int(dg.ExitCode.INPUT_ERROR)
