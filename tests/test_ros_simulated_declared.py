"""Simulated and replayed behaviours on declared ROS 2 interfaces (issue 12, simulation side).

One member chart runs four behaviours; a pair of hand-made specs binds them to the private
actions of an interface package built here, or to declared types: the platform's user action
`platform_msgs/action/GoTo`, `std_srvs/srv/Trigger`, and `geometry_msgs/msg/PoseStamped` (a topic
the member waits on, and one it publishes). The real runtime runs both, in a subprocess under a
time limit (`python -m tests.test_ros_simulated_declared replay|simulate`): the replay driver and
the simulated behaviours serve whichever interface the spec has. Everything runs in that one
process, with discovery OFF (in-process only: no other test can interfere) and a domain id of
this test run.
"""

from __future__ import annotations

import json
import os
import sys
import time
from typing import Any

import pytest

from swarmgen.ros.domains import hold
from swarmgen.ros_harness import ros_env
from tests.conftest import ROOT
from tests.hostile import run_module

DOMAIN = hold(1, 139, start=201 + os.getpid() % 30)  # leased: see swarmgen/ros/domains.py
PACKAGE = "sgsimdecl_interfaces"
GOTO = ("platform_msgs", "action", "GoTo")
TRIGGER = ("std_srvs", "srv", "Trigger")
POSE = ("geometry_msgs", "msg", "PoseStamped")
PRIVATE_ACTIONS = {
    "Go": "float64 x\nstring mode\n---\nfloat64 rx\nstring outcome\n---\nstring status\n",
    "Arm": "---\nstring message\nstring outcome\n---\nstring status\n",
    "Watch": "---\nfloat64 tx\nstring frame\nstring outcome\n---\nstring status\n",
    "Announce": "float64 x\n---\nstring outcome\n---\nstring status\n",
}
OUTCOMES = ("succeeded", "aborted", "preempted", "blocked")
# (state, behaviour, arguments from data, results (output, data key), next state on success)
STEPS = (
    ("Going", "Go", ("x", "mode"), (("rx", "rx"),), "Arming"),
    ("Arming", "Arm", (), (("message", "message"),), "Watching"),
    ("Watching", "Watch", (), (("tx", "tx"), ("frame", "frame")), "Announcing"),
    ("Announcing", "Announce", ("rx",), (), "Done"),
)
SCENARIOS = [
    [{"event": "go"}, {"complete": "Go", "outputs": {"rx": 3.0}},
     {"complete": "Arm", "outputs": {"message": "armed"}},
     {"complete": "Watch", "outputs": {"tx": 4.0, "frame": "map"}}],
    [{"event": "go"}, {"complete": "Go", "outcome": "blocked"}],
    [{"event": "go"}, {"complete": "Go", "outcome": "aborted"}],
    [{"event": "go"}, {"complete": "Go", "outputs": {"rx": 1.0}},
     {"complete": "Arm", "outcome": "aborted", "outputs": {"message": "battery low"}}],
    [{"event": "go"}, {"complete": "Go"}, {"complete": "Arm"}, {"event": "stop"}],
    [{"event": "go"}, {"event": "stop"}, {"complete": "Go", "outputs": {"rx": 9.0}}],
    [{"event": "go"}, {"complete": "Go", "outputs": {"rx": "not a number"}}],
]  # fmt: skip
SCRIPT = {
    "behaviours": {
        "Go": {"duration": 0.2, "outputs": {"rx": "${goal.x * 2}"}},
        "Arm": {"duration": 0.4, "outputs": {"message": "armed"}},
        "Watch": {"duration": 0.2, "outputs": {"tx": 4.0, "frame": "map"}},
        "Announce": {"duration": 0.1},
    }
}
SCRIPTED_S = 0.2 + 0.4 + 0.2  # Announce: the declared publisher behaviour ends by itself


# --- the specs (also imported by the subprocess) ----------------------------------------------


