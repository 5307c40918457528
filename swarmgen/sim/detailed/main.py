"""`swarmgen simulate --level detailed`: plan, run and report a scenario's sweep on ROS 2."""

from __future__ import annotations

import contextlib
import json
import shutil
import signal
import tempfile
import threading
from collections.abc import Callable, Iterator
from dataclasses import asdict
from pathlib import Path

from swarmgen import outtree
from swarmgen.sim.detailed.params import detailed_params
from swarmgen.sim.detailed.plan import Planner
from swarmgen.sim.detailed.results import run_record, run_result
from swarmgen.sim.detailed.run import prepare, run_all
from swarmgen.sim.machines import compile_machines
from swarmgen.sim.run import outputs, write_outputs
from swarmgen.sim.scenario import Scenario
from swarmgen.sim.sweep import Simulation, configurations


@contextlib.contextmanager
def _signals_interrupt() -> Iterator[None]:
    """SIGTERM and SIGHUP unwind like Ctrl-C while runs are going, so every run's processes
    are stopped (their sessions are their own: a signal to ours does not reach them)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(number: int, _frame: object) -> None:
        raise KeyboardInterrupt(f"signal {number}")

    previous = {n: signal.signal(n, interrupt) for n in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def simulate_detailed(
    model: Path,
    scenario: Scenario,
    out_dir: Path | None,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    keep: Path | None = None,
    record: Path | None = None,
    storage: str = "mcap",
) -> tuple[Simulation, dict[str, bytes]]:
    """Every configuration and repetition of `scenario` as a detailed run; the same result
    files as the abstract level (`keep`: a new directory to keep every run's files and logs
    in; by default they are removed; `record`: a new directory for one bag per run)."""
    if out_dir is not None:
        outtree.preflight(out_dir, "simulate")
    params = detailed_params(scenario)
    machines = compile_machines(model)  # the configurations, exactly as the abstract level
    configs = configurations(machines, scenario)
    root = Path(tempfile.mkdtemp(prefix="swarmgen-detailed-")) if keep is None else keep
    if keep is not None:
        keep.mkdir(parents=True, exist_ok=False)
    try:
        workspace, validation = prepare(model, root)
        assert validation.model is not None
        planner = Planner(validation.model, validation.charts, validation.interfaces,
                          scenario, params)  # fmt: skip
        with _signals_interrupt():
            bags = None if record is None else (record, storage)
            if record is not None:
                record.mkdir(parents=True)
            runs = run_all(workspace, planner, configs, scenario.reps, workers, progress, bags)
    finally:
        if keep is None:
            shutil.rmtree(root, ignore_errors=True)
    results = [run_result(r, configs[r.config], scenario, params) for r in runs]
    sim = Simulation(machines, scenario, configs, results)
    files = outputs(sim)
    payload = json.loads(files["results.json"])
    payload["level"] = "detailed"
    payload["detailed"] = {"params": asdict(params), "runs": [run_record(r) for r in runs]}
    files["results.json"] = (json.dumps(payload, indent=1, sort_keys=True) + "\n").encode()
    if out_dir is not None:
        write_outputs(files, out_dir, model.name)
    return sim, files
