"""The generated asyncio runtime under faulty behaviours and bad arguments.

A small model (one member type, Bot: Idle --go--> Work, which runs the behaviour Work; Work ends in
Done on `succeeded`, in Failed on `aborted`, in Stopped on the station event `stop`) is compiled
with the real `swarmgen compile`; its package then runs as `python -m faults_swarm` in a
subprocess, with the platform library `hostile_library` (written below) given by `--library`. The
fault the library injects (and on which members) comes from the environment. Each fault runs with
one member (`--member`) and with the swarm of three (`--swarm`, only bot_2 faulty: the others must
finish their work). The rules are those of docs/runtime.md, "Behaviours under faults".
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from swarmgen.ros.domains import hold
from tests.hostile import Outcome, assert_clean, assert_refused, run_module, swarmgen
from tests.modelkit import ModelKit

PACKAGE = "faults_swarm"

LIBRARY = '''
import asyncio, os, time
from faults_swarm._runtime.member import Outcome

FAULT = os.environ.get("HOSTILE_FAULT", "healthy")
FAULTY = os.environ.get("HOSTILE_MEMBERS", "")  # comma-separated ids; empty: every member


async def healthy(request):
    await asyncio.sleep(0.01)
    return Outcome("succeeded", {"count": 7, "note": "ok"})


async def hostile(request):
    await asyncio.sleep(0.05)  # the healthy members finish first
    if FAULT == "raise":
        raise RuntimeError("boom")
    if FAULT == "none":
        return None
    if FAULT == "string":
        return "succeeded"
    if FAULT == "wrong_type":
        return Outcome("succeeded", {"count": "seven"})
    if FAULT == "unknown_output":
        return Outcome("succeeded", {"bogus": 1})
    if FAULT == "undeclared":
        return Outcome("banana")
    if FAULT == "keyboard_interrupt":
        raise KeyboardInterrupt
    if FAULT == "system_exit":
        raise SystemExit(3)
    if FAULT == "cancelled_error":
        raise asyncio.CancelledError
    if FAULT == "swallow":
        while True:
            try:
                await asyncio.sleep(100)
            except asyncio.CancelledError:
                pass
    if FAULT == "block":
        time.sleep(1.0)
        return Outcome("succeeded", {"count": 1})
    if FAULT == "block_then_wait":
        time.sleep(1.0)
        await asyncio.sleep(100)
    if FAULT == "block_forever":
        time.sleep(60)
    raise AssertionError(FAULT)


class Library:
    """Shared by every member of the process: get() cannot tell members apart."""

    def get(self, name):
        if FAULT == "get_raises":
            raise LookupError(name)
        if FAULT == "missing" or name != "Work":
            return None

        async def work(request):
            faulty = not FAULTY or request.member_id in FAULTY.split(",")
            return await (hostile if faulty and FAULT != "healthy" else healthy)(request)

        return work


def library(time_scale):
    return Library()
'''


def _model() -> str:
    kit = ModelKit("Faults")
    kit.behaviour("Work", outputs={"count": "Integer", "note": "String"})
    kit.event("go", sender="station")
    kit.event("stop", sender="station")
    m = kit.machine("BotMission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Work", do="Work")
    m.final("Done")
    m.final("Failed")
    m.final("Stopped")
    m.transition("Idle", "Work", "go")
    m.transition("Work", "Done", "succeeded")
    m.transition("Work", "Failed", "aborted")
    m.transition("Work", "Stopped", "stop")
    kit.member("Bot", machine=m, data={"count": ("Integer", 0), "note": ("String", "")})
    kit.swarm("Swarm", {"Bot": 3})
    return kit.xmi()


@pytest.fixture(scope="module")
def package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The compiled asyncio package's parent directory, with the hostile library beside it."""
    work = tmp_path_factory.mktemp("hostile_runtime")
    (work / "faults.xmi").write_text(_model(), encoding="utf-8")
    compiled = swarmgen("compile", "faults.xmi", "-o", "out", "--backend", "asyncio", cwd=work)
    assert_clean(compiled, (0,))
    parent = work / "out" / "asyncio"
    assert (parent / PACKAGE / "__main__.py").is_file(), compiled
    (parent / "hostile_library.py").write_text(LIBRARY, encoding="utf-8")
    return parent


