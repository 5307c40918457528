"""Detailed runs as the abstract level's results: the same `RunResult`s, tables and figures.

Times are reported in abstract ticks (`tick_s` simulated seconds each) from the clock origin
(the scenario's `clock_origin` event), so the two levels' tables compare cell by cell;
results.json adds each run's simulated seconds, wall seconds, real-time factor and faults.
A run that failed (a process died, the wall limit, a partial result) keeps what it measured up
to then, with the failure among its errors and the reason `failed`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from swarmgen.sim.batch import Config, RunResult
from swarmgen.sim.detailed.params import DetailedParams
from swarmgen.sim.detailed.run import DetailedRun
from swarmgen.sim.scenario import Scenario

REASONS = {"coverage": "coverage", "all_rescued": "rescued", "time_limit": "max_ticks"}


def run_result(
    run: DetailedRun, config: Config, scenario: Scenario, params: DetailedParams
) -> RunResult:
    """One detailed run as a `RunResult` (times in ticks from the clock origin)."""
    result = run.result or {}
    origin = params.seconds(scenario.origin_tick())

    def ticks(seconds: float | None) -> float | None:
        return None if seconds is None else (seconds - origin) / params.tick_s

    samples = result.get("samples", [])
    dt = float(result.get("dt", params.dt))
    coverage = [ticks(_first_at(samples, level, dt)) for level in scenario.coverage_levels]
    targets = result.get("targets", {})
    found, rescued = [], []
    for number in range(1, config.targets + 1):
        target = targets.get(str(number), {})
        found.append(ticks(target.get("first_detection")))
        rescued.append(ticks(target.get("rescued")))
    reason = "failed" if run.failure else REASONS.get(str(result.get("reason")), "max_ticks")
    return RunResult(
        config=run.config,
        rep=run.rep,
        end_tick=int(ticks(float(result.get("sim_s", origin))) or 0),
        reason=reason,
        coverage=coverage,  # ticks of a continuous clock: floats
        coverage_final=float(result.get("coverage", 0.0)),
        found=found,
        rescued=rescued,
        events=0,
        errors=[run.failure] if run.failure else [],
    )


def _first_at(samples: Sequence[Sequence[float]], level: float, dt: float) -> float | None:
    """The simulated second of the first sample at or above a coverage level."""
    for k, share in samples:
        if share >= level - 1e-12:
            return k * dt
    return None


def run_record(run: DetailedRun) -> dict[str, Any]:
    """What results.json keeps of a detailed run beyond its `RunResult`."""
    result = run.result or {}
    wall = result.get("wall", {})
    return {
        "config": run.config,
        "rep": run.rep,
        "failure": run.failure,
        "sim_s": result.get("sim_s"),
        "wall_s": round(run.wall_s, 3),
        "world_wall_s": wall.get("wall_s"),
        "real_time_factor": wall.get("real_time_factor"),
        "timeouts": result.get("timeouts"),
        "stale": result.get("stale"),
        "logs": run.logs if run.failure else {},
    }
