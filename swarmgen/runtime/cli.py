"""The command line of a generated asyncio swarm package (standard library only).

    python -m <package> --member UAV --id 3 --events launch@0.1,missionStart@0.5
    python -m <package> --swarm --time-scale 0.01 --duration 5

Prints one JSON line per processed event and member: time, member, event, active states.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any

from swarmgen.runtime.engine import Event
from swarmgen.runtime.member import InMemoryBus, Library, Member


class JsonTracer:
    def __init__(self, out: Any = sys.stdout) -> None:
        self.out = out
        self.start = time.monotonic()

    def step(self, member: Member, event: Event | None) -> None:
        record = {
            "t": round(time.monotonic() - self.start, 4),
            "member": f"{member.member_type}/{member.member_id}",
            "event": event.name if event is not None else None,
            "active": member.active,
        }
        print(json.dumps(record), file=self.out, flush=True)


def _station_events(text: str) -> list[tuple[float, str]]:
    events = []
    for item in filter(None, (part.strip() for part in text.split(","))):
        name, _, at = item.partition("@")
        events.append((float(at or 0), name))
    return sorted(events)


def main(
    member_types: Mapping[str, ModuleType],
    composition: Mapping[str, int],
    library_factory: Callable[..., Library],
    prog: str = "swarm",
    argv: list[str] | None = None,
) -> int:
    parser = argparse.ArgumentParser(
        prog=prog, description="Run swarm members with simulated behaviours."
    )
    who = parser.add_mutually_exclusive_group(required=True)
    who.add_argument("--member", choices=sorted(member_types), help="member type to run")
    who.add_argument("--swarm", action="store_true", help="run the whole swarm composition")
    parser.add_argument("--id", default="1", help="member id (with --member)")
    parser.add_argument("--events", default="", help="station events: name@seconds,...")
    parser.add_argument(
        "--time-scale", type=float, default=1.0, help="scale of simulated durations"
    )
    parser.add_argument("--duration", type=float, default=10.0, help="stop after this many seconds")
    args = parser.parse_args(argv)
    if args.member:
        members = [(args.member, str(args.id))]
    else:
        members = [
            (kind, f"{kind.lower()}_{n}")
            for kind, count in composition.items()
            for n in range(1, count + 1)
        ]
    return asyncio.run(_run(member_types, members, library_factory(args.time_scale), args))


async def _run(
    member_types: Mapping[str, ModuleType],
    members: list[tuple[str, str]],
    library: Library,
    args: Any,
) -> int:
    bus = InMemoryBus()
    tracer = JsonTracer()
    running = [
        Member(
            member_types[kind].build(),
            kind,
            member_id,
            library,
            bus,
            event_scopes=member_types[kind].EVENT_SCOPES,
            tracer=tracer,
        )
        for kind, member_id in members
    ]
    tasks = [asyncio.create_task(m.run()) for m in running]
    started = time.monotonic()
    for at, name in _station_events(args.events):
        await asyncio.sleep(max(0.0, at - (time.monotonic() - started)))
        bus.broadcast(name)
    remaining = args.duration - (time.monotonic() - started)
    await asyncio.wait(tasks, timeout=max(0.0, remaining))
    for member in running:
        member.stop()
    await asyncio.gather(*tasks, return_exceptions=True)
    for member in running:
        for error in member.errors:
            print(f"{member.member_type}/{member.member_id}: {error}", file=sys.stderr)
    return 1 if any(m.errors for m in running) else 0