def specs(announce: bool) -> dict[str, Any]:
    """The private and the declared spec of one member type (`announce`: with the publisher)."""
    from swarmgen.ros.runtime.spec import BehaviourSpec, Binding, Field, MemberSpec

    bindings = {
        "Go": Binding(
            "action", GOTO, "go", (("x", "target_pose.pose.position.x"), ("mode", "mode")),
            (("reached.x", "rx"),), outcome="outcome",
        ),
        "Arm": Binding("service", TRIGGER, "arm", (), (("message", "message"),), outcome="success"),
        "Watch": Binding(
            "topic", POSE, "watch", (), (("pose.position.x", "tx"), ("header.frame_id", "frame")),
            direction="subscribe",
        ),
        "Announce": Binding(
            "topic", POSE, "announce", (("rx", "pose.position.x"),), timeout_s=5.0,
            direction="publish",
        ),
    }  # fmt: skip
    fields = {"x": "float64", "mode": "string", "rx": "float64", "message": "string"}
    fields.update(tx="float64", frame="string")
    steps = STEPS if announce else STEPS[:3]
    found = {}
    for kind in ("private", "declared"):
        behaviours = {}
        for _, name, inputs, results, _next in steps:
            binding = bindings[name] if kind == "declared" else None
            behaviours[name] = BehaviourSpec(
                name, name, name.lower(), "HardwareFunction",
                inputs=tuple(Field(i, "x" if i == "rx" else i, fields[i]) for i in inputs),
                outputs=tuple(Field(o, o, fields[o]) for o, _ in results),
                outcomes=OUTCOMES, binding=binding,
            )  # fmt: skip
        found[kind] = MemberSpec(
            member_type="Rover",
            chart_name="rover",
            node_name="rover",
            interfaces=PACKAGE,
            build=lambda: _chart(steps),
            event_scopes={},
            behaviours=behaviours,
        )
    return found


def _chart(steps: tuple[Any, ...]) -> Any:
    from swarmgen.runtime.chart import Call, ChartBuilder

    b = ChartBuilder("rover", data={"x": 1.5, "mode": "", "rx": None, "message": None,
                                    "tx": None, "frame": None})  # fmt: skip
    b.node("Idle", "state")
    for final in ("Done", "Blocked", "Failed", "Stopped"):
        b.node(final, "final")
    b.transition("Idle", ("go",), ("Going",))
    last = steps[-1][0]
    for state, name, inputs, results, after in steps:

        def args(ctx: Any, inputs: tuple[str, ...] = inputs) -> dict[str, Any]:
            return {i: ctx.data[i] for i in inputs}

        b.node(state, "state", call=Call(name, "HardwareFunction", args, results, OUTCOMES))
        b.transition(state, (f"outcome.{state}.succeeded",), ("Done" if state == last else after,))
        b.transition(state, (f"outcome.{state}.blocked",), ("Blocked",))
        for failed in ("aborted", "preempted"):
            b.transition(state, (f"outcome.{state}.{failed}",), ("Failed",))
        b.transition(state, ("stop",), ("Stopped",))
    b.initial(None, ("Idle",))
    return b.build()


# --- the subprocess -----------------------------------------------------------------------------


def _replay() -> dict[str, Any]:
    import rclpy
    from rclpy.context import Context

    from swarmgen.ros.runtime.replay import Replay

    found: dict[str, Any] = {}
    for kind, spec in specs(announce=False).items():
        context = Context()
        rclpy.init(args=["replay"], context=context)
        replay = Replay(spec, context)
        try:
            traces = [replay.run(steps) for steps in SCENARIOS]
            stats = dict(replay.stats, goals=replay.driver.started)
            found[kind] = {"traces": traces, "stats": stats}
        finally:
            replay.close()
            rclpy.try_shutdown(context=context)
    return found


