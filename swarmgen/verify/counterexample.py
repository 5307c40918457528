"""Counterexamples: the shortest path the search found, run again member by member with real
identities, printed as a timeline and written as one `swarmgen replay` scenario per member.

Under symmetry the search numbers members by their place in each state's canonical order; the
path is re-run from the initial state without reduction, mapping each step's member through the
canonical order of the state it is taken in, so the trace names real members. Each member's
scenario is the inputs it took, in order (deliveries as `event` steps, behaviour ends as
`complete` steps naming their state): its engine is deterministic, so `swarmgen replay` of the
scenario reaches the member's configuration at the end of the trace.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import field, replace
from pathlib import Path
from typing import Any

from swarmgen.records import dataclass
from swarmgen.verify.state import thaw
from swarmgen.verify.system import Message, Step, SwarmState, System, canonical

MAX_SHOWN = 200  # timeline lines printed (the scenarios hold every step)


@dataclass
class Trace:
    """A counterexample: its timeline, the final state (members in system order) and each
    member's replay scenario."""

    lines: list[str]
    final: SwarmState
    scenarios: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    length: int = 0
    loop: int | None = None  # a lasso: the steps from this one on repeat for ever
    # for the bag (`verify.bag`): (step, event, data, sender) and (step, member, active states)
    events: list[tuple[int, str, Any, str]] = field(default_factory=list)
    states: list[tuple[int, str, tuple[str, ...]]] = field(default_factory=list)


def rerun(
    system: System, steps: list[Step], symmetry: bool, tail: Sequence[tuple[int, Step]] = ()
) -> Trace:
    """The path's steps again, on real members (see the module docstring); then the `tail`:
    steps of single members, by their position in the state the path reached (`decouple`)."""
    state = system.initial()
    trace = Trace([], state, {member_id: [] for member_id in system.ids}, len(steps) + len(tail))
    order: list[int] = []
    trace.states = [(0, m, _active(system, state, i)) for i, m in enumerate(system.ids)]
    for number, step in enumerate([*steps, *(s for _, s in tail)], start=1):
        if number == len(steps) + 1:  # the tail's positions: the order of the state reached
            order = canonical(system, state)[1] if symmetry else list(range(len(state.members)))
        if number > len(steps):
            step = replace(step, member=order[tail[number - len(steps) - 1][0]])
        elif step.member >= 0 and symmetry:
            step = replace(step, member=canonical(system, state)[1][step.member])
        trace.events.extend((number, *sent) for sent in _sent(system, state, step))
        taken = _head(system, state, step)
        state, effect = system.apply(state, step)
        if step.member >= 0:
            trace.states.append(
                (number, system.ids[step.member], _active(system, state, step.member))
            )
        if effect.replay is not None:
            trace.scenarios[system.ids[effect.member]].append(dict(effect.replay))
        trace.lines.append(f"{number:4d}  {_describe(system, step, state, taken)}")
        for index, message in effect.dropped:  # ignored at once (`reduce`): replayed alike
            trace.scenarios[system.ids[index]].append(_replayed(system, index, message))
            trace.lines.append(
                f"        {system.ids[index]} ignores {_name(system, index, message)}"
            )
    trace.final = state
    return trace


def _head(system: System, state: SwarmState, step: Step) -> str:
    """What a delivery takes from the member's inbox, in words ("" for another step)."""
    if step.kind != "deliver":
        return ""
    return _name(system, step.member, system.member(state, step.member).inbox[0])


def _name(system: System, index: int, message: Message) -> str:
    """A message in words: an event's name, or a behaviour's end."""
    if message.kind != "outcome":
        return message.name
    chart = system.kinds[system.types[index]].chart
    return f"the end of {chart.names.get(message.state, message.state)} ({message.name})"


def _replayed(system: System, index: int, message: Message) -> dict[str, Any]:
    """A message as the `swarmgen replay` step that gives it to the member."""
    if message.kind == "outcome":
        call = system.kinds[system.types[index]].chart.nodes[message.state].call
        return {
            "complete": call.behaviour if call is not None else message.state,
            "outcome": message.name,
            "outputs": thaw(message.data) or {},
            "state": message.state,
        }
    replayed: dict[str, Any] = {"event": message.name}
    if message.data is not None:
        replayed["data"] = thaw(message.data)
    return replayed


