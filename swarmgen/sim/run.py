"""The simulator: compiled machines as engines, a discrete-time host, batches and sweeps.

Each member of each repetition is a `SimMember`: `swarmgen.runtime.member.Member` (the class the
generated asyncio code runs) whose engine is built from the chart the asyncio backend generates
for its member type, attached to the run's `InMemoryBus`. Only the host services differ: instead
of asyncio tasks and `call_later`, a `Batch` keeps one clock per run and a schedule of what is
due, and advances time in rounds:

1. at its current tick each run handles the finds made there, the scheduled items that are due
   (station events, behaviour completions, timers) and then every queued event, one engine
   macrostep each, until nothing is queued (behaviours started or cancelled on the way);
2. each run's horizon is its next scheduled tick (or a chunk of ticks when nothing is due);
3. the world moves every covering member of every run to its horizon at once (numpy), stopping
   a run early at the first tick one of its members has an unfound target in view.

Repetitions of one configuration share a batch (the leading axis of every world array);
configurations and chunks of repetitions are spread over processes. A run's random numbers
depend only on (seed, configuration, repetition), so results do not depend on `--workers`.

With `record` (`swarmgen simulate --record DIR`), each run writes a ROS 2 bag,
`DIR/<configuration>-<rep>` (see `Config.slug`), in the process that simulates it: every event
every member processes and every change of its active states, stamped with the run's tick
(`tick * tick_ms` ms since the start, launch being tick 0 in the shipped scenarios).
"""

from __future__ import annotations

import hashlib
import heapq
import itertools
import math
import multiprocessing
from collections import deque
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any

import numpy as np

from swarmgen import outtree
from swarmgen.runtime.chart import Call, Chart, Node
from swarmgen.runtime.engine import FINALIZE_PREFIX, OUTCOME_PREFIX, Event
from swarmgen.runtime.member import Behaviour, InMemoryBus, Member, Request
from swarmgen.sim.library import Activation, Library, SimBehaviour, claims, found
from swarmgen.sim.scenario import Scenario
from swarmgen.sim.world import FOUND, INF, RESCUED, Geometry, World, fan_headings, south_line

if TYPE_CHECKING:
    from swarmgen.trace.bag import BagRecorder

POINTS_PER_ROUND = 1_000_000  # positions computed per round at most (memory bound)
MIN_CHUNK = 256
EVENTS_PER_TICK = 200_000  # more events than this in one tick of one run: a livelock


class SimulationError(Exception):
    """The model or scenario cannot be simulated (a user error)."""


# --- the compiled machines --------------------------------------------------------------------


@dataclass(frozen=True)
class MemberMachine:
    """One member type's compiled behaviour: the module the asyncio backend generates for it
    (importing `swarmgen.runtime` instead of a vendored copy), plus what the library needs."""

    member_type: str
    chart_name: str
    code: str
    outputs: dict[str, tuple[tuple[str, str | None], ...]]  # behaviour -> (output, type)
    scopes: dict[str, str]  # event -> "swarm" | "local"


@dataclass(frozen=True)
class Machines:
    model: str
    source: str
    members: tuple[MemberMachine, ...]
    composition: dict[str, int]

    def types(self) -> list[str]:
        return [m.member_type for m in self.members]


def compile_machines(model: Path) -> Machines:
    """Validate and lower the model, and render each member type's module with the asyncio
    backend, exactly as `swarmgen compile` does."""
    from swarmgen import __version__, pipeline
    from swarmgen import diagnostics as dg
    from swarmgen.backends.asyncio_backend import render_member
    from swarmgen.chart.lower import lower
    from swarmgen.ir.query import composition as swarm_composition

    validation = pipeline.validate(model)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        raise SimulationError(dg.refusal_line(model, validation.diagnostics))
    common = {"version": __version__, "source": model.name, "runtime": "swarmgen.runtime"}
    members = []
    for chart in lower(validation.model):
        if chart.member is None:
            continue  # a stand-alone machine: no member runs it
        members.append(
            MemberMachine(
                chart.member,
                chart.name,
                render_member(chart, common),
                {b.name: b.outputs for b in chart.behaviours},
                {e.name: e.scope or "swarm" for e in chart.events},
            )
        )
    if not members:
        raise SimulationError(f"{model}: no member type has a state machine; nothing to simulate")
    composition = swarm_composition(validation.model)
    return Machines(validation.model.name, model.name, tuple(members), composition)