def _simulate(kind: str, script: dict[str, Any]) -> dict[str, Any]:
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    from swarmgen.ros.runtime.node import MemberNode
    from swarmgen.ros.runtime.process import spin_until
    from swarmgen.ros.runtime.simulated import SimulatedBehaviours

    spec = specs(announce=True)[kind]
    context = Context()
    rclpy.init(args=["simulate"], context=context)
    executor = SingleThreadedExecutor(context=context)
    namespace = f"/{kind}"
    sim = SimulatedBehaviours({"Rover": spec}, {}, {}, script=script, namespace=namespace,
                              context=context)  # fmt: skip
    member = MemberNode(spec, namespace=namespace, scheduler=sim.scheduler, context=context)
    ticks = [0]  # the executor keeps serving other callbacks while a service call is held
    sim.create_timer(0.02, lambda: ticks.__setitem__(0, ticks[0] + 1))
    try:
        executor.add_node(sim)
        executor.add_node(member)
        spin_until(executor, member.servers_ready, timeout=10.0)
        member.start()
        started, ticks[0] = time.monotonic(), 0
        member.deliver(member.engine.make_event("go", None, "station"))
        spin_until(executor, lambda: member.finished, timeout=10.0)
        seconds = time.monotonic() - started
        spin_until(executor, lambda: len(sim.servers.received) > 0 or kind == "private", 2.0)
        return {
            "final": member.active(),
            "data": {k: member.engine.data.get(k) for k in ("rx", "message", "tx", "frame")},
            "started": sim.started,
            "received": sim.servers.received,
            "errors": member.errors + sim.errors,
            "seconds": round(seconds, 3),
            "ticks_per_s": round(ticks[0] / max(seconds, 1e-3), 1),
        }
    finally:
        member.stop()
        executor.shutdown()
        member.destroy_node()
        sim.destroy_node()
        rclpy.try_shutdown(context=context)


# Data type keys that are not ROS field names travel renamed (`Binding.renames`): the model's
# `{"frameId": ...}` is a std_msgs/Header's `frame_id`, both in a goal the simulated server reads
# and in a message it publishes.
HEADER_RENAMES = (("frameId", "frame_id", ()),)
RENAMED_SCRIPT = {
    "behaviours": {
        "Fly": {"duration": 0.1, "outcome": "${'succeeded' if goal.target.frameId == 'map' else 'blocked'}"},
        "Look": {"duration": 0.1, "outputs": {"head": {"frameId": "odom"}}},
    }
}  # fmt: skip


def renamed_spec() -> Any:
    """Fly (GoTo, input `target` -> `target_pose.header`), Look (PoseStamped, output `head`
    <- `header`), both with the Header's `frame_id` as the model's `frameId`."""
    from swarmgen.ros.runtime.spec import BehaviourSpec, Binding, MemberSpec

    fly = Binding("action", GOTO, "fly", (("target", "target_pose.header"),), outcome="outcome",
                  renames=(("input", "target", HEADER_RENAMES),))  # fmt: skip
    look = Binding("topic", POSE, "look", (), (("header", "head"),), timeout_s=3.0,
                   direction="subscribe", renames=(("output", "head", HEADER_RENAMES),))  # fmt: skip
    behaviours = {
        name: BehaviourSpec(
            name, "", name.lower(), "HardwareFunction", outcomes=OUTCOMES, binding=binding
        )
        for name, binding in (("Fly", fly), ("Look", look))
    }
    return MemberSpec("Rover", "rover", "rover", PACKAGE, _renamed_chart, {}, behaviours)


def _renamed_chart() -> Any:
    from swarmgen.runtime.chart import Call, ChartBuilder

    b = ChartBuilder("rover", data={"target": {"frameId": "map"}, "head": None})
    b.node("Idle", "state")
    for final in ("Done", "Blocked", "Failed"):
        b.node(final, "final")
    b.transition("Idle", ("go",), ("Flying",))
    fly = Call("Fly", "HardwareFunction", lambda ctx: {"target": ctx.data["target"]}, (), OUTCOMES)
    look = Call("Look", "HardwareFunction", lambda ctx: {}, (("head", "head"),), OUTCOMES)
    for state, call, after in (("Flying", fly, "Looking"), ("Looking", look, "Done")):
        b.node(state, "state", call=call)
        b.transition(state, (f"outcome.{state}.succeeded",), (after,))
        b.transition(state, (f"outcome.{state}.blocked",), ("Blocked",))
        for failed in ("aborted", "preempted"):
            b.transition(state, (f"outcome.{state}.{failed}",), ("Failed",))
    b.initial(None, ("Idle",))
    return b.build()


