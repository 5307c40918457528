"""Throughput of an N-run coverage sweep through the executors: 1 and 2 local workers, and a
2-worker Dask cluster (a LocalCluster of 2 single-threaded worker processes on loopback).

The sweep: the SAR model's UAVs (2 of them) covering a 41 x 41 world to 100 percent, 50
repetitions per point, `--param seed=1..N/50` (N runs in all). Reported: wall time and runs per
second of each, scaling efficiency at 2 workers (t1 / (2 t2)), Dask's overhead per run (extra
worker time per run against 2 local workers: (t_dask - t_local2) * 2 / N), and the round trip
of an empty task on the cluster. The result files of the three are compared byte for byte.

    .venv/bin/python benchmarks/bench_sweep.py [--runs 10000]

Writes benchmarks/results/sweep.json. The machine is shared: the load average is recorded.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.sim import params, stats  # noqa: E402
from swarmgen.sim import scenario as sc  # noqa: E402
from swarmgen.sim.executors import DaskExecutor, Executor, LocalExecutor  # noqa: E402
from swarmgen.sim.machines import compile_machines  # noqa: E402
from swarmgen.sim.sweep import Point, simulate  # noqa: E402

MODEL = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = ROOT / "benchmarks" / "results" / "sweep.json"
REPS = 50


def _noop(value: int) -> int:
    return value


def sweep(runs: int) -> tuple[Any, list[Point]]:
    """The machines and the sweep's points: seeds 1..runs/REPS on a 41 x 41 world."""
    machines = compile_machines(MODEL)
    base = sc.load("coverage").with_overrides({"UAV": [2]}, reps=REPS)
    names = params.Names(("UAV", "UGV"))
    axes: list[tuple[str, list[params.Value]]] = [
        ("seed", list(range(1, runs // REPS + 1))),
        ("world.width", [41]),
        ("world.height", [41]),
    ]
    variants = params.variants(base, params.product(axes), names, "bench")
    return (machines, base), [(machines, v.scenario, v.columns()) for v in variants]


def timed(setup: tuple[Any, Any], points: list[Point], executor: Executor) -> tuple[float, bytes]:
    """Wall seconds of the sweep on the executor, and its runs.csv."""
    machines, base = setup
    started = time.perf_counter()
    sim = simulate(machines, base, points=points, executor=executor)
    seconds = time.perf_counter() - started
    return seconds, stats.runs_table(sim).encode()


def main() -> None:
    """Run the three sweeps and write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2000, help="runs in the sweep (x50)")
    args = parser.parse_args()
    import importlib

    distributed: Any = importlib.import_module("distributed")  # Dask's annotations are partial
    setup, points = sweep(args.runs)
    load_start = os.getloadavg()
    t1, files1 = timed(setup, points, LocalExecutor(1))
    t2, files2 = timed(setup, points, LocalExecutor(2))
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        client.wait_for_workers(2, timeout=60)
        executor = DaskExecutor(client)
        timed(setup, points[:2], executor)  # workers import swarmgen once, outside the timing
        td, filesd = timed(setup, points, executor)
        count = 200
        started = time.perf_counter()
        executor.map(_noop, list(range(count)), [1] * count, lambda _: None)
        noop_ms = (time.perf_counter() - started) / count * 1000
    runs = len(points) * REPS
    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average_at_start": [round(v, 2) for v in load_start],
            "load_average_at_end": [round(v, 2) for v in os.getloadavg()],
            "note": "shared machine: other jobs ran at the same time",
        },
        "sweep": f"{runs} coverage runs: 2 UAVs, 41 x 41 to 100 percent, {len(points)} seeds x "
        f"{REPS} reps",
        "seconds": {"local_1": round(t1, 3), "local_2": round(t2, 3), "dask_2": round(td, 3)},
        "runs_per_second": {
            "local_1": round(runs / t1, 1),
            "local_2": round(runs / t2, 1),
            "dask_2": round(runs / td, 1),
        },
        "scaling_efficiency_2_workers": {
            "local": round(t1 / (2 * t2), 3),
            "dask": round(t1 / (2 * td), 3),
        },
        "dask_overhead_ms_per_run": round((td - t2) * 2 / runs * 1000, 3),
        "dask_empty_task_round_trip_ms": round(noop_ms, 3),
        "identical_files": files1 == files2 == filesd,
    }
    RESULTS.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
