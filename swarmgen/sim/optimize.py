"""`swarmgen optimize`: optuna studies over the sweep parameters of `sim.params`.

A search space names the same parameters as `--param`, as ranges or choices (`UAV.count=1:4`
an integer range, `world.view=0:3`, `stop_level=0.5:1.0` a float range, `allocation=paired,
nearest` choices). Every trial is one point: its scenario (every configuration of it, `--reps`
repetitions each) is run through the executor, and the objectives (`sim.objectives`) are
computed over its runs. Repetitions share the scenario's seed from trial to trial (common random
numbers), so two trials differ by their parameters, not by their luck.

The study lives in optuna's RDB storage (SQLite by default, any SQLAlchemy URL). Resuming
(`load_if_exists`): a RUNNING trial left by a process of this host that is gone (killed) is
marked FAIL (with SQLite, a lock file beside the database tells that no other process is
running the study: then every RUNNING trial is such an orphan, even one killed before it
recorded its process), flagged `swarmgen.interrupted`, and enqueued again with the parameters it had drawn,
so no trial is lost; the budget (`--trials`) counts finished trials other than those, so none is run
twice. Trials of other hosts are left to optuna's heartbeat (`HEARTBEAT`, `GRACE`): stale ones
fail and are retried once with the same parameters (`RetryHeartbeatStaleTrialCallback`). The sampler is
seeded with `--seed` (default: the scenario's seed) plus the number of trials already in the study: a study is reproducible,
and a resumed one does not replay the first run's proposals. A point that a completed trial
already evaluated is answered from that trial (the runs are deterministic), not run again.

Trials in parallel (`parallel` > 1, `--parallel K`): the study asks K trials at once (TPE with
its constant liar, so the K differ), runs their points as one sweep through the executor (every
run of the K trials in flight together), and tells the K results in the order asked. Everything
happens in one thread in that order, so the study is a function of (seed, K): the same seed and K
give the same trials; another K gives another (equally valid) study. A kill mid-batch leaves up
to K RUNNING trials, recovered as above.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import math
import os
import socket
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from swarmgen.console import shown
from swarmgen.records import dataclass
from swarmgen.sim import objectives as obj
from swarmgen.sim import params
from swarmgen.sim.executors import Executor, LocalExecutor
from swarmgen.sim.scenario import Scenario

if TYPE_CHECKING:
    import optuna

    from swarmgen.sim.machines import Machines

SAMPLERS = ("tpe", "cmaes", "nsga2")
HEARTBEAT = 30  # seconds between a running trial's heartbeats (shared databases)
GRACE = 120  # seconds without a heartbeat before another process fails the trial
MAX_TRIALS = 100_000
_HOST, _PID, _INTERRUPTED = "swarmgen.host", "swarmgen.pid", "swarmgen.interrupted"


class OptimizeError(params.ParamError):
    """A study that cannot run: a bad space, sampler or storage (exit 2)."""


@dataclass(frozen=True)
class Dimension:
    """One parameter of the search space: an int or float range, or categorical choices."""

    name: str
    kind: str  # "int", "float" or "categorical"
    low: float = 0
    high: float = 0
    choices: tuple[params.Value, ...] = ()

    def corners(self) -> list[params.Value]:
        """The values that bound the dimension: checked before any trial."""
        if self.kind == "int":
            return [int(self.low), int(self.high)]
        if self.kind == "float":
            return [float(self.low), float(self.high)]
        return list(self.choices)

    def suggest(self, trial: optuna.Trial) -> params.Value:
        """The trial's value of this dimension."""
        if self.kind == "int":
            return int(trial.suggest_int(self.name, int(self.low), int(self.high)))
        if self.kind == "float":
            return float(trial.suggest_float(self.name, float(self.low), float(self.high)))
        return cast(params.Value, trial.suggest_categorical(self.name, list(self.choices)))


