"""`swarmgen verify` on the SAR sample: states explored and time, with and without symmetry
reduction and partial-order reduction, for growing compositions; and the symmetry factor on a
swarm of identical members (`takeoff`: the test suite's take-off model, N UAVs that take off,
may abort and retry, and land on the abort), where it grows like N!.

Each configuration runs in a process of its own (`--one`), so the peak resident set and the
whole-process time of each are its own: `swarmgen verify MODEL --members UAV=a,UGV=b
[--no-symmetry] [--no-por] --max-states N`, the sample's own property included. A configuration
that does not finish within its budget of states is recorded as bounded with how far it got.

    .venv/bin/python benchmarks/bench_verify.py [--max-states 1500000] [--quick] [--upto N] [-o F]

Writes benchmarks/results/verify.json, or F (`--quick` leaves out the runs bounded by the budget
and writes nothing; `--upto N` runs only the SAR compositions of at most N members). The machine is shared: the load average is recorded.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = ROOT / "benchmarks" / "results" / "verify.json"
# (model, UAVs, UGVs, symmetry, partial-order reduction, bounded by the budget)
CONFIGS = [
    ("sar", 1, 1, True, True, False),
    ("sar", 2, 1, True, True, False), ("sar", 2, 1, False, True, False),
    ("sar", 2, 2, True, True, False), ("sar", 2, 2, False, True, False),
    ("sar", 2, 2, True, False, False),
    ("sar", 2, 0, True, True, False), ("sar", 2, 0, False, True, False),
    ("sar", 3, 0, True, True, False), ("sar", 3, 0, False, True, False),
    ("sar", 4, 0, True, True, False), ("sar", 4, 0, False, True, False),
    ("sar", 3, 3, True, True, False),
    ("sar", 3, 3, False, True, True),
    ("sar", 4, 4, True, True, True),
    *(("takeoff", n, 0, sym, True, False) for n in (3, 4, 5, 6) for sym in (True, False)),
]  # fmt: skip


# configurations whose full space needs more than the default budget: their own budget
BUDGETS = {("sar", 3, 3, True, True): 3_000_000, ("sar", 4, 0, False, True): 8_000_000}


def takeoff_model(directory: Path) -> Path:
    """The test suite's swarm of identical take-off UAVs (`tests.test_verify.take_off`)."""
    from tests.test_verify import take_off

    return take_off(directory)


def one(
    model: Path, uavs: int, ugvs: int, symmetry: bool, por: bool, max_states: int
) -> dict[str, Any]:
    """One verification in this process: its verdict, size and cost."""
    from swarmgen.verify import run
    from swarmgen.verify.explore import Budget

    started = time.perf_counter()
    members = {"UAV": uavs, "UGV": ugvs} if model == SAR else {"UAV": uavs}
    result = run.verify(model, Budget(max_states=max_states, symmetry=symmetry, por=por), members)
    seconds = time.perf_counter() - started
    search = result.search
    assert search is not None
    return {
        "members": members,
        "symmetry": symmetry,
        "por": por,
        "max_states": max_states,
        "verdict": run.summary(result).split(":", 1)[0],
        "states": search.states,
        "depth": search.max_depth,
        "expanded": search.expanded,
        "expanded_by_ample_set": search.reduced,
        "stopped_decoupled": len(search.decoupled),
        "seconds": round(seconds, 2),
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "findings": sorted(f.diagnostic.code.id for f in result.findings),
    }


# issue 17's speed goal: (UAVs, UGVs, budget of states)
SPEED_CONFIGS = [(2, 2, 1_500_000), (3, 3, 3_000_000), (4, 4, 1_500_000)]
SPEED_RESULTS = ROOT / "benchmarks" / "results" / "verify_speed.json"