_BUILT: dict[str, tuple[Chart, dict[str, str]]] = {}


def build_chart(machine: MemberMachine) -> tuple[Chart, dict[str, str]]:
    """Run the generated module and its `build()` (once per process)."""
    key = hashlib.sha256(machine.code.encode()).hexdigest()
    if key not in _BUILT:
        namespace: dict[str, Any] = {"__name__": f"swarmgen_sim_{machine.chart_name}"}
        exec(compile(machine.code, f"<generated {machine.chart_name}>", "exec"), namespace)
        _BUILT[key] = (namespace["build"](), dict(namespace["EVENT_SCOPES"]))
    return _BUILT[key]


def waited_outcomes(chart: Chart) -> dict[str, frozenset[str]]:
    """Per state with a behaviour: the outcomes some transition waits for ('*': any)."""
    descriptors = {e for n in chart.nodes.values() for t in n.transitions for e in t.events}
    waited: dict[str, frozenset[str]] = {}
    for node in chart.nodes.values():
        if node.call is None:
            continue
        prefix = f"{OUTCOME_PREFIX}{node.id}."
        names = {d[len(prefix) :] for d in descriptors if d.startswith(prefix)}
        if names & {"*", ""} or descriptors & {"*", "outcome", "outcome.*", prefix[:-1]}:
            names = {"*"}
        waited[node.id] = frozenset(n for n in names if n)
    return waited


# --- one member -------------------------------------------------------------------------------


class _NoLibrary:
    def get(self, name: str) -> Behaviour | None:
        return None


class SimMember(Member):
    """A runtime `Member` whose host services are the batch's discrete-time ones."""

    def __init__(
        self,
        batch: Batch,
        run: int,
        g: int,
        chart: Chart,
        member_type: str,
        index: int,
        bus: InMemoryBus,
        scopes: Mapping[str, str],
        chart_name: str,
    ) -> None:
        self.batch = batch
        self.rank = run  # the run (repetition) of the batch it belongs to
        self.g = g
        self.index = index
        self.chart_name = chart_name
        self.live: dict[str, Activation] = {}  # state id -> its running behaviour
        self.timer_tokens: dict[str, int] = {}
        super().__init__(
            chart, member_type, f"{member_type}-{index}", _NoLibrary(), bus, event_scopes=scopes
        )
        self.engine.clock = lambda: float(batch.t[run])

    def deliver(self, event: Event) -> None:
        self.batch.pending[self.rank].append((self, event))

    def start_call(self, node: Node, call: Call, args: dict[str, Any], activation: int) -> None:
        self.batch.start_call(self, node, call, args, activation)

    def cancel_call(self, node: Node, activation: int) -> None:
        act = self.live.get(node.id)
        if act is not None and act.number == activation:
            self.batch.end(act)

    def start_timer(self, node: Node, event: str, delay_ms: int) -> None:
        token = self.timer_tokens.get(event, 0) + 1
        self.timer_tokens[event] = token
        ticks = max(1, math.ceil(delay_ms / self.batch.scenario.timing["tick_ms"]))

        def fire() -> None:
            if self.timer_tokens.get(event) == token:
                del self.timer_tokens[event]
                self.deliver(self.engine.make_event(event, None, self.member_id))

        self.batch.at(self.rank, self.batch.t[self.rank] + ticks, fire)

    def cancel_timer(self, node: Node, event: str) -> None:
        self.timer_tokens.pop(event, None)


