"""`swarmgen verify`, phase 2: user properties (in the model and on the command line, type-checked
like guards), liveness under the fairness assumption with lasso counterexamples, lost events, and
the reductions (partial-order, symmetry, stutter) giving the same verdicts. Every counterexample
is replayed by `swarmgen replay` to the configuration the verifier reached."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from swarmgen import pipeline
from swarmgen.commands.verify import verify as verify_command
from swarmgen.verify import run
from swarmgen.verify.counterexample import Trace, timeline
from swarmgen.verify.explore import Budget
from tests.modelkit import ModelKit
from tests.test_verify import SAR, codes, replays_to_the_same_configuration, write


def finding(result: run.Result, code: str, name: str = "") -> Trace:
    (trace,) = [
        f.trace
        for f in result.findings
        if f.diagnostic.code.id == code and name in f.diagnostic.message
    ]
    assert trace is not None
    return trace


def flight(name: str, *, preempted: str, properties: tuple[str, ...] = ()) -> ModelKit:
    """A UAV that takes off on `launch` (TakeOff retried when aborted) and is Done when it
    succeeds; `preempted` says where a preempted take-off goes."""
    kit = ModelKit(name)
    kit.hardware("Flight", "Controller")
    outcomes = ["succeeded", "aborted", "preempted"]
    kit.behaviour("TakeOff", "HardwareFunction", requires=["Flight"], outcomes=outcomes)
    kit.behaviour("Hover", "HardwareFunction", requires=["Flight"], outcomes=outcomes)
    kit.event("launch", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Up", do="TakeOff")
    m.state("Hovering", do="Hover")
    m.final("Done")
    m.transition("Idle", "Up", "launch")
    m.transition("Up", "Done", "succeeded")
    m.transition("Up", "Up", "aborted")  # retried: fairness makes it succeed in the end
    m.transition("Up", preempted, "preempted")
    for outcome in outcomes:
        m.transition("Hovering", "Hovering", outcome)  # hovers for ever
    kit.member("UAV", machine=m, parts={"fc": "Flight"})
    kit.swarm("Swarm", {"UAV": 1})
    for number, text in enumerate(properties, start=1):
        kit.property("Swarm", f"p{number}", text)
    return kit


def test_leads_to_violated_after_a_preemption_is_a_lasso(tmp_path: Path) -> None:
    """A preempted take-off hovers for ever: `launch leads to UAV in Done` fails on a fair
    cycle (the retried abort does not: fairness lets the retry succeed)."""
    kit = flight("Preempted", preempted="Hovering", properties=("launch leads to UAV in Done",))
    model = write(kit, tmp_path, "preempted")
    result = run.verify(model, Budget())
    assert result.exit_code == run.VIOLATED
    assert codes(result) == ["SG407"]
    trace = finding(result, "SG407")
    # launch, taken, preempted (queued, taken); then the cycle, fair: Hover ends with each of
    # its outcomes, each queued and taken
    assert trace.loop == 4 and trace.length == 10
    assert trace.scenarios["UAV_1"][1:] == [
        {"complete": "TakeOff", "outcome": "preempted", "outputs": {}, "state": "Up"},
        *(
            {"complete": "Hover", "outcome": o, "outputs": {}, "state": "Hovering"}
            for o in ("succeeded", "aborted", "preempted")
        ),
    ]
    assert result.loaded.system is not None
    shown = timeline(result.loaded.system, trace)
    assert "      --- from here on, the steps repeat for ever ---" in shown
    replays_to_the_same_configuration(model, result.loaded.system, trace)


def test_the_same_property_holds_when_the_preemption_is_retried(tmp_path: Path) -> None:
    kit = flight("Retried", preempted="Up", properties=("launch leads to UAV in Done",))
    result = run.verify(write(kit, tmp_path, "retried"), Budget())
    # Hovering is never entered any more (SG403 is a finding of its own)
    assert codes(result) == ["SG403"]
    assert "Hovering" in result.findings[0].diagnostic.message


def test_a_leads_to_whose_premise_never_holds_is_vacuous(tmp_path: Path) -> None:
    """With one UAV, `count(UAV in Up) > 1` never holds: `... leads to UAV in Done` then holds
    for no reason, and says so (SG409, a warning on the property) instead of a silent
    `verified`; a premise that does hold (`launch`) gives no warning. The verdict stays 0."""
    texts = ("count(UAV in Up) > 1 leads to UAV in Done", "launch leads to UAV in Up")
    kit = flight("Vacuous", preempted="Hovering", properties=texts)
    result = run.verify(write(kit, tmp_path, "vacuous"), Budget())
    assert result.exit_code == run.VERIFIED
    assert codes(result) == ["SG409"]
    (vacuous,) = [f.diagnostic for f in result.findings]
    assert result.search is not None
    assert vacuous.message == (
        "property 'p1' holds vacuously: count(UAV in Up) > 1 leads to UAV in Done ('count(UAV "
        f"in Up) > 1' never holds before the abort in the {result.search.states:,} states "
        "explored)"
    )
    assert vacuous.span.line > 0  # located on the model's constraint
    assert result.findings[0].trace is None


def test_a_lost_event_under_one_interleaving_only(tmp_path: Path) -> None:
    """The UGV sends `go` as soon as it is launched; the UAV takes it only once its take-off
    succeeded. If the UGV is first, `go` reaches the UAV taking off and is lost (SG406), and
    the UAV waits for ever (SG401); if the UAV is first, `go` is received."""
    kit = ModelKit("Lost")
    kit.hardware("Flight", "Controller")
    kit.behaviour("TakeOff", "HardwareFunction", requires=["Flight"], outcomes=["succeeded"])
    kit.event("launch", sender="station")
    kit.event("go")
    uav = kit.machine("UavMission")
    uav.initial("Idle")
    for name in ("Idle", "Ready"):
        uav.state(name)
    uav.state("Up", do="TakeOff")
    uav.final("Done")
    uav.transition("Idle", "Up", "launch")
    uav.transition("Up", "Ready", "succeeded")
    uav.transition("Ready", "Done", "go")
    ugv = kit.machine("UgvMission")
    ugv.initial("Idle")
    ugv.state("Idle")
    ugv.final("Done")
    ugv.transition("Idle", "Done", "launch", effect="send go")
    kit.member("UAV", machine=uav, parts={"fc": "Flight"})
    kit.member("UGV", machine=ugv)
    kit.swarm("Swarm", {"UAV": 1, "UGV": 1})
    model = write(kit, tmp_path, "lost")
    result = run.verify(model, Budget())
    assert codes(result) == ["SG401", "SG406"]
    lost = next(f for f in result.findings if f.diagnostic.code.id == "SG406")
    assert lost.diagnostic.message.startswith("'go' sent by UGV_1 can be lost")
    trace = finding(result, "SG406")
    assert trace.length == 3  # launch sent, the UAV takes it, the UGV takes it and sends go
    assert trace.scenarios["UAV_1"] == [{"event": "launch"}, {"event": "go"}]  # ignored
    assert result.search is not None and "go" in result.search.received  # other interleavings
    assert result.loaded.system is not None
    replays_to_the_same_configuration(model, result.loaded.system, trace)


def take_offs(tmp_path: Path, count: int, prop: str) -> Path:
    kit = flight("Several", preempted="Up", properties=(prop,))
    kit.swarm("Swarm", {"UAV": count})
    return write(kit, tmp_path, "several")


def test_a_safety_property_over_member_counts(tmp_path: Path) -> None:
    model = take_offs(tmp_path, 3, "always count(UAV in Up) <= 1")
    result = run.verify(model, Budget())
    assert codes(result) == ["SG403", "SG407"]
    trace = finding(result, "SG407")
    assert trace.length == 3  # launch sent, two UAVs take it
    assert result.loaded.system is not None
    replays_to_the_same_configuration(model, result.loaded.system, trace)


@pytest.mark.parametrize(
    ("por", "symmetry"), [(True, True), (False, True), (True, False), (False, False)]
)
def test_the_reductions_keep_the_verdicts(tmp_path: Path, por: bool, symmetry: bool) -> None:
    model = take_offs(tmp_path, 3, "eventually every UAV in Done")
    result = run.verify(model, Budget(por=por, symmetry=symmetry))
    assert (result.exit_code, codes(result)) == (run.VIOLATED, ["SG403"])  # Hovering only


STATE_PROPERTIES = (
    "never (UGV in MoveToTarget and UAV in Coverage)",
    "always count(UGV in Rescuing) <= 0",
    "UGV in Bidding leads to UGV in Ready",
    "UAV in SelectRover leads to UGV in MoveToTarget",
    "always UGV.target_id == 0",
)


@pytest.mark.parametrize("text", STATE_PROPERTIES)
def test_a_property_sees_its_own_states_through_the_reduction(text: str) -> None:
    """The partial-order reduction hides a member's step only when the property cannot see it:
    its visibility is the states the atoms name and the data they read, per member type (a
    rover going from Ready to Bidding is invisible to `UGV in MoveToTarget`). On SAR the verdict
    and the findings are those of the whole graph, property by property (an agreement check:
    the case an unsound visibility gets wrong is the next test's)."""
    outcomes = []
    for por in (True, False):
        result = run.verify(SAR, Budget(por=por), {"UAV": 1, "UGV": 1}, properties=(text,))
        assert result.search is not None and not result.search.bounded
        outcomes.append((result.exit_code, codes(result)))
    assert outcomes[0] == outcomes[1]


def test_a_transient_state_the_property_names_is_never_skipped(tmp_path: Path) -> None:
    """A passes through X (`launch` in, `start` out) while B goes to Y on `start`: the property
    is broken only when B takes `start` before A does. Each delivery sends nothing, so without
    visibility the reduction would take A's two deliveries as one chain and never see A in X
    with B in Y (measured: a projection that sees nothing misses the SG407). A's delivery into
    or out of X is visible, B's into Y too: both orders are kept; A's other steps are not."""
    kit = ModelKit("Transient")
    kit.event("launch", sender="station")
    kit.event("start", sender="station")
    for member, states in (("A", ("Idle", "X", "Z")), ("B", ("Wait", "Ready", "Y"))):
        machine = kit.machine(f"{member}Machine")
        machine.initial(states[0])
        for state in states:
            machine.state(state)
        machine.transition(states[0], states[1], "launch")
        machine.transition(states[1], states[2], "start")
        kit.member(member, machine=machine)
    kit.swarm("Swarm", {"A": 1, "B": 1})
    kit.property("Swarm", "p1", "never (A in X and B in Y)")
    model = write(kit, tmp_path, "transient")
    states = {}
    for por in (True, False):
        result = run.verify(model, Budget(por=por))
        assert codes(result) == ["SG401", "SG407"]  # no final state: it stops (SG401)
        assert result.search is not None
        states[por] = result.search.states
        trace = finding(result, "SG407")
        assert result.loaded.system is not None
        replays_to_the_same_configuration(model, result.loaded.system, trace)
    assert states[True] < states[False]


def test_partial_order_reduction_explores_fewer_states() -> None:
    counts = {}
    for por in (True, False):
        result = run.verify(SAR, Budget(por=por), {"UAV": 1, "UGV": 1})
        assert result.search is not None and result.exit_code == run.VERIFIED
        counts[por] = result.search.states
    assert counts[True] < counts[False]


def test_properties_are_type_checked_like_guards(tmp_path: Path) -> None:
    kit = flight("Typos", preempted="Up", properties=("always count(UAV in Upp) <= 1",))
    diagnostics = pipeline.validate(write(kit, tmp_path, "typos")).diagnostics
    (bad,) = [d for d in diagnostics if d.code.id == "SG408"]
    assert "no state of UAV 'Upp'" in bad.message and bad.hint == "did you mean 'Up'?"
    assert bad.span.line > 0  # on the Constraint


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("always UGV in Up", "no member type 'UGV'"),
        ("launch leads", "expected `to`"),
        ("eventually UAV.height > 2", "no datum of UAV 'height'"),
        ("never lanch", "no event 'lanch'"),
    ],
)
def test_a_bad_property_option_exits_2(tmp_path: Path, text: str, expected: str) -> None:
    model = write(flight("Cli", preempted="Up"), tmp_path, "cli")
    result = CliRunner().invoke(verify_command, [str(model), "--property", text, "--quiet"])
    assert result.exit_code == 2, result.output
    assert "[SG408]" in result.output and expected in result.output
    assert "Traceback" not in result.output


def test_a_property_option_is_checked(tmp_path: Path) -> None:
    model = write(flight("Cli", preempted="Up"), tmp_path, "cli")
    runner = CliRunner()
    holds = runner.invoke(verify_command, [str(model), "--property", "never UAV in Hovering"])
    assert holds.exit_code == run.VIOLATED  # SG403: Hovering is unreachable
    assert "[SG407]" not in holds.output
    fails = runner.invoke(verify_command, [str(model), "--quiet", "--property", "never UAV in Up"])
    assert fails.exit_code == run.VIOLATED and "[SG407]" in fails.output
    assert "counterexample of SG407 (2 steps):" in fails.output