def run_package(
    parent: Path, *args: str, env: Mapping[str, str] | None = None, timeout: float = 20.0
) -> Outcome:
    """`python -m faults_swarm ARGS` with the hostile library; a run past `timeout` is a Hang."""
    environment = {**os.environ, "PYTHONPATH": str(parent), **(env or {})}
    return run_module(PACKAGE, *args, cwd=parent, env=environment, timeout=timeout)


@dataclass(frozen=True)
class Trace:
    steps: list[dict[str, Any]]
    faults: list[dict[str, Any]]

    @classmethod
    def of(cls, outcome: Outcome) -> Trace:
        lines = [json.loads(line) for line in outcome.stdout.splitlines() if line.strip()]
        return cls([r for r in lines if "fault" not in r], [r for r in lines if "fault" in r])

    def final(self, member: str) -> list[str]:
        active: list[str] = [s["active"] for s in self.steps if s["member"] == member][-1]
        return active

    def faults_of(self, member: str) -> list[dict[str, Any]]:
        return [f for f in self.faults if f["member"] == member]


def run_fault(package: Path, fault: str, swarm: bool, *extra: str, **options: Any) -> Outcome:
    who = ["--swarm"] if swarm else ["--member", "Bot", "--id", "bot_2"]
    env = {"HOSTILE_FAULT": fault, "HOSTILE_MEMBERS": "bot_2"}
    args = [*who, "--library", "hostile_library:library", "--events", "go@0", *extra]
    outcome = run_package(package, *args, env=env, **options)
    assert_clean(outcome, (0, 1))
    assert all(json.loads(line) for line in outcome.stdout.splitlines()), (
        "every stdout line is JSON"
    )
    return outcome


def assert_others_done(trace: Trace, swarm: bool) -> None:
    """The healthy members of the swarm finished their work, whatever bot_2 did."""
    if swarm:
        for other in ("Bot/bot_1", "Bot/bot_3"):
            assert trace.final(other) == ["Done"], trace
            assert not trace.faults_of(other), trace


# --- a behaviour that breaks the contract ends with `aborted`, reported in the trace

FAILING = {
    "raise": "raised RuntimeError('boom')",
    "none": "returned None, not an Outcome",
    "string": "returned 'succeeded', not an Outcome",
    "wrong_type": "returned 'seven' for the output count",
    "unknown_output": "returned unknown outputs 'bogus'",
    "undeclared": "returned the undeclared outcome 'banana'",
    "keyboard_interrupt": "raised KeyboardInterrupt()",
    "system_exit": "raised SystemExit(3)",
    "cancelled_error": "raised CancelledError without being cancelled",
    "get_raises": "Library.get raised LookupError('Work')",
    "missing": "no implementation",
}
LIBRARY_FAULTS = {"get_raises", "missing"}
SHAPES = [("member", False), ("swarm", True)]


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
@pytest.mark.parametrize("fault", sorted(FAILING))
def test_failing_behaviour_aborts(package: Path, fault: str, shape: str, swarm: bool) -> None:
    outcome = run_fault(package, fault, swarm, "--duration", "5")
    trace = Trace.of(outcome)
    assert outcome.exit == 1, outcome
    assert outcome.seconds < 5, f"members all end at once, not at --duration\n{outcome}"
    everyone = fault in LIBRARY_FAULTS  # the library fails every member alike
    faulty = ["Bot/bot_1", "Bot/bot_2", "Bot/bot_3"] if swarm and everyone else ["Bot/bot_2"]
    for member in faulty:
        assert trace.final(member) == ["Failed"], outcome  # the outcome `aborted`
        (fault_line,) = trace.faults_of(member)
        assert fault_line["fault"] == "failed" and fault_line["behaviour"] == "Work"
        assert fault_line["state"] == "Work" and fault_line["error"] == FAILING[fault]
        assert f"{member}: behaviour Work in Work failed: {FAILING[fault]}" in outcome.stderr
    if not everyone:
        assert_others_done(trace, swarm)


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
def test_healthy_run_is_clean_and_traces_as_before(package: Path, shape: str, swarm: bool) -> None:
    outcome = run_fault(package, "healthy", swarm, "--duration", "5")
    trace = Trace.of(outcome)
    assert outcome.exit == 0 and outcome.stderr == "", outcome
    assert not trace.faults
    assert all(set(s) == {"t", "member", "event", "active"} for s in trace.steps)
    members = ["Bot/bot_1", "Bot/bot_2", "Bot/bot_3"] if swarm else ["Bot/bot_2"]
    for member in members:
        events = [s["event"] for s in trace.steps if s["member"] == member]
        assert events == [None, "go", "done.invoke.Work.succeeded"], trace
        assert trace.final(member) == ["Done"]


