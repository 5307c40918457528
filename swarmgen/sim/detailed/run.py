"""`swarmgen simulate --level detailed`: every configuration and repetition of a scenario as a
real ROS 2 run (docs/detailed.md, "Running the detailed level").

A run is three process groups in one ROS domain of its own, on simulated time: the behaviour
servers (`swarmgen_library.servers`), the generated swarm, unmodified (`launch_swarm
--no-simulation`, `use_sim_time`), and, once the swarm is connected and waits for the world's
first probe, the world node, the only clock. The run ends when the world node writes its
result; then every process is stopped (`procs.ProcessGroup`: nothing outlives a run, also on
Ctrl-C). A process that dies first, a world that does not finish within the wall limit, or a
result marked partial makes the run *failed*: it is reported with the reason and the tail of
the guilty log, never dropped.
"""

from __future__ import annotations

import json
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import field
from pathlib import Path
from typing import Any

from swarmgen import pipeline
from swarmgen import ros_harness as harness
from swarmgen.backends.rclpy_backend import nodes_package
from swarmgen.records import dataclass
from swarmgen.ros.domains import lease
from swarmgen.sim.batch import Config
from swarmgen.sim.detailed.bags import record_run
from swarmgen.sim.detailed.plan import Planner, RunPlan
from swarmgen.sim.detailed.procs import ProcessGroup
from swarmgen.sim.scenario import SimulationError

LIBRARY_ROOT = Path(__file__).resolve().parents[2] / "ros" / "library"  # the ament package
START_LIMIT_S = 60.0  # for the swarm to enter its initial configuration
CANCELLED = "cancelled (interrupted)"


@dataclass
class Workspace:
    """The compiled rclpy package and its built interfaces, shared by every run."""

    nodes: Path  # rclpy/<swarm>_nodes (on PYTHONPATH)
    prefix: Path  # the user interface packages' prefix
    root: Path  # where runs keep their files


@dataclass
class DetailedRun:
    """What one run gave: its result file (None if it failed), why it failed, timings."""

    config: int
    rep: int
    result: dict[str, Any] | None
    failure: str | None = None
    wall_s: float = 0.0
    logs: dict[str, str] = field(default_factory=dict)  # process -> the tail of its log


def prepare(model_path: Path, root: Path) -> tuple[Workspace, Any]:
    """Validate and compile the model's rclpy package into `root` and build its interfaces."""
    harness.check_rclpy()
    result = pipeline.compile_model(model_path, backends=["rclpy"])
    model = result.validation.model
    if model is None or not result.files:
        raise SimulationError(f"{model_path}: does not compile (run `swarmgen validate`)")
    pipeline.write_tree(result.files, root / "ws")
    prefix = harness.build_interfaces(root / "ws" / "rclpy", model)
    nodes = root / "ws" / "rclpy" / nodes_package(model)
    return Workspace(nodes, prefix, root), result.validation


def run_one(
    workspace: Workspace,
    plan: RunPlan,
    where: tuple[int, int],
    domain: int,
    limit_s: float,
    cancel: threading.Event,
    bag: tuple[Path, str] | None = None,
) -> DetailedRun:
    """One repetition (`where`: configuration, repetition) as real processes (the module
    docstring); never raises for a bad run; `cancel` (Ctrl-C) stops it at once; `bag`: (a new
    bag directory, its storage) to record the swarm's trace into."""
    config, rep = where
    here = Path(tempfile.mkdtemp(prefix=f"run-c{config}-r{rep}-", dir=workspace.root))
    (here / "world.json").write_text(json.dumps(plan.world), encoding="utf-8")
    (here / "servers.json").write_text(json.dumps(plan.servers), encoding="utf-8")
    env = harness.ros_env(
        here / "roslog",
        domain_id=domain,
        python_path=[workspace.nodes, LIBRARY_ROOT],
        prefixes=[workspace.prefix],
    )
    started = time.monotonic()
    run = DetailedRun(config, rep, None)
    python = sys.executable
    with ProcessGroup(here / "logs") as group:
        group.start(
            "servers", [python, "-m", "swarmgen_library.servers", "servers.json"], env, here
        )
        swarm = [python, "-m", f"{plan.package}.launch_swarm", *plan.launcher,
                 "--ros-args", "-p", "use_sim_time:=true",
                 "-p", "lockstep_topic:=/world/settle"]  # fmt: skip
        group.start("swarm", swarm, env, here)
        run.failure = _await_swarm(group, START_LIMIT_S, cancel)
        if run.failure is None:
            group.start("world", [python, "-m", "swarmgen_library.world_node", "world.json"],
                        env, here)  # fmt: skip
            run.failure = _await_world(group, limit_s, cancel)
        run.logs = {s.name: s.tail() for s in group.started}
    run.wall_s = time.monotonic() - started
    if bag is not None and not cancel.is_set():
        record_run(here / "logs" / "swarm.log", *bag)
    if run.failure is None:
        run.result, run.failure = _read_result(here / "result.json")
    return run


