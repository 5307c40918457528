"""The UDP multicast transport across processes on loopback (docs/network.md): events per
second from one sender to N receiver processes, and the end-to-end latency of a swarm event
from the sender to the last of the N receivers (p50/p99).

    .venv/bin/python benchmarks/bench_udp.py [--members 2 8 32] [--events 20000] [--paced 500]

Each receiver is its own process with the runtime's `Endpoint` (decoding, validation, the
duplicate filter), as a member's `UdpBus` has it; the engine is not involved (bench_dispatch
measures it). Latency: `--paced` events 2 ms apart, each stamped with the sender's
`time.monotonic()` (one clock for every process of the host); an event's latency is when the
last receiver decoded it. Throughput: `--events` sent back to back; each receiver reports how
many it got and over how long, so loss (a full socket buffer) shows; the sender's own rate is
how fast it got the burst out. Writes benchmarks/results/udp.json.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.runtime.netoptions import Options  # noqa: E402
from swarmgen.runtime.transport import Endpoint, Seen  # noqa: E402

END = "benchEnd"
TIMEOUT = 60.0


class Receiver(Endpoint):
    """Stamps every event it takes (first copy only) until the sender's end."""

    def __init__(self, options: Options, name: str) -> None:
        super().__init__(options, name=name)
        self.seen = Seen()
        self.latency: dict[int, float] = {}  # paced event id -> seconds
        self.burst: list[float] = []  # receive times of the burst
        self.ended = asyncio.Event()

    def handle(self, message: dict[str, Any]) -> None:
        if message["kind"] != "event":
            return
        if not self.seen.first((message["origin"], message["sender"], message["id"])):
            return
        now = time.monotonic()
        if message["name"] == END:
            self.ended.set()
        elif message["name"] == "paced":
            self.latency[message["id"]] = now - message["timestamp"]
        else:
            self.burst.append(now)


async def receive(options: Options, name: str) -> dict[str, Any]:
    """A receiver process: announce until the first event, take events until the end."""
    receiver = Receiver(options, name)
    await receiver.open()
    try:
        deadline = time.monotonic() + TIMEOUT
        while not receiver.latency and not receiver.ended.is_set():
            receiver.send(
                {"kind": "announce", "sender": name, "member_type": "R", "active": []}
            )  # fmt: skip
            await asyncio.sleep(0.05)
            if time.monotonic() > deadline:
                break
        with contextlib.suppress(TimeoutError):  # what it got so far is the result
            await asyncio.wait_for(receiver.ended.wait(), max(0.0, deadline - time.monotonic()))
    finally:
        receiver.close()
    span = receiver.burst[-1] - receiver.burst[0] if len(receiver.burst) > 1 else 0.0
    return {"latency": receiver.latency, "burst": len(receiver.burst), "span": span}


async def send(options: Options, members: int, paced: int, events: int) -> float:
    """The sender: wait for every receiver, the paced events, the burst, the end; the seconds
    the burst took to send."""
    sender = Endpoint(options, name="sender")
    await sender.open()
    try:
        deadline = time.monotonic() + TIMEOUT
        while len(sender.peers) < members and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
        for n in range(1, paced + 1):
            sender.send(_event(n, "paced"))
            await asyncio.sleep(0.002)
        await asyncio.sleep(0.2)
        began = time.monotonic()
        for n in range(paced + 1, paced + events + 1):
            sender.send(_event(n, "burst"))
            if n % 64 == 0:
                await asyncio.sleep(0)  # let the transport write out its buffer
        sent = time.monotonic() - began
        await asyncio.sleep(0.5)
        for n in range(3):
            sender.send(_event(paced + events + 1 + n, END))
            await asyncio.sleep(0.05)
    finally:
        sender.close()
    return sent


def _event(n: int, name: str) -> dict[str, Any]:
    return {
        "kind": "event",
        "id": n,
        "name": name,
        "sender": "sender",
        "timestamp": time.monotonic(),
        "data": {"n": n},
    }


def run(members: int, paced: int, events: int) -> dict[str, Any]:
    """One measurement: N receiver processes and a sender on a fresh port."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    group = f"239.255.{os.getpid() % 250 + 1}.{members % 250 + 1}"
    me = [sys.executable, __file__, "--group", group, "--port", str(port)]
    procs = [
        subprocess.Popen([*me, "--receiver", f"r{n}"], stdout=subprocess.PIPE, text=True)
        for n in range(members)
    ]
    load = os.getloadavg()[0]  # the machine may be shared: what else ran then
    try:
        sent = asyncio.run(send(Options(group=group, port=port), members, paced, events))
        results = [json.loads(p.communicate(timeout=TIMEOUT)[0]) for p in procs]
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
    last = [
        max(r["latency"][i] for r in results)
        for i in results[0]["latency"]
        if all(i in r["latency"] for r in results)
    ]
    quantiles = statistics.quantiles(last, n=100) if len(last) > 1 else [0.0] * 99
    rates = [r["burst"] / r["span"] for r in results if r["span"] > 0]
    return {
        "members": members,
        "latency_p50_ms": round(quantiles[49] * 1000, 3),
        "latency_p99_ms": round(quantiles[98] * 1000, 3),
        "paced_delivered_to_all": len(last),
        "paced_sent": paced,
        "events_per_s_per_receiver_median": round(statistics.median(rates)) if rates else 0,
        "deliveries_per_s_total": round(sum(rates)),
        "burst_received_min": min(r["burst"] for r in results),
        "burst_sent": events,
        "sender_events_per_s": round(events / sent) if sent > 0 else 0,
        "load_average_1min_before": round(load, 2),
    }


def main() -> None:
    """Measure each member count and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, nargs="+", default=[2, 8, 32])
    parser.add_argument("--events", type=int, default=20_000)
    parser.add_argument("--paced", type=int, default=500)
    parser.add_argument("--receiver", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--group", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--port", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.receiver:
        found = asyncio.run(receive(Options(group=args.group, port=args.port), args.receiver))
        print(json.dumps(found))
        return
    results = [run(n, args.paced, args.events) for n in args.members]
    for line in results:
        print(json.dumps(line))
    out = ROOT / "benchmarks" / "results" / "udp.json"
    out.write_text(json.dumps({"cpus": os.cpu_count(), "runs": results}, indent=2) + "\n")


if __name__ == "__main__":
    main()