# --- a behaviour that swallows its cancellation is abandoned; preemption is immediate


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
def test_swallowed_cancellation_is_abandoned(package: Path, shape: str, swarm: bool) -> None:
    outcome = run_fault(
        package, "swallow", swarm, "--events", "go@0,stop@0.2", "--grace", "0.3", "--duration", "5"
    )
    trace = Trace.of(outcome)
    assert outcome.exit == 1, outcome
    assert outcome.seconds < 3, outcome
    stopped = [s for s in trace.steps if s["member"] == "Bot/bot_2" and s["event"] == "stop"]
    assert stopped and stopped[0]["active"] == ["Stopped"], trace
    (abandoned,) = trace.faults_of("Bot/bot_2")
    assert abandoned["fault"] == "abandoned" and abandoned["behaviour"] == "Work", abandoned
    # preemption took effect at once; the behaviour was given up only after the grace period
    assert stopped[0]["t"] < 0.6 and abandoned["t"] - stopped[0]["t"] >= 0.25, trace
    assert_others_done(trace, swarm)


# --- a behaviour that blocks the event loop is reported; preemption and --duration still work


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
def test_blocking_behaviour_is_reported(package: Path, shape: str, swarm: bool) -> None:
    outcome = run_fault(package, "block", swarm, "--duration", "5")
    trace = Trace.of(outcome)
    assert outcome.exit == 1, outcome
    assert trace.final("Bot/bot_2") == ["Done"], outcome  # it did end, late
    (blocked,) = trace.faults_of("Bot/bot_2")
    assert blocked["fault"] == "blocked" and blocked["behaviour"] == "Work", blocked
    assert blocked["error"].startswith("kept the event loop busy for "), blocked
    seconds = float(blocked["error"].split()[-2])
    assert 0.9 <= seconds < 3, blocked
    assert_others_done(trace, swarm)


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
def test_preemption_waits_only_for_the_loop(package: Path, shape: str, swarm: bool) -> None:
    """`stop` at 0.1 s arrives while Work blocks the loop (1 s): it is taken as soon as the loop
    is free, without waiting for the behaviour."""
    outcome = run_fault(
        package, "block_then_wait", swarm, "--events", "go@0,stop@0.1", "--duration", "5"
    )
    trace = Trace.of(outcome)
    assert outcome.exit == 1, outcome
    assert outcome.seconds < 4, outcome
    stopped = [s for s in trace.steps if s["member"] == "Bot/bot_2" and s["event"] == "stop"]
    assert stopped and stopped[0]["active"] == ["Stopped"], trace
    assert 0.9 <= stopped[0]["t"] < 2.0, stopped
    assert [f["fault"] for f in trace.faults_of("Bot/bot_2")] == ["blocked"], trace.faults


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
def test_duration_waits_only_for_the_loop(package: Path, shape: str, swarm: bool) -> None:
    """--duration 0.3 passes while Work blocks the loop (1 s): the run stops as soon as the
    loop is free, before the hard deadline (1.5 s)."""
    outcome = run_fault(package, "block_then_wait", swarm, "--duration", "0.3", "--grace", "0.2")
    trace = Trace.of(outcome)
    assert outcome.exit == 1, outcome
    assert 1.0 <= outcome.seconds < 3, outcome
    assert [f["fault"] for f in trace.faults_of("Bot/bot_2")] == ["blocked"], trace.faults
    assert trace.final("Bot/bot_2") == ["Work"], trace  # stopped where it was
    assert_others_done(trace, swarm)


