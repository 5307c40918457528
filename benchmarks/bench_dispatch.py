"""Event dispatch: the generated asyncio code (its vendored engine) vs sismic vs Qt SCXML, on
the SAR UAV machine and the same event trace, side by side in one run; and the engine on a
synthetic chart of `--synth-states` states (benchmarks/synth_model.py) against a small one of
the same shape, on seeded walks: the per-event cost must not grow with the chart.

    .venv/bin/python benchmarks/bench_dispatch.py [--events 30000] [--reps 5] [--synth-states N]

Each repetition runs every case once, in turn; the figures are the medians over repetitions
(the machine is shared: read the ratios). What the harness holds before a timed loop (the
compiler, the lowered charts, the events made beforehand) is frozen out of the garbage collector
(`gc.freeze`) for every in-process case alike: else the collector's full passes over the
compiler's heap, which a generated package's process does not have, are a third of the time. The
timed loops start after the chart's first engine, which builds the dispatch tables that do not
depend on the events (`first_engine_seconds`, CPU time, is reported beside them). Needs `sismic`
(pip install -e '.[bench]') and Qt SCXML (make sysdeps). Writes benchmarks/results/dispatch.json.
Before and after a change: benchmarks/compare_dispatch.py.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import gc
import importlib
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen import pipeline  # noqa: E402
from swarmgen.chart import model as c  # noqa: E402
from swarmgen.chart.lower import lower  # noqa: E402
from swarmgen.runtime.chart import FINALIZE_PREFIX, Chart  # noqa: E402
from swarmgen.runtime.engine import Engine, NullHost  # noqa: E402

MODEL = ROOT / "sample_models" / "sar" / "sar.xmi"
# One mission loop of the UAV: the trace repeats it (after launch and take-off).
PROLOGUE = ["launch", "outcome.TakeOff.succeeded", "missionStart"]
LOOP = [
    "targetFound",
    "outcome.SelectRover.succeeded",
    "outcome.Tracking.targetLost",
    "outcome.LocalCoverage.succeeded",
    "outcome.Tracking.succeeded",
    "unrelatedEvent",  # events nobody reacts to are part of real traffic
]


@contextlib.contextmanager
def settled_heap() -> Iterator[None]:
    """The timed loop's collector sees only what the loop allocates (see the docstring)."""
    gc.collect()
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def trace(count: int) -> list[str]:
    events = list(PROLOGUE)
    while len(events) < count:
        events.extend(LOOP)
    return events[:count]


def uav_chart() -> c.Chart:
    model = pipeline.validate(MODEL).model
    assert model is not None
    return next(ch for ch in lower(model) if ch.member == "UAV")


# --- swarmgen: the generated asyncio package ---------------------------------------------------


def generated_module(tmp: Path) -> Any:
    result = pipeline.compile_model(MODEL, backends=["asyncio"])
    pipeline.write_tree(result.files, tmp / "out")
    sys.path.insert(0, str(tmp / "out" / "asyncio"))
    return importlib.import_module("search_and_rescue_swarm")


def bench_swarmgen_engine(package: Any, events: list[str]) -> tuple[float, list[str]]:
    """The generated chart on its vendored engine: synchronous dispatch, no behaviours run."""
    engine_module = importlib.import_module("search_and_rescue_swarm._runtime.engine")
    engine = engine_module.Engine(package.uav.build(), engine_module.NullHost())
    engine.start()
    made = [engine.make_event(name) for name in events]
    with settled_heap():
        started = time.perf_counter()
        for event in made:
            engine.send(event)
        elapsed = time.perf_counter() - started
    return elapsed, engine.active()