def parse_space(text: str) -> Dimension:
    """`--space NAME=LOW:HIGH` (int when both are integers, else float) or `NAME=A,B,C`."""
    name, sep, body = text.partition("=")
    name = name.strip()
    where = f"--space {shown(name or text)}"
    if not sep or not name or not body.strip():
        raise OptimizeError(f"--space {shown(text)!r}: write NAME=LOW:HIGH or NAME=A,B,C")
    if ":" in body and "," not in body:
        ends = [params._scalar(p.strip()) for p in body.split(":")]
        numbers = all(
            isinstance(e, int | float) and not isinstance(e, bool) and math.isfinite(e)
            for e in ends
        )
        if len(ends) != 2 or not numbers:
            raise OptimizeError(f"{where}: range {shown(body)!r}: write LOW:HIGH (numbers)")
        low, high = (float(e) for e in ends)
        if high <= low:
            raise OptimizeError(f"{where}: range {shown(body)!r}: needs HIGH > LOW")
        kind = "int" if all(isinstance(e, int) for e in ends) else "float"
        return Dimension(name, kind, low, high)
    _, values = params.parse_option(f"{name}={body}")
    if len(set(map(json.dumps, values))) != len(values):
        raise OptimizeError(f"{where}: a choice is given twice")
    return Dimension(name, "categorical", choices=tuple(values))


def check_space(
    space: Sequence[Dimension],
    base: Scenario,
    names: params.Names,
    check: Callable[[Scenario], None],
) -> None:
    """Every dimension's bounds applied to the scenario (name, type, range), and `check` (the
    scenario's checks against the model) on each: before any trial runs."""
    seen = [d.name for d in space]
    if not space:
        raise OptimizeError("--space: give at least one parameter to optimise")
    for name in seen:
        if seen.count(name) > 1:
            raise OptimizeError(f"--space {shown(name)}: given twice")
    for dim in space:
        for value in dim.corners():
            variant = params.apply(base, ((dim.name, value),), names, f"--space {dim.name}")
            check(variant.scenario)


# --- the study ---------------------------------------------------------------------------------


@dataclass
class Study:
    """What a study runs: the model, the base scenario, the space and the objectives."""

    model: Path
    scenario: Scenario
    space: list[Dimension]
    objectives: list[obj.Objective]
    names: params.Names
    executor: Executor | None = None
    progress: Callable[[int, int], None] | None = None

    def __post_init__(self) -> None:
        """The compiled machines, by data defaults (most spaces have none: one compile)."""
        self._machines: dict[str, Machines] = {}

    def machines(self, data: Mapping[str, Mapping[str, params.Value]]) -> Machines:
        """The model compiled with these data defaults (cached)."""
        from swarmgen.sim.machines import compile_variants

        key = json.dumps(data, sort_keys=True)
        if key not in self._machines:
            self._machines[key] = compile_variants(self.model, [data])[0]
        return self._machines[key]

    def evaluate(self, point: params.Point) -> tuple[list[float], int, int]:
        """The objectives of one point over its runs, the number of runs and of failed runs."""
        return self.evaluate_many([point])[0]

    def evaluate_many(self, points: Sequence[params.Point]) -> list[tuple[list[float], int, int]]:
        """`evaluate` of several points, their runs in one sweep through the executor."""
        from swarmgen.sim.sweep import configurations, simulate

        variants = [params.apply(self.scenario, p, self.names, "--space") for p in points]
        machines = [self.machines(v.data) for v in variants]
        sim = simulate(
            machines[0], variants[0].scenario, progress=self.progress,
            points=[(m, v.scenario, v.columns()) for m, v in zip(machines, variants, strict=True)],
            executor=self.executor or LocalExecutor(1),
        )  # fmt: skip
        owner = [i for i, v in enumerate(variants) for _ in configurations(machines[i], v.scenario)]
        results = []
        for i, variant in enumerate(variants):
            runs = [r for r in sim.runs if owner[r.config] == i]
            failed = sum(1 for r in runs if r.reason == "failed")
            values = [obj.evaluate(o, runs, sim.configs, variant.scenario) for o in self.objectives]
            results.append((values, len(runs), failed))
        return results


def make_sampler(
    name: str, seed: int, trials_so_far: int, objectives: int, parallel: bool = False
) -> Any:
    """The seeded sampler: `--seed` plus the trials already in the study (see the module);
    `parallel`: TPE lies about the trials still running (constant liar) so a batch differs."""
    import optuna

    if name == "nsga2" or objectives > 1:
        if name != "nsga2":
            raise OptimizeError(f"--sampler {name}: two objectives need --sampler nsga2")
        return optuna.samplers.NSGAIISampler(seed=(seed + trials_so_far) % 2**32)
    if name == "cmaes":
        return optuna.samplers.CmaEsSampler(
            seed=(seed + trials_so_far) % 2**32, warn_independent_sampling=False
        )
    if name == "tpe":
        if not parallel:
            return optuna.samplers.TPESampler(seed=(seed + trials_so_far) % 2**32)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            return optuna.samplers.TPESampler(
                seed=(seed + trials_so_far) % 2**32, constant_liar=True
            )
    raise OptimizeError(f"--sampler {name!r}: one of {', '.join(SAMPLERS)}")


