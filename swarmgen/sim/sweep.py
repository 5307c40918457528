"""Sweeps: every configuration of a scenario, its repetitions spread over processes."""

from __future__ import annotations

import itertools
import math
import multiprocessing
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from swarmgen.sim.batch import Batch, Config, RunResult
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


def _job(
    machines: Machines,
    scenario: Scenario,
    config: Config,
    index: int,
    reps: list[int],
    record: Path | None = None,
    storage: str = "mcap",
) -> list[RunResult]:
    results = Batch(machines, scenario, config, reps, record=record, storage=storage).run_all()
    for result in results:
        result.config = index
    return results


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


def simulate(
    machines: Machines,
    scenario: Scenario,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    record: Path | None = None,
    storage: str = "mcap",
) -> Simulation:
    """Run every configuration `scenario.reps` times; `progress(done, total)` after each batch.
    `record`: a new directory to write one bag per run into (`storage`: mcap or sqlite3)."""
    configs = configurations(machines, scenario)
    parts = max(1, math.ceil(workers / len(configs))) if workers > 1 else 1
    jobs = [(i, chunk) for i, _ in enumerate(configs) for chunk in _chunks(scenario.reps, parts)]
    total = len(configs) * scenario.reps
    done = 0
    results: list[RunResult] = []
    if progress is not None:
        progress(0, total)
    if workers <= 1 or len(jobs) == 1:
        for index, reps in jobs:
            results += _job(machines, scenario, configs[index], index, reps, record, storage)
            done += len(reps)
            if progress is not None:
                progress(done, total)
    else:
        methods = multiprocessing.get_all_start_methods()
        for machine in machines.members:  # built once here: forked workers inherit the charts
            build_chart(machine)
        context = multiprocessing.get_context("fork" if "fork" in methods else None)
        with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
            futures = {
                pool.submit(
                    _job, machines, scenario, configs[index], index, reps, record, storage
                ): len(reps)
                for index, reps in jobs
            }
            for future in as_completed(futures):
                results += future.result()
                done += futures[future]
                if progress is not None:
                    progress(done, total)
    results.sort(key=lambda r: (r.config, r.rep))
    return Simulation(machines, scenario, configs, results)
