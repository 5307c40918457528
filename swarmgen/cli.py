"""The `swarmgen` command line: thin click commands over `swarmgen.pipeline`.

Exit codes: 0 clean (warnings allowed), 1 model errors or `--check` drift, 2 unreadable input or
misuse, 3 an internal error (a bug in swarmgen: please report it).
"""

from __future__ import annotations

import difflib
import json
import os
import sys
import traceback
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, ParamSpec, TypeVar

import click

from swarmgen import __version__, console, pipeline
from swarmgen import diagnostics as dg
from swarmgen.backends import SCXML
from swarmgen.backends import names as backend_names
from swarmgen.backends import runnable as runnable_outputs
from swarmgen.errors import SwarmgenError

if TYPE_CHECKING:
    from swarmgen.sim.scenario import Scenario

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
        except SwarmgenError as err:  # every user error, mapped to its exit code here only
            _fail(str(err), err.exit_code)
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
    return os.environ.get("SWARMGEN_DEBUG", "") not in {"", "0"}


def _fail(message: str, code: int = dg.ExitCode.INPUT_ERROR) -> NoReturn:
    """A user error: one line on stderr, exit `code` (2 unless the error says otherwise)."""
    click.echo(f"swarmgen: error: {dg.one_line(' '.join(message.splitlines()))}", err=True)
    sys.exit(code)


class _PathType(click.Path):
    """A path argument: an empty string is refused (Path("") would silently be ".")."""

    def convert(
        self,
        value: str | os.PathLike[str],
        param: click.Parameter | None,
        ctx: click.Context | None,
    ) -> str | bytes | os.PathLike[str]:
        if not os.fspath(value):
            self.fail("an empty path; give a file or directory name", param, ctx)
        return super().convert(value, param, ctx)


PATH = _PathType(path_type=Path)


