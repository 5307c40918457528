"""The smach backend: SMACH-shaped generated code over the bundled runtime.

Its containers must compile into exactly the chart the asyncio backend builds (so the engine
gives identical traces), the code must be clean and import, replay must match asyncio and Qt
SCXML, and the SMACH services (preemption, introspection, outcomes) must work as documented.
"""

from __future__ import annotations

import ast
import asyncio
import importlib
import random
import subprocess
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path, PurePosixPath
from types import ModuleType
from typing import Any

import pytest

from swarmgen import expr, pipeline, replay
from swarmgen.backends import asyncio_backend, names, registry, smach_backend
from swarmgen.backends.vendor import runtime_files
from swarmgen.chart import model as c
from swarmgen.chart.lower import lower
from swarmgen.runtime import smach
from swarmgen.runtime.chart import Context
from swarmgen.runtime.member import InMemoryBus
from swarmgen.runtime.simulated import Script, SimulatedLibrary
from tests.conftest import ROOT, SAMPLE_MODELS, run_cli, tool, xmi_sample_files

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
UAV_MISSION = ROOT / "sample_models" / "sar" / "scenarios" / "uav_mission.json"
BAD = ROOT / "tests" / "fixtures" / "bad"
HOSTILE = BAD / "hostile_names.xmi"
RUFF_CHECK = [
    "check",
    "--isolated",
    "--select",
    "E,F,W,I,B,UP,SIM,RUF",
    "--ignore",
    "E501",
    "--quiet",
]
MODELS = [*SAMPLE_MODELS, *xmi_sample_files(), HOSTILE, BAD / "hostile_comment_dashes.xmi"]


# --- helpers


@contextmanager
def imported(package: Path) -> Iterator[str]:
    """Import a generated package from its directory; removed from sys.modules afterwards."""
    name = replay._import_package(package)
    try:
        yield name
    finally:
        for key in [k for k in sys.modules if k == name or k.startswith(f"{name}.")]:
            del sys.modules[key]


def compiled(model: Path, out: Path) -> tuple[list[c.Chart], str, dict[str, str]]:
    """Compile every backend into `out`; (charts, package name, chart name -> module name)."""
    result = pipeline.compile_model(model)
    assert result.files, pipeline.dg.render_text(result.validation.diagnostics)
    pipeline.write_tree(result.files, out)
    assert result.validation.model is not None
    charts = lower(result.validation.model)
    package = asyncio_backend.package_name(result.validation.model)
    return charts, package, asyncio_backend.member_modules(tuple(charts))


def shape(chart: Any) -> dict[str, Any]:
    """Everything structural about a runtime chart (functions only by presence)."""

    def transition(t: Any) -> tuple[Any, ...]:
        targets = tuple(x.id for x in t.targets)
        functions = (t.cond is not None, t.action is not None)  # compared by presence
        return (t.source.id, t.events, targets, t.internal, t.order, *functions)

    nodes = []
    for n in sorted([chart.root, *chart.nodes.values()], key=lambda n: n.order):
        initial = n.initial
        nodes.append(
            {
                "id": n.id,
                "kind": n.kind,
                "name": n.name,
                "parent": n.parent.id if n.parent is not None else None,
                "order": n.order,
                "depth": n.depth,
                "history": n.history,
                "timers": n.timers,
                "onentry": n.onentry is not None,
                "onexit": n.onexit is not None,
                "call": (n.call.behaviour, n.call.kind, n.call.results) if n.call else None,
                "initial": tuple(x.id for x in initial.targets) if initial else None,
                "initial_action": initial.action is not None if initial else None,
                "transitions": [transition(t) for t in n.transitions],
            }
        )
    return {"name": chart.name, "data": chart.data, "names": chart.names, "nodes": nodes}


def call_args(chart: Any, context: Callable[[Any], Any]) -> dict[str, Any]:
    """Each call's arguments evaluated on the initial data (or the error they raise)."""
    found: dict[str, Any] = {}
    for node in chart.nodes.values():
        if node.call is not None:
            try:
                found[node.id] = node.call.args(context(chart))
            except Exception as err:
                found[node.id] = type(err).__name__
    return found


def assert_same_chart(asyncio_module: ModuleType, smach_module: ModuleType) -> None:
    theirs, ours = asyncio_module.build(), smach_module.build()
    assert shape(ours) == shape(theirs)

    def context(chart: Any) -> Context:
        return Context(None, chart.fresh_data())

    assert call_args(ours, context) == call_args(theirs, context)


