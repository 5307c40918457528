"""`swarmgen verify`: the composed swarm explored breadth first on the members' real engines,
seeded bugs found with their shortest counterexamples, and those counterexamples replayed by
`swarmgen replay` (asyncio, smach and Qt SCXML) to the same configuration and written as bags
`swarmgen timeline` reads."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from swarmgen import replay as replaying
from swarmgen.commands.timeline import timeline as timeline_command
from swarmgen.commands.verify import verify as verify_command
from swarmgen.trace.reader import read_run
from swarmgen.verify import run
from swarmgen.verify.counterexample import Trace
from swarmgen.verify.explore import Budget, digest
from swarmgen.verify.state import thaw
from swarmgen.verify.system import System, canonical
from tests.modelkit import ModelKit

ROOT = Path(__file__).resolve().parent.parent
SAR = ROOT / "sample_models" / "sar" / "sar.xmi"


def write(kit: ModelKit, tmp_path: Path, name: str) -> Path:
    path = tmp_path / f"{name}.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    return path


def codes(result: run.Result) -> list[str]:
    return sorted(f.diagnostic.code.id for f in result.findings)


def finding(result: run.Result, code: str) -> Trace:
    (trace,) = [f.trace for f in result.findings if f.diagnostic.code.id == code]
    assert trace is not None
    return trace


def replays_to_the_same_configuration(
    model: Path,
    system: System,
    trace: Trace,
    backends: tuple[str, ...] = ("asyncio", "smach", "scxml"),
) -> None:
    """Every member's scenario, run by `swarmgen replay`, ends where the trace left it."""
    for index, member_id in enumerate(system.ids):
        kind = system.kinds[system.types[index]].name
        engine = system.engine(trace.final, index)
        expected_data = replaying.canonical(json.loads(json.dumps(thaw(engine.data))))
        for backend in backends:
            last = replaying.replay(model, kind, trace.scenarios[member_id], backend)[-1]
            assert last["active"] == sorted(engine.config), (member_id, backend)
            assert last["data"] == expected_data, (member_id, backend)


def searched(result: run.Result, trace: Trace) -> int:
    """The number the search gave the state the counterexample, re-run on real members, ends
    in (up to the symmetry): a KeyError if the search never saw it."""
    search, system = result.search, result.loaded.system
    assert search is not None and system is not None
    key = canonical(system, trace.final)[0] if result.budget.symmetry else trace.final
    return search.seen[digest(key)]


# --- the models ----------------------------------------------------------------------------


def waiting_for_each_other(tmp_path: Path) -> Path:
    """A UAV waits for the UGV's `b` before it sends `a`; the UGV waits for `a` before `b`."""
    kit = ModelKit("Deadlock")
    kit.event("launch", sender="station")
    kit.event("a")
    kit.event("b")
    uav = kit.machine("UavMission")
    uav.initial("Idle")
    uav.state("Idle")
    uav.state("WaitB")
    uav.final("Done")
    uav.transition("Idle", "WaitB", "launch")
    uav.transition("WaitB", "Done", "b", effect="send a")
    ugv = kit.machine("UgvMission")
    ugv.initial("Idle")
    ugv.state("Idle")
    ugv.state("WaitA")
    ugv.final("Done")
    ugv.transition("Idle", "WaitA", "launch")
    ugv.transition("WaitA", "Done", "a", effect="send b")
    kit.member("UAV", machine=uav)
    kit.member("UGV", machine=ugv)
    kit.swarm("Swarm", {"UAV": 1, "UGV": 1})
    return write(kit, tmp_path, "deadlock")