def _simulate_renamed() -> dict[str, Any]:
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    from swarmgen.ros.runtime.node import MemberNode
    from swarmgen.ros.runtime.process import spin_until
    from swarmgen.ros.runtime.simulated import SimulatedBehaviours

    spec = renamed_spec()
    context = Context()
    rclpy.init(args=["renamed"], context=context)
    executor = SingleThreadedExecutor(context=context)
    sim = SimulatedBehaviours({"Rover": spec}, {}, {}, script=RENAMED_SCRIPT,
                              namespace="/renamed", context=context)  # fmt: skip
    member = MemberNode(spec, namespace="/renamed", scheduler=sim.scheduler, context=context)
    try:
        executor.add_node(sim)
        executor.add_node(member)
        spin_until(executor, member.servers_ready, timeout=10.0)
        member.start()
        member.deliver(member.engine.make_event("go", None, "station"))
        spin_until(executor, lambda: member.finished, timeout=10.0)
        return {"final": member.active(), "head": member.engine.data.get("head"),
                "errors": member.errors + sim.errors}  # fmt: skip
    finally:
        member.stop()
        executor.shutdown()
        member.destroy_node()
        sim.destroy_node()
        rclpy.try_shutdown(context=context)


def main(argv: list[str]) -> int:
    """`replay`: both specs' traces; `simulate`: both specs under SCRIPT (and a variant)."""
    if argv[0] == "replay":
        print(json.dumps(_replay()))
        return 0
    if argv[0] == "renamed":
        print(json.dumps(_simulate_renamed()))
        return 0
    blocked = {
        "behaviours": {**SCRIPT["behaviours"], "Go": {"duration": 0.1, "outcome": "blocked"}}
    }
    failed = {
        "behaviours": {**SCRIPT["behaviours"], "Arm": {"duration": 0.1, "outcome": "aborted"}}
    }
    report = {
        f"{kind}/{name}": _simulate(kind, script)
        for kind in ("private", "declared")
        for name, script in (("mission", SCRIPT), ("blocked", blocked), ("failed", failed))
    }
    # Trigger's bool `success` cannot say `blocked`: a script failure, the call fails
    uncarried = {"behaviours": {**SCRIPT["behaviours"], "Arm": {"outcome": "blocked"}}}
    report["declared/uncarried"] = _simulate("declared", uncarried)
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))


