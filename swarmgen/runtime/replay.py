"""Replay one member against a scenario and record its trace (standard library only).

A scenario is a list of steps; each step is an input or a burst of inputs submitted together:
    {"event": "targetFound", "data": {"target_id": 7}}             a swarm or station event
    {"complete": "TakeOff", "outcome": "succeeded", "outputs": {}}   the running behaviour ends
    {"burst": [step, step, ...]}                                     inputs queued back to back
    {"wait": 250}                        that many ms pass (real time): timers, delayed raises
A `complete` step ends the behaviour in the first active state (document order) that runs it;
`"state": "<id>"` picks the state explicitly. After each step the trace records the active
states (sorted) and the member data. The same rules are implemented for Qt SCXML in
`swarmgen/scxml/qt_script.py`, so traces from every backend can be compared line by line.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Mapping, Sequence
from typing import Any

from swarmgen.runtime.chart import Call, Chart, Node
from swarmgen.runtime.engine import FINALIZE_PREFIX
from swarmgen.runtime.member import Member, Outcome, Request

Step = Mapping[str, Any]


def expand(step: Step) -> list[Step]:
    """The steps of a step: a burst's, or the step itself."""
    burst = step.get("burst")
    return list(burst) if isinstance(burst, list) else [step]


def describe(step: Step) -> str:
    """A step in words, for messages."""
    if "burst" in step:
        return " + ".join(describe(s) for s in expand(step))
    if "complete" in step:
        return f"{step['complete']} -> {step.get('outcome', 'succeeded')}"
    if "wait" in step:
        return f"wait {step['wait']} ms"
    return str(step.get("event", "?"))


def running_state(chart: Chart, active: set[str], behaviour: str, state: str | None) -> Node | None:
    """The active state that runs `behaviour` (first in document order), or the one named."""
    nodes = sorted(chart.nodes.values(), key=lambda n: n.order)
    for node in nodes:
        runs = node.call is not None and node.call.behaviour == behaviour
        if runs and node.id in active and (state is None or node.id == state):
            return node
    return None


class _ScenarioLibrary:
    """Behaviours that end only when the scenario says so."""

    def __init__(self) -> None:
        self.pending: dict[str, asyncio.Future[Outcome]] = {}

    def get(self, name: str) -> Any:
        async def run(request: Request) -> Outcome:
            future: asyncio.Future[Outcome] = asyncio.get_running_loop().create_future()
            self.pending[request.state] = future
            try:
                return await future
            finally:
                if self.pending.get(request.state) is future:
                    del self.pending[request.state]

        return run


class _NoBus:
    """Replay isolates the member: what it sends is recorded, nothing comes back."""

    def __init__(self) -> None:
        self.sent: list[tuple[str, Any]] = []

    def attach(self, member: Member) -> None:
        pass

    def publish(self, event: Any, scope: str) -> None:
        self.sent.append((event.name, event.data))


async def replay_async(
    chart: Chart, member_type: str, steps: Sequence[Step]
) -> list[dict[str, Any]]:
    """Run the member on asyncio (behaviours as tasks, cancellation on exit) step by step."""
    library = _ScenarioLibrary()
    member = Member(chart, member_type, "replay", library, _NoBus())
    runner = asyncio.create_task(member.run())
    await _settle(member)
    trace = [_record(0, None, member)]
    for number, step in enumerate(steps, start=1):
        for item in expand(step):
            if "wait" in item:
                await _settle(member)
                await asyncio.sleep(float(item["wait"]) / 1000)
            else:
                _submit(chart, member, library, item)
        await _settle(member)
        trace.append(_record(number, step, member))
    member.stop()
    await runner
    return trace


def _submit(chart: Chart, member: Member, library: _ScenarioLibrary, step: Step) -> None:
    if "complete" in step:
        node = running_state(chart, set(member.active), str(step["complete"]), step.get("state"))
        if node is None:
            return  # nothing runs that behaviour now: the step has no effect
        outcome = str(step.get("outcome", "succeeded"))
        outputs = dict(step.get("outputs") or {})
        origin = (node.id, member.engine.activation(node.id))
        member.deliver(
            member.engine.make_event(outcome_event(node, outcome), outputs, "replay", origin=origin)
        )
        future = library.pending.get(node.id)
        if future is not None and not future.done():  # the behaviour's task ends normally
            future.set_result(Outcome(outcome, outputs, reported=True))
        return
    member.deliver(member.engine.make_event(str(step["event"]), step.get("data"), "station"))


async def _settle(member: Member) -> None:
    """Let the loop run until the member has nothing left to do (queue empty, tasks parked)."""
    for _ in range(1000):
        await asyncio.sleep(0)
        if member.queue.empty() and all(t.done() or _parked(t) for t in member.tasks.values()):
            await asyncio.sleep(0)
            if member.queue.empty():
                return


def _parked(task: asyncio.Task[None]) -> bool:
    waiter = getattr(task, "_fut_waiter", None)
    return waiter is not None and not waiter.done()


def _record(number: int, step: Step | None, member: Member) -> dict[str, Any]:
    return {
        "step": number,
        "input": describe(step) if step is not None else None,
        "active": member.active,
        "data": json.loads(json.dumps(member.engine.data, default=str)),
        "errors": member.engine.error_count,  # error events so far (docs/semantics.md)
    }


def outcome_event(node: Node, outcome: str) -> str:
    """The event that reports a behaviour's outcome to the state's finalize."""
    return f"{FINALIZE_PREFIX}{node.id}.{outcome}"


__all__ = ["Call", "describe", "expand", "outcome_event", "replay_async", "running_state"]
