"""`swarmgen optimize`: an optuna study over the simulator's sweep parameters, stored in a
database, with its best point written back as a model variant (docs/simulate.md,
"Optimisation")."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from swarmgen import console
from swarmgen.commands.common import MODEL, PATH, guarded

if TYPE_CHECKING:
    import optuna

    from swarmgen.ir.nodes import Model
    from swarmgen.sim.optimize import Study
    from swarmgen.sim.scenario import Scenario

STUDY_DB = "study.db"  # the default SQLite database, in the output directory


@click.command()
@MODEL
@click.option(
    "--space", "space", multiple=True, required=True, metavar="NAME=LOW:HIGH|NAME=A,B,...",
    help="A parameter to optimise (repeatable), named as for simulate --param: UAV.count=1:8 "
    "(integers), stop_level=0.5:1.0 (reals), allocation=paired,nearest (choices).",
)  # fmt: skip
@click.option(
    "--objective", "objective", multiple=True, required=True, metavar="[minimize|maximize] EXPR",
    help="What to optimise over each trial's runs, e.g. 'minimize mean(rescue_100%)'; twice for "
    "two objectives (NSGA-II).",
)  # fmt: skip
@click.option(
    "--scenario", default="coverage", show_default=True, metavar="coverage|sar|PATH",
    help="The scenario every trial runs (its member and target sweeps included).",
)  # fmt: skip
@click.option("--reps", type=click.IntRange(1, 10_000), help="Repetitions per configuration.")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1),
              help="Seeds the runs and the sampler (default: the scenario's seed): the same "
              "seed gives the same study.")  # fmt: skip
@click.option("--trials", type=click.IntRange(1, 100_000), default=20, show_default=True,
              help="Finished trials the study should have (a resumed study runs the rest).")  # fmt: skip
@click.option("--parallel", type=click.IntRange(1, 256), default=1, show_default=True,
              help="Trials in flight at once: asked together, their runs one sweep through the "
              "executor (the study then depends on the seed and this number).")  # fmt: skip
@click.option(
    "--sampler", type=click.Choice(["tpe", "cmaes", "nsga2"]), default=None,
    help="tpe (default, one objective), cmaes (one objective) or nsga2 (default for two).",
)  # fmt: skip
@click.option("--storage", "storage", metavar="URL",
              help=f"An SQLAlchemy URL for the study (default: sqlite:///OUTPUT/{STUDY_DB}).")  # fmt: skip
@click.option("--study-name", default="swarmgen", show_default=True, help="The study's name.")
@click.option("--cluster", metavar="tcp://HOST:PORT|local:N",
              help="Run each trial's repetitions on a Dask scheduler (or a local Dask cluster).")  # fmt: skip
@click.option("-o", "--output", type=PATH, required=True,
              help="Write best.json, trials.csv, figures and the best variant here.")  # fmt: skip
@guarded
def optimize(
    model: Path, space: tuple[str, ...], objective: tuple[str, ...], scenario: str,
    reps: int | None, seed: int | None, trials: int, parallel: int, sampler: str | None,
    storage: str | None,
    study_name: str, cluster: str | None, output: Path,
) -> None:  # fmt: skip
    """Search MODEL's parameters for the best value of the objectives over simulated runs."""
    from swarmgen.sim import optimize as opt

    started = time.perf_counter()
    if len(objective) > 2:
        raise click.UsageError("--objective: one or two objectives")
    chosen_sampler = sampler or ("nsga2" if len(objective) == 2 else "tpe")
    spec, validated = _prepare(model, space, objective, scenario, reps, seed)
    seed = spec.scenario.seed
    opt.make_sampler(chosen_sampler, seed, 0, len(objective))  # a bad pairing: before any trial
    _claim(output)
    url = storage or f"sqlite:///{(output / STUDY_DB).resolve()}"
    executor = None
    if cluster is not None:
        from swarmgen.sim.executors import connect

        executor = connect(cluster)
    spec.executor = executor
    try:
        study = opt.run_study(spec, url, study_name, chosen_sampler, seed, trials, parallel)
    finally:
        if executor is not None:
            executor.close()
    _write(study, spec, validated, output)
    best = _summary(study)
    click.echo(
        f"swarmgen: {console.shown(model)} -> {console.shown(output)}: {len(study.trials)} "
        f"trial(s) in {time.perf_counter() - started:.1f} s; {best}",
        err=True,
    )


def _prepare(
    model: Path, space: tuple[str, ...], objective: tuple[str, ...], scenario: str,
    reps: int | None, seed: int | None,
) -> tuple[Study, Model]:  # fmt: skip
    """The study's parts, every one checked (space, objectives, scenario) before any trial."""
    from swarmgen import diagnostics as dg
    from swarmgen import pipeline
    from swarmgen.ir.query import composition
    from swarmgen.sim import objectives as obj
    from swarmgen.sim import optimize as opt
    from swarmgen.sim import params
    from swarmgen.sim import scenario as sim_scenario
    from swarmgen.sim.scenario import SimulationError

    dims = [opt.parse_space(item) for item in space]
    goals = [obj.parse(item) for item in objective]
    base: Scenario = sim_scenario.load(scenario).with_overrides({}, None, reps, seed)
    for goal in goals:
        obj.check(goal, base)
    validation = pipeline.validate(model)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        raise SimulationError(dg.refusal_line(model, validation.diagnostics))
    types = [t.name for t in validation.model.member_types if t.machine]
    defaults = composition(validation.model)
    sim_scenario.check(base, types, defaults)
    names = params.names_of(validation.model, validation.charts)

    def check(variant_scenario: Scenario) -> None:
        sim_scenario.check(variant_scenario, types, defaults)

    opt.check_space(dims, base, names, check)
    return opt.Study(model, base, dims, goals, names), validation.model


def _claim(output: Path) -> None:
    """Make `output` a swarmgen output tree before the database goes into it (a directory
    holding an unlisted file and no manifest would be refused when the results are written)."""
    from swarmgen import outtree
    from swarmgen.sim.run import write_outputs

    outtree.preflight(output, "optimize")
    if not (output / outtree.MANIFEST).is_file():
        write_outputs({}, output, "", "optimize")


def _write(study: optuna.Study, spec: Study, model: Model, output: Path) -> None:
    """best.json, trials.csv, the figures and the best variant, replaced atomically."""
    from swarmgen.sim import optimize_out as out
    from swarmgen.sim import params
    from swarmgen.sim.run import write_outputs

    texts = [o.text for o in spec.objectives]
    names = [d.name for d in spec.space]
    files = {"trials.csv": out.trials_csv(study, names, texts).encode()}
    files.update(out.figures(study, texts))
    notes: list[str] = []
    best = out.best_trials(study)
    if best:
        point = tuple((n, best[0].params[n]) for n in names)
        variant = params.apply(spec.scenario, point, spec.names, "best")
        variant_files, notes = out.variant_files(spec.model, model, variant)
        files.update(variant_files)
    else:
        notes.append("no trial completed")
    files["best.json"] = out.best_json(study, texts, notes)
    write_outputs(files, output, spec.model.name, "optimize")


def _summary(study: optuna.Study) -> str:
    """The best value(s) in one phrase."""
    from swarmgen.sim import optimize_out as out

    best = out.best_trials(study)
    if not best:
        return "no trial completed"
    if len(best) == 1:
        return f"best {best[0].values} at {best[0].params}"
    return f"{len(best)} Pareto-optimal trial(s)"