@pytest.mark.parametrize("shape,swarm", SHAPES, ids=[s for s, _ in SHAPES])
def test_blocked_loop_ends_at_the_hard_deadline(package: Path, shape: str, swarm: bool) -> None:
    """time.sleep(60) in a behaviour: the process ends at --duration + --grace + 1 s."""
    outcome = run_fault(package, "block_forever", swarm, "--duration", "0.5", "--grace", "0.2")
    trace = Trace.of(outcome)
    assert outcome.exit == 1, outcome
    assert 1.7 <= outcome.seconds < 4, outcome
    (overran,) = trace.faults_of("Bot/bot_2")
    assert overran["fault"] == "overran" and overran["behaviour"] == "Work", overran
    assert "Bot/bot_2: behaviour Work in Work overran" in outcome.stderr
    assert_others_done(trace, swarm)


def test_duration_ends_a_run_with_later_station_events(package: Path) -> None:
    outcome = run_fault(package, "healthy", True, "--events", "go@100", "--duration", "0.3")
    assert outcome.exit == 0, outcome
    assert outcome.seconds < 3, outcome
    assert [s["event"] for s in Trace.of(outcome).steps] == [None, None, None]


# --- bad arguments: one line, exit 2, at once

BAD_ARGUMENTS = {
    "event_time_not_a_number": (["--events", "go@abc"], "go@abc"),
    "event_two_times": (["--events", "go@1@2"], "expected name@seconds"),
    "event_time_inf": (["--events", "go@inf"], "finite number"),
    "event_time_negative": (["--events", "go@-1"], "finite number"),
    "event_time_nan": (["--events", "go@nan"], "finite number"),
    "event_time_missing": (["--events", "go@"], "expected name@seconds"),
    "event_without_name": (["--events", "@1"], "no event name"),
    "event_unknown": (["--events", "go@0,lunch@1"], "no member reacts to an event 'lunch'"),
    "duration_negative": (["--duration", "-1"], "--duration"),
    "duration_nan": (["--duration", "nan"], "--duration"),
    "duration_inf": (["--duration", "inf"], "--duration"),
    "id_empty": (["--id", ""], "--id"),
    "id_with_newline": (["--id", "a\nb"], "--id"),
    "time_scale_zero": (["--time-scale", "0"], "--time-scale"),
    "grace_negative": (["--grace", "-0.5"], "--grace"),
    "library_not_importable": (["--library", "no_such_module:lib"], "cannot import"),
    "library_no_factory": (["--library", "hostile_library:nothing"], "no callable nothing"),
    "library_malformed": (["--library", "hostile_library"], "MODULE:FACTORY"),
}


@pytest.mark.parametrize("case", sorted(BAD_ARGUMENTS))
def test_bad_arguments_are_refused(package: Path, case: str) -> None:
    args, says = BAD_ARGUMENTS[case]
    outcome = run_package(package, "--member", "Bot", *args, timeout=10)
    assert_refused(outcome, exit=2, says=says)
    assert outcome.stdout == "" and len(outcome.stderr.strip().splitlines()) == 1, outcome
    assert outcome.stderr.startswith(f"python -m {PACKAGE}: error: "), outcome
    assert outcome.seconds < 5, outcome


# --- the ROS 2 launcher and simulated servers (rclpy from the venv; no DDS traffic needed)

HAS_RCLPY = importlib.util.find_spec("rclpy") is not None
requires_rclpy = pytest.mark.skipif(not HAS_RCLPY, reason="rclpy is not installed (make ros)")