def storage_of(url: str) -> Any:
    """optuna's RDB storage at `url` (any SQLAlchemy URL), with heartbeats for shared ones
    (an in-memory SQLite database is this process's alone, and a heartbeat thread would get an
    empty database of its own)."""
    import optuna
    from sqlalchemy.exc import SQLAlchemyError

    try:
        if url == "sqlite:///:memory:":
            return optuna.storages.RDBStorage(url)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            retry = optuna.storages.RetryHeartbeatStaleTrialCallback(max_retry=1)
            return optuna.storages.RDBStorage(
                url, heartbeat_interval=HEARTBEAT, grace_period=GRACE,
                heartbeat_stale_trial_callback=retry,
            )  # fmt: skip
    except (SQLAlchemyError, ValueError, ImportError) as err:
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise OptimizeError(f"--storage {shown(url)}: {first}") from None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True


@contextlib.contextmanager
def sqlite_lease(url: str) -> Iterator[bool]:
    """For an SQLite study: a shared lock on `DB.lock` while this process runs trials; yields
    True when no other process held it (then every RUNNING trial in the file is an orphan,
    even one killed before it recorded its process). Other URLs: False."""
    if not url.startswith("sqlite:///") or url == "sqlite:///:memory:":
        yield False
        return
    with open(url.removeprefix("sqlite:///") + ".lock", "a+b") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            alone = True
        except BlockingIOError:
            alone = False
        fcntl.flock(lock, fcntl.LOCK_SH)  # downgrade: others may join, none think us dead
        yield alone


def recover(study: optuna.Study, alone: bool = False) -> int:
    """RUNNING trials whose process is gone (`alone`: every one; else those of this host whose
    process is not alive): FAIL, flagged, and enqueued again with the parameters they had
    drawn. Returns how many."""
    from optuna.trial import TrialState

    storage = study._storage
    count = 0
    for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        host, pid = trial.user_attrs.get(_HOST), trial.user_attrs.get(_PID)
        ours = host == socket.gethostname() and isinstance(pid, int)
        if not alone and (not ours or (isinstance(pid, int) and _alive(pid))):
            continue
        storage.set_trial_user_attr(trial._trial_id, _INTERRUPTED, True)
        storage.set_trial_state_values(trial._trial_id, TrialState.FAIL)
        if trial.params:  # killed before its parameters were drawn: nothing to repeat
            study.enqueue_trial(trial.params, user_attrs={"swarmgen.retry_of": trial.number})
        count += 1
    return count


def finished(study: optuna.Study) -> int:
    """Trials that count against the budget: finished, except those interrupted by a kill."""
    from optuna.trial import TrialState

    done = (TrialState.COMPLETE, TrialState.PRUNED, TrialState.FAIL)
    return sum(
        1
        for t in study.get_trials(deepcopy=False, states=done)
        if not t.user_attrs.get(_INTERRUPTED)
    )


def _cached(study: optuna.Study, chosen: Mapping[str, Any]) -> list[float] | None:
    """The values of a completed trial with exactly these parameters, if any."""
    from optuna.trial import TrialState

    for trial in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
        if trial.params == dict(chosen):
            return list(trial.values)
    return None


def _claim(spec: Study, trial: optuna.Trial) -> params.Point:
    """A trial this process runs: its host and process recorded, its point drawn."""
    trial.set_user_attr(_HOST, socket.gethostname())
    trial.set_user_attr(_PID, os.getpid())
    return tuple((d.name, d.suggest(trial)) for d in spec.space)


def _result(trial: optuna.Trial, values: list[float], runs: int, failed: int, cached: bool) -> Any:
    """What optuna is told: the value(s), or RuntimeError (a FAIL trial). `cached`: answered
    from another trial's runs."""
    if cached:
        trial.set_user_attr("swarmgen.cached", True)
    else:
        trial.set_user_attr("swarmgen.runs", runs)
        trial.set_user_attr("swarmgen.failed_runs", failed)
    if failed:
        raise RuntimeError(f"{failed} of {runs} runs failed")
    if any(not math.isfinite(v) for v in values):
        raise RuntimeError(f"an objective is not a number: {values}")
    return values[0] if len(values) == 1 else tuple(values)


