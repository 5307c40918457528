"""What the `swarmgen` commands share: the one user-error handler, path and output types, the
common options, and how diagnostics are printed."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, ParamSpec, TypeVar

import click

from swarmgen import __version__, collector, console
from swarmgen.errors import SwarmgenError

if TYPE_CHECKING:
    from swarmgen import diagnostics as dg

# The diagnostics package (pydantic spans, every code) is imported inside the functions that use
# it: defining the commands and showing their help must not pay for it (docs/performance.md).

P = ParamSpec("P")
R = TypeVar("R")
INTERNAL_ERROR = 3


def guarded(command: Callable[P, R]) -> Callable[P, R]:
    """Turn unexpected exceptions into one clear line (and the traceback only on request)."""

    @wraps(command)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        """The command, with every exception it raises mapped to its output and exit code."""
        try:
            return command(*args, **kwargs)
        except (click.exceptions.Exit, click.ClickException, click.Abort):
            raise
        except SwarmgenError as err:  # every user error, mapped to its exit code here only
            report(err)
        except Exception as err:  # a bug: report it without a traceback wall
            click.echo(f"swarmgen: internal error: {type(err).__name__}: {err}", err=True)
            click.echo(
                "  please report this with the model attached; SWARMGEN_DEBUG=1 shows the traceback",
                err=True,
            )
            if _debug():
                import traceback  # only then: it imports textwrap, linecache, tokenize

                traceback.print_exc()
            sys.exit(INTERNAL_ERROR)

    return wrapper


def batch(command: Callable[P, R]) -> Callable[P, R]:
    """A batch command (validate, compile, graph): run with the cyclic garbage collector off
    (`swarmgen.collector`), its imports included."""

    @wraps(command)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        """The command with the collector off."""
        with collector.off_for_batch():
            return command(*args, **kwargs)

    return wrapper


def _debug() -> bool:
    """SWARMGEN_DEBUG is set (and not 0): show the traceback of an internal error."""
    return os.environ.get("SWARMGEN_DEBUG", "") not in {"", "0"}


def report(err: SwarmgenError) -> NoReturn:
    """A user error: its message on stderr (one escaped line unless `verbatim`), its exit code."""
    if err.verbatim:
        click.echo(f"swarmgen: error: {err}", err=True)
        sys.exit(err.exit_code)
    fail(str(err), err.exit_code)


def fail(message: str, code: int | None = None) -> NoReturn:
    """A user error: one line on stderr, exit `code` (2, `ExitCode.INPUT_ERROR`, unless the
    error says otherwise)."""
    from swarmgen import diagnostics as dg

    click.echo(f"swarmgen: error: {dg.one_line(' '.join(message.splitlines()))}", err=True)
    sys.exit(dg.ExitCode.INPUT_ERROR if code is None else code)


class PathType(click.Path):
    """A path argument: an empty string is refused (Path("") would silently be ".")."""

    def convert(
        self,
        value: str | os.PathLike[str],
        param: click.Parameter | None,
        ctx: click.Context | None,
    ) -> str | bytes | os.PathLike[str]:
        """The path, or a usage error for an empty one."""
        if not os.fspath(value):
            self.fail("an empty path; give a file or directory name", param, ctx)
        return super().convert(value, param, ctx)


PATH = PathType(path_type=Path)


class OutputChoice(click.Choice[str]):
    """One of the registry's outputs (`swarmgen.backends`); a wrong name gets the close ones.

    The names come from `outputs`, called the first time they are needed (a value to check,
    help to show), not when the command is defined: the registry imports the IR and the
    charts, which a command's definition must not pay for."""

    def __init__(self, outputs: Callable[[], Sequence[str]]) -> None:
        """The choice of the names `outputs()` returns, asked for when first needed."""
        super().__init__(())
        self._outputs = outputs
        self._names: tuple[str, ...] | None = None

    @property
    def choices(self) -> tuple[str, ...]:
        """The registry's names, in its order."""
        if self._names is None:
            self._names = tuple(self._outputs())
        return self._names

    @choices.setter
    def choices(self, value: Sequence[str]) -> None:
        """click.Choice sets its choices on construction (to nothing, here: see `outputs`)."""
        self._names = tuple(value) if value else None

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        """The name itself, or a usage error naming the choices and the closest of them."""
        try:
            return str(super().convert(value, param, ctx))
        except click.BadParameter:
            import difflib  # only for this message: not on every command's start-up

            close = difflib.get_close_matches(str(value), list(self.choices), n=1)
            also = f"; did you mean '{close[0]}'?" if close else ""
            choices = ", ".join(map(str, self.choices))
            self.fail(f"unknown backend '{value}'; choose from {choices}{also}", param, ctx)


