"""`swarmgen simulate`: a model's compiled behaviours in the paper's abstract world, swept over
member and target counts, with its statistics, tables and figures."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from swarmgen import console
from swarmgen.commands.common import MODEL, PATH, check_record, guarded, record_options

if TYPE_CHECKING:
    from swarmgen.pipeline import Validation
    from swarmgen.sim.params import Variant
    from swarmgen.sim.scenario import Scenario

# The pipeline and the diagnostics are imported in the command functions: `swarmgen --help` and
# `swarmgen simulate --help` must not load the compiler (docs/performance.md).


@click.command()
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
    "--param", "param", multiple=True, metavar="NAME=V1,V2,...|NAME=START:STOP:STEP",
    help="Sweep a parameter (repeatable; every combination): UAV.count, UAV.data.NAME, targets, "
    "seed, world.view, UAV.camera.fovRadius, timing.KEY, placement.TYPE.spacing, ...; see "
    "docs/simulate.md.",
)  # fmt: skip
@click.option(
    "--sweep", "sweep_file", type=PATH,
    help="A sweep file (JSON, or TOML by extension): {\"factorial\": {NAME: [values]}} and/or "
    "{\"design\": [{NAME: value, ...}, ...]}.",
)  # fmt: skip
@click.option(
    "--cluster", metavar="tcp://HOST:PORT|local:N",
    help="Run on a Dask scheduler (or local:N, a local Dask cluster of N worker processes); "
    "the same seed gives the same files as local runs.",
)  # fmt: skip
@record_options(
    "Also write one ROS 2 bag per run, DIR/<configuration>-<rep>, into this new directory."
)
@click.option(
    "--level", type=click.Choice(["abstract", "detailed"]), default="abstract",
    show_default=True,
    help="abstract: the grid world in-process; detailed: the generated rclpy swarm, "
    "unmodified, against the behaviour library in the continuous world on ROS 2 "
    "(docs/detailed.md).",
)  # fmt: skip
@click.option(
    "--keep-runs", type=PATH,
    help="(detailed) Keep every run's world and servers files and process logs in this new "
    "directory.",
)  # fmt: skip
@guarded
def simulate(
    model: Path,
    scenario: str,
    members: tuple[str, ...],
    targets: str | None,
    reps: int | None,
    seed: int | None,
    workers: int,
    param: tuple[str, ...],
    sweep_file: Path | None,
    cluster: str | None,
    output: Path | None,
    record: Path | None,
    storage: str,
    level: str,
    keep_runs: Path | None,
) -> None:
    """Run MODEL's compiled behaviours in the paper's abstract world (or, with `--level
    detailed`, the generated ROS 2 swarm in the continuous world) and report the statistics."""
    from swarmgen import diagnostics as dg
    from swarmgen.sim import run as sim_run

    check_record(record)
    if level == "abstract" and keep_runs is not None:
        raise click.UsageError("--keep-runs is for --level detailed")
    _check_study_options(level, param, sweep_file, cluster, workers, record)
    started = time.perf_counter()
    chosen = _sweep(scenario, members, targets, reps, seed)
    variants, validation = _check_sweep(model, chosen, param, sweep_file)
    progress = _ProgressBar(started)
    if level == "detailed":
        from swarmgen.sim.detailed.main import simulate_detailed

        sim, files = simulate_detailed(
            model, chosen, output, workers, progress, keep_runs, record, storage
        )
    else:
        executor = None
        if cluster is not None:  # Dask is imported only here
            from swarmgen.sim.executors import connect

            executor = connect(cluster)
        try:
            sim, files = sim_run.simulate_model(
                model, chosen, output, workers, progress, record, storage,
                variants=variants, executor=executor, validation=validation,
            )  # fmt: skip
        finally:
            if executor is not None:
                executor.close()
    if output is None:
        _print_tables(files)
    errors = sum(len(r.errors) for r in sim.runs)
    unfinished = sum(1 for r in sim.runs if r.reason in ("max_ticks", "stalled", "failed"))
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
    failed = [r for r in sim.runs if r.reason == "failed"]
    for run in failed[:10]:
        label = sim.configs[run.config].label()
        click.echo(f"swarmgen: run {run.rep} of {label} failed: {run.errors[0]}", err=True)
    if failed:  # results were written, with these runs marked failed
        sys.exit(int(dg.ExitCode.MODEL_ERRORS))


def _sweep(
    scenario: str, members: tuple[str, ...], targets: str | None, reps: int | None,
    seed: int | None,
) -> Scenario:  # fmt: skip
    """The chosen scenario with the command line's member and target counts, reps and seed."""
    from swarmgen.sim import scenario as sim_scenario

    chosen = sim_scenario.load(scenario)
    counts: dict[str, list[int]] = {}
    for item in members:
        counts.update(sim_scenario.parse_members(item))
    target_counts = sim_scenario.parse_counts(targets, "--targets") if targets else None
    return chosen.with_overrides(counts, target_counts, reps, seed)


