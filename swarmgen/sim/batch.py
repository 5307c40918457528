"""A batch: repetitions of one configuration simulated together, the engines' discrete-time host.

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
configurations and chunks of repetitions are spread over processes (`swarmgen.sim.sweep`). A run's
random numbers depend only on (seed, configuration, repetition), so results do not depend on
`--workers`.

With `record` (`swarmgen simulate --record DIR`), each run writes a ROS 2 bag,
`DIR/<configuration>-<rep>` (see `Config.slug`), in the process that simulates it: every event
every member processes and every change of its active states, stamped with the run's tick
(`tick * tick_ms` ms since the start, launch being tick 0 in the shipped scenarios).
"""

from __future__ import annotations

import copy
import heapq
import itertools
import math
import re
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from swarmgen.records import dataclass
from swarmgen.runtime.chart import Call, Node
from swarmgen.runtime.engine import FINALIZE_PREFIX, Event
from swarmgen.runtime.member import InMemoryBus, Request
from swarmgen.sim.grid import INF, Geometry, fan_headings, south_line
from swarmgen.sim.library import Activation, Library, SimBehaviour, claims, found
from swarmgen.sim.machines import Machines, MemberMachine, build_chart, waited_outcomes
from swarmgen.sim.member import SimMember
from swarmgen.sim.scenario import Scenario, SimulationError
from swarmgen.sim.world import FOUND, RESCUED, World

if TYPE_CHECKING:
    from swarmgen.trace.recorder import BagRecorder

POINTS_PER_ROUND = 1_000_000  # positions computed per round at most (memory bound)
_SLUG = re.compile(r"[^A-Za-z0-9.-]")
MIN_CHUNK = 256
EVENTS_PER_TICK = 200_000  # more events than this in one tick of one run: a livelock

# --- results ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Config:
    """One swarm configuration of a sweep: member counts and the number of targets."""

    counts: tuple[tuple[str, int], ...]  # (member type, count) in model order
    targets: int
    # the swept parameters other than counts and targets (`sim.params`), in sweep order; they
    # do not key the random streams: the points of a sweep share them (common random numbers)
    params: tuple[tuple[str, bool | int | float | str], ...] = ()

    def label(self) -> str:
        """The configuration as reports show it: `UAV=2 UGV=2 targets=4 world.view=2`."""
        parts = [f"{k}={v}" for k, v in self.counts]
        return " ".join([*parts, f"targets={self.targets}", *(f"{k}={v}" for k, v in self.params)])

    def slug(self) -> str:
        """A directory name: `UAV2_UGV2_targets4` (then `_world.view2`: parameters, with any
        character but letters, digits, `.` and `-` as `-`)."""
        swept = (_SLUG.sub("-", f"{k}{v}") for k, v in self.params)
        return "_".join([*(f"{k}{v}" for k, v in self.counts), f"targets{self.targets}", *swept])

    def seed_key(self) -> list[int]:
        """The numbers that key the configuration's random streams."""
        return [self.targets, *(count for _, count in self.counts)]


@dataclass
class RunResult:
    """What one repetition measured: why it stopped, coverage, search and rescue times."""

    config: int  # index into the sweep's configurations
    rep: int
    end_tick: int
    reason: str  # "coverage", "rescued", "ticks" (the stop conditions), "max_ticks", "stalled"
    coverage: list[float | None]  # time to each coverage level (None: not reached)
    coverage_final: float  # share of patches seen at the end
    found: list[float | None]  # per target: time it was found (reported and taken up)
    rescued: list[float | None]  # per target: time it was rescued
    events: int  # events processed by the engines
    errors: list[str] = field(default_factory=list)


