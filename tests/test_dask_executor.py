"""The executor interface on Dask: an in-process LocalCluster, a scheduler and two workers as
separate processes on loopback, a worker killed mid-sweep, and runs that fail twice. Every
result file must be byte-identical to the local run's."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest

from swarmgen.sim import scenario as sc
from swarmgen.sim.executors import DaskExecutor, Failure, LocalExecutor
from swarmgen.sim.machines import Machines, compile_machines
from swarmgen.sim.run import outputs
from swarmgen.sim.sweep import simulate
from tests.conftest import SAMPLE_MODELS

distributed = pytest.importorskip("distributed", reason="the `study` extra (dask) is not installed")

SAR = next(m for m in SAMPLE_MODELS if m.parent.name == "sar")
DASK = Path(sys.executable).with_name("dask")
WAIT = 60.0  # seconds: the longest any process start or sweep may take here


@pytest.fixture(scope="module")
def machines() -> Machines:
    return compile_machines(SAR)


def small(**changes: object) -> sc.Scenario:
    """SAR on a 31 x 31 world: 1 and 2 UAVs (with their UGVs), 1 and 3 targets, 6 reps."""
    base = sc.load("sar").with_overrides({"UAV": [1, 2]}, [1, 3], reps=6, seed=7)
    return replace(base, width=31, height=31, **changes)  # type: ignore[arg-type]


def files_of(
    machines: Machines, scenario: sc.Scenario, executor: object = None
) -> dict[str, bytes]:
    return outputs(simulate(machines, scenario, executor=executor))  # type: ignore[arg-type]


def test_in_process_local_cluster_gives_the_same_files(machines: Machines) -> None:
    local = files_of(machines, small())
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        executor = DaskExecutor(client)
        assert executor.slots == 2
        seen: list[tuple[int, int]] = []
        sim = simulate(
            machines, small(), executor=executor, progress=lambda d, t: seen.append((d, t))
        )
        assert outputs(sim) == local
    assert seen[0] == (0, 24) and seen[-1] == (24, 24)  # progress as the local runs give it
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)


_ATTEMPTS: list[int] = []


def _fails_on_odd(value: int) -> int:
    """A task that raises for odd inputs (counting its attempts: the cluster is in process)."""
    _ATTEMPTS.append(value)
    if value % 2:
        raise ValueError(f"odd {value}")
    return value * 10


def test_a_task_failing_twice_is_a_failure_in_its_place() -> None:
    _ATTEMPTS.clear()
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        done: list[int] = []
        got = DaskExecutor(client).map(_fails_on_odd, [0, 1, 2], [1, 1, 1], done.append)
    assert got == [0, Failure("ValueError: odd 1"), 20]
    assert sorted(_ATTEMPTS) == [0, 1, 1, 2]  # retried once (retries=1), then reported
    assert done == [1, 1, 1]
    _ATTEMPTS.clear()
    assert LocalExecutor(1).map(_fails_on_odd, [1], [1], done.append) == [
        Failure("ValueError: odd 1")
    ]
    assert _ATTEMPTS == [1, 1]


def broken(machines: Machines) -> Machines:
    """The machines with the UGV's generated module replaced by one that raises on import."""
    members = tuple(
        replace(m, code="raise RuntimeError('broken module')") if m.member_type == "UGV" else m
        for m in machines.members
    )
    return replace(machines, members=members)


def test_runs_that_fail_twice_are_rows_marked_failed(machines: Machines) -> None:
    bad = broken(machines)
    chosen = small(reps=2)
    local = simulate(bad, chosen)
    assert len(local.runs) == 2 * 2 * 2 and {r.reason for r in local.runs} == {"failed"}
    assert local.runs[0].errors == ["RuntimeError: broken module"]
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert files_of(bad, chosen, DaskExecutor(client)) == outputs(local)
    runs = json.loads(outputs(local)["results.json"])["runs"]
    assert [(r["config"], r["rep"], r["reason"]) for r in runs][:3] == [
        (0, 0, "failed"),
        (0, 1, "failed"),
        (1, 0, "failed"),
    ]