def bench_swarmgen_member(package: Any, events: list[str]) -> float:
    """The same, through the asyncio member: queue, engine, behaviour tasks started/cancelled."""
    member_module = importlib.import_module("search_and_rescue_swarm._runtime.member")
    simulated = importlib.import_module("search_and_rescue_swarm._runtime.simulated")
    behaviours = importlib.import_module("search_and_rescue_swarm.behaviours")
    library = simulated.SimulatedLibrary(
        {b: simulated.Script(forever=True) for b in behaviours.SIGNATURES}
    )

    class _Bus:
        def attach(self, member: Any) -> None: ...
        def publish(self, event: Any, scope: str) -> None: ...

    async def run() -> float:
        member = member_module.Member(package.uav.build(), "UAV", "1", library, _Bus())
        runner = asyncio.create_task(member.run())
        await asyncio.sleep(0)
        with settled_heap():
            started = time.perf_counter()
            for name in events:
                member.deliver(member.engine.make_event(name))
            while not member.queue.empty():
                await asyncio.sleep(0)
            elapsed = time.perf_counter() - started
        member.stop()
        await runner
        return elapsed

    return asyncio.run(run())


# --- sismic -------------------------------------------------------------------------------------


def sismic_yaml(chart: c.Chart) -> str:
    """The chart as a sismic statechart (JSON is YAML). Guards and actions are not needed for
    the UAV trace (it has none but assignments on targetFound, written as sismic actions)."""

    def state(node: c.Node) -> dict[str, Any]:
        data: dict[str, Any] = {"name": node.id}
        if node.kind == "final":
            data["type"] = "final"
        if node.kind == "history":
            data["type"] = f"{node.history} history"
            if node.initial is not None:
                data["memory"] = node.initial.targets[0]
            return data
        children = [state(child) for child in node.children]
        if node.kind == "parallel":
            data["parallel states"] = children
        elif children:
            data["states"] = children
            if node.initial is not None:
                data["initial"] = node.initial.targets[0]
        transitions = []
        for transition in node.transitions:
            item: dict[str, Any] = {}
            if transition.targets:
                item["target"] = transition.targets[0]
            if transition.events:
                item["event"] = transition.events[0]
            if transition.actions:
                item["action"] = "count = count + 1"
            transitions.append(item)
        if transitions:
            data["transitions"] = transitions
        return data

    root = {
        "name": "root",
        "initial": chart.initial[0],
        "states": [state(n) for n in chart.children],
    }
    statechart = {"statechart": {"name": chart.name, "preamble": "count = 0", "root state": root}}
    return json.dumps(statechart)


def bench_sismic(chart: c.Chart, events: list[str]) -> tuple[float, list[str]]:
    from sismic.interpreter import Interpreter
    from sismic.io import import_from_yaml

    interpreter = Interpreter(import_from_yaml(text=sismic_yaml(chart)))
    interpreter.execute()
    with settled_heap():
        started = time.perf_counter()
        for name in events:
            interpreter.queue(name)
            interpreter.execute()
        elapsed = time.perf_counter() - started
    return elapsed, sorted(s for s in interpreter.configuration if s != "root")


# --- Qt SCXML -----------------------------------------------------------------------------------

QT_BENCH = """
import json, os, sys, time
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
from PySide2.QtCore import QCoreApplication
from PySide2.QtScxml import QScxmlStateMachine
app = QCoreApplication([])
machine = QScxmlStateMachine.fromFile(sys.argv[1])
events = json.load(open(sys.argv[2]))
machine.start()
app.processEvents()
started = time.perf_counter()
for name in events:
    machine.submitEvent(name)
    app.processEvents()
elapsed = time.perf_counter() - started
print(json.dumps({"elapsed": elapsed, "active": sorted(machine.activeStateNames(False))}))
"""


def bench_qt(tmp: Path, events: list[str]) -> tuple[float, list[str]]:
    result = pipeline.compile_model(MODEL, backends=[])
    document = tmp / "UAV.scxml"
    document.write_text(result.files[pipeline.PurePosixPath("scxml/UAV.scxml")])
    trace_file = tmp / "events.json"
    trace_file.write_text(json.dumps(events))
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("_ROS_WHEELS") and k != "LD_LIBRARY_PATH"
    }
    completed = subprocess.run(
        ["/usr/bin/python3", "-c", QT_BENCH, str(document), str(trace_file)],
        capture_output=True, text=True, check=True, env=env, timeout=600,
    )  # fmt: skip
    payload = json.loads(completed.stdout)
    return payload["elapsed"], payload["active"]


# --- a synthetic chart of N states ---------------------------------------------------------------


