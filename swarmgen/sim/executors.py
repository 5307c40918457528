"""Where a sweep's tasks run: one interface over local processes and a Dask cluster.

An executor maps a function over tasks and returns the results in task order, whatever order
they finished in, calling `progress(size)` as each one finishes. A task that raises is run once
more (Dask: `retries=1`; locally: again in this process); one that fails twice comes back as a
`Failure` carrying its error, never dropped. A user error (`SwarmgenError`) is not a failure of
the run: it is raised at once, as it would be without an executor.

Dask is imported only here and only when `--cluster` is given: the compiler and `swarmgen
--help` never load it. `--cluster tcp://HOST:PORT` connects to a running scheduler;
`--cluster local:N` starts a `distributed.LocalCluster` of N single-threaded worker processes
for this sweep (docs/simulate.md, "Executors").
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from types import TracebackType
from typing import Any, Protocol, TypeVar

from swarmgen.errors import SwarmgenError
from swarmgen.records import dataclass

T = TypeVar("T")
R = TypeVar("R")
Progress = Callable[[int], None]  # called with the size (runs) of each finished task
CONNECT_TIMEOUT = "20s"  # reaching the scheduler; a cluster that never answers is an error


class ClusterError(SwarmgenError):
    """A `--cluster` that cannot be used: a bad address, or no scheduler there (exit 2)."""


@dataclass(frozen=True)
class Failure:
    """A task that failed twice: its last error, as the results report it."""

    error: str


def describe(err: BaseException) -> str:
    """An error as results show it: its type and message (no addresses, which vary by run)."""
    name = type(err).__name__
    if name == "KilledWorker":  # names the dead workers' random ports: keep results stable
        return "KilledWorker: every worker that ran this task died"
    return f"{name}: {err}"


class Executor(Protocol):
    """Runs tasks somewhere; `slots` is how many run at once (the sweep sizes its batches)."""

    slots: int

    def map(
        self, fn: Callable[[T], R], tasks: Sequence[T], sizes: Sequence[int], progress: Progress
    ) -> list[R | Failure]:
        """`fn` over `tasks`, results in task order; `progress(sizes[i])` as task i ends."""
        ...

    def close(self) -> None:
        """Release what the executor holds (processes, connections)."""
        ...


def _retry(fn: Callable[[T], R], task: T) -> R | Failure:
    """The task's second attempt, in this process."""
    try:
        return fn(task)
    except SwarmgenError:
        raise
    except Exception as err:  # the run's own failure: reported in the results
        return Failure(describe(err))


class LocalExecutor:
    """Today's behaviour: in this process (`workers` 1) or over forked local processes."""

    def __init__(self, workers: int = 1) -> None:
        """An executor over `workers` local processes."""
        self.slots = max(1, workers)

    def map(
        self, fn: Callable[[T], R], tasks: Sequence[T], sizes: Sequence[int], progress: Progress
    ) -> list[R | Failure]:
        """`fn` over `tasks`, results in task order; a failed task is run again here."""
        results: list[R | Failure | None] = [None] * len(tasks)
        if self.slots <= 1 or len(tasks) <= 1:
            for i, task in enumerate(tasks):
                try:
                    results[i] = fn(task)
                except SwarmgenError:
                    raise
                except Exception:
                    results[i] = _retry(fn, task)
                progress(sizes[i])
            return [r for r in results if r is not None]
        methods = multiprocessing.get_all_start_methods()
        # fork: workers inherit what the parent built (the sweep builds the charts first)
        context = multiprocessing.get_context("fork" if "fork" in methods else None)
        with ProcessPoolExecutor(max_workers=self.slots, mp_context=context) as pool:
            futures: dict[Future[R], int] = {pool.submit(fn, t): i for i, t in enumerate(tasks)}
            for future in as_completed(futures):
                i = futures[future]
                error = future.exception()
                if isinstance(error, SwarmgenError):
                    raise error
                # a dead process breaks the pool: its tasks are run again here
                results[i] = _retry(fn, tasks[i]) if error is not None else future.result()
                progress(sizes[i])
        return [r for r in results if r is not None]

    def close(self) -> None:
        """Nothing to release: the pool lives only for one `map`."""


class DaskExecutor:
    """Tasks submitted to a Dask distributed scheduler, each with `retries=1`."""

    def __init__(self, client: Any, cluster: Any = None) -> None:
        """An executor over a connected `distributed.Client` (and the cluster it owns)."""
        self.client = client
        self.cluster = cluster
        self.slots = max(1, sum(client.nthreads().values()))

    def map(
        self, fn: Callable[[T], R], tasks: Sequence[T], sizes: Sequence[int], progress: Progress
    ) -> list[R | Failure]:
        """`fn` over `tasks` on the cluster, results in task order."""
        dask_completed = _distributed().as_completed
        # pure=False: two equal tasks are still two runs (Dask would merge them by key)
        futures = [self.client.submit(fn, t, retries=1, pure=False) for t in tasks]
        where = {f.key: i for i, f in enumerate(futures)}
        results: list[R | Failure | None] = [None] * len(tasks)
        try:
            for future in dask_completed(futures):
                i = where[future.key]
                if future.status == "finished":
                    results[i] = future.result()
                elif future.status == "cancelled":
                    results[i] = Failure("CancelledError: the scheduler dropped the task")
                else:
                    error = future.exception()
                    if isinstance(error, SwarmgenError):
                        raise error
                    results[i] = Failure(describe(error))
                progress(sizes[i])
        finally:
            self.client.cancel([f for f in futures if not f.done()])
        return [r for r in results if r is not None]

    def close(self) -> None:
        """Close the client, and the cluster if this executor started it."""
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()

    def __enter__(self) -> DaskExecutor:
        """The executor itself."""
        return self

    def __exit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        """Close on leaving the block."""
        self.close()


def _distributed() -> Any:
    """The `distributed` module (loaded on first use; untyped here: Dask's own annotations are
    partial), or ClusterError when Dask is not installed."""
    import importlib

    try:
        return importlib.import_module("distributed")
    except ImportError:
        raise ClusterError(
            "--cluster needs Dask: pip install 'swarmgen[study]' (dask[distributed])"
        ) from None


def connect(cluster: str) -> DaskExecutor:
    """The executor `--cluster` names: `tcp://HOST:PORT` (a running scheduler), or `local:N`
    (a LocalCluster of N single-threaded worker processes, closed with the executor)."""
    distributed = _distributed()
    Client, LocalCluster = distributed.Client, distributed.LocalCluster
    if cluster.startswith("local:"):
        count = cluster.removeprefix("local:")
        if not count.isdigit() or not 1 <= int(count) <= 256:
            raise ClusterError(f"--cluster {cluster!r}: write local:N with N from 1 to 256")
        local = LocalCluster(
            n_workers=int(count), threads_per_worker=1, processes=True, dashboard_address=None
        )
        return DaskExecutor(Client(local), local)
    if "://" not in cluster:
        raise ClusterError(f"--cluster {cluster!r}: write tcp://HOST:PORT or local:N")
    try:
        client = Client(cluster, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError) as err:
        raise ClusterError(f"--cluster {cluster}: no Dask scheduler answers ({err})") from None
    return DaskExecutor(client)
