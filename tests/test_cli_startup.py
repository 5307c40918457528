"""The command line starts without the compiler: `import swarmgen.cli`, `--version` and `--help`
load no pydantic, lxml, Jinja2 or black (each checked in a fresh interpreter), and the group's
command summaries are the commands' own help. How fast is benchmarks/bench_startup.py's job."""

from __future__ import annotations

import json
import subprocess
import sys

import click
import pytest

from swarmgen import __version__
from swarmgen.cli import COMMANDS, main
from tests.conftest import ROOT, run_cli

HEAVY = ("pydantic", "pydantic_core", "lxml", "jinja2", "black", "numpy")
COMPILER = ("swarmgen.pipeline", "swarmgen.ir", "swarmgen.diagnostics", "swarmgen.backends")


def loaded_after(code: str) -> list[str]:
    """The modules a fresh interpreter has imported after running `code`."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
        check=True,
    )
    return list(json.loads(done.stdout.splitlines()[-1]))


def heavy(modules: list[str]) -> list[str]:
    """The modules of `modules` that start-up must not load."""
    return [m for m in modules if m.split(".")[0] in HEAVY or m.startswith(COMPILER)]


def test_importing_the_cli_loads_no_compiler() -> None:
    assert heavy(loaded_after("import swarmgen.cli")) == []


@pytest.mark.parametrize("args", [["--version"], ["--help"], ["validate", "--help"]])
def test_version_and_help_load_no_compiler(args: list[str]) -> None:
    code = (
        "import contextlib, io\n"
        "from swarmgen.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
        f"    main({args!r})"
    )
    assert heavy(loaded_after(code)) == []


def test_version_in_a_fresh_process() -> None:
    done = run_cli("--version")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"swarmgen, version {__version__}\n"


def test_help_in_a_fresh_process_lists_every_command() -> None:
    done = run_cli("--help")
    assert done.returncode == 0, done.stderr
    listed = done.stdout.split("Commands:\n", 1)[1].splitlines()
    assert [line.split()[0] for line in listed] == sorted(COMMANDS)


def test_every_command_help_works_in_a_fresh_process() -> None:
    for name in COMMANDS:
        done = run_cli(name, "--help")
        assert done.returncode == 0, (name, done.stderr)
        assert done.stdout.startswith("Usage: ") and f" {name} [OPTIONS]" in done.stdout, name


def test_the_summaries_are_the_commands_own_help() -> None:
    """What `--help` shows without importing a command is what the command itself would show,
    at every width click may shorten it to."""
    for name, entry in COMMANDS.items():
        command = entry.load()
        assert command.name == name
        stand_in = click.Command(name, help=entry.summary)
        for limit in range(10, 200):
            assert stand_in.get_short_help_str(limit) == command.get_short_help_str(limit), name


@pytest.mark.parametrize("width", [50, 80, 200])
def test_the_group_help_is_clicks_own(width: int) -> None:
    """The lazy group's help equals that of a plain click group holding the imported commands."""
    eager = click.Group(
        name=main.name,
        commands={name: entry.load() for name, entry in COMMANDS.items()},
        params=main.params,
        help=main.help,
        context_settings=main.context_settings,
    )
    fresh = type(main)(
        name=main.name,
        commands=type(main.commands)(),
        params=main.params,
        help=main.help,
        context_settings=main.context_settings,
    )
    shown = [
        group.get_help(click.Context(group, info_name="swarmgen", terminal_width=width))
        for group in (eager, fresh)
    ]
    assert shown[0] == shown[1]


def test_the_commands_are_known_before_they_are_imported() -> None:
    assert list(main.commands) == list(COMMANDS)
    assert all(name in main.commands for name in COMMANDS)
    assert "frobnicate" not in main.commands
    assert len(main.commands) == len(COMMANDS)


COLLECTOR_PROBE = """
import gc, sys
from swarmgen import collector
from swarmgen.cli import main
if sys.argv[1] == "ends":
    collector.process_ends_after_command()
try:
    main(["validate", "sample_models/patrol/patrol.xmi"])
except SystemExit:
    pass
print(gc.isenabled())
"""


@pytest.mark.parametrize(("mode", "enabled"), [("ends", "False"), ("in-process", "True")])
def test_batch_commands_leave_the_collector_on_unless_the_process_ends(
    mode: str, enabled: str
) -> None:
    """`swarmgen.collector`: validate runs with the cyclic collector off; it stays off only when
    the console entry point ends the process right after, so in-process callers get it back."""
    done = subprocess.run(
        [sys.executable, "-c", COLLECTOR_PROBE, mode],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
        check=True,
    )
    assert done.stdout.splitlines()[-1] == enabled, done.stderr