def synth_chart(tmp: Path, states: int) -> Callable[[], Chart]:
    """The `build()` of the synthetic model's Scout chart, as the asyncio backend renders it
    (on `swarmgen.runtime`; not formatted with black, which only changes the layout)."""
    from swarmgen.backends.pycommon import member_view
    from swarmgen.backends.pyrender import ChartRenderer
    from swarmgen.render import render

    sys.path.insert(0, str(ROOT / "benchmarks"))
    import synth_model

    xmi = tmp / f"synth{states}.xmi"
    xmi.write_text(synth_model.generate(states), encoding="utf-8")
    chart = next(ch for ch in pipeline.validate(xmi).charts if ch.member == "Scout")
    common = {"version": "bench", "source": xmi.name, "runtime": "swarmgen.runtime"}
    code = render(
        "asyncio/member.py.j2", **member_view(chart, common, ChartRenderer(chart).render())
    )
    namespace: dict[str, Any] = {"__name__": f"bench_synth_{states}"}
    exec(compile(code, f"<synthetic {states}>", "exec"), namespace)
    build: Callable[[], Chart] = namespace["build"]
    return build


Step = tuple[str, dict[str, Any] | None]  # an event of a walk: name, data


def walk(build: Callable[[], Chart], count: int, seed: int = 1) -> list[Step]:
    """A seeded walk: each event one that some transition of the configuration waits for (a
    behaviour's end as `done.invoke.<state>.<outcome>`), with data that lets the synthetic
    model's guards pass as often as not (so the walk moves through its groups), every sixth
    one nobody handles; an event that ends the machine is left out from then on (the walk
    replays to go on)."""
    rng = random.Random(seed)
    events: list[Step] = []
    banned: set[str] = set()
    engine = Engine(build(), NullHost())
    engine.start()
    while len(events) < count:
        if len(events) % 6 == 5:
            step: Step = ("unrelatedEvent", None)
        else:
            names = sorted(set(_waited(engine)) - banned)
            if not names:
                raise RuntimeError(f"the walk is stuck in {engine.active()}")
            name = rng.choice(names)
            step = (name, _walk_data(engine, name, rng))
        engine.send(engine.make_event(*step))
        if not engine.running:
            banned.add(step[0])
            engine = Engine(build(), NullHost())
            engine.start()
            for earlier in events:
                engine.send(engine.make_event(*earlier))
            continue
        events.append(step)
    return events


def _walk_data(engine: Engine, name: str, rng: random.Random) -> dict[str, Any] | None:
    """Fields for the synthetic model's guarded events (benchmarks/synth_model.py)."""
    if name == "advance":  # `event.step == j` leaves group j
        groups = [n for n in engine.active() if n.count("_") == 1 and "_G" in n]
        return {"step": int(groups[0].split("_G")[1]) if groups else 1}
    if name == "targetFound":
        return {"target_id": rng.choice([0, 1])}
    if name == "alarm":
        return {"level": rng.choice([1, 3])}
    return None


def _waited(engine: Engine) -> list[str]:
    found = []
    for node in engine.config:
        for transition in node.transitions:
            for descriptor in transition.events:
                if "*" in descriptor:
                    continue
                if descriptor.startswith(FINALIZE_PREFIX) and node.call is not None:
                    found.extend(f"{descriptor}.{o}" for o in node.call.outcomes)
                else:
                    found.append(descriptor)
    return found


def explored(build: Callable[[], Chart], events: list[Step]) -> int:
    """How many states the walk makes active at some point."""
    engine = Engine(build(), NullHost())
    engine.start()
    seen = set(engine.active())
    for step in events:
        engine.send(engine.make_event(*step))
        seen.update(engine.active())
    return len(seen)


def bench_engine(build: Callable[[], Chart], events: list[Step]) -> float:
    """The engine alone: synchronous dispatch, no behaviours run (events made beforehand)."""
    engine = Engine(build(), NullHost())
    engine.start()
    made = [engine.make_event(*step) for step in events]
    with settled_heap():
        started = time.perf_counter()
        for event in made:
            engine.send(event)
        return time.perf_counter() - started