@pytest.fixture(scope="module")
def ros_nodes(package: Path) -> Path:
    """The rclpy node package of the same model (its interfaces are not built: arguments are
    checked before ROS starts)."""
    work = package.parent.parent
    compiled = swarmgen("compile", "faults.xmi", "-o", "ros", "--backend", "rclpy", cwd=work)
    assert_clean(compiled, (0,))
    (nodes,) = (work / "ros" / "rclpy").glob("*_nodes")
    return nodes


BAD_STATION = {
    "station_time_inf": (["--station", "go@inf"], "finite number >= 0"),
    "station_time_nan": (["--station", "go@nan"], "finite number >= 0"),
    "station_time_negative": (["--station", "go@-1"], "finite number >= 0"),
    "station_two_times": (["--station", "go@1@2"], "expected name@seconds or name@state"),
    "station_without_name": (["--station", "@1"], "no event name"),
    "station_unknown_event": (["--station", "lunch@1"], "no member reacts to an event 'lunch'"),
    "station_unknown_state": (["--station", "go@Nowhere"], "no member has a state 'Nowhere'"),
    "members_negative": (["--bot", "-1"], "expected 0 to 1000 members"),
    "members_too_many": (["--bot", "1000000"], "expected 0 to 1000 members"),
    "time_scale_zero": (["--time-scale", "0"], "--time-scale"),
    "duration_inf": (["--duration", "inf"], "--duration"),
}


@requires_rclpy
@pytest.mark.parametrize("case", sorted(BAD_STATION))
def test_ros_launcher_refuses_bad_arguments(ros_nodes: Path, case: str) -> None:
    args, says = BAD_STATION[case]
    (module,) = {p.parent.name for p in ros_nodes.glob("*/launch_swarm.py")}
    command = [sys.executable, "-m", f"{module}.launch_swarm", *args]
    started = time.perf_counter()
    run = subprocess.run(
        command, cwd=ros_nodes, capture_output=True, text=True, timeout=60, check=False
    )
    outcome = Outcome(tuple(args), run.returncode, run.stdout, run.stderr, 0.0)
    assert_refused(outcome, exit=2, says=says)
    assert len(run.stderr.strip().splitlines()) == 1, outcome
    assert time.perf_counter() - started < 20, "refused before ROS starts"


@requires_rclpy
@pytest.mark.parametrize(
    "expression",
    ["${2 ** 10 ** 9}", "${'x' * 10 ** 12}", "${[0] * 10 ** 9}", "${10 ** 9 * 'x'}"],
    ids=["power", "string_repeat", "list_repeat", "repeat_reversed"],
)
def test_ros_script_expressions_are_bounded(expression: str) -> None:
    """A script expression that would keep the executor busy (or exhaust memory) raises at
    once; the server then aborts the goal (simulated.py `_result`)."""
    from swarmgen.ros.runtime.simulated import render

    started = time.perf_counter()
    with pytest.raises(ValueError, match=r"exponent|repetition"):
        render(expression, {})
    assert time.perf_counter() - started < 1
    assert render("${2 ** 10}", {}) == 1024 and render("${'ab' * 3}", {}) == "ababab"


@pytest.fixture(scope="module")
def ros_built(ros_nodes: Path) -> Path:
    """The node package with its interface package built into the venv (cached by content
    hash: the first run on a venv takes 10-25 s, later ones a few ms)."""
    from swarmgen import pipeline
    from swarmgen import ros_harness as harness

    model = pipeline.compile_model(ros_nodes.parent.parent.parent / "faults.xmi").validation.model
    assert model is not None
    harness.build_interfaces(ros_nodes.parent, model)
    return ros_nodes


# Scripts are per member type: `member.index` makes Work fail on bot_2 only.
ROS_FAULTS: dict[str, tuple[dict[str, Any], str]] = {
    # a script expression that raises when the goal ends: the server aborts that goal
    "server_script_raises": (
        {"outcome": "${'succeeded' if 1 / (member.index - 2) else ''}"},
        "script failed: ZeroDivisionError",
    ),
    # an output the result field (int64) cannot hold: the same
    "server_output_out_of_range": (
        {"outputs": {"count": "${10 ** 30 if member.index == 2 else 1}"}},
        "script failed",
    ),
    # a result with an outcome Work does not declare: the member takes `aborted`
    "undeclared_outcome": (
        {"outcome": "${'banana' if member.index == 2 else 'succeeded'}"},
        "returned the undeclared outcome 'banana'",
    ),
}