def _sent(system: System, state: SwarmState, step: Step) -> list[tuple[str, Any, str]]:
    """What a step puts on the swarm's record: the station's event, a behaviour's end (as
    replay bags name it, `<Behaviour>.<outcome>` with its outputs), a timer, the events the
    member sends (each with its data, sent by the member)."""
    if step.kind == "station":
        return [(step.event, None, "station")]
    who = system.ids[step.member]
    found: list[tuple[str, Any, str]] = []
    if step.kind == "outcome":
        call = system.kinds[system.types[step.member]].chart.nodes[step.state].call
        behaviour = call.behaviour if call is not None else step.state
        found.append(
            (f"{behaviour}.{step.event}", {**(thaw(step.data) or {}), "state": step.state}, who)
        )
    elif step.kind == "timer":
        found.append((step.event, None, who))
    move = system.move(state.members[step.member], step)
    found.extend((m.name, thaw(m.data), who) for m in move.posts)
    return found


def _active(system: System, state: SwarmState, index: int) -> tuple[str, ...]:
    return tuple(sorted(system.engine(state, index).config))


def active_names(system: System, state: SwarmState, index: int) -> list[str]:
    """The model names of a member's active atomic states, in document order."""
    chart = system.kinds[system.types[index]].chart
    nodes = sorted(
        (chart.nodes[i] for i in system.engine(state, index).config), key=lambda n: n.order
    )
    return [chart.names.get(n.id, n.id) for n in nodes if n.is_atomic]


def _describe(system: System, step: Step, after: SwarmState, taken: str) -> str:
    if step.kind == "station":
        return f"station sends {step.event}"
    who = system.ids[step.member]
    where = ", ".join(active_names(system, after, step.member)) or "-"
    chart = system.kinds[system.types[step.member]].chart
    state = chart.names.get(step.state, step.state)
    if step.kind == "deliver":
        return f"{who} takes {taken} from its inbox  -> {who}: {where}"
    if step.kind == "outcome":
        return f"{who}: the behaviour of {state} ends with '{step.event}' (queued)"
    if step.kind == "emit":
        return f"{who}: the behaviour of {state} sends {step.event}"
    if step.kind == "delayed":
        return f"{who}: the delayed {step.event} ({step.state}) arrives (queued)"
    return f"{who}: the timer {step.event} of {state} fires (queued)"


def timeline(system: System, trace: Trace) -> list[str]:
    """The trace's lines (clipped to MAX_SHOWN) and the final configuration of every member."""
    shown = list(trace.lines[:MAX_SHOWN])
    if trace.loop is not None:  # before the line of the cycle's first step
        first = str(trace.loop + 1)
        at = next((i for i, line in enumerate(shown) if line[:4].strip() == first), len(shown))
        shown.insert(at, "      --- from here on, the steps repeat for ever ---")
    if len(trace.lines) > MAX_SHOWN:
        shown.append(f"      ... {len(trace.lines) - MAX_SHOWN} more step(s) in the scenarios")
    shown.append("      then:")
    for index, member_id in enumerate(system.ids):
        engine = system.engine(trace.final, index)
        status = "final" if engine.finished else "running"
        names = ", ".join(active_names(system, trace.final, index))
        shown.append(f"        {member_id} ({status}): {names}")
    return shown


def write_scenarios(system: System, trace: Trace, directory: Path, title: str) -> list[Path]:
    """One replay scenario per member in `directory` (created): `<member id>.json`."""
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for index, member_id in enumerate(system.ids):
        active = system.engine(trace.final, index).config
        payload = {
            "member": system.kinds[system.types[index]].name,
            "description": f"swarmgen verify: {title}; {member_id} ends in {', '.join(active)}",
            "steps": trace.scenarios[member_id],
        }
        path = directory / f"{member_id}.json"
        path.write_text(json.dumps(payload, indent=2, sort_keys=True, default=str) + "\n")
        written.append(path)
    return written
