"""Event dispatch: the generated asyncio code (its vendored engine) vs sismic vs Qt SCXML, on
the SAR UAV machine and the same event trace, side by side in one run.

    .venv/bin/python benchmarks/bench_dispatch.py [--events 30000]

Needs `sismic` (pip install -e '.[bench]') and Qt SCXML (make sysdeps). Writes
benchmarks/results/dispatch.json.
"""

from __future__ import annotations

import argparse
import asyncio
import importlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen import pipeline  # noqa: E402
from swarmgen.chart import model as c  # noqa: E402
from swarmgen.chart.lower import lower  # noqa: E402

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--events", type=int, default=30_000)
    args = parser.parse_args()
    events = trace(args.events)
    chart = uav_chart()
    rows: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        package = generated_module(tmp)
        elapsed, ours_active = bench_swarmgen_engine(package, events)
        rows["swarmgen engine (generated asyncio package)"] = {"seconds": elapsed}
        rows["swarmgen asyncio member (queue + tasks)"] = {
            "seconds": bench_swarmgen_member(package, events)
        }
        elapsed, sismic_active = bench_sismic(chart, events)
        rows["sismic 1.6"] = {"seconds": elapsed}
        elapsed, qt_active = bench_qt(tmp, events)
        rows["Qt SCXML 5.15 (PySide2)"] = {"seconds": elapsed}
    for row in rows.values():
        row["events_per_second"] = round(len(events) / row["seconds"])
    reference = rows["sismic 1.6"]["events_per_second"]
    for row in rows.values():
        row["x_sismic"] = round(row["events_per_second"] / reference, 1)
    agree = ours_active == sismic_active == [s for s in qt_active]
    print(f"{len(events)} events on the SAR UAV machine; final configurations agree: {agree}")
    print(f"{'implementation':48} {'events/s':>10} {'x sismic':>9}")
    for name, row in rows.items():
        print(f"{name:48} {row['events_per_second']:>10} {row['x_sismic']:>9}")
    out = ROOT / "benchmarks" / "results"
    out.mkdir(parents=True, exist_ok=True)
    payload = {"events": len(events), "configurations_agree": agree, "results": rows}
    (out / "dispatch.json").write_text(json.dumps(payload, indent=2) + "\n")


if __name__ == "__main__":
    main()