# --- results ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Config:
    counts: tuple[tuple[str, int], ...]  # (member type, count) in model order
    targets: int

    def label(self) -> str:
        parts = [f"{k}={v}" for k, v in self.counts]
        return " ".join([*parts, f"targets={self.targets}"])

    def slug(self) -> str:
        """A directory name: `UAV2_UGV2_targets4`."""
        return "_".join([*(f"{k}{v}" for k, v in self.counts), f"targets{self.targets}"])

    def seed_key(self) -> list[int]:
        return [self.targets, *(count for _, count in self.counts)]


@dataclass
class RunResult:
    config: int  # index into the sweep's configurations
    rep: int
    end_tick: int
    reason: str  # "coverage", "rescued", "ticks" (the stop conditions), "max_ticks", "stalled"
    coverage: list[int | None]  # time to each coverage level (None: not reached)
    coverage_final: float  # share of patches seen at the end
    found: list[int | None]  # per target: time it was found (reported and taken up)
    rescued: list[int | None]  # per target: time it was rescued
    events: int  # events processed by the engines
    errors: list[str] = field(default_factory=list)


# --- a batch of runs --------------------------------------------------------------------------


class Batch:
    """Repetitions of one configuration, simulated together; the engines' host."""

    def __init__(
        self,
        machines: Machines,
        scenario: Scenario,
        config: Config,
        reps: Sequence[int],
        *,
        record: Path | None = None,
        storage: str = "mcap",
    ) -> None:
        self.scenario = scenario
        self.record = record  # a directory: one bag per run, written by `run_all`
        self.storage = storage
        self.recorders: list[BagRecorder] = []
        self.config = config
        self.reps = list(reps)
        runs = len(self.reps)
        self.geometry = geo = Geometry(scenario.width, scenario.height, scenario.view)
        counts = dict(config.counts)
        kinds = [m for m in machines.members if counts.get(m.member_type, 0) > 0]
        self._outputs: dict[str, tuple[tuple[str, str | None], ...]] = {}
        self.scopes: dict[str, str] = {}
        for m in machines.members:
            self._outputs.update(m.outputs)
            self.scopes.update(m.scopes)
        xs, ys, heads, layout = [], [], [], []
        for m in kinds:
            n = counts[m.member_type]
            place = scenario.placement_of(m.member_type)
            x, y = south_line(n, geo, place.spacing)
            xs.append(x)
            ys.append(y)
            heads.append(fan_headings(n) if place.headings == "fan" else np.full(n, math.pi / 2))
            layout += [(m, i + 1) for i in range(n)]
        keys, targets = [], []
        for rep in self.reps:
            seq = np.random.SeedSequence([scenario.seed, *config.seed_key(), rep])
            turns, places = seq.spawn(2)
            keys.append(turns.generate_state(1, np.uint64)[0])
            targets.append(self._targets(np.random.default_rng(places)))
        empty = np.zeros(0)
        self.world = World(
            geo,
            np.array(keys, dtype=np.uint64),
            np.concatenate(xs) if xs else empty,
            np.concatenate(ys) if ys else empty,
            np.concatenate(heads) if heads else empty,
            np.array(targets, dtype=np.int64).reshape(runs, config.targets, 2),
        )
        self.library = Library(scenario.library)
        self.t: list[int] = [0] * runs
        self.pending: list[deque[tuple[SimMember, Event]]] = [deque() for _ in range(runs)]
        self.schedule: list[list[tuple[int, int, Callable[[], None]]]] = [[] for _ in range(runs)]
        self._seq = itertools.count()
        self.finds: dict[int, list[tuple[int, int, int]]] = {}  # run -> (member, x, y)
        self.events = [0] * runs
        self.members: list[SimMember] = []
        self.waited: dict[str, dict[str, frozenset[str]]] = {}
        self.buses: list[InMemoryBus] = []
        for run in range(runs):
            bus = InMemoryBus()
            self.buses.append(bus)
            for m, index in layout:
                chart, scopes = build_chart(m)
                if m.chart_name not in self.waited:
                    self.waited[m.chart_name] = waited_outcomes(chart)
                self.members.append(
                    SimMember(
                        self,
                        run,
                        len(self.members),
                        chart,
                        m.member_type,
                        index,
                        bus,
                        scopes,
                        m.chart_name,
                    )
                )
            for item in scenario.station:
                self.at(run, item.tick, self._broadcast(bus, item.event, item.data))
        self.origin = scenario.origin_tick()
        self.done: list[str | None] = [None] * runs

    def _targets(self, rng: np.random.Generator) -> list[tuple[int, int]]:
        s = self.scenario
        if s.target_positions is not None:
            return list(s.target_positions)
        count = min(self.config.targets, s.width * s.height)
        cells = rng.choice(s.width * s.height, size=count, replace=False)
        return [(int(c % s.width), int(c // s.width)) for c in cells]

    @staticmethod
    def _broadcast(
        bus: InMemoryBus, event: str, data: Mapping[str, Any] | None
    ) -> Callable[[], None]:
        return lambda: bus.broadcast(event, data)

    # --- the host services (swarmgen.sim.library.Host)

    def now(self, run: int) -> int:
        return self.t[run]

    def at(self, run: int, tick: int, then: Callable[[], None]) -> None:
        heapq.heappush(self.schedule[run], (tick, next(self._seq), then))

    def after(self, act: Activation, ticks: int, then: Callable[[], None]) -> None:
        if ticks <= 0:
            then()
            return

        def due() -> None:
            if not act.done:
                then()

        self.at(act.run, self.t[act.run] + ticks, due)

    def finish(self, act: Activation, outcome: str, outputs: Mapping[str, Any] | None) -> None:
        """The behaviour ends: its outcome event goes to the member (the engine drops it if
        the state was left meanwhile, as with asyncio tasks)."""
        if act.done:
            return
        self.end(act)
        member = self.members[act.g]
        member.deliver(
            member.engine.make_event(
                f"{FINALIZE_PREFIX}{act.node_id}.{outcome}",
                dict(outputs or {}),
                member.member_id,
                origin=(act.node_id, act.number),
            )
        )

    def end(self, act: Activation) -> None:
        if act.done:
            return
        act.done = True
        member = self.members[act.g]
        if member.live.get(act.node_id) is act:
            del member.live[act.node_id]
        act.impl.stop(self, act)

    def emit(self, act: Activation, event: str, data: Mapping[str, Any]) -> None:
        act.request.emit(event, data, self.scopes.get(event, "swarm"))

    def outputs_of(self, behaviour: str) -> tuple[tuple[str, str | None], ...]:
        return self._outputs.get(behaviour, ())

    def activation_of(self, g: int, impl: SimBehaviour) -> Activation | None:
        for act in self.members[g].live.values():
            if act.impl is impl:
                return act
        return None

    def start_call(
        self, member: SimMember, node: Node, call: Call, args: dict[str, Any], activation: int
    ) -> None:
        impl = self.library.get(call.behaviour)
        request = Request(
            member.member_type,
            member.member_id,
            node.id,
            call.behaviour,
            args,
            member._emit,
            member.engine.data,
        )
        act = Activation(
            member.g,
            member.rank,
            node.id,
            activation,
            call.behaviour,
            request,
            self.waited[member.chart_name].get(node.id, frozenset()),
            self.t[member.rank],
            impl,
        )
        old = member.live.get(node.id)
        if old is not None:
            self.end(old)
        member.live[node.id] = act
        claims(self.world, member.rank, member.g, args)
        impl.start(self, act)

    # --- time

    def run_all(self) -> list[RunResult]:
        if self.record is None:
            return self._run_all()
        from swarmgen.trace.bag import BagRecorder, VirtualClock

        try:
            for rep in self.reps:
                path = self.record / f"{self.config.slug()}-{rep:04d}"
                self.recorders.append(BagRecorder(path, storage=self.storage, clock=VirtualClock()))
            return self._run_all()
        finally:
            for recorder in self.recorders:
                recorder.close()

    def _run_all(self) -> list[RunResult]:
        runs = len(self.reps)
        for member in self.members:
            member.engine.start()
            if self.recorders:
                self.recorders[member.rank].step(member, None, stamp_ns=0)
        for run in range(runs):
            self._drain(run)
        active = list(range(runs))
        while active:
            for run in active:
                self._process(run)
                self._check(run)
            active = [r for r in active if self.done[r] is None]
            if not active:
                break
            per = self.world.per_run
            movers = sum(int(self.world.moving[r * per : (r + 1) * per].sum()) for r in active)
            cap = max(MIN_CHUNK, POINTS_PER_ROUND // max(1, movers))
            now = np.array(self.t, dtype=np.int64)
            horizon = now.copy()
            for run in active:
                t = self.t[run]
                schedule = self.schedule[run]
                due = schedule[0][0] if schedule else INF
                chunk = min(cap, max(MIN_CHUNK, (t - self.origin) // 8))
                horizon[run] = max(t, min(due, t + chunk, self.scenario.max_ticks))
            end, finds = self.world.advance(now, horizon)
            for run, g, ix, iy in finds:
                self.finds.setdefault(run, []).append((g, ix, iy))
            for run in active:
                self.t[run] = int(end[run])
        return [self._result(run) for run in range(runs)]

    def _moving(self, run: int) -> bool:
        per = self.world.per_run
        return bool(self.world.moving[run * per : (run + 1) * per].any())

    def _process(self, run: int) -> None:
        t = self.t[run]
        for g, ix, iy in self.finds.pop(run, []):
            targets = self.world.targets_in_view(g, ix, iy)
            if targets:
                found(self, run, g, targets)
        schedule = self.schedule[run]
        while schedule and schedule[0][0] <= t:
            heapq.heappop(schedule)[2]()
            self._drain(run)
        self._drain(run)
        fresh = self.world.fresh[run]
        for target in fresh:  # finds nobody took up are forgotten
            if self.world.status[run, target] == FOUND:
                self.world.forget(run, target)
        fresh.clear()

    def _drain(self, run: int) -> None:
        queue = self.pending[run]
        recorder = self.recorders[run] if self.recorders else None
        count = 0
        while queue:
            member, event = queue.popleft()
            member.engine.send(event)
            if recorder is not None:
                stamp = self.t[run] * self.scenario.timing["tick_ms"] * 1_000_000
                recorder.step(member, event, stamp_ns=stamp)
            count += 1
            if count > EVENTS_PER_TICK:
                raise SimulationError(
                    f"run {self.reps[run]} of {self.config.label()}: more than "
                    f"{EVENTS_PER_TICK} events at tick {self.t[run]} (a livelock in the model?)"
                )
        self.events[run] += count

    def _check(self, run: int) -> None:
        if self.done[run] is not None:
            return
        s = self.scenario
        if s.stop == "coverage":
            need = max(1, math.ceil(s.stop_level * self.geometry.cells - 1e-9))
            if self.world.covered[run] >= need:
                self.done[run] = "coverage"
        elif s.stop == "rescued":
            status = self.world.status[run]
            need = math.ceil(s.stop_level * len(status) - 1e-9)
            if int((status == RESCUED).sum()) >= need and self.t[run] >= self.origin:
                self.done[run] = "rescued"
        if self.done[run] is None:
            if self.t[run] >= s.max_ticks:
                self.done[run] = "ticks" if s.stop == "ticks" else "max_ticks"
            elif not self.schedule[run] and not self._moving(run):
                self.done[run] = "stalled"  # nothing will ever happen again
        if self.done[run] is not None:
            per = self.world.per_run
            self.world.moving[run * per : (run + 1) * per] = False

    def _result(self, run: int) -> RunResult:
        w = self.world
        seen = np.sort(w.seen_times(run).reshape(-1))
        cells = len(seen)
        coverage: list[int | None] = []
        for level in self.scenario.coverage_levels:
            need = max(1, math.ceil(level * cells - 1e-9))
            value = int(seen[need - 1])
            coverage.append(None if value == INF else value - self.origin)
        errors = [
            e for m in self.members[run * w.per_run : (run + 1) * w.per_run] for e in m.errors
        ]

        def times(ticks: np.ndarray) -> list[int | None]:
            return [None if v < 0 else int(v) - self.origin for v in ticks.tolist()]

        end = self.t[run]
        if self.done[run] == "coverage":  # rounds may overshoot: the tick it was reached
            end = int(seen[max(1, math.ceil(self.scenario.stop_level * cells - 1e-9)) - 1])
        return RunResult(
            config=-1,
            rep=self.reps[run],
            end_tick=end,
            reason=self.done[run] or "stalled",
            coverage=coverage,
            coverage_final=float(np.count_nonzero(seen != INF)) / cells,
            found=times(w.found_tick[run]),
            rescued=times(w.rescued_tick[run]),
            events=self.events[run],
            errors=errors[:20],
        )


# --- sweeps -----------------------------------------------------------------------------------


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


# --- outputs ----------------------------------------------------------------------------------


def outputs(sim: Simulation) -> dict[str, bytes]:
    """The result files: tables (CSV), everything as JSON, and the figures (PNG, SVG)."""
    import json
    from dataclasses import asdict

    from swarmgen import __version__
    from swarmgen.sim import plots, stats

    summary = stats.summarise(sim)
    types = summary.types
    files: dict[str, bytes] = {}
    files["runs.csv"] = stats.runs_table(sim).encode()
    files["coverage.csv"] = stats.table(summary.coverage, types, "coverage").encode()
    if summary.search:
        files["search.csv"] = stats.table(summary.search, types, "targets").encode()
        files["rescue.csv"] = stats.table(summary.rescue, types, "targets").encode()
    payload = {
        "generator": "swarmgen simulate",
        "version": __version__,
        "model": sim.machines.model,
        "source": sim.machines.source,
        "scenario": sim.scenario.to_json(),
        "configurations": [{"members": dict(c.counts), "targets": c.targets} for c in sim.configs],
        "summary": stats.to_json(summary),
        "runs": [asdict(r) for r in sim.runs],
    }
    files["results.json"] = (json.dumps(payload, indent=1, sort_keys=True) + "\n").encode()
    title = f"{sim.machines.model}: {sim.scenario.name}"
    for name, figure in (
        ("coverage", plots.coverage_figure(summary, title)),
        ("sar", plots.sar_figure(summary, title)),
    ):
        for fmt, data in (figure or {}).items():
            files[f"{name}.{fmt}"] = data
    return files


def write_outputs(files: Mapping[str, bytes], out_dir: Path, source: str) -> None:
    """Make `out_dir` hold exactly `files` and their manifest, under the rules of
    `swarmgen.outtree` (only swarmgen's own unedited files are replaced; crash-safe)."""
    tree: dict[PurePosixPath, str | bytes] = {PurePosixPath(n): d for n, d in files.items()}
    tree[PurePosixPath(outtree.MANIFEST)] = outtree.manifest_text("simulate", source, tree)
    outtree.write(tree, out_dir)


def simulate_model(
    model: Path,
    scenario: Scenario,
    out_dir: Path | None,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    record: Path | None = None,
    storage: str = "mcap",
) -> tuple[Simulation, dict[str, bytes]]:
    """`swarmgen simulate`: compile MODEL, run the scenario's sweep, write the results (and with
    `record`, one bag per run into that new directory)."""
    if out_dir is not None:
        outtree.preflight(out_dir, "simulate")  # a bad -o is refused before the runs, not after
    machines = compile_machines(model)
    sim = simulate(
        machines, scenario, workers=workers, progress=progress, record=record, storage=storage
    )
    files = outputs(sim)
    if out_dir is not None:
        write_outputs(files, out_dir, model.name)
    return sim, files