def objective_of(spec: Study, study: optuna.Study) -> Callable[[optuna.Trial], Any]:
    """The function optuna calls per trial: parameters -> runs -> objective values."""

    def run(trial: optuna.Trial) -> Any:
        point = _claim(spec, trial)
        cached = _cached(study, dict(point))
        if cached is not None:
            return _result(trial, cached, 0, 0, True)
        values, runs, failed = spec.evaluate(point)
        return _result(trial, values, runs, failed, False)

    return run


def run_batches(spec: Study, study: optuna.Study, count: int, parallel: int) -> None:
    """`count` trials, `parallel` at a time: ask a batch, run its new points as one sweep
    (a point repeated in the batch, or already completed, is run once), tell in order."""
    import optuna

    while count > 0:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            optuna.storages.fail_stale_trials(study)
        with warnings.catch_warnings():  # the heartbeats are ours (`_heartbeats`)
            warnings.filterwarnings("ignore", "Heartbeat of storage", UserWarning)
            trials = [study.ask() for _ in range(min(parallel, count))]
        told = 0
        try:
            with _heartbeats(study, [t._trial_id for t in trials]):
                points = [_claim(spec, t) for t in trials]
                known = {json.dumps(p): _cached(study, dict(p)) for p in points}
                fresh = {json.dumps(p): p for p in points if known[json.dumps(p)] is None}
                runs = spec.evaluate_many(list(fresh.values())) if fresh else []
                evaluated = dict(zip(fresh, runs, strict=True))
            first: set[str] = set()
            for trial, point in zip(trials, points, strict=True):
                key = json.dumps(point)
                values, count_runs, failed = evaluated.get(key) or (known[key] or [], 0, 0)
                cached = key not in evaluated or key in first  # run once, by its first trial
                first.add(key)
                try:
                    study.tell(trial, _result(trial, values, count_runs, failed, cached))
                except RuntimeError:
                    study.tell(trial, state=optuna.trial.TrialState.FAIL)
                told += 1
        except BaseException:  # as optuna does for one trial: FAIL, then the error
            for trial in trials[told:]:
                study.tell(trial, state=optuna.trial.TrialState.FAIL)
            raise
        count -= len(trials)


@contextlib.contextmanager
def _heartbeats(study: optuna.Study, trial_ids: list[int]) -> Iterator[None]:
    """Record the batch's heartbeats (shared databases) while it runs, as optuna does for one."""
    import threading

    storage = cast(Any, study._storage)  # RDBStorage: optuna's heartbeat interface
    interval = getattr(storage, "get_heartbeat_interval", lambda: None)()
    if interval is None:
        yield
        return
    stop = threading.Event()

    def beat() -> None:
        while True:
            for trial_id in trial_ids:
                storage.record_heartbeat(trial_id)
            if stop.wait(interval):
                return

    thread = threading.Thread(target=beat, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def run_study(
    spec: Study,
    storage_url: str,
    study_name: str,
    sampler: str,
    seed: int,
    trials: int,
    parallel: int = 1,
) -> optuna.Study:
    """Create or resume the study and run trials until `trials` have finished, `parallel` of
    them at a time."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    storage = storage_of(storage_url)
    directions = [o.direction for o in spec.objectives]
    try:
        study = optuna.create_study(
            storage=storage,
            study_name=study_name,
            directions=cast(Any, directions),
            load_if_exists=True,
        )
    except ValueError as err:
        raise OptimizeError(f"--study-name {shown(study_name)}: {err}") from None
    if [d.name.lower() for d in study.directions] != directions:
        raise OptimizeError(
            f"study {shown(study_name)} in {shown(storage_url)} has directions "
            f"{[d.name.lower() for d in study.directions]}, not {directions}: use --study-name"
        )
    with sqlite_lease(storage_url) as alone:
        recover(study, alone)
        study.sampler = make_sampler(
            sampler, seed, len(study.trials), len(spec.objectives), parallel > 1
        )
        remaining = max(0, trials - finished(study))
        if remaining and parallel > 1:
            run_batches(spec, study, remaining, parallel)
        elif remaining:
            study.optimize(objective_of(spec, study), n_trials=remaining, catch=(RuntimeError,))
    return study
