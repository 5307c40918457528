"""What two more reductions would buy the SAR swarm's search, measured before building them
(docs/verify.md, "Lever 2 and outcome merging, measured").

This is a measurement, not a verifier: it runs the verifier's search (`explore`, no property
observer) with one or both experimental reductions swapped into this process only, and prints
the states it stores:

- `--own` (issue 17's lever 2): a member whose inbox is empty, whose only steps are its own
  queued inputs (behaviour ends, timers, delayed raises) and which ignores every event a member
  or the station may send, both now and in each engine its ends lead to, takes those steps
  alone (a persistent set). **The station's abort is left out** of the events it must ignore,
  so the figure is an upper bound of what a sound version gains: the abort goes to every inbox
  and is dependent on every end. `--own` also drops, on arrival, a queued event that the
  engine the events ahead of it lead to will ignore (*doomed*); without it an end and an
  ignored arrival do not commute exactly (the arrival would wait behind the end).
- `--merge`: the outcomes of a behaviour that the engine meeting them takes alike (the same
  engine after, the same sends, states entered and states left) are queued as one (the least
  by name), so their interleavings are explored once.

    .venv/bin/python benchmarks/verify_levers.py UAVS UGVS [--own] [--merge] [--max-states N]

Prints one JSON line (states, expanded, expanded by an ample set, depth, bounded, seconds,
peak RSS).
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.verify import ample as ample_module  # noqa: E402
from swarmgen.verify import explore as explore_module  # noqa: E402
from swarmgen.verify.explore import Budget, explore  # noqa: E402
from swarmgen.verify.load import load  # noqa: E402
from swarmgen.verify.reduce import Normal, Reducer  # noqa: E402
from swarmgen.verify.state import EngineState  # noqa: E402
from swarmgen.verify.system import MemberState, Message, Step, SwarmState, System  # noqa: E402

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
OWN_QUEUE = ("outcome", "timer", "delayed")


class Levers:
    """The experimental reductions, installed into the verifier's modules for this process."""

    def __init__(self, own: bool, merge: bool) -> None:
        self.own, self.merge = own, merge
        self.qualifies: dict[int, bool] = {}
        self.base_normal = Reducer._normal
        self.base_ample = ample_module.ample

    def install(self) -> None:
        levers = self

        def normal(reducer: Reducer, kind: int, member: MemberState) -> Normal:
            return levers.normal(reducer, kind, member)

        # swapped in this process only (a measurement: see the module docstring)
        setattr(Reducer, "_normal", normal)  # noqa: B010
        if self.own:
            setattr(explore_module, "ample", self.ample)  # noqa: B010

    def normal(self, reducer: Reducer, kind: int, member: MemberState) -> Normal:
        """The verifier's normal form, then doomed arrivals dropped and outcomes merged."""
        found = self.base_normal(reducer, kind, member)
        engine, inbox = found.member.engine, found.member.inbox
        if not engine.running or not inbox:
            return found
        kept, doomed = self._queue(reducer.system, kind, engine, inbox)
        if kept == inbox:
            return found
        return Normal(MemberState(engine, kept), found.dropped + tuple(doomed))

    def _queue(
        self, system: System, kind: int, engine: EngineState, inbox: tuple[Message, ...]
    ) -> tuple[tuple[Message, ...], list[Message]]:
        """Walk the inbox with the engine each event will meet (the events ahead of it taken)."""
        kept: list[Message] = []
        doomed: list[Message] = []
        left: set[str] = set()
        for message in inbox:
            stale = message.kind == "outcome" and message.state in left
            if self.own and kept and (not engine.running or stale):
                doomed.append(message)
                continue
            if self.merge and message.kind == "outcome" and not stale and engine.running:
                message = _merged(system, kind, engine, message)
            ran = system.take(kind, engine, message) if engine.running and not stale else None
            if self.own and kept and ran is not None and not ran.sent and ran.after == engine:
                doomed.append(message)
                continue
            kept.append(message)
            if ran is not None:
                engine, left = ran.after, left | ran.left
        return tuple(kept), doomed

    def ample(self, system: System, state: SwarmState, visible: Any) -> list[Step] | None:
        """The verifier's ample set, else one member's own-queue steps (see the docstring)."""
        found = self.base_ample(system, state, visible)
        if found is not None:
            return found
        for index, value in enumerate(state.members):
            if self._own_only(system, value):
                return [
                    Step(s.kind, index, s.event, s.state, s.data) for s in system.local_steps(value)
                ]
        return None

    def _own_only(self, system: System, value: int) -> bool:
        known = self.qualifies.get(value)
        if known is None:
            known = self.qualifies[value] = _own_only(system, value)
        return known


def _merged(system: System, kind: int, engine: EngineState, message: Message) -> Message:
    """The least outcome of the same behaviour that `engine` takes as it takes `message`."""
    ran = system.take(kind, engine, message)
    best = message
    for outcome in system.kinds[kind].endings[message.state]:
        other = Message(outcome.name, outcome.outputs, message.source, "outcome", message.state)
        if (other.name, repr(other.data)) >= (best.name, repr(best.data)):
            continue
        alike = system.take(kind, engine, other)
        if (alike.after, alike.sent, alike.entered, alike.left) == (
            ran.after, ran.sent, ran.entered, ran.left,
        ):  # fmt: skip
            best = other
    return best


def _own_only(system: System, value: int) -> bool:
    member = system.values[value]
    steps = system.local_steps(value)
    if member.inbox or not member.engine.running or not steps:
        return False
    if any(s.kind not in OWN_QUEUE for s in steps):
        return False
    kind = system.value_type[value]
    heard = [e for e in dict.fromkeys([*system.member_events, *system.station])]
    heard = [e for e in heard if e not in system.abort]  # the upper bound: see the docstring
    if not _deaf(system, kind, member.engine, heard):
        return False
    for step in steps:
        after = system.values[system.move(value, step).after]
        if after.inbox:
            ran = system.take(kind, after.engine, after.inbox[0])
            if ran.after.running and not _deaf(system, kind, ran.after, heard):
                return False
    return True


def _deaf(system: System, kind: int, engine: EngineState, events: list[str]) -> bool:
    for name in events:
        ran = system.run_input(kind, engine, "deliver", name, None, "")
        if ran.sent or ran.after != engine:
            return False
    return True


def main() -> None:
    """Measure one composition and print it as JSON."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("uavs", type=int)
    parser.add_argument("ugvs", type=int)
    parser.add_argument("--own", action="store_true", help="lever 2 (an upper bound)")
    parser.add_argument("--merge", action="store_true", help="outcomes taken alike merged")
    parser.add_argument("--max-states", type=int, default=20_000_000)
    args = parser.parse_args()
    Levers(args.own, args.merge).install()
    members = {"UAV": args.uavs, "UGV": args.ugvs}
    loaded = load(SAR, members, ("missionAbort",))
    assert loaded.system is not None
    started = time.perf_counter()
    search = explore(loaded.system, Budget(max_states=args.max_states))
    row = {"members": members, "own": args.own, "merge": args.merge, "states": search.states}
    row |= {"expanded": search.expanded, "expanded_by_ample_set": search.reduced}
    row |= {"depth": search.max_depth, "bounded": search.bounded}
    row |= {"seconds": round(time.perf_counter() - started, 2)}
    row |= {"peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)}
    print(json.dumps(row))


if __name__ == "__main__":
    main()