def run_draws(scenario: Scenario, config: Config, rep: int) -> tuple[int, list[tuple[int, int]]]:
    """A run's random draws, the same at every level (the detailed one places its targets and
    keys its members' streams with them): the key of its members' turn streams, and its target
    patches (the scenario's, or drawn without repeats)."""
    seq = np.random.SeedSequence([scenario.seed, *config.seed_key(), rep])
    turns, places = seq.spawn(2)
    key = int(turns.generate_state(1, np.uint64)[0])
    if scenario.target_positions is not None:
        return key, list(scenario.target_positions)
    count = min(config.targets, scenario.width * scenario.height)
    cells = np.random.default_rng(places).choice(
        scenario.width * scenario.height, size=count, replace=False
    )
    return key, [(int(c % scenario.width), int(c // scenario.width)) for c in cells]


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
        counts = dict(config.counts)
        kinds = [m for m in machines.members if counts.get(m.member_type, 0) > 0]
        # the grid is padded by the largest view of the members it holds
        views = [scenario.view_of(m.member_type) for m in kinds]
        self.geometry = Geometry(scenario.width, scenario.height, max(views, default=scenario.view))
        self._outputs: dict[str, tuple[tuple[str, str | None], ...]] = {}
        self.scopes: dict[str, str] = {}
        self._initials: dict[tuple[str, str], Any] = {}
        self._emits: dict[str, tuple[str, ...]] = {}
        for m in machines.members:
            self._outputs.update(m.outputs)
            self._emits.update(m.emits)
            self.scopes.update(m.scopes)
            self._initials.update(m.initials)
        self.world = self._world(kinds, counts)
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
        layout = [(m, i + 1) for m in kinds for i in range(counts[m.member_type])]
        for run in range(runs):
            self._populate(run, layout)
        self.origin = scenario.origin_tick()
        self.done: list[str | None] = [None] * runs

    def _world(self, kinds: list[MemberMachine], counts: dict[str, int]) -> World:
        """Every run's world: the members in a line along the south edge, targets drawn per run."""
        scenario, geo = self.scenario, self.geometry
        xs, ys, heads, views = [], [], [], []
        for m in kinds:
            n = counts[m.member_type]
            views.append(np.full(n, scenario.view_of(m.member_type), dtype=np.int64))
            place = scenario.placement_of(m.member_type)
            x, y = south_line(n, geo, place.spacing)
            xs.append(x)
            ys.append(y)
            heads.append(fan_headings(n) if place.headings == "fan" else np.full(n, math.pi / 2))
        keys, targets = [], []
        for rep in self.reps:
            key, placed = run_draws(scenario, self.config, rep)
            keys.append(key)
            targets.append(placed)
        empty = np.zeros(0)
        return World(
            geo,
            np.array(keys, dtype=np.uint64),
            np.concatenate(xs) if xs else empty,
            np.concatenate(ys) if ys else empty,
            np.concatenate(heads) if heads else empty,
            np.array(targets, dtype=np.int64).reshape(len(self.reps), self.config.targets, 2),
            np.concatenate(views) if views else None,
        )

    def _populate(self, run: int, layout: list[tuple[MemberMachine, int]]) -> None:
        """The members of one run on its own bus, and the station's events in its schedule."""
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
        for item in self.scenario.station:
            self.at(run, item.tick, self._broadcast(bus, item.event, item.data))

    @staticmethod
    def _broadcast(
        bus: InMemoryBus, event: str, data: Mapping[str, Any] | None
    ) -> Callable[[], None]:
        return lambda: bus.broadcast(event, data)

    # --- the host services (swarmgen.sim.library.Host)

    def now(self, run: int) -> int:
        """The current tick of a run."""
        return self.t[run]

    def at(self, run: int, tick: int, then: Callable[[], None]) -> None:
        """Schedule `then` at a tick of a run."""
        heapq.heappush(self.schedule[run], (tick, next(self._seq), then))

    def after(self, act: Activation, ticks: int, then: Callable[[], None]) -> None:
        """Run `then` `ticks` from now, unless the activation has ended by then."""
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
        """End an activation (idempotent): forget it and stop its implementation."""
        if act.done:
            return
        act.done = True
        member = self.members[act.g]
        if member.live.get(act.node_id) is act:
            del member.live[act.node_id]
        act.impl.stop(self, act)

    def emit(self, act: Activation, event: str, data: Mapping[str, Any]) -> None:
        """Emit an event of a behaviour through its member's bus, in the event's scope."""
        act.request.emit(event, data, self.scopes.get(event, "swarm"))

    def outputs_of(self, behaviour: str) -> tuple[tuple[str, str | None], ...]:
        """The outputs (identifier, type) a behaviour declares."""
        return self._outputs.get(behaviour, ())

    def emits_of(self, behaviour: str) -> tuple[str, ...]:
        """The events a behaviour's `emits` tag names."""
        return self._emits.get(behaviour, ())

    def initial_of(self, owner: str, name: str) -> Any:
        """The initial value of a behaviour's output or an event's field (None: unknown)."""
        return copy.deepcopy(self._initials.get((owner, name)))

    def activation_of(self, g: int, impl: SimBehaviour) -> Activation | None:
        """The member's live activation of an implementation, if any."""
        for act in self.members[g].live.values():
            if act.impl is impl:
                return act
        return None

    def start_call(
        self, member: SimMember, node: Node, call: Call, args: dict[str, Any], activation: int
    ) -> None:
        """Start a state's behaviour in the simulated library (the engine's host call)."""
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
        """Run every repetition (recording a bag per run with `record`); their results."""
        if self.record is None:
            return self._run_all()
        from swarmgen.trace.recorder import BagRecorder, VirtualClock

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
            self._check(active)
            active = [r for r in active if self.done[r] is None]
            if not active:
                break
            now = np.array(self.t, dtype=np.int64)
            end, finds = self.world.advance(now, self._horizons(now, active))
            for run, g, ix, iy in finds:
                self.finds.setdefault(run, []).append((g, ix, iy))
            ends = end.tolist()
            for run in active:
                self.t[run] = ends[run]
        return [self._result(run) for run in range(runs)]

    def _horizons(self, now: np.ndarray, active: list[int]) -> np.ndarray:
        """Each active run's next round ends at its next scheduled tick, or after a chunk of
        ticks that grows with the elapsed time (bounded by the points a round may compute)."""
        per = self.world.per_run
        movers = int(self.world.moving.reshape(-1, per)[active].sum())
        cap = max(MIN_CHUNK, POINTS_PER_ROUND // max(1, movers))
        horizon = now.copy()
        for run in active:
            t = self.t[run]
            schedule = self.schedule[run]
            due = schedule[0][0] if schedule else INF
            chunk = min(cap, max(MIN_CHUNK, (t - self.origin) // 8))
            horizon[run] = max(t, min(due, t + chunk, self.scenario.max_ticks))
        return horizon

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

    def _check(self, active: list[int]) -> None:
        """Which active runs stop now, and why (one pass over the world's per-run arrays)."""
        s, w = self.scenario, self.world
        covered = w.covered.tolist()
        moving = np.any(w.moving.reshape(-1, w.per_run), axis=1).tolist()
        need = max(1, math.ceil(s.stop_level * self.geometry.cells - 1e-9))
        for run in active:
            if s.stop == "coverage":
                if covered[run] >= need:
                    self.done[run] = "coverage"
            elif s.stop == "rescued":
                status = w.status[run]
                rescued = math.ceil(s.stop_level * len(status) - 1e-9)
                if int((status == RESCUED).sum()) >= rescued and self.t[run] >= self.origin:
                    self.done[run] = "rescued"
            if self.done[run] is None:
                if self.t[run] >= s.max_ticks:
                    self.done[run] = "ticks" if s.stop == "ticks" else "max_ticks"
                elif not self.schedule[run] and not moving[run]:
                    self.done[run] = "stalled"  # nothing will ever happen again
            if self.done[run] is not None:
                w.moving[run * w.per_run : (run + 1) * w.per_run] = False

    def _result(self, run: int) -> RunResult:
        w = self.world
        seen = w.seen_times(run).reshape(-1)
        cells = len(seen)
        levels = [*self.scenario.coverage_levels, self.scenario.stop_level]
        needs = [max(1, math.ceil(level * cells - 1e-9)) - 1 for level in levels]
        # the order statistics the levels need, each exact (a partial sort: O(cells))
        seen = np.partition(seen, sorted(set(needs)))
        coverage: list[float | None] = []
        for need in needs[:-1]:
            value = int(seen[need])
            coverage.append(None if value == INF else value - self.origin)
        errors = [
            e for m in self.members[run * w.per_run : (run + 1) * w.per_run] for e in m.errors
        ]

        def times(ticks: np.ndarray) -> list[float | None]:
            return [None if v < 0 else int(v) - self.origin for v in ticks.tolist()]

        end = self.t[run]
        if self.done[run] == "coverage":  # rounds may overshoot: the tick it was reached
            end = int(seen[needs[-1]])
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
