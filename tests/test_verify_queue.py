"""`swarmgen verify` follows the member's one FIFO queue: a behaviour's end is an input queued
behind the events already waiting (as the asyncio member's task delivers it), not a step that
overtakes them; so an ignored event at the head of an inbox can be dropped at once, and a
behaviour end that comes before an event is queued before it (docs/verify.md, "Why an ignored
head may be dropped")."""

from __future__ import annotations

from pathlib import Path

from swarmgen.verify import run
from swarmgen.verify.explore import Budget
from tests.modelkit import ModelKit
from tests.test_verify import codes, replays_to_the_same_configuration, write
from tests.test_verify_props import finding


def end_before_the_queued_event(tmp_path: Path) -> Path:
    """The worker's Job ends while `e` is on its way to it: the end is queued first, so the
    worker takes it, sends `g` (behind the `e` the sender already queued to itself) and then,
    in Next, takes `e`. So the sender sees `e` before `g` and reaches Bad, while the worker
    reaches Took. A verifier that dropped `e` at once (ignored in Work) but let the end
    overtake queued events would only see `g` sent before `e`: never both."""
    kit = ModelKit("Queue")
    kit.hardware("Cpu", "Controller")
    kit.behaviour("Job", "HardwareFunction", requires=["Cpu"], outcomes=["succeeded"])
    kit.behaviour("Tick", "HardwareFunction", requires=["Cpu"], outcomes=["succeeded"])
    kit.event("go", sender="station")
    kit.event("e")
    kit.event("g")
    worker = kit.machine("WorkerMachine")
    worker.initial("Idle")
    worker.state("Idle")
    worker.state("Work", do="Job")
    worker.state("Next")
    worker.final("Took")
    worker.transition("Idle", "Work", "go")
    worker.transition("Work", "Next", "succeeded", effect="send g")
    worker.transition("Next", "Took", "e")
    sender = kit.machine("SenderMachine")
    sender.initial("Idle")
    for name in ("Idle", "Sent", "Heard"):
        sender.state(name)
    sender.state("Ticking", do="Tick")
    sender.final("Bad")
    sender.transition("Idle", "Ticking", "go")
    sender.transition("Ticking", "Sent", "succeeded", effect="send e")
    sender.transition("Sent", "Heard", "e")
    sender.transition("Heard", "Bad", "g")
    kit.member("Worker", machine=worker, parts={"cpu": "Cpu"})
    kit.member("Sender", machine=sender, parts={"cpu": "Cpu"})
    kit.swarm("Swarm", {"Worker": 1, "Sender": 1})
    kit.property("Swarm", "apart", "never (Worker in Took and Sender in Bad)")
    return write(kit, tmp_path, "queue")


def test_a_behaviour_end_queued_before_an_event_is_taken_first(tmp_path: Path) -> None:
    model = end_before_the_queued_event(tmp_path)
    for budget in (Budget(), Budget(por=False, symmetry=False)):
        result = run.verify(model, budget)
        assert result.exit_code == run.VIOLATED, budget
        assert "SG407" in codes(result)
    trace = finding(result, "SG407", "apart")
    # go; both take it; Job ends; Tick ends; the sender takes its end (sends e to both);
    # the worker takes Job's end (sends g); the worker takes e; the sender takes e, then g
    assert trace.length == 10
    job = {"complete": "Job", "outcome": "succeeded", "outputs": {}, "state": "Work"}
    # the worker's own g is dropped at once (nothing Next leads to takes it), then e is taken
    assert trace.scenarios["Worker_1"] == [{"event": "go"}, job, {"event": "g"}, {"event": "e"}]
    tick = {"complete": "Tick", "outcome": "succeeded", "outputs": {}, "state": "Ticking"}
    assert trace.scenarios["Sender_1"] == [{"event": "go"}, tick, {"event": "e"}, {"event": "g"}]
    assert result.loaded.system is not None
    replays_to_the_same_configuration(model, result.loaded.system, trace)
