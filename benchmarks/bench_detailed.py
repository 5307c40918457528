"""The detailed level's speed: real-time factor with 8 UAVs covering, and the paper's campaign.

Every number comes from whole `swarmgen simulate --level detailed` processes (the SAR sample's
generated rclpy nodes, unmodified, the behaviour servers and the world node on real ROS 2,
loopback discovery, one ROS domain per run):

- real-time factor: 8 UAVs covering the paper's 66 m x 66 m area to `--rtf-level` (default
  50 percent), at dt 0.1 s and at the scenario's own dt; `--repeat` runs (default 3) each, one
  at a time; the world node's simulated seconds over its wall seconds, median, min and max;
- the paper's detailed campaign (10 repetitions per swarm size, 1, 2, 4, 8 UAVs, to 96.875
  percent): per swarm size the median wall time of `--repeat` measured runs (whole runs:
  process start-up, discovery, the run, the teardown), times 10, summed; one run at a time.
  `--campaign-from DIR` takes the runs from an earlier detailed results.json instead (e.g.
  `benchmarks/results/compare_levels.runs/paper-coverage/detailed`).

    .venv/bin/python benchmarks/bench_detailed.py [--scenario paper-coverage] [--repeat 3]
        [--skip-rtf] [--skip-campaign] [--campaign-from DIR]

Writes benchmarks/results/detailed.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.sim import scenario as sc  # noqa: E402

MODEL = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = ROOT / "benchmarks" / "results" / "detailed.json"


def swarmgen_command(*args: str) -> list[str]:
    """`swarmgen ARGS` as a whole process (its detailed runs lease ROS domains machine-wide,
    swarmgen/ros/domains.py, so a test suite beside the benchmark never shares one)."""
    return [sys.executable, "-m", "swarmgen", *args]


SIZES = (1, 2, 4, 8)
CAMPAIGN_REPS = 10
PAPER_DAYS = 27  # the paper's Gazebo campaign: 246 runs


def variant(base: str, where: Path, dt: float | None, level: float | None) -> Path:
    """The scenario with another detailed dt and stop level, as a file for --scenario."""
    raw = sc.load(base).to_json()
    if dt is not None:
        raw["detailed"] = {**raw.get("detailed", {}), "dt": dt}
    if level is not None:
        raw["stop_level"] = level
        raw["coverage_levels"] = [x for x in raw["coverage_levels"] if x <= level] or [level]
    path = where / f"{raw['name']}-dt{dt}-to{level}.json"
    path.write_text(json.dumps(raw), encoding="utf-8")
    return path


def detailed(scenario: Path | str, members: str, reps: int, out: Path) -> dict[str, Any]:
    """One `swarmgen simulate --level detailed` process, one run at a time; its results.json
    and the whole process's wall seconds."""
    command = swarmgen_command(
        "simulate", str(MODEL), "--scenario", str(scenario),
        "--level", "detailed", "--members", members, "--reps", str(reps), "--workers", "1",
        "-o", str(out),
    )  # fmt: skip
    started = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, check=False)
    wall = time.perf_counter() - started
    if done.returncode not in (0, 1):
        raise SystemExit(f"swarmgen simulate exited with {done.returncode}: {command}")
    results = json.loads((out / "results.json").read_text(encoding="utf-8"))
    return {"results": results, "wall_s": round(wall, 2), "exit": done.returncode}


def spread(values: list[float], digits: int = 1) -> dict[str, float] | None:
    """Median, min and max."""
    if not values:
        return None
    return {"median": round(statistics.median(values), digits),
            "min": round(min(values), digits), "max": round(max(values), digits)}  # fmt: skip