@requires_rclpy
@pytest.mark.parametrize("case", sorted(ROS_FAULTS))
def test_ros_failing_server_aborts_the_goal(ros_built: Path, tmp_path: Path, case: str) -> None:
    """Two members in one launcher: bot_2's goal ends in Failed (`aborted`); the process and
    bot_1 go on; exit 1, the error named in the summary."""
    from swarmgen import ros_harness as harness

    behaviour, says = ROS_FAULTS[case]
    script = tmp_path / "script.json"
    work = {"duration": 0.05, **behaviour}
    script.write_text(json.dumps({"behaviours": {"Work": work}}), encoding="utf-8")
    (module,) = {p.parent.name for p in ros_built.glob("*/launch_swarm.py")}
    env = harness.ros_env(tmp_path / "roslog", domain_id=hold(1, 139, start=201 + os.getpid() % 20))
    env["PYTHONPATH"] = str(ros_built)
    command = [
        sys.executable,
        "-m",
        f"{module}.launch_swarm",
        "--bot",
        "2",
        "--script",
        str(script),
    ]
    command += ["--station", "go@0", "--duration", "20", "--time-scale", "0.5"]
    run = subprocess.run(
        ["timeout", "-k", "5", "60", *command],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=90, check=False,
    )  # fmt: skip
    assert run.returncode == 1, f"{run.stdout[-2000:]}\n{run.stderr[-3000:]}"
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    members = summary["members"]
    assert members["bot_1"]["finished"] and members["bot_1"]["active"] == ["Done"], summary
    assert members["bot_2"]["finished"] and members["bot_2"]["active"] == ["Failed"], summary
    assert says in json.dumps(summary), summary
    assert "Traceback" not in run.stderr, run.stderr[-3000:]


def _echo_model() -> str:
    """Every member answers every `ping` with a `ping` to the whole swarm (itself included): its
    queue never empties, and no step bound applies (each ping is a message from the bus)."""
    kit = ModelKit("Echo")
    kit.event("go", sender="station")
    kit.event("ping")
    m = kit.machine("EchoMission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Chat")
    m.transition("Idle", "Chat", "go", effect="send ping")
    m.transition("Chat", "Chat", "ping", effect="send ping")
    kit.member("Bot", machine=m)
    kit.swarm("Swarm", {"Bot": 2})
    return kit.xmi()


ENDS_AFTER_1S = ("--duration", "1", "--grace", "2")


def test_a_swarm_that_never_stops_talking_still_ends_at_its_duration(tmp_path: Path) -> None:
    (tmp_path / "echo.xmi").write_text(_echo_model(), encoding="utf-8")
    compiled = swarmgen("compile", "echo.xmi", "-o", "out", "--backend", "asyncio", cwd=tmp_path)
    assert_clean(compiled, (0,))
    parent = tmp_path / "out" / "asyncio"
    environment = {**os.environ, "PYTHONPATH": str(parent)}
    started = time.perf_counter()
    done = subprocess.run(
        # a grace of 2 s: on a loaded machine (the suite runs on two workers) shutting the flood
        # down can take longer than the default second, which is not what this test is about
        [sys.executable, "-m", "echo_swarm", "--swarm", "--events", "go@0", *ENDS_AFTER_1S],
        cwd=parent,
        env=environment,
        stdout=subprocess.DEVNULL,  # millions of trace lines: only the ending matters here
        stderr=subprocess.PIPE,
        timeout=30,
        check=False,
    )
    seconds = time.perf_counter() - started
    assert done.returncode == 0, done.stderr.decode()[-2000:]  # ended by --duration, not killed
    assert seconds < 1 + 2 + 1.0 + 0.5, seconds  # the hard deadline: duration + grace + 1 s
    assert b"overran" not in done.stderr
