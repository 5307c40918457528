"""Dispatch before and after: bench_dispatch.py's in-process cases of two source trees, timed in
process CPU time, interleaved case by case, medians (the machine is shared: CPU time counts
others' load less than the wall clock, and interleaving gives both trees the same load).

    .venv/bin/python benchmarks/compare_dispatch.py BASE_TREE [--rounds 7] [--reps 3]

BASE_TREE is a checkout of the commit to compare with (`git worktree add /tmp/base <commit>`);
this tree is the other. Each tree runs in a worker process of its own that imports its own
`swarmgen` (and so vendors its own runtime into the generated package) and sets its cases up
once; then every round runs each case `--reps` times in one tree, then in the other (which one
goes first alternates). Cases: the UAV trace on the generated engine and through the asyncio
member, the walks of the 100- and 10,000-state synthetic charts on a chart built afresh
(`cold`: its dispatch tables start empty) and on one whose tables the same walk built (`warm`).
Writes nothing: prints a table and, with `--json`, the figures.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent.parent
CASES = ("uav engine", "uav member", "walk 100", "walk 10k cold", "walk 10k warm")


def worker(root: Path, events: int, states: int) -> None:
    """Set the cases of the tree at `root` up, then time the case named on each input line."""
    sys.path.insert(0, str(root))
    spec = importlib.util.spec_from_file_location(
        "bench_dispatch", root / "benchmarks/bench_dispatch.py"
    )
    assert spec is not None and spec.loader is not None
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    time.perf_counter = time.process_time  # the timed loops of bench_dispatch.py, in CPU time
    trace = bench.trace(events)
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        package = bench.generated_module(tmp)
        small = bench.synth_chart(tmp, 100)
        big = bench.synth_chart(tmp, states)
        small_walk, big_walk = bench.walk(small, events), bench.walk(big, events)
        warm = big()
        bench.bench_engine(lambda: warm, big_walk)  # builds the tables of `warm`
        cases: dict[str, Callable[[], float]] = {
            "uav engine": lambda: bench.bench_swarmgen_engine(package, trace)[0],
            "uav member": lambda: bench.bench_swarmgen_member(package, trace),
            "walk 100": lambda: bench.bench_engine(small, small_walk),
            "walk 10k cold": lambda: bench.bench_engine(big, big_walk),
            "walk 10k warm": lambda: bench.bench_engine(lambda: warm, big_walk),
        }
        print("ready", flush=True)
        for line in sys.stdin:
            name, reps = line.rsplit(" ", 1)
            print(json.dumps([cases[name]() for _ in range(int(reps))]), flush=True)


class Worker:
    """A worker process of one tree."""

    def __init__(self, root: Path, events: int, states: int) -> None:
        command = [sys.executable, __file__, "--worker", str(root)]
        command += ["--events", str(events), "--states", str(states)]
        self.process = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=root
        )
        assert self.process.stdout is not None
        if self.process.stdout.readline().strip() != "ready":
            raise RuntimeError(f"the worker of {root} did not start")

    def run(self, case: str, reps: int) -> list[float]:
        """Time `case` `reps` times."""
        assert self.process.stdin is not None and self.process.stdout is not None
        self.process.stdin.write(f"{case} {reps}\n")
        self.process.stdin.flush()
        seconds: list[float] = json.loads(self.process.stdout.readline())
        return seconds

    def close(self) -> None:
        """End the worker."""
        assert self.process.stdin is not None
        self.process.stdin.close()
        self.process.wait(timeout=60)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("base", type=Path, nargs="?", default=Path("."))
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--events", type=int, default=30_000)
    parser.add_argument("--states", type=int, default=10_000)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    if args.worker is not None:
        worker(args.worker, args.events, args.states)
        return
    trees = {"before": args.base.resolve(), "after": HERE}
    workers = {name: Worker(root, args.events, args.states) for name, root in trees.items()}
    seconds: dict[str, dict[str, list[float]]] = {n: {c: [] for c in CASES} for n in trees}
    for number in range(args.rounds):
        order = list(trees) if number % 2 == 0 else list(reversed(trees))
        for case in CASES:
            for name in order:
                seconds[name][case] += workers[name].run(case, args.reps)
    for each in workers.values():
        each.close()
    report(seconds, args.events)
    if args.json is not None:
        args.json.write_text(json.dumps(seconds, indent=1) + "\n")


def report(seconds: dict[str, dict[str, list[float]]], events: int) -> None:
    """Medians and best of each case in each tree, events/s and after/before."""
    print(f"{'case':16} {'before med/best s':>20} {'after med/best s':>20} {'after/before':>12}")
    rows: dict[str, Any] = {}
    for case in CASES:
        before, after = seconds["before"][case], seconds["after"][case]
        b, a = statistics.median(before), statistics.median(after)
        rows[case] = a
        print(f"{case:16} {b:9.4f} / {min(before):8.4f} {a:9.4f} / {min(after):8.4f} {a / b:12.2f}")
    for name in seconds:
        uav = statistics.median(seconds[name]["uav engine"])
        print(
            f"{name}: UAV engine {events / uav:,.0f} events/s, member "
            f"{events / statistics.median(seconds[name]['uav member']):,.0f}, 10k cold at "
            f"{uav / statistics.median(seconds[name]['walk 10k cold']):.0%} of the UAV rate, "
            f"warm {uav / statistics.median(seconds[name]['walk 10k warm']):.0%}"
        )


if __name__ == "__main__":
    main()