def rtf(args: argparse.Namespace, where: Path) -> list[dict[str, Any]]:
    """The real-time factor of 8 UAVs covering, at dt 0.1 s and at the scenario's dt."""
    own = sc.load(args.scenario).detailed.get("dt", 0.1)
    out = []
    for dt in dict.fromkeys((0.1, float(own))):
        path = variant(args.scenario, where, dt, args.rtf_level)
        run = detailed(path, "UAV=8", args.repeat, where / f"rtf-{dt}")
        records = run["results"]["detailed"]["runs"]
        factors = [r["real_time_factor"] for r in records if r.get("real_time_factor")]
        steps = [r["sim_s"] / dt / r["world_wall_s"] for r in records if r.get("world_wall_s")]
        item = {
            "dt": dt, "uavs": 8, "to_coverage": args.rtf_level, "runs": len(records),
            "failed": sum(1 for r in records if r.get("failure")),
            "sim_s": spread([r["sim_s"] or 0.0 for r in records]),
            "real_time_factor": spread(factors),
            "steps_per_s": spread(steps),
            "timeouts": [r.get("timeouts") for r in records],
            "command_wall_s": run["wall_s"],
        }  # fmt: skip
        print(f"rtf: {json.dumps(item)}", flush=True)
        out.append(item)
    return out


def campaign_runs(args: argparse.Namespace, where: Path) -> tuple[dict[str, Any], str]:
    """Detailed runs to the scenario's stop level for every swarm size: measured now, or an
    earlier results.json (--campaign-from)."""
    if args.campaign_from is not None:
        path = Path(args.campaign_from) / "results.json"
        return json.loads(path.read_text(encoding="utf-8")), str(path)
    members = "UAV=" + ",".join(str(n) for n in SIZES)
    run = detailed(args.scenario, members, args.repeat, where / "campaign")
    return run["results"], f"measured now: {args.repeat} runs per swarm size"


def campaign(args: argparse.Namespace, where: Path) -> dict[str, Any]:
    """The paper's campaign (10 runs per swarm size), extrapolated from measured runs."""
    results, source = campaign_runs(args, where)
    sizes = [c["members"].get("UAV", 0) for c in results["configurations"]]
    per_size, total = [], 0.0
    for index, size in enumerate(sizes):
        mine = [r for r in results["detailed"]["runs"] if r["config"] == index]
        walls = [r["wall_s"] for r in mine]
        median = statistics.median(walls)
        total += CAMPAIGN_REPS * median
        per_size.append({
            "uavs": size, "runs": len(mine), "failed": sum(1 for r in mine if r.get("failure")),
            "sim_s": spread([r["sim_s"] or 0.0 for r in mine]),
            "wall_s_per_run": spread(walls),
            "real_time_factor": spread([r["real_time_factor"] for r in mine
                                        if r.get("real_time_factor")]),
            "campaign_wall_s": round(CAMPAIGN_REPS * median, 1),
        })  # fmt: skip
    return {
        "source": source, "reps_per_size": CAMPAIGN_REPS, "one_run_at_a_time": True,
        "to_coverage": results["scenario"]["stop_level"], "per_size": per_size,
        "campaign_wall_s": round(total, 1), "campaign_hours": round(total / 3600, 2),
        "paper_days": PAPER_DAYS,
    }  # fmt: skip


def main() -> None:
    """Measure, write benchmarks/results/detailed.json, print it."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="paper-coverage")
    parser.add_argument("--repeat", type=int, default=3, help="runs per measurement")
    parser.add_argument("--rtf-level", type=float, default=0.5)
    parser.add_argument("--skip-rtf", action="store_true")
    parser.add_argument("--skip-campaign", action="store_true")
    parser.add_argument("--campaign-from", help="a detailed `simulate -o` directory to reuse")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    report: dict[str, Any] = {
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "load_average_at_start": [round(x, 2) for x in os.getloadavg()]},
        "scenario": args.scenario, "model": str(MODEL.relative_to(ROOT)),
    }  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench-detailed-") as tmp:
        if not args.skip_rtf:
            report["real_time_factor_8_uavs"] = rtf(args, Path(tmp))
        if not args.skip_campaign:
            report["campaign"] = campaign(args, Path(tmp))
    report["machine"]["load_average_at_end"] = [round(x, 2) for x in os.getloadavg()]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