# --- the tests ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """platform_msgs and this test's private interface package, built into the venv once."""
    pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
    from swarmgen.ros.interfaces import (
        ACTIVE_STATES_MSG,
        EVENT_MSG,
        build_and_install,
        render_interface_package,
    )
    from tests.ros_platform.packages import build_packages

    work = tmp_path_factory.mktemp("simdeclared")
    build_packages(work / "packages")
    messages = {"Event": EVENT_MSG, "ActiveStates": ACTIVE_STATES_MSG}
    files = render_interface_package(PACKAGE, messages, PRIVATE_ACTIONS, "simulated-declared tests")
    for path, text in dict(files).items():
        target = work / PACKAGE / str(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
    build_and_install(work / PACKAGE)
    return ros_env(work / "roslog", domain_id=DOMAIN, discovery="OFF", python_path=[ROOT])


def _run(env: dict[str, str], mode: str) -> dict[str, Any]:
    outcome = run_module("tests.test_ros_simulated_declared", mode, cwd=ROOT, env=env, timeout=120)
    assert outcome.exit == 0, str(outcome)
    print(f"{mode}: {outcome.seconds:.2f} s")
    result: dict[str, Any] = json.loads(outcome.stdout.strip().splitlines()[-1])
    return result


@pytest.fixture(scope="module")
def replayed(env: dict[str, str]) -> dict[str, Any]:
    """Both specs replayed through the real runtime."""
    return _run(env, "replay")


@pytest.fixture(scope="module")
def simulated(env: dict[str, str]) -> dict[str, Any]:
    """Both specs run by their simulated behaviours."""
    return _run(env, "simulate")


def test_replay_traces_equal_private_and_declared(replayed: dict[str, Any]) -> None:
    private, declared = replayed["private"], replayed["declared"]
    assert declared["traces"] == private["traces"]
    finals = [trace[-1]["active"] for trace in declared["traces"]]
    assert finals == [["Done"], ["Blocked"], ["Failed"], ["Failed"], ["Stopped"], ["Stopped"],
                      ["Arming"]], finals  # fmt: skip
    first = declared["traces"][0][-1]["data"]
    assert (first["rx"], first["message"], first["tx"], first["frame"]) == (
        3.0,
        "armed",
        4.0,
        "map",
    )
    assert declared["traces"][3][-1]["data"]["message"] == "battery low"  # success: false


def test_replay_serves_the_declared_types(replayed: dict[str, Any]) -> None:
    """Every `complete` the interfaces can carry came back over ROS, none was delivered
    directly except the output a float64 field cannot hold (and the private action's too)."""
    declared, private = replayed["declared"]["stats"], replayed["private"]["stats"]
    assert declared["direct"] == private["direct"] == 1, (declared, private)
    assert declared["results"] == private["results"] == 9, (declared, private)
    assert declared["goals"] == private["goals"]  # one goal, call or wait per state entered


def test_simulation_equal_on_both_interfaces(simulated: dict[str, Any]) -> None:
    for name in ("mission", "blocked", "failed"):
        private, declared = simulated[f"private/{name}"], simulated[f"declared/{name}"]
        assert declared["final"] == private["final"], name
        assert declared["data"] == private["data"], name
        assert declared["errors"] == private["errors"] == [], name
    mission = simulated["declared/mission"]
    assert mission["final"] == ["Done"]
    assert mission["data"] == {"rx": 3.0, "message": "armed", "tx": 4.0, "frame": "map"}
    assert simulated["declared/blocked"]["final"] == ["Blocked"]  # GoTo's outcome field
    assert simulated["declared/failed"]["final"] == ["Failed"]  # Trigger success: false


def test_simulated_delays_are_honoured_without_blocking(simulated: dict[str, Any]) -> None:
    for kind in ("private", "declared"):
        run = simulated[f"{kind}/mission"]
        assert SCRIPTED_S <= run["seconds"] < SCRIPTED_S + 1.5, run
        assert run["ticks_per_s"] > 20, run  # a 50 Hz timer kept running during held calls


def test_simulated_publisher_behaviour_is_recorded(simulated: dict[str, Any]) -> None:
    received = simulated["declared/mission"]["received"]
    assert len(received) == 1 and received[0][0] == "Announce"
    assert received[0][1]["pose"]["position"] == {"x": 3.0, "y": 0.0, "z": 0.0}
    started = simulated["declared/mission"]["started"]
    assert ("Watch", "succeeded") in [tuple(s) for s in started]


def test_an_outcome_the_interface_cannot_carry_is_a_script_failure(
    simulated: dict[str, Any],
) -> None:
    run = simulated["declared/uncarried"]
    assert run["final"] == ["Failed"]  # success: false
    assert (
        len(run["errors"]) == 1
        and "cannot be carried by the bool field 'success'" in (run["errors"][0])
    ), run["errors"]


def test_simulated_servers_apply_renamed_keys(env: dict[str, str]) -> None:
    """The simulated GoTo server reads the goal's Header as `{"frameId": "map"}` (its script
    succeeds only then), and the PoseStamped it publishes from the script's
    `{"frameId": "odom"}` reaches the member as the model's key again."""
    run = _run(env, "renamed")
    assert run["errors"] == [] and run["final"] == ["Done"], run
    assert run["head"]["frameId"] == "odom" and "frame_id" not in run["head"], run
