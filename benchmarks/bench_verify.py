"""`swarmgen verify` on the SAR sample: states explored and time, with and without symmetry
reduction and partial-order reduction, for growing compositions.

Each configuration runs in a process of its own (`--one`), so the peak resident set of each is
its own: `swarmgen verify sample_models/sar/sar.xmi --members UAV=a,UGV=b [--no-symmetry]
[--no-por]` as a library call, the sample's own property included. A configuration that does not
finish within `--max-states` states is recorded as bounded with how far it got.

    .venv/bin/python benchmarks/bench_verify.py [--max-states 400000]

Writes benchmarks/results/verify.json. The machine is shared: the load average is recorded.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

MODEL = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = ROOT / "benchmarks" / "results" / "verify.json"
# (UAVs, UGVs, symmetry, partial-order reduction)
CONFIGS = [
    (1, 1, True, True), (1, 1, False, True), (1, 1, True, False),
    (2, 1, True, True), (2, 1, False, True), (2, 1, True, False),
    (2, 2, True, True),
]  # fmt: skip


def one(uavs: int, ugvs: int, symmetry: bool, por: bool, max_states: int) -> dict[str, Any]:
    """One verification in this process: its verdict, size and cost."""
    from swarmgen.verify import run
    from swarmgen.verify.explore import Budget

    started = time.perf_counter()
    result = run.verify(
        MODEL, Budget(max_states=max_states, symmetry=symmetry, por=por), {"UAV": uavs, "UGV": ugvs}
    )
    seconds = time.perf_counter() - started
    search = result.search
    assert search is not None
    return {
        "members": {"UAV": uavs, "UGV": ugvs},
        "symmetry": symmetry,
        "por": por,
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


def main() -> None:
    """Run every configuration in a child process and write the results."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--max-states", type=int, default=400_000)
    parser.add_argument("--one", nargs=4, type=int, metavar=("UAVS", "UGVS", "SYM", "POR"))
    args = parser.parse_args()
    if args.one:
        uavs, ugvs, sym, por = args.one
        print(json.dumps(one(uavs, ugvs, bool(sym), bool(por), args.max_states)))
        return
    rows = []
    for uavs, ugvs, sym, por in CONFIGS:
        command = [sys.executable, __file__, "--max-states", str(args.max_states), "--one"]
        command += [str(uavs), str(ugvs), str(int(sym)), str(int(por))]
        done = subprocess.run(command, check=True, capture_output=True, text=True)
        row = json.loads(done.stdout)
        rows.append(row)
        print(json.dumps(row), flush=True)
    payload = {
        "command": "benchmarks/bench_verify.py --max-states " + str(args.max_states),
        "python": platform.python_version(),
        "cpus": os.cpu_count(),
        "load_average": os.getloadavg(),
        "results": rows,
    }
    RESULTS.write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
