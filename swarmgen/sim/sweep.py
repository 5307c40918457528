"""Sweeps: every configuration of a scenario (or of each point of a parameter sweep), its
repetitions cut into jobs and run through an executor (`sim.executors`)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from swarmgen.records import dataclass
from swarmgen.sim.batch import Batch, Config, RunResult
from swarmgen.sim.executors import Executor, Failure, LocalExecutor
from swarmgen.sim.heap import kept_heap
from swarmgen.sim.machines import Machines, build_chart
from swarmgen.sim.scenario import Scenario, SimulationError


def configurations(machines: Machines, scenario: Scenario) -> list[Config]:
    """Every combination of the swept member counts and target counts, in a stable order."""
    types = machines.types()
    unknown = sorted(set(scenario.members) - set(types))
    if unknown and (set(unknown) & set(scenario.given) or not set(scenario.members) & set(types)):
        # types given on the command line must exist; the scenario's own are ignored as long as
        # it (or the command line) names one the model has
        raise SimulationError(
            f"member type(s) {', '.join(unknown)} not in model {machines.model} "
            f"(it has: {', '.join(types)}); use --members TYPE=N[,N...]"
        )
    swept: dict[str, list[int]] = {}
    follow: dict[str, str] = {}
    for kind in types:
        spec = scenario.members.get(kind)
        if spec is None:
            swept[kind] = [machines.composition.get(kind, 1)]
        elif isinstance(spec, str):
            other = spec[1:]
            if other not in types or isinstance(scenario.members.get(other), str):
                raise SimulationError(f"members.{kind} = '{spec}': no counted member type {other}")
            follow[kind] = other
        else:
            swept[kind] = list(spec)
    order = [k for k in types if k in swept]
    configs = []
    for combo in itertools.product(*(swept[k] for k in order)):
        counts = dict(zip(order, combo, strict=True))
        for kind, other in follow.items():
            counts[kind] = counts[other]
        for targets in scenario.targets:
            configs.append(Config(tuple((k, counts[k]) for k in types), targets))
    return configs


@dataclass(frozen=True)
class Job:
    """Some repetitions of one configuration: what one batch runs (pickled to workers)."""

    machines: Machines
    scenario: Scenario
    config: Config
    index: int
    reps: list[int]
    record: Path | None = None
    storage: str = "mcap"


def run_jobs(jobs: Sequence[Job]) -> list[RunResult]:
    """Run the jobs one after the other: one executor task."""
    results: list[RunResult] = []
    for job in jobs:
        batch = Batch(
            job.machines, job.scenario, job.config, job.reps, record=job.record,
            storage=job.storage,
        )  # fmt: skip
        for result in batch.run_all():
            result.config = job.index
            results.append(result)
    return results


def failed_runs(job: Job, error: str) -> list[RunResult]:
    """The runs of a job that failed twice: present in the results, marked failed."""
    levels, targets = len(job.scenario.coverage_levels), job.config.targets
    return [
        RunResult(
            config=job.index,
            rep=rep,
            end_tick=0,
            reason="failed",
            coverage=[None] * levels,
            coverage_final=0.0,
            found=[None] * targets,
            rescued=[None] * targets,
            events=0,
            errors=[error],
        )
        for rep in job.reps
    ]


def _chunks(reps: int, parts: int) -> Iterator[list[int]]:
    size = math.ceil(reps / max(1, parts))
    for start in range(0, reps, size):
        yield list(range(start, min(reps, start + size)))


@dataclass
class Simulation:
    """A finished sweep: the machines, the scenario, its configurations and every run."""

    machines: Machines
    scenario: Scenario
    configs: list[Config]
    runs: list[RunResult]  # ordered by (config, rep)


# One point of a sweep: the machines it runs (a data parameter changes them), its scenario, and
# the parameters that are columns of their own (sim.params.Variant.columns).
Point = tuple[Machines, Scenario, tuple[tuple[str, Any], ...]]
TASKS_PER_SLOT = 4  # beyond this many jobs per slot, jobs are grouped into fewer tasks


def simulate(
    machines: Machines,
    scenario: Scenario,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    record: Path | None = None,
    storage: str = "mcap",
    *,
    points: Sequence[Point] | None = None,
    executor: Executor | None = None,
) -> Simulation:
    """Run every configuration `scenario.reps` times; `progress(done, total)` after each task.
    `record`: a new directory to write one bag per run into (`storage`: mcap or sqlite3).
    `points`: the sweep's points (default: the scenario alone); `executor`: where the tasks
    run (default: `workers` local processes)."""
    chosen = executor or LocalExecutor(workers)
    owners: list[tuple[Machines, Scenario]] = []
    configs: list[Config] = []
    for owner, point, columns in points or [(machines, scenario, ())]:
        for config in configurations(owner, point):
            configs.append(replace(config, params=columns))
            owners.append((owner, point))
    slots = chosen.slots
    parts = max(1, math.ceil(slots / len(configs))) if slots > 1 else 1
    jobs = [
        Job(*owners[i], config, i, reps, record, storage)
        for i, config in enumerate(configs)
        for reps in _chunks(owners[i][1].reps, parts)
    ]
    tasks = _group(jobs, slots)
    total = sum(len(j.reps) for j in jobs)
    done = 0

    def finished(size: int) -> None:
        nonlocal done
        done += size
        if progress is not None:
            progress(done, total)

    if progress is not None:
        progress(0, total)
    if slots > 1 and isinstance(chosen, LocalExecutor):
        for owner, _ in owners:  # built once here: forked workers inherit the charts
            for machine in owner.members:
                build_chart(machine)
    sizes = [sum(len(j.reps) for j in t) for t in tasks]
    with kept_heap():  # here and in forked workers: rounds reuse their temporaries' pages
        outcomes = chosen.map(run_jobs, tasks, sizes, finished)
    results: list[RunResult] = []
    for task, outcome in zip(tasks, outcomes, strict=True):
        if isinstance(outcome, Failure):
            results += [r for job in task for r in failed_runs(job, outcome.error)]
        else:
            results += outcome
    results.sort(key=lambda r: (r.config, r.rep))
    return Simulation(machines, scenario, configs, results)


def _group(jobs: list[Job], slots: int) -> list[list[Job]]:
    """One job per task, or, with many more jobs than slots, runs of consecutive jobs (fewer
    tasks keep the per-task overhead of a cluster small against the runs)."""
    if slots <= 1 or len(jobs) <= TASKS_PER_SLOT * slots:
        return [[job] for job in jobs]
    count = TASKS_PER_SLOT * slots
    size = math.ceil(len(jobs) / count)
    return [jobs[i : i + size] for i in range(0, len(jobs), size)]