def run_one(code: Path, uavs: int, ugvs: int, budget: int) -> dict[str, Any]:
    """One SAR configuration in a child process, on the code under `code` (that checkout's
    own copy of this script, which puts its `swarmgen` first on the path)."""
    script = code / "benchmarks" / "bench_verify.py"
    model = code / "sample_models" / "sar" / "sar.xmi"  # the script knows SAR by its path
    command = [sys.executable, str(script), "--one", str(model), str(uavs), str(ugvs), "1", "1"]
    command.append(str(budget))
    environment = {**os.environ, "PYTHONPATH": str(code)}
    started = time.perf_counter()
    done = subprocess.run(command, check=True, capture_output=True, text=True, env=environment)
    row: dict[str, Any] = json.loads(done.stdout)
    row["process_seconds"] = round(time.perf_counter() - started, 2)
    row["load_average_after"] = [round(x, 2) for x in os.getloadavg()]
    return row


def compare(baseline: Path) -> None:
    """The speed goal's configurations on the baseline code and on this code, alternately
    (the machine is shared: compare the ratios of one run)."""
    rows = []
    for uavs, ugvs, budget in SPEED_CONFIGS:
        pair: dict[str, Any] = {"members": {"UAV": uavs, "UGV": ugvs}, "max_states": budget}
        for name, code in (("baseline", baseline), ("this", ROOT)):
            pair[name] = run_one(code, uavs, ugvs, budget)
            print(name, json.dumps(pair[name]), flush=True)
        for field in ("seconds", "process_seconds", "peak_rss_mb"):
            pair[f"{field}_ratio"] = round(pair["baseline"][field] / pair["this"][field], 2)
        rows.append(pair)
    payload = {
        "command": f"benchmarks/bench_verify.py --baseline {baseline}",
        "python": platform.python_version(),
        "cpus": os.cpu_count(),
        "load_average": os.getloadavg(),
        "results": rows,
    }
    SPEED_RESULTS.write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")


def main() -> None:
    """Run every configuration in a child process and write the results."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--max-states", type=int, default=1_500_000)
    parser.add_argument("--quick", action="store_true", help="leave out the bounded runs")
    parser.add_argument("--one", nargs=6, metavar=("MODEL", "UAVS", "UGVS", "SYM", "POR", "N"))
    parser.add_argument(
        "--upto",
        type=int,
        help="only the SAR compositions of at most this many members in all (no take-off runs)",
    )
    parser.add_argument("-o", "--output", type=Path, default=RESULTS)
    parser.add_argument(
        "--baseline",
        type=Path,
        help="a checkout of the code before a change: run SPEED_CONFIGS with it and with this "
        "code, alternately, and write benchmarks/results/verify_speed.json",
    )
    args = parser.parse_args()
    if args.one:
        model, uavs, ugvs, sym, por, budget = args.one
        row = one(Path(model), int(uavs), int(ugvs), sym == "1", por == "1", int(budget))
        print(json.dumps(row))
        return
    if args.baseline is not None:
        compare(args.baseline.resolve())
        return
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        models = {"sar": SAR, "takeoff": takeoff_model(Path(scratch))}
        for name, uavs, ugvs, sym, por, bounded in CONFIGS:
            if bounded and args.quick:
                continue
            if args.upto is not None and (name != "sar" or uavs + ugvs > args.upto):
                continue
            command = [sys.executable, __file__, "--one", str(models[name]), str(uavs)]
            budget = max(args.max_states, BUDGETS.get((name, uavs, ugvs, sym, por), 0))
            command += [str(ugvs), str(int(sym)), str(int(por)), str(budget)]
            started = time.perf_counter()
            done = subprocess.run(command, check=True, capture_output=True, text=True)
            row = {"model": name, **json.loads(done.stdout)}
            row["process_seconds"] = round(time.perf_counter() - started, 2)
            rows.append(row)
            print(json.dumps(row), flush=True)
    if args.quick:
        return
    payload = {
        "command": " ".join(["benchmarks/bench_verify.py", *sys.argv[1:]]),
        "python": platform.python_version(),
        "cpus": os.cpu_count(),
        "load_average": os.getloadavg(),
        "results": rows,
    }
    args.output.write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