def _print_tables(files: dict[str, bytes]) -> None:
    """Without -o: the coverage table on stdout, then the search and rescue tables if any."""
    click.echo(files.get("coverage.csv", b"").decode(), nl=False)
    for name in ("search.csv", "rescue.csv"):
        if name in files:
            click.echo(f"\n# {name}\n{files[name].decode()}", nl=False)


class _ProgressBar:
    """simulate's progress on stderr: redrawn in place on a terminal, else one line per tenth."""

    WIDTH = 30

    def __init__(self, started: float) -> None:
        """A bar for a simulation that started at `started` (time.perf_counter)."""
        self.started = started
        self.shown = -1

    def __call__(self, done: int, total: int) -> None:
        """Show that `done` of `total` runs are finished."""
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


def _check_study_options(
    level: str, param: tuple[str, ...], sweep_file: Path | None, cluster: str | None,
    workers: int, record: Path | None,
) -> None:  # fmt: skip
    """--param, --sweep and --cluster: only at the abstract level, without --workers/--record."""
    if level == "detailed" and (param or sweep_file is not None or cluster is not None):
        raise click.UsageError("--param, --sweep and --cluster are for --level abstract")
    if cluster is not None and workers > 1:
        raise click.UsageError("--workers is for local runs; a --cluster has its own workers")
    if cluster is not None and record is not None:
        raise click.UsageError("--record writes on this machine: it cannot go with --cluster")


def _check_sweep(
    model: Path, chosen: Scenario, param: tuple[str, ...], sweep_file: Path | None
) -> tuple[list[Variant] | None, Validation]:
    """The sweep's limits, the member types of --members and every point of --param/--sweep,
    before anything runs (a model with errors is reported by the simulation itself); and the
    model's validation, which the simulation reuses."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline
    from swarmgen.ir.query import composition
    from swarmgen.sim import params
    from swarmgen.sim import scenario as sim_scenario
    from swarmgen.sim.limits import MAX_RUNS

    axes = [params.parse_option(item) for item in param]
    rows = params.load_file(sweep_file) if sweep_file is not None else [()]
    points = params.product(axes, rows) if axes or sweep_file is not None else None
    validation = pipeline.validate(model)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        return (None if points is None else []), validation  # refused by the run
    types = [t.name for t in validation.model.member_types if t.machine]
    defaults = composition(validation.model)
    sim_scenario.check(chosen, types, defaults)
    if points is None:
        return None, validation
    where = console.shown(sweep_file) if sweep_file is not None else "--param"
    names = params.names_of(validation.model, validation.charts)
    variants = params.variants(chosen, points, names, where)
    for variant in variants:
        sim_scenario.check(variant.scenario, types, defaults)
    runs = len(variants) * _runs(chosen, types, defaults)
    if runs > MAX_RUNS:
        raise params.ParamError(
            f"{runs:,} runs ({len(variants):,} sweep points): more than the limit of "
            f"{MAX_RUNS:,} (docs/simulate.md)"
        )
    return variants, validation


def _runs(chosen: Scenario, types: list[str], defaults: dict[str, int]) -> int:
    """Runs of one sweep point, at most: its member sweeps x target counts x repetitions."""
    sizes = [len(s) for k in types if isinstance(s := chosen.members.get(k), list)]
    combos = 1
    for size in sizes:
        combos *= size
    return combos * len(chosen.targets) * chosen.reps