class DeferredHelpOption(click.Option):
    """An option whose help text is made when help is shown, by `help_text()`: it names the
    registry's outputs, which are imported only then (see `OutputChoice`)."""

    def __init__(self, *args: Any, help_text: Callable[[], str], **kwargs: Any) -> None:
        """A click option (`click.option(..., cls=DeferredHelpOption, help_text=...)`)."""
        super().__init__(*args, **kwargs)
        self.help_text = help_text

    def get_help_record(self, ctx: click.Context) -> tuple[str, str] | None:
        """The help line, with the help text made now."""
        self.help = self.help_text()
        return super().get_help_record(ctx)


def outputs(*leaving_out: str) -> list[str]:
    """The registry's outputs but those left out (`swarmgen.backends.names`), imported now."""
    from swarmgen.backends import names

    return names(*leaving_out)


def runnable_outputs() -> list[str]:
    """The outputs `swarmgen replay` can run (`swarmgen.backends.runnable`), imported now."""
    from swarmgen.backends import runnable

    return runnable()


def render_diagnostics(diagnostics: list[dg.Diagnostic], fmt: str) -> str:
    """The diagnostics as `--format` asks: text, JSON or SARIF."""
    from swarmgen import diagnostics as dg

    if fmt == "json":
        return dg.render_json(diagnostics)
    if fmt == "sarif":
        return dg.render_sarif(diagnostics, __version__)
    return dg.render_text(diagnostics)


def emit_diagnostics(diagnostics: list[dg.Diagnostic], fmt: str, *, to_stdout: bool) -> None:
    """Print the diagnostics in `fmt` on stdout (validate) or stderr (the other commands)."""
    text = render_diagnostics(diagnostics, fmt)
    if text:
        click.echo(text, nl=False, err=not to_stdout)


def check_codes(codes: tuple[str, ...]) -> None:
    """Every --disable code is a known diagnostic code, or a usage error (exit 2)."""
    from swarmgen import diagnostics as dg

    unknown = [c for c in codes if c.upper() not in dg.CODES]
    if unknown:
        raise click.BadParameter(f"unknown code(s) {', '.join(unknown)}", param_hint="--disable")


def require_trace(what: str) -> None:
    """The `trace` extra (rosbags, numpy, matplotlib) is installed, or exit 2 saying so."""
    try:
        import matplotlib  # noqa: F401
        import numpy  # noqa: F401
        import rosbags  # noqa: F401
    except ModuleNotFoundError as err:
        fail(f"{what} needs {err.name}: pip install 'swarmgen[trace]'")


def check_record(record: Path | None) -> None:
    """--record names a new directory and the trace extra is there, checked before anything
    runs: on failure nothing is written."""
    if record is not None:
        console.check_new_directory(record, "--record")
        require_trace("--record")


MODEL = click.argument("model", type=PATH)
FORMAT = click.option(
    "--format",
    "fmt",
    type=click.Choice(["text", "json", "sarif"]),
    default="text",
    show_default=True,
    help="How diagnostics are printed (SARIF 2.1.0 for code-scanning tools).",
)
STRICT = click.option("--strict", is_flag=True, help="Treat warnings as errors.")
STORAGE = click.option(
    "--storage",
    type=click.Choice(["mcap", "sqlite3"]),
    default="mcap",
    show_default=True,
    help="Bag storage for --record.",
)
DISABLE = click.option(
    "--disable",
    "disabled",
    multiple=True,
    metavar="CODE",
    help="Do not report this diagnostic code (repeatable), e.g. --disable SG205.",
)


def _interface_dirs(
    ctx: click.Context, param: click.Parameter, value: tuple[Path, ...]
) -> tuple[Path, ...]:
    """Every `--interfaces` value must be a directory: otherwise one line and exit 2."""
    for directory in value:
        if not directory.is_dir():
            fail(f"--interfaces {console.shown(directory)}: not a directory")
    return value


INTERFACES = click.option(
    "--interfaces",
    "interfaces",
    multiple=True,
    metavar="DIR",
    type=PATH,
    callback=_interface_dirs,
    help="A directory of ROS interface definitions (pkg/msg|srv|action/Name.*) searched after "
    "the installed packages (repeatable; docs/ros2.md).",
)


def record_options(help_text: str) -> Callable[[Callable[P, R]], Callable[P, R]]:
    """`--record DIR` (described by `help_text`) and `--storage`, for replay and simulate."""

    def decorate(command: Callable[P, R]) -> Callable[P, R]:
        """The command with both options, --record first in its help."""
        return click.option("--record", type=PATH, help=help_text)(STORAGE(command))

    return decorate