class _OutputChoice(click.Choice[str]):
    """One of the registry's outputs (`swarmgen.backends`); a wrong name gets the close ones."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        """The name itself, or a usage error naming the choices and the closest of them."""
        try:
            return str(super().convert(value, param, ctx))
        except click.BadParameter:
            close = difflib.get_close_matches(str(value), list(self.choices), n=1)
            also = f"; did you mean '{close[0]}'?" if close else ""
            choices = ", ".join(map(str, self.choices))
            self.fail(f"unknown backend '{value}'; choose from {choices}{also}", param, ctx)


def _emit_diagnostics(diagnostics: list[dg.Diagnostic], fmt: str, *, to_stdout: bool) -> None:
    if fmt == "json":
        text = dg.render_json(diagnostics)
    elif fmt == "sarif":
        text = dg.render_sarif(diagnostics, __version__)
    else:
        text = dg.render_text(diagnostics)
    if text:
        click.echo(text, nl=False, err=not to_stdout)


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
    click.echo(f"swarmgen: {console.shown(model)}: {dg.summary_line(diagnostics)}", err=True)
    sys.exit(dg.exit_code_for(diagnostics))


def _check_codes(codes: tuple[str, ...]) -> None:
    unknown = [c for c in codes if c.upper() not in dg.CODES]
    if unknown:
        raise click.BadParameter(f"unknown code(s) {', '.join(unknown)}", param_hint="--disable")


@main.command(name="compile")
@MODEL
@click.option("-o", "--output", type=PATH, required=True, help="Output directory.")
@click.option("--check", is_flag=True, help="Write nothing; exit 1 with a diff if OUTPUT is stale.")
@click.option(
    "--backend",
    "backends",
    multiple=True,
    metavar="NAME",
    type=_OutputChoice(backend_names()),
    help=f"Only these outputs besides SCXML (repeatable: {', '.join(backend_names(SCXML))}; "
    "`scxml` alone: SCXML only). Default: all.",
)
@click.option(
    "--templates",
    type=_PathType(path_type=Path, exists=True, file_okay=False),
    help="A directory of Jinja2 templates used before the shipped ones (same relative paths).",
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
    templates: Path | None,
    fmt: str,
    strict: bool,
    disabled: tuple[str, ...],
) -> None:
    """Compile MODEL into OUTPUT (SCXML and every backend), replacing it atomically."""
    _check_codes(disabled)
    result = pipeline.compile_model(model, backends=backends or None, templates=templates)
    diagnostics = dg.apply_options(result.validation.diagnostics, strict=strict, disabled=disabled)
    _emit_diagnostics(diagnostics, fmt, to_stdout=False)
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
        difference = pipeline.diff_tree(result.files, output)
        if difference:
            click.echo(difference, nl=False)
            click.echo(
                f"swarmgen: {console.shown(output)} is stale; run: swarmgen compile "
                f"{console.shown(model)} -o {console.shown(output)}",
                err=True,
            )
            sys.exit(dg.ExitCode.MODEL_ERRORS)
        click.echo(f"swarmgen: {console.shown(output)} is up to date", err=True)
        return
    pipeline.write_tree(result.files, output)
    count = sum(1 for p in result.files if p.suffix == ".scxml")
    click.echo(
        f"swarmgen: {console.shown(model)} -> {console.shown(output)}: {count} SCXML document(s); "
        f"{dg.summary_line(diagnostics)}",
        err=True,
    )


@main.command()
@click.option(
    "-o",
    "--output",
    type=PATH,
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
        try:
            current = target.read_bytes() if target.is_file() else b""
        except OSError as err:
            _fail(f"{console.shown(target)}: cannot read: {err.strerror}")
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


@main.command()
@MODEL
@click.option("--member", required=True, help="Member type to run.")
@click.option("--script", "scenario", type=PATH, required=True, help="Scenario (JSON).")
@click.option(
    "--backend", type=_OutputChoice(runnable_outputs()), default="asyncio", show_default=True,
    help="Where to run: the generated asyncio, smach or rclpy code, or the SCXML in Qt SCXML.",
)  # fmt: skip
@click.option(
    "--record", type=PATH,
    help="Also write the trace as a ROS 2 bag into this new directory (docs/trace.md).",
)  # fmt: skip
@STORAGE
@_guarded
def replay(
    model: Path, member: str, scenario: Path, backend: str, record: Path | None, storage: str
) -> None:
    """Run one member of MODEL against a scenario; print its trace as JSON lines."""
    from swarmgen import replay as replaying

    if record is not None:  # checked before anything runs: on failure nothing is written
        console.check_new_directory(record, "--record")
        _require_trace("--record")
    _, steps = replaying.load_scenario(scenario)
    trace = replaying.replay(model, member, steps, backend)
    for line in trace:
        click.echo(json.dumps(line, sort_keys=True))
    sys.stdout.flush()  # a full stdout is reported before the bag is written
    if record is not None:
        _record_replay(record, member, steps, trace, storage)


def _record_replay(
    path: Path, member: str, steps: list[dict[str, object]], trace: list[dict[str, object]],
    storage: str,
) -> None:  # fmt: skip
    from swarmgen.trace.recorder import record_replay

    record_replay(path, member, steps, trace, storage=storage)
    shown = console.shown(path)
    click.echo(f"swarmgen: recorded {len(steps)} step(s) into {shown} ({storage})", err=True)


def _require_trace(what: str) -> None:
    """The `trace` extra (rosbags, numpy, matplotlib) is installed, or exit 2 saying so."""
    try:
        import matplotlib  # noqa: F401
        import numpy  # noqa: F401
        import rosbags  # noqa: F401
    except ModuleNotFoundError as err:
        _fail(f"{what} needs {err.name}: pip install 'swarmgen[trace]'")


@main.command(name="graph")
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
@_guarded
def graph_(model: Path, member: str | None, diagram_format: str, output: Path | None) -> None:
    """Draw MODEL's state machines (one diagram each) and its swarm composition."""
    from swarmgen.graph import GraphError

    if diagram_format == "svg" and output is None:
        raise click.UsageError("--format svg writes files: give -o DIR")
    try:
        result = pipeline.graph_model(model, diagram_format, member)
    except GraphError as err:  # printed as it is, not escaped to one line like other errors
        click.echo(f"swarmgen: error: {err}", err=True)
        sys.exit(dg.ExitCode.INPUT_ERROR)
    diagnostics = result.validation.diagnostics
    if not result.files:
        _emit_diagnostics(diagnostics, "text", to_stdout=False)
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