def _await_swarm(group: ProcessGroup, limit: float, cancel: threading.Event) -> str | None:
    """Wait until the swarm waits for the world's first probe (`{"lockstep": "waiting"}`: its
    members are connected to their servers, and start at the first probe)."""
    swarm = next(s for s in group.started if s.name == "swarm")
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        if cancel.is_set():
            return CANCELLED
        gone = group.exited()
        if gone:
            return f"{', '.join(sorted(gone))} exited before the run started: {gone}"
        try:
            lines = swarm.log.read_text(encoding="utf-8", errors="replace").splitlines()
        except OSError:
            lines = []
        if any(line.startswith('{"lockstep": "waiting"') for line in lines):
            return None
        time.sleep(0.05)
    return f"the swarm did not start within {limit:g} s"


def _await_world(group: ProcessGroup, limit: float, cancel: threading.Event) -> str | None:
    """Wait for the world node to finish; the failure, if it did not do so cleanly."""
    code = group.wait("world", limit, watch=("servers", "swarm"), cancel=cancel)
    if code == 0:
        return None
    if cancel.is_set():
        return CANCELLED
    gone = group.exited()
    if code is None and "world" not in gone:
        others = {k: v for k, v in gone.items() if k != "world"}
        if others:
            return f"{', '.join(sorted(others))} exited during the run: {others}"
        return f"the world did not finish within the wall limit of {limit:g} s"
    return f"the world node exited with {gone.get('world', code)}"


def _read_result(path: Path) -> tuple[dict[str, Any] | None, str | None]:
    try:
        result = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        return None, f"no result file: {err}"
    if not result.get("complete", False):
        return result, f"partial result ({result.get('reason')})"
    return result, None


def run_all(
    workspace: Workspace,
    planner: Planner,
    configs: Sequence[Config],
    reps: int,
    workers: int,
    progress: Callable[[int, int], None] | None = None,
    record: tuple[Path, str] | None = None,
) -> list[DetailedRun]:
    """Every (configuration, repetition), `workers` at a time, each in a ROS domain no other
    running run on this machine has (`domains.lease`); in (configuration, repetition) order. Ctrl-C stops every run's processes
    before it propagates. `record`: (a new directory, the bag storage) for one bag per run,
    `DIR/<configuration>-<rep>` as at the abstract level."""
    jobs = [(c, r) for c in range(len(configs)) for r in range(reps)]
    workers = max(1, min(workers, len(jobs)))
    cancel = threading.Event()
    done: list[DetailedRun] = []
    if progress is not None:
        progress(0, len(jobs))

    def job(number: int) -> DetailedRun:
        config, rep = jobs[number]
        plan = planner.plan(configs[config], rep)
        bag = None
        if record is not None:
            bag = (record[0] / f"{configs[config].slug()}-{rep:04d}", record[1])
        with lease(cancel) as domain:
            limit = planner.params.wall_limit_s
            return run_one(workspace, plan, jobs[number], domain, limit, cancel, bag)

    pool = ThreadPoolExecutor(max_workers=workers)  # each run is its own processes
    try:
        for finished in pool.map(job, range(len(jobs))):
            done.append(finished)
            if progress is not None:
                progress(len(done), len(jobs))
    except BaseException:
        cancel.set()  # every running run stops its processes; the rest do not start
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return done