def first_engine(build: Callable[[], Any], engine_class: Callable[..., Any], host: Any) -> float:
    """CPU seconds of a chart's first engine, which builds the chart's dispatch tables (what
    `Tables` makes ahead of the first event is paid there, not in the timed loops above)."""
    chart = build()
    with settled_heap():  # as for the timed loops: the harness's heap is not the process's
        started = time.process_time()
        engine_class(chart, host)
        return time.process_time() - started


# --- the run --------------------------------------------------------------------------------------


def repeated(cases: dict[str, Callable[[], float]], reps: int) -> dict[str, list[float]]:
    """Every case once per repetition, in turn, so that all see the same load."""
    seconds: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(reps):
        for name, case in cases.items():
            seconds[name].append(case())
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--events", type=int, default=30_000)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--synth-states", type=int, default=10_000, help="0: leave it out")
    parser.add_argument("--synth-small", type=int, default=100)
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results")
    args = parser.parse_args()
    events = trace(args.events)
    chart = uav_chart()
    rows: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        package = generated_module(tmp)
        _, ours_active = bench_swarmgen_engine(package, events)
        _, sismic_active = bench_sismic(chart, events)
        _, qt_active = bench_qt(tmp, events)
        cases: dict[str, Callable[[], float]] = {
            "swarmgen engine (generated asyncio package)": lambda: bench_swarmgen_engine(
                package, events
            )[0],
            "swarmgen asyncio member (queue + tasks)": lambda: bench_swarmgen_member(
                package, events
            ),
            "sismic 1.6": lambda: bench_sismic(chart, events)[0],
            "Qt SCXML 5.15 (PySide2)": lambda: bench_qt(tmp, events)[0],
        }
        engine_module = importlib.import_module("search_and_rescue_swarm._runtime.engine")
        firsts = {
            "swarmgen engine (generated asyncio package)": lambda: first_engine(
                package.uav.build, engine_module.Engine, engine_module.NullHost()
            )
        }
        walks: dict[str, tuple[int, int]] = {}
        for states in (args.synth_small, args.synth_states):
            if states:
                synth = synth_chart(tmp, states)
                synth_events = walk(synth, args.events)
                name = f"swarmgen engine, synthetic {states}-state chart (walk)"
                walks[name] = (states, explored(synth, synth_events))
                # a chart built afresh each time (its dispatch tables start empty), as the UAV's
                cases[name] = lambda synth=synth, ev=synth_events: bench_engine(synth, ev)
                firsts[name] = lambda synth=synth: first_engine(synth, Engine, NullHost())
        seconds = repeated(cases, args.reps)
        tables = repeated(firsts, args.reps)
    for name, values in seconds.items():
        median = statistics.median(values)
        rows[name] = {
            "seconds": median,
            "events_per_second": round(len(events) / median),
            "seconds_each": [round(v, 4) for v in values],
        }
    reference = rows["sismic 1.6"]["events_per_second"]
    uav = rows["swarmgen engine (generated asyncio package)"]["events_per_second"]
    for name, row in rows.items():
        row["x_sismic"] = round(row["events_per_second"] / reference, 1)
        if name in tables:  # CPU time, before the first event
            row["first_engine_seconds"] = round(statistics.median(tables[name]), 4)
        if name in walks:
            row["states"], row["states_the_walk_visits"] = walks[name]
            row["of_uav_rate"] = round(row["events_per_second"] / uav, 2)
    agree = ours_active == sismic_active == [s for s in qt_active]
    print(f"{len(events)} events on the SAR UAV machine; final configurations agree: {agree}")
    print(f"medians of {args.reps} repetitions")
    print(f"{'implementation':56} {'events/s':>10} {'x sismic':>9}")
    for name, row in rows.items():
        print(f"{name:56} {row['events_per_second']:>10} {row['x_sismic']:>9}")
    for name, values in tables.items():
        print(f"first engine (its dispatch tables), {name}: {statistics.median(values):.4f} s CPU")
    args.output.mkdir(parents=True, exist_ok=True)
    payload = {
        "events": len(events),
        "repetitions": args.reps,
        "configurations_agree": agree,
        "results": rows,
    }
    (args.output / "dispatch.json").write_text(json.dumps(payload, indent=2) + "\n")


if __name__ == "__main__":
    main()