@main.command()
@click.argument("bags", nargs=-1, required=True, type=PATH)
@click.option(
    "--events", help="Comma-separated event names, shown in this order (default: all of them, "
    "in mission order).",
)  # fmt: skip
@click.option(
    "--plot", "plot_path", type=PATH,
    help="Write a horizontal box plot (.png or .svg).",
)  # fmt: skip
@click.option("--csv", "csv_path", type=PATH, help="Write the statistics as CSV.")
@click.option(
    "--alias", "aliases", multiple=True, metavar="OLD=NEW",
    help="Rename an event while reading (repeatable), e.g. --alias targetDone=targetRescued.",
)  # fmt: skip
@_guarded
def timeline(
    bags: tuple[Path, ...],
    events: str | None,
    plot_path: Path | None,
    csv_path: Path | None,
    aliases: tuple[str, ...],
) -> None:
    """Each event's time since launch over many runs (one run per bag; a directory holds bags).

    Prints lower whisker, quartiles, median, upper whisker (1.5 IQR) and outliers in seconds,
    and the number of runs in which the event occurred; see docs/trace.md.
    """
    renames: dict[str, str] = {}
    for alias in aliases:
        old, sep, new = alias.partition("=")
        if not sep or not old.strip() or not new.strip():
            raise click.BadParameter(f"{alias!r} is not OLD=NEW", param_hint="--alias")
        renames[old.strip()] = new.strip()
    if plot_path is not None and plot_path.suffix.lower() not in (".png", ".svg"):
        shown = console.shown(plot_path)
        raise click.BadParameter(f"{shown}: use a .png or .svg file", param_hint="--plot")
    _require_trace("timeline")
    from swarmgen.trace import timeline as timelines
    from swarmgen.trace.bag import TraceError
    from swarmgen.trace.reader import read_events

    made: list[Path] = []  # the output files' directories, checked (made) before reading
    for path, option in ((csv_path, "--csv"), (plot_path, "--plot")):
        made += console.check_file(path, option) if path is not None else []
    try:
        runs = read_events(bags, renames)
    except TraceError:
        console.remove_made(made)
        raise
    chosen = [e.strip() for e in events.split(",") if e.strip()] if events else None
    result = timelines.build(runs, chosen)
    picture = timelines.render(result, plot_path.suffix.lower()[1:]) if plot_path else b""
    click.echo(timelines.table(result), nl=False)
    sys.stdout.flush()
    if csv_path is not None:
        console.write_file(csv_path, timelines.csv_text(result).encode(), "--csv")
    if plot_path is not None:
        console.write_file(plot_path, picture, "--plot")
    click.echo(f"swarmgen: {len(runs)} run(s), {len(result.events)} event(s)", err=True)