# --- a scheduler and two workers as separate processes -----------------------------------------


def _wait_for(path: Path, process: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + WAIT
    while not path.exists() or not path.read_text().strip():
        assert process.poll() is None, "the scheduler exited"
        assert time.monotonic() < deadline, f"no scheduler file {path} after {WAIT} s"
        time.sleep(0.1)


@pytest.fixture
def cluster(tmp_path: Path) -> Iterator[tuple[str, list[subprocess.Popen[bytes]]]]:
    """`dask scheduler` and two `dask worker`s (no nanny: a killed worker stays dead), on
    loopback; every process is killed at the end."""
    scheduler_file = tmp_path / "scheduler.json"
    logs = (tmp_path / "logs.txt").open("wb")
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    processes: list[subprocess.Popen[bytes]] = []
    try:
        scheduler = subprocess.Popen(
            [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
             "--scheduler-file", str(scheduler_file)],
            stdout=logs, stderr=logs, env=env,
        )  # fmt: skip
        processes.append(scheduler)
        _wait_for(scheduler_file, scheduler)
        workers = [
            subprocess.Popen(
                [
                    str(DASK),
                    "worker",
                    "--scheduler-file",
                    str(scheduler_file),
                    "--nthreads",
                    "1",
                    "--no-dashboard",
                    "--no-nanny",
                    "--host",
                    "127.0.0.1",
                ],
                stdout=logs,
                stderr=logs,
                env=env,
            )
            for _ in range(2)
        ]
        processes += workers
        address = json.loads(scheduler_file.read_text())["address"]
        with distributed.Client(address, timeout=WAIT) as client:
            client.wait_for_workers(2, timeout=WAIT)
        yield address, workers
    finally:
        for process in reversed(processes):
            if process.poll() is None:
                process.kill()
            process.wait(timeout=WAIT)
        logs.close()


def test_separate_processes_give_the_same_files_through_the_cli(
    tmp_path: Path, cluster: tuple[str, list[subprocess.Popen[bytes]]]
) -> None:
    address, _ = cluster
    swarmgen = Path(sys.executable).with_name("swarmgen")
    base = [str(swarmgen), "simulate", str(SAR), "--scenario", "coverage", "--members",
            "UAV=1,2", "--reps", "4", "--seed", "3", "--param", "world.width=31,41"]  # fmt: skip
    local, remote = tmp_path / "local", tmp_path / "remote"
    run = {"capture_output": True, "text": True, "timeout": WAIT * 3}
    done = subprocess.run([*base, "-o", str(local)], check=False, **run)  # type: ignore[call-overload]
    assert done.returncode == 0, done.stderr
    done = subprocess.run(  # type: ignore[call-overload]
        [*base, "--cluster", address, "-o", str(remote)], check=False, **run
    )
    assert done.returncode == 0, done.stderr
    assert "16/16 runs" in done.stderr  # the progress bar, as for local runs
    names = sorted(p.name for p in local.iterdir())
    assert names == sorted(p.name for p in remote.iterdir())
    for name in names:
        assert (local / name).read_bytes() == (remote / name).read_bytes(), name


def test_a_worker_killed_mid_sweep_loses_no_run(
    machines: Machines, cluster: tuple[str, list[subprocess.Popen[bytes]]]
) -> None:
    address, workers = cluster
    chosen = small(reps=12)  # 48 runs in 16 tasks: most still queued when the kill comes
    local = files_of(machines, chosen)
    killed: list[int] = []

    def progress(done: int, total: int) -> None:
        if done > 0 and not killed:
            workers[0].send_signal(signal.SIGKILL)
            killed.append(done)

    with distributed.Client(address, timeout=WAIT) as client:
        sim = simulate(machines, chosen, executor=DaskExecutor(client), progress=progress)
    workers[0].wait(timeout=WAIT)
    assert killed and killed[0] < 48 and workers[0].returncode == -signal.SIGKILL
    assert [(r.config, r.rep) for r in sim.runs] == [(c, r) for c in range(4) for r in range(12)]
    assert outputs(sim) == local  # every run accounted for, and the same numbers