def ruff(*paths: Path) -> None:
    result = subprocess.run(
        [tool("ruff"), *RUFF_CHECK, *map(str, paths)],
        capture_output=True,
        text=True,
        cwd=paths[0].parent,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


# --- the registry


def test_smach_is_registered_after_asyncio() -> None:
    assert names().index("smach") == names().index("asyncio") + 1
    assert list(registry()) == names()
    assert "smach" in replay.BACKENDS


# --- every model: same chart, clean code


@pytest.mark.parametrize("model", MODELS, ids=lambda p: p.stem)
def test_chart_is_the_asyncio_chart(model: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    charts, package, modules = compiled(model, out)
    if not charts:
        assert not (out / "smach").exists()  # no state machine: nothing to run
        return
    ruff(out / "smach")
    with imported(out / "asyncio" / package) as a, imported(out / "smach" / package) as s:
        for chart in charts:
            theirs = importlib.import_module(f"{a}.{modules[chart.name]}")
            ours = importlib.import_module(f"{s}.{modules[chart.name]}")
            assert_same_chart(theirs, ours)
            assert ours.EVENT_SCOPES == theirs.EVENT_SCOPES
            top = ours.build_state_machine()
            assert isinstance(top, sys.modules[f"{s}._runtime.smach"].StateMachine)
        package_module = sys.modules[s]
        assert package_module.COMPOSITION == sys.modules[a].COMPOSITION
        assert set(package_module.MEMBER_TYPES) == set(sys.modules[a].MEMBER_TYPES)


def test_generated_code_reads_like_smach(tmp_path: Path) -> None:
    out = tmp_path / "out"
    _, package, _ = compiled(ROOT / "sample_models" / "patrol" / "patrol.xmi", out)
    text = (out / "smach" / package / "scout.py").read_text(encoding="utf-8")
    assert text.startswith("# @generated by swarmgen ")
    assert "from ._runtime import smach" in text
    assert 'sm = smach.StateMachine(outcomes=["Stopped"])' in text
    assert "sm.userdata.battery = 100.0" in text
    assert "with sm:" in text and 'sm.set_initial_state(["Waiting"])' in text
    assert "smach.Concurrence(outcomes=[])" in text
    assert 'smach.HistoryState(deep=True, default=["GetZone"])' in text
    assert 'smach.PseudoState("choice")' in text
    assert 'remapping={"target_pose": "goal_pose"}' in text
    assert '"Patrol/History"' in text  # a target below the current container
    assert 'transitions={"GoToZone__Done": "Sweeping"}' in text  # completion outcome
    assert 'smach.Transition(("missionAbort", "recall"), "Stopped")' in text


# --- replay


@pytest.mark.parametrize("other", ["asyncio", "scxml"])
def test_replay_matches(other: str, request: pytest.FixtureRequest) -> None:
    if other == "scxml":
        request.getfixturevalue("qt_available")
    args = ["replay", str(SAR), "--member", "UAV", "--script", str(UAV_MISSION), "--backend"]
    ours, theirs = run_cli(*args, "smach"), run_cli(*args, other)
    assert ours.returncode == 0, ours.stderr
    assert theirs.returncode == 0, theirs.stderr
    assert ours.stdout == theirs.stdout
    assert len(ours.stdout.splitlines()) == 11


# --- running the generated package


def _wait(condition: Callable[[], bool]) -> Callable[[], Any]:
    async def waiting() -> None:
        for _ in range(2000):
            if condition():
                return
            await asyncio.sleep(0.001)
        raise AssertionError("condition not reached")

    return waiting


def test_preemption_cancels_behaviours_and_hooks_see_active_states(tmp_path: Path) -> None:
    out = tmp_path / "out"
    _, package, modules = compiled(SAR, out)
    with imported(out / "smach" / package) as name:
        uav = importlib.import_module(f"{name}.{modules['UAV']}")
        behaviours = importlib.import_module(f"{name}.behaviours")
        runtime = importlib.import_module(f"{name}._runtime.smach")
        member = importlib.import_module(f"{name}._runtime.member")
        sm = uav.build_state_machine()
        published: list[list[str]] = []
        runtime.IntrospectionHook(sm, publish=published.append)
        library = behaviours.simulated_library(time_scale=100.0)  # TakeOff takes 100 s
        bus = member.InMemoryBus()

        async def scenario() -> str:
            task = asyncio.create_task(
                sm.execute_async(
                    library,
                    member_type="UAV",
                    member_id="uav_1",
                    bus=bus,
                    event_scopes=uav.EVENT_SCOPES,
                )
            )
            # before launch only positioning runs (target monitoring starts on launch)
            await _wait(lambda: len(library.started) == 1)()
            assert sm.is_running() and sm.get_active_states() == ["Mission"]
            assert sm.userdata.altitude == 1.5
            bus.broadcast("launch")
            await _wait(lambda: len(library.started) == 3)()
            sm.request_preempt()
            return str(await task)

        outcome = asyncio.run(scenario())
    assert outcome == runtime.PREEMPTED
    assert not sm.is_running() and not sm.preempt_requested()
    started = {(state, behaviour) for _, state, behaviour in library.started}
    assert started == {
        ("TargetMonitoring", "TargetMonitoring"),
        ("Positioning", "UwbPositioning"),
        ("TakeOff", "TakeOff"),
    }
    assert sorted(library.cancelled) == sorted(library.started)
    assert published[0] == [
        "Behavior",
        "HardwareFunctions",
        "Idle",
        "Mission",
        "Positioning",
        "SarBehavior",
        "Standby",
        "SwarmFunctions",
    ]
    assert "TakeOff" in published[-1] and "Idle" not in published[-1]
    assert "TargetMonitoring" in published[-1] and "Standby" not in published[-1]


def test_execution_ends_with_the_final_state_label(tmp_path: Path) -> None:
    out = tmp_path / "out"
    _, package, modules = compiled(SAR, out)
    with imported(out / "smach" / package) as name:
        ugv = importlib.import_module(f"{name}.{modules['UGV']}")
        behaviours = importlib.import_module(f"{name}.behaviours")
        member = importlib.import_module(f"{name}._runtime.member")
        sm = ugv.build_state_machine()
        bus = member.InMemoryBus()

        async def scenario() -> str:
            task = asyncio.create_task(
                sm.execute_async(behaviours.simulated_library(), member_type="UGV", bus=bus)
            )
            await _wait(lambda: sm.get_active_states() == ["Operating"])()
            bus.broadcast("missionAbort")
            return str(await task)

        assert asyncio.run(scenario()) == "Stopped"


def test_generated_package_command_line(tmp_path: Path) -> None:
    out = tmp_path / "out"
    _, package, _ = compiled(SAR, out)
    options = ["--member", "UAV", "--id", "7", "--events", "launch@0.05", "--time-scale", "0.01"]
    run = subprocess.run(
        [sys.executable, "-m", package, *options, "--duration", "0.5"],
        cwd=out / "smach",
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    assert '"member": "UAV/7"' in run.stdout
    assert '"TakeOff"' in run.stdout and '"Loitering"' in run.stdout


# --- hostile names

HOSTILE_MEMBER = 'Drone"""\nimport os #\\'


def _hostile_models(tmp_path: Path) -> list[Path]:
    """hostile_names.xmi, and a copy whose model and member type names would end a docstring."""
    text = HOSTILE.read_text(encoding="utf-8")
    worse = text.replace(
        'name="Drone" classifierBehavior',
        'name="Drone&quot;&quot;&quot;&#10;import os #\\" classifierBehavior',
    ).replace('name="MiniSwarm"', 'name="Mini&quot;&quot;&quot;\\Swarm"')
    assert worse.count("&quot;&quot;&quot;") == 2
    (tmp_path / "worse.xmi").write_text(worse, encoding="utf-8")
    return [HOSTILE, tmp_path / "worse.xmi"]


def test_hostile_names_stay_string_literals(tmp_path: Path) -> None:
    for number, model in enumerate(_hostile_models(tmp_path)):
        result = pipeline.compile_model(model, backends=["smach"])
        assert result.files, pipeline.dg.render_text(result.validation.diagnostics)
        out = tmp_path / f"out{number}"
        pipeline.write_tree(result.files, out)
        (package,) = (out / "smach").iterdir()
        ruff(package)
        with imported(package) as name:
            members = sys.modules[name].MEMBER_TYPES
            assert set(members) == {"Drone" if number == 0 else HOSTILE_MEMBER}
            for module in members.values():
                module.build()
        for path in sorted(package.glob("*.py")):
            _assert_only_runtime_code(path, hostile_strings=path.stem.startswith("drone"))


def _assert_only_runtime_code(path: Path, hostile_strings: bool) -> None:
    """Model text only as string constants, comments and defused docstrings: the imports and
    calls are the runtime's."""
    text = path.read_text(encoding="utf-8")
    tree = ast.parse(text)
    assert '"""' not in (ast.get_docstring(tree) or "")
    imports = [n for n in ast.walk(tree) if isinstance(n, ast.Import | ast.ImportFrom)]
    assert not [n for n in imports if isinstance(n, ast.Import)], path
    modules = {(n.module or "", n.level) for n in imports if isinstance(n, ast.ImportFrom)}
    assert modules <= {
        ("__future__", 0),
        ("typing", 0),
        ("types", 0),
        ("", 1),
        ("_runtime", 1),
        ("_runtime.chart", 1),
        ("_runtime.cli", 1),
        ("_runtime.simulated", 1),
        ("behaviours", 1),
        # behaviour_types.py (docs/plugins.md)
        ("behaviour_types", 1),
        ("collections.abc", 0),
        ("dataclasses", 0),
        ("_runtime.member", 1),
        ("_runtime.plugins", 1),
    }, modules
    calls = {ast.unparse(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
    calls -= {"bool", "main", "SimulatedLibrary", "Script", "simulated_library", "SystemExit"}
    calls -= {"dataclass", "Plugins", "PLUGINS.library", "TypedDict"}  # behaviour_types.py
    assert all(
        name.startswith(("smach.", "make_", "ctx.", "build_state_machine", "sm.")) for name in calls
    ), calls
    if hostile_strings:
        strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and n.value}
        assert "</state><script>alert(1)</script>" in strings
        assert '");alert(1);("\n-->' in strings
        assert "sm.userdata.note_quoted_single_data = " in text


# --- charts the sample models do not have


def _name(data: str) -> expr.Name:
    return expr.Name(name=data)


def _assign(location: str, value: expr.Expr) -> c.Assign:
    return c.Assign(location, value)


PLUS_ONE = expr.Binary(op="+", left=_name("a"), right=expr.Const(value=1))
WORK = c.BehaviourInfo(
    "Work",
    "Work",
    "SwarmBehavior",
    "Lib",
    ("succeeded", "aborted", "go"),
    (),
    (("x", "Integer"), ("y", "Integer")),
    (("x", "Integer"), ("out", "Integer")),
)
WORK_CALL = c.Call(
    "Work",
    "Work",
    "SwarmBehavior",
    (c.Arg("x", _name("x"), implicit=True), c.Arg("y", PLUS_ONE, implicit=False)),
    (("x", "b"), ("out", "out")),  # x is read from `x` but written to `b`: no one remapping
    ("succeeded", "aborted", "go"),
)


def synthetic_chart() -> c.Chart:
    """Completion of a Concurrence (outcome_map), several finals, an event named like an
    outcome, a compound state running a behaviour, computed inputs, internal and multi-key
    transitions, timers, exit actions, an initial action, history with a default action, fork
    targets and a cross-level target into a history state."""
    r1 = c.Node(
        "R1",
        "state",
        initial=c.Transition((), ("R1a",), actions=(_assign("b", expr.Const(value=3)),)),
        children=(
            c.Node(
                "R1a",
                "state",
                name="First of R1",
                call=WORK_CALL,
                transitions=(
                    c.Transition(("outcome.R1a.succeeded",), ("R1done",)),
                    c.Transition(("outcome.R1a.go",), ("R1fail",)),
                    c.Transition(("go",), ("R1b",)),
                    c.Transition(("outcome.R1a.aborted", "tick"), ("R1b",)),
                ),
            ),
            c.Node(
                "R1b",
                "state",
                transitions=(
                    c.Transition(
                        ("tick",), (), actions=(c.Raise("ping", (c.Param("v", PLUS_ONE),)),)
                    ),
                    c.Transition(("ping",), ("R1done",), in_states=("R2a",)),
                    c.Transition(("ping",), ("R1fail",)),
                ),
            ),
            c.Node("R1done", "final"),
            c.Node("R1fail", "final", onentry=(_assign("a", PLUS_ONE),)),
        ),
        transitions=(c.Transition(("done.state.R1",), (), actions=(_assign("x", PLUS_ONE),)),),
    )
    r2 = c.Node(
        "R2",
        "state",
        children=(
            c.Node(
                "H2",
                "history",
                history="shallow",
                initial=c.Transition((), ("R2a",), actions=(c.Send("hello", ()),)),
            ),
            c.Node(
                "R2a",
                "state",
                transitions=(
                    c.Transition(("tick",), ("R2done",)),
                    c.Transition(("quit",), ("End",)),
                ),
            ),
            c.Node("R2done", "final", onexit=(c.Opaque("C", "x++;"),)),
        ),
    )
    par = c.Node(
        "Par",
        "parallel",
        name="Par'\"\n\\",
        children=(r1, r2),
        onentry=(c.Send("hello", (c.Param("v", _name("a")),)),),
        transitions=(
            c.Transition(("done.state.Par",), ("Box",)),
            c.Transition(("stop",), ("Start",)),
        ),
    )
    box = c.Node(
        "Box",
        "state",
        call=WORK_CALL,
        initial=c.Transition((), ("BoxInner",)),
        children=(
            c.Node("BoxInner", "state", transitions=(c.Transition(("next",), ("aborted",)),)),
            c.Node("aborted", "final"),  # a final labelled like one of the behaviour's outcomes
        ),
        transitions=(
            c.Transition(("outcome.Box.aborted",), ("End",)),
            c.Transition(("tick",), ("BoxInner",), internal=True),
            c.Transition(("done.state.Box",), ("Par",)),
            c.Transition(("back",), ("H2",)),
        ),
    )
    start = c.Node(
        "Start",
        "state",
        onexit=(_assign("a", PLUS_ONE),),
        timers=(c.Timer("after.Start.0", 50),),
        transitions=(
            c.Transition(("after.Start.0",), ("Par",)),
            c.Transition(("go",), ("R1b", "R2a")),
            c.Transition(
                ("back",),
                ("H2",),
                cond=expr.Binary(op=">", left=_name("a"), right=expr.Const(value=1)),
            ),
            c.Transition(("jump",), ("Box",)),
            c.Transition(
                (), ("End",), cond=expr.Binary(op=">", left=_name("a"), right=expr.Const(value=9))
            ),
        ),
    )
    return c.Chart(
        name="Synth",
        machine="Synth",
        member="Synth",
        role=None,
        source="synth.xmi",
        data=tuple(
            c.DataItem(name, name, "Integer", value, value, 0)
            for name, value in [("a", 1), ("b", 2), ("x", 5), ("out", 0), ("match", 0)]
        ),
        initial=("Start",),
        children=(start, par, box, c.Node("End", "final")),
        behaviours=(WORK,),
        events=(c.EventInfo("hello", "hello", "member", "swarm", (("v", "Integer"),)),),
    )


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ModuleType, ModuleType]]:
    """The synthetic chart rendered by both backends into one package."""
    folder = tmp_path_factory.mktemp("synthetic") / "synth_pkg"
    common = {"version": "test", "source": "synth.xmi", "runtime": "._runtime"}
    chart = synthetic_chart()
    files = {
        PurePosixPath("__init__.py"): '"""Synthetic."""\n',
        PurePosixPath("theirs.py"): asyncio_backend.render_member(chart, common),
        PurePosixPath("ours.py"): smach_backend.render_member(chart, common),
        **runtime_files(PurePosixPath("_runtime"), smach_backend.SMACH_RUNTIME),
    }
    for relative, text in files.items():
        (folder / relative).parent.mkdir(parents=True, exist_ok=True)
        (folder / relative).write_text(text, encoding="utf-8")
    ruff(folder / "ours.py", folder / "_runtime")
    with imported(folder) as name:
        yield (
            importlib.import_module(f"{name}.theirs"),
            importlib.import_module(f"{name}.ours"),
        )


def test_synthetic_chart_is_the_asyncio_chart(synthetic: tuple[ModuleType, ModuleType]) -> None:
    theirs, ours = synthetic
    assert_same_chart(theirs, ours)
    text = Path(ours.__file__ or "").read_text(encoding="utf-8")
    outcome_map = '{"done": {"R1": ("R1done", "R1fail"), "R2": "R2done"}}'
    assert (
        f'smach.Concurrence(\n        outcomes=["done"],\n        default_outcome="done",\n        outcome_map={outcome_map},'
        in text
    )
    assert 'transitions={"done": "Box", "stop": "Start"}' in text
    assert 'smach.Transition(("R1done", "R1fail"), action=' in text
    assert 'smach.Transition(smach.Event("go"), "R1b"' in text
    assert 'smach.Transition(("aborted", "tick"), "R1b")' in text
    assert 'smach.Transition("done.state.Box", "Par")' in text  # `aborted` is an outcome too
    assert "behaviour=smach.Behaviour(" in text and "goal_cb=" in text
    assert '"back", "Par/R2/H2"' in text and '{"tick": "R2done", "quit": "/End"}' in text
    assert 'smach.Transition("tick", "Box/BoxInner", internal=True)' in text
    assert "sm.userdata.match = 0" in text


def test_synthetic_chart_runs_like_the_asyncio_chart(
    synthetic: tuple[ModuleType, ModuleType],
) -> None:
    """Both charts in the engine (no behaviours running), on the same random inputs."""
    theirs, ours = synthetic
    engine = importlib.import_module(f"{theirs.__name__.rpartition('.')[0]}._runtime.engine")
    events = ["after.Start.0", "go", "tick", "stop", "back", "jump", "next", "ping", "quit"]
    events += [
        f"done.invoke.{s}.{o}" for s in ("R1a", "Box") for o in ("succeeded", "aborted", "go")
    ]
    rng = random.Random(7)
    for _ in range(30):
        runs = [engine.Engine(module.build()) for module in (theirs, ours)]
        for run in runs:
            run.start()
        for _ in range(25):
            name = rng.choice(events)
            data = {"out": rng.randint(0, 9)} if name.startswith("done.invoke.") else None
            for run in runs:
                run.send(run.make_event(name, data))
            left, right = runs
            assert left.active() == right.active()
            assert left.data == right.data
            assert left.host.calls == right.host.calls
            assert [e.name for e in left.host.sent] == [e.name for e in right.host.sent]


# --- the runtime API


def _work_library(**scripts: Script) -> SimulatedLibrary:
    return SimulatedLibrary({"Work": Script(duration=0.0), **scripts}, time_scale=0.0)


def _two_step_machine() -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["Done"])
    sm.userdata.count = 0
    with sm:
        smach.StateMachine.add(
            "Working",
            smach.BehaviourState("Work", "SwarmBehavior", outcomes=["succeeded", "aborted"]),
            transitions={"succeeded": "Done"},
        )
        smach.StateMachine.add("Done", smach.FinalState())
    return sm


def test_execute_returns_the_final_outcome_and_updates_userdata() -> None:
    sm = _two_step_machine()
    published: list[list[str]] = []
    hook = smach.IntrospectionHook(sm, publish=published.append)
    assert sm.execute(_work_library()) == "Done"
    assert published == [["Working"], ["Done"]]
    assert sm.userdata.count == 0 and sm.userdata["count"] == 0
    hook.close()
    sm.request_preempt()  # before execution: it returns at once
    assert sm.execute(_work_library()) == smach.PREEMPTED
    assert published == [["Working"], ["Done"]]


def test_concurrence_outcome_map_is_checked_and_evaluated() -> None:
    def region(final: str) -> smach.StateMachine:
        sm = smach.StateMachine(outcomes=[final])
        with sm:
            smach.StateMachine.add("Wait" + final, smach.EventState(), transitions={"go": final})
            smach.StateMachine.add(final, smach.FinalState())
        return sm

    def machine(outcome_map: dict[str, dict[str, str]]) -> tuple[Any, smach.Concurrence]:
        sm = smach.StateMachine(outcomes=[])
        with sm:
            par = smach.Concurrence(
                outcomes=list(outcome_map), default_outcome=None, outcome_map=outcome_map
            )
            with par:
                smach.Concurrence.add("A", region("EndA"))
                smach.Concurrence.add("B", region("EndB"))
            smach.StateMachine.add("Par", par)
        return sm, par

    for wrong in ({"done": {"A": "EndA"}}, {"done": {"A": "EndA", "B": "Nope"}}):
        with pytest.raises(ValueError, match="outcome_map must name every region"):
            machine(wrong)[0].build_chart("m")
    sm, par = machine({"done": {"A": "EndA", "B": "EndB"}})
    outcomes: list[str | None] = []
    smach.IntrospectionHook(sm, publish=lambda active: outcomes.append(par.current_outcome()))

    async def scenario() -> str:
        bus = InMemoryBus()
        task = asyncio.create_task(sm.execute_async(_work_library(), bus=bus))
        await _wait(lambda: sm.is_running() and bool(outcomes))()
        bus.broadcast("go")
        await _wait(lambda: len(outcomes) == 2)()
        sm.request_preempt()
        return await task

    assert asyncio.run(scenario()) == smach.PREEMPTED
    assert outcomes == [None, "done"]


def test_completion_keys_resolve_to_done_state() -> None:
    sm = smach.StateMachine(outcomes=["End"])
    with sm:
        inner = smach.StateMachine(outcomes=["Ok", "Failed"])
        with inner:
            smach.StateMachine.add(
                "Try", smach.EventState(), transitions={"a": "Ok", "b": "Failed"}
            )
            smach.StateMachine.add("Ok", smach.FinalState())
            smach.StateMachine.add("Failed", smach.FinalState())
        smach.StateMachine.add("Inner", inner, transitions=[(("Ok", "Failed"), "End")])
        smach.StateMachine.add("End", smach.FinalState())
    chart = sm.build_chart("m")
    (transition,) = chart.nodes["Inner"].transitions
    assert transition.events == ("done.state.Inner",)
    assert [t.id for t in transition.targets] == ["End"]

    partial = smach.StateMachine(outcomes=["End"])
    with partial:
        inner = smach.StateMachine(outcomes=["Ok", "Failed"])
        with inner:
            smach.StateMachine.add("Ok", smach.FinalState())
            smach.StateMachine.add("Failed", smach.FinalState())
        smach.StateMachine.add("Inner", inner, transitions={"Ok": "End"})
        smach.StateMachine.add("End", smach.FinalState())
    with pytest.raises(ValueError, match="list all of"):
        partial.build_chart("m")


def test_construction_errors_are_clear() -> None:
    with pytest.raises(RuntimeError, match="needs an open StateMachine"):
        smach.StateMachine.add("A", smach.EventState())
    sm = smach.StateMachine(outcomes=["Done"])
    with sm:
        with pytest.raises(ValueError, match="without '/'"):
            smach.StateMachine.add("a/b", smach.EventState())
        with pytest.raises(RuntimeError, match="needs an open Concurrence"):
            smach.Concurrence.add("A", smach.EventState())

        class Custom(smach.State):
            def execute(self, userdata: smach.UserData) -> str:
                return "succeeded"

        with pytest.raises(TypeError, match="defines execute"):
            smach.StateMachine.add("Custom", Custom(outcomes=["succeeded"]))
        with pytest.raises(ValueError, match="remapping of keys"):
            smach.StateMachine.add("E", smach.EventState(), remapping={"x": "y"})
        smach.StateMachine.add("A", smach.EventState(), transitions={"go": "Nowhere"})
    with pytest.raises(ValueError, match="FinalStates"):
        sm.build_chart("m")
    with sm:
        smach.StateMachine.add("Done", smach.FinalState())
    with pytest.raises(ValueError, match="unknown target 'Nowhere'"):
        sm.build_chart("m")

    nested = smach.StateMachine(outcomes=[])
    with nested:
        child = smach.StateMachine(outcomes=[])
        with child:
            smach.StateMachine.add("X", smach.EventState())
        smach.StateMachine.add("Child", child)
    with pytest.raises(RuntimeError, match="top container"):
        child.request_preempt()
    assert child.get_active_states() == [] and not child.is_running()
    assert nested.get_children()["Child"] is child and child.label == "Child"


def test_behaviour_inputs_use_remapping_and_goal_callback() -> None:
    sm = smach.StateMachine(outcomes=[])
    sm.userdata.goal = 4
    sm.userdata.speed = 2
    with sm:
        smach.StateMachine.add(
            "Move",
            smach.BehaviourState(
                "MoveTo",
                "HardwareFunction",
                outcomes=["succeeded"],
                input_keys=["target"],
                output_keys=["reached"],
                goal_cb=lambda ctx: {"speed": ctx.data["speed"] * 2},
            ),
            remapping={"target": "goal", "reached": "goal"},
        )
    chart = sm.build_chart("m")
    call = chart.nodes["Move"].call
    assert call is not None and call.results == (("reached", "goal"),)
    assert call.args(Context(None, chart.fresh_data())) == {"target": 4, "speed": 4}