@main.command()
@MODEL
@click.option(
    "--scenario", default="coverage", show_default=True, metavar="coverage|sar|PATH",
    help="A shipped scenario (the paper's two) or a scenario file (JSON); see docs/simulate.md.",
)  # fmt: skip
@click.option(
    "--members", "members", multiple=True, metavar="TYPE=N[,N...]",
    help="Member counts to sweep, e.g. UAV=1,2,4,8 (repeatable); overrides the scenario.",
)  # fmt: skip
@click.option("--targets", metavar="N[,N...]", help="Target counts to sweep, e.g. 1,2,4,8,16,32.")
@click.option("--reps", type=click.IntRange(1, 10_000), help="Repetitions per configuration.")
@click.option(
    "--seed", type=click.IntRange(0, 2**63 - 1), help="Random seed (same seed, same numbers)."
)
@click.option(
    "--workers", type=click.IntRange(1, 256), default=1, show_default=True,
    help="Processes to spread configurations over (results do not depend on it).",
)  # fmt: skip
@click.option(
    "-o", "--output", type=PATH,
    help="Write tables (CSV), results.json and figures (PNG, SVG) here, replaced atomically.",
)  # fmt: skip
@click.option(
    "--record", type=PATH,
    help="Also write one ROS 2 bag per run, DIR/<configuration>-<rep>, into this new directory.",
)  # fmt: skip
@STORAGE
@_guarded
def simulate(
    model: Path,
    scenario: str,
    members: tuple[str, ...],
    targets: str | None,
    reps: int | None,
    seed: int | None,
    workers: int,
    output: Path | None,
    record: Path | None,
    storage: str,
) -> None:
    """Run MODEL's compiled behaviours in the paper's abstract world and report the statistics."""
    import time

    from swarmgen.sim import run as sim_run
    from swarmgen.sim import scenario as sim_scenario

    if record is not None:  # checked before anything runs: on failure nothing is written
        console.check_new_directory(record, "--record")
        _require_trace("--record")

    started = time.perf_counter()
    chosen = sim_scenario.load(scenario)
    counts: dict[str, list[int]] = {}
    for item in members:
        counts.update(sim_scenario.parse_members(item))
    target_counts = sim_scenario.parse_counts(targets, "--targets") if targets else None
    chosen = chosen.with_overrides(counts, target_counts, reps, seed)
    _check_sweep(model, chosen)
    progress = _ProgressBar(started)

    sim, files = sim_run.simulate_model(model, chosen, output, workers, progress, record, storage)
    coverage = files.get("coverage.csv", b"").decode()
    if output is None:
        click.echo(coverage, nl=False)
        for name in ("search.csv", "rescue.csv"):
            if name in files:
                click.echo(f"\n# {name}\n{files[name].decode()}", nl=False)
    errors = sum(len(r.errors) for r in sim.runs)
    unfinished = sum(1 for r in sim.runs if r.reason in ("max_ticks", "stalled"))
    where = f" -> {console.shown(output)}" if output is not None else ""
    click.echo(
        f"swarmgen: {console.shown(model)}{where}: {len(sim.runs)} runs of "
        f"{len(sim.configs)} configuration(s) in {time.perf_counter() - started:.1f} s; "
        f"{unfinished} did not reach the stop "
        f"condition; {errors} behaviour error(s)",
        err=True,
    )
    if record is not None:
        click.echo(f"swarmgen: recorded {len(sim.runs)} run(s) into {record} ({storage})", err=True)


class _ProgressBar:
    """simulate's progress on stderr: redrawn in place on a terminal, else one line per tenth."""

    WIDTH = 30

    def __init__(self, started: float) -> None:
        self.started = started
        self.shown = -1

    def __call__(self, done: int, total: int) -> None:
        import time

        filled = self.WIDTH * done // max(1, total)
        tenth = 10 * done // max(1, total)
        if sys.stderr.isatty() or tenth != self.shown or done == total:
            self.shown = tenth
            end = "" if sys.stderr.isatty() and done < total else "\n"
            sys.stderr.write(
                f"\rswarmgen: simulate [{'#' * filled}{'.' * (self.WIDTH - filled)}] "
                f"{done}/{total} runs {time.perf_counter() - self.started:.1f} s{end}"
            )
            sys.stderr.flush()


def _check_sweep(model: Path, chosen: Scenario) -> None:
    """The sweep's limits and the member types of --members, before anything runs (a model
    with errors is reported by the simulation itself)."""
    from swarmgen.ir.query import composition
    from swarmgen.sim import scenario as sim_scenario

    validation = pipeline.validate(model)
    if validation.model is not None and not dg.has_errors(validation.diagnostics):
        types = [t.name for t in validation.model.member_types if t.machine]
        sim_scenario.check(chosen, types, composition(validation.model))


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