def abort_in_one_region(tmp_path: Path, *, handled: bool) -> Path:
    """Work has two regions; only the first leaves on missionAbort unless `handled`."""
    kit = ModelKit("Abort")
    kit.event("launch", sender="station")
    kit.event("missionAbort", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    first, second = m.composite("Work", ["R1", "R2"])
    m.initial("A", region=first)
    m.state("A", region=first)
    m.final("F1", region=first)
    m.initial("B", region=second)
    m.state("B", region=second)
    m.final("Done")
    m.transition("Idle", "Work", "launch")
    m.transition("Idle", "Done", "missionAbort")
    m.transition("A", "F1", "missionAbort")
    if handled:
        m.final("F2", region=second)
        m.transition("B", "F2", "missionAbort")
        m.transition("Work", "Done")  # completion: both regions final
    kit.member("UAV", machine=m)
    kit.swarm("Swarm", {"UAV": 1})
    return write(kit, tmp_path, f"abort_{handled}")


def circular_help(tmp_path: Path) -> Path:
    """Track is entered on `found`, which the UGV sends only after `help`, which the UAV
    sends only on entering Track: each machine alone can reach it, the swarm cannot."""
    kit = ModelKit("Circular")
    kit.event("launch", sender="station")
    kit.event("missionAbort", sender="station")
    kit.event("found")
    kit.event("help")
    uav = kit.machine("UavMission")
    uav.initial("Idle")
    for name in ("Idle", "Search", "Track"):
        uav.state(name)
    uav.final("Done")
    uav.transition("Idle", "Search", "launch")
    uav.transition("Search", "Track", "found", effect="send help")
    ugv = kit.machine("UgvMission")
    ugv.initial("Idle")
    for name in ("Idle", "Wait", "Helping"):
        ugv.state(name)
    ugv.final("Done")
    ugv.transition("Idle", "Wait", "launch")
    ugv.transition("Wait", "Helping", "help", effect="send found")
    for machine in (uav, ugv):
        for name in ("Idle", "Search", "Track", "Wait", "Helping"):
            if any(s.name == name for s in machine.states):
                machine.transition(name, "Done", "missionAbort")
    kit.member("UAV", machine=uav)
    kit.member("UGV", machine=ugv)
    kit.swarm("Swarm", {"UAV": 1, "UGV": 1})
    return write(kit, tmp_path, "circular")


def counter(tmp_path: Path, limit: int) -> Path:
    """A member counting station ticks up to `limit`; `stop` ends it."""
    kit = ModelKit("Counter")
    kit.event("tick", sender="station")
    kit.event("stop", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.final("Done")
    m.transition("Idle", "Idle", "tick", guard=f"n < {limit}", effect="n = n + 1")
    m.transition("Idle", "Done", "stop")
    kit.member("UAV", machine=m, data={"n": ("Integer", 0)})
    kit.swarm("Swarm", {"UAV": 1})
    return write(kit, tmp_path, "counter")


def take_off(tmp_path: Path) -> Path:
    """Identical UAVs taking off (which may abort and be retried), then landing on abort."""
    kit = ModelKit("TakeOff")
    kit.hardware("Flight", "Controller")
    kit.behaviour(
        "TakeOff", "HardwareFunction", requires=["Flight"], outcomes=["succeeded", "aborted"]
    )
    kit.event("launch", sender="station")
    kit.event("missionAbort", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Up", do="TakeOff")
    m.state("Flying")
    m.final("Done")
    m.transition("Idle", "Up", "launch")
    m.transition("Up", "Flying", "succeeded")
    m.transition("Up", "Idle", "aborted")
    for name in ("Idle", "Up", "Flying"):
        m.transition(name, "Done", "missionAbort")
    kit.member("UAV", machine=m, parts={"fc": "Flight"})
    kit.swarm("Swarm", {"UAV": 3})
    return write(kit, tmp_path, "takeoff")


# --- seeded bugs ---------------------------------------------------------------------------


def test_a_deadlock_between_two_member_types(tmp_path: Path) -> None:
    model = waiting_for_each_other(tmp_path)
    result = run.verify(model, Budget())
    assert result.exit_code == run.VIOLATED
    # Done is never entered either: the swarm never gets there (SG403, once per machine)
    assert codes(result) == ["SG401", "SG403", "SG403"]
    trace = finding(result, "SG401")
    assert trace.length == 3  # the station sends launch, each member takes it
    assert [s["event"] for s in trace.scenarios["UAV_1"]] == ["launch"]
    assert [s["event"] for s in trace.scenarios["UGV_1"]] == ["launch"]
    assert result.loaded.system is not None
    assert result.search is not None
    assert searched(result, trace) == result.search.deadlocks[False]
    replays_to_the_same_configuration(model, result.loaded.system, trace)


def test_an_abort_not_handled_in_one_region(tmp_path: Path) -> None:
    model = abort_in_one_region(tmp_path, handled=False)
    result = run.verify(model, Budget())
    assert result.exit_code == run.VIOLATED
    assert codes(result) == ["SG401", "SG402"]
    abort = next(f for f in result.findings if f.diagnostic.code.id == "SG402")
    assert "in 'B'" in abort.diagnostic.message
    trace = finding(result, "SG402")
    assert trace.length == 4  # launch and the abort sent, both taken
    assert [s["event"] for s in trace.scenarios["UAV_1"]] == ["launch", "missionAbort"]
    assert result.search is not None and result.loaded.system is not None
    # the member no longer interacts with anyone after the abort: the search stopped there and
    # read the member's own graph (`decouple`), whose stuck value the trace ends in
    assert result.search.decoupled and not result.search.deadlocks
    replays_to_the_same_configuration(model, result.loaded.system, trace)
    assert sorted(result.loaded.system.engine(trace.final, 0).config) == [
        "B",
        "F1",
        "R1",
        "R2",
        "Work",
    ]


def test_the_same_model_with_the_abort_handled_verifies(tmp_path: Path) -> None:
    result = run.verify(abort_in_one_region(tmp_path, handled=True), Budget())
    assert (result.exit_code, codes(result)) == (run.VERIFIED, [])


def test_a_state_reachable_per_machine_but_not_in_the_swarm(tmp_path: Path) -> None:
    result = run.verify(circular_help(tmp_path), Budget())
    assert result.exit_code == run.VIOLATED
    messages = sorted(f.diagnostic.message for f in result.findings)
    assert messages == [
        "state 'Helping' of UGV is never entered in the swarm UAV=1, UGV=1",
        "state 'Track' of UAV is never entered in the swarm UAV=1, UGV=1",
    ]
    # a state nothing reaches has no trace: the evidence is the whole space explored
    assert all(f.trace is None for f in result.findings)
    assert all(f.diagnostic.span.line > 0 for f in result.findings)  # located on the state


# --- the sample model ----------------------------------------------------------------------


def test_sar_with_one_uav_and_one_ugv(tmp_path: Path) -> None:
    """The sample verifies: no deadlock, abort safety (Land retries a preempted landing), every
    state entered, and its own property `UGV in MoveToTarget leads to targetRescued` (a rover
    that won an auction rescues) under the fairness assumption (the rover retries a failed drive
    or rescue), not vacuously (no SG409: rovers do win). The warning is honest: a rescue can be
    announced while no UAV tracks that target, so nobody takes it (SG406)."""
    result = run.verify(SAR, Budget(), {"UAV": 1, "UGV": 1})
    assert result.exit_code == run.VERIFIED
    assert codes(result) == ["SG406"]
    assert "'targetRescued' sent by UGV_1 can be lost" in result.findings[0].diagnostic.message
    assert result.search is not None and not result.search.bounded
    assert not result.search.deadlocks
    assert result.loaded.model is not None
    (prop,) = [p for s in result.loaded.model.swarms for p in s.properties]
    assert (prop.name, prop.text) == (
        "assignedTargetsAreRescued",
        "UGV in MoveToTarget leads to targetRescued",
    )


def test_a_found_target_can_be_dropped_when_every_bid_fails(tmp_path: Path) -> None:
    """`targetFound leads to targetRescued` does not follow from the machines alone: a rover
    that loses its bid goes back to Ready (it must, to bid for the next target), and when every
    bid ends `aborted` the target is dropped. The real auction gives each target to one bidder,
    a contract of the behaviours that verify does not assume (outcomes are free)."""
    result = run.verify(
        SAR, Budget(), {"UAV": 1, "UGV": 1}, properties=("targetFound leads to targetRescued",)
    )
    assert result.exit_code == run.VIOLATED and "SG407" in codes(result)
    trace = finding(result, "SG407")
    assert {
        "complete": "TaskBidding", "outcome": "aborted", "outputs": {}, "state": "Bidding",
    } in trace.scenarios["UGV_1"]  # fmt: skip
    assert result.loaded.system is not None
    replays_to_the_same_configuration(SAR, result.loaded.system, trace)


# --- budget and symmetry -------------------------------------------------------------------


def test_the_budget_gives_a_bounded_verdict(tmp_path: Path) -> None:
    model = counter(tmp_path, 10)
    runner = CliRunner()
    sends = ["--station-sends", "12"]
    bounded = runner.invoke(verify_command, [str(model), "--max-states", "20", *sends])
    assert bounded.exit_code == run.BOUNDED, bounded.output
    assert "[SG405]" in bounded.output
    assert "bounded: " in bounded.output and "states, depth" in bounded.output
    assert "verify: " in bounded.output  # the progress line (stderr, mixed in by the runner)
    whole = run.verify(model, Budget(max_states=5000), station_bound=12)
    assert whole.exit_code == run.VERIFIED and whole.search is not None
    assert whole.search.states > 20


def test_symmetry_explores_fewer_states_with_the_same_verdict(tmp_path: Path) -> None:
    model = take_off(tmp_path)
    reduced = run.verify(model, Budget(symmetry=True))
    full = run.verify(model, Budget(symmetry=False))
    assert reduced.search is not None and full.search is not None
    assert (reduced.exit_code, codes(reduced)) == (full.exit_code, codes(full))
    assert reduced.exit_code == run.VERIFIED
    # each canonical state stands for at most 3! = 6 states of the full space
    assert reduced.search.states < full.search.states <= 6 * reduced.search.states
    assert (reduced.search.states, full.search.states) == (65, 229)


# --- the command ---------------------------------------------------------------------------


def test_the_command_writes_replay_scenarios_and_json(tmp_path: Path) -> None:
    model = waiting_for_each_other(tmp_path)
    out = tmp_path / "cex"
    runner = CliRunner()
    text = runner.invoke(verify_command, [str(model), "--counterexample", str(out), "--quiet"])
    assert text.exit_code == run.VIOLATED
    assert "counterexample of SG401 (3 steps):" in text.output
    written = sorted(p.name for p in (out / "SG401").iterdir())
    assert written == ["UAV_1.json", "UGV_1.json", "bag"]
    member, steps = replaying.load_scenario(out / "SG401" / "UAV_1.json")
    assert (member, steps) == ("UAV", [{"event": "launch"}])
    # the trace as a bag: step n at n seconds, each member's states after its step 1 ms later
    recorded = read_run([out / "SG401" / "bag"])
    assert [(e.name, e.sender, e.stamp_ns) for e in recorded.events] == [
        ("launch", "station", 1_000_000_000)
    ]
    assert [(s.member, s.states, s.stamp_ns) for s in recorded.states] == [
        ("UAV_1", ("Idle",), 0), ("UGV_1", ("Idle",), 0),
        ("UAV_1", ("WaitB",), 2_000_000_000), ("UGV_1", ("WaitA",), 3_000_000_000),
    ]  # fmt: skip
    shown = runner.invoke(timeline_command, [str(out / "SG401" / "bag")])
    assert shown.exit_code == 0 and "launch" in shown.output, shown.output
    as_json = runner.invoke(verify_command, [str(model), "--format", "json", "--quiet"])
    payload = json.loads(as_json.output.split("\nswarmgen: ")[0])
    assert payload["verify"]["verdict"] == "violated"
    assert [c["length"] for c in payload["verify"]["counterexamples"]] == [3]
    sarif = runner.invoke(verify_command, [str(model), "--format", "sarif", "--quiet"])
    assert '"ruleId": "SG401"' in sarif.output


@pytest.mark.parametrize("members", ["UAV", "UAV=x", "Nope=1"])
def test_bad_member_counts_are_one_line(tmp_path: Path, members: str) -> None:
    result = CliRunner().invoke(verify_command, [str(counter(tmp_path, 2)), "--members", members])
    assert result.exit_code == 2
    assert "--members" in result.output and "Traceback" not in result.output


def test_a_model_with_errors_is_not_verified(tmp_path: Path) -> None:
    kit = ModelKit("Broken")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.transition("Idle", "Idle", "nosuchevent")
    kit.member("UAV", machine=m)
    kit.swarm("Swarm", {"UAV": 1})
    result = CliRunner().invoke(verify_command, [str(write(kit, tmp_path, "broken")), "--quiet"])
    assert result.exit_code == 1
    assert "error: " in result.output and "not verified" in result.output


# --- snapshots -----------------------------------------------------------------------------


def test_a_restored_engine_behaves_as_the_one_captured(tmp_path: Path) -> None:
    """Capture a member mid-run (data written, behaviour running), restore it into another
    engine of its type, and give both the same input: same result, same host calls."""
    from swarmgen.runtime.engine import Engine, Event
    from swarmgen.verify.load import load
    from swarmgen.verify.state import VerifyHost, capture, restore

    loaded = load(SAR, {"UAV": 1, "UGV": 0})
    assert loaded.system is not None
    kind = loaded.system.kinds[0]
    host = VerifyHost()
    first = Engine(kind.chart, host, "a")
    first.start()
    first.send(Event("launch"))
    first.send(first.make_event("done.invoke.TakeOff.succeeded", {}, origin=("TakeOff", 1)))
    snapshot = capture(first, host)
    assert "Loitering" in snapshot.config and snapshot.calls  # running behaviours recorded
    other_host = VerifyHost()
    second = Engine(kind.chart, other_host, "b")
    second.start()
    second.send(Event("missionAbort"))  # somewhere else entirely, then overwritten
    restore(second, other_host, snapshot)
    assert capture(second, other_host) == snapshot
    for engine in (first, second):
        engine.send(Event("missionStart"))
    assert capture(first, host) == capture(second, other_host)
    assert capture(first, host).config != snapshot.config


def test_sar_with_two_uavs_and_two_ugvs_verifies_its_property(tmp_path: Path) -> None:
    """Issue 17's correct model: two UAVs can each find a target for two rovers; a rover that
    won an auction still rescues under the fairness assumption, and the abort is safe. (3 UAVs
    + 3 UGVs: benchmarks/bench_verify.py.)"""
    result = run.verify(SAR, Budget(), {"UAV": 2, "UGV": 2})
    assert result.exit_code == run.VERIFIED
    assert codes(result) == ["SG406", "SG406"]  # warnings: 'targetFound' and 'targetRescued'
    assert result.search is not None and not result.search.bounded
    assert result.search.states == 81_810  # with every reduction (docs/verify.md, the table)
