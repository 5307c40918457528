"""`swarmgen simulate` against the paper's NetLogo figure and a per-agent Mesa reference.

The paper's 200 coverage runs (1, 2, 4, 8 UAVs x 50 repetitions, 201 x 201 patches, random
direction, Moore view, to 100 percent coverage) took 4 min 40 s in NetLogo on an i7-5500U. Here,
in one run on this machine:

- swarmgen: the compiled SAR model's machines (`sample_models/sar/sar.xmi`) in the numpy world,
  `--workers 2`, timed a few times (and once with one worker), and the whole command
  (`swarmgen simulate ... --scenario coverage --workers 2`, start-up included);
- Mesa: a plain per-agent implementation of the same coverage model (one `mesa.Agent` per UAV,
  a `step()` per tick, a Python grid of seen patches), the same 200 runs over 2 processes;
- scale: 1,000 UAVs on a 2001 x 2001 grid to 100 percent coverage, in a fresh process whose
  peak memory (ru_maxrss) is reported.

    .venv/bin/python benchmarks/bench_simulate.py [--mesa-reps 50] [--skip-mesa] [--skip-scale]
        [--against TREE [--pairs 7] [--against-name TEXT]]

`--against TREE` (a checkout of another commit, e.g. `git worktree add /tmp/base HEAD~3` or
`git archive HEAD~3 | tar -x -C /tmp/base`) also times the 200 runs side by side: each pair is a
fresh process on TREE then one on this tree, alternating, with 2 workers and then with 1; the
report keeps every pair's wall and CPU seconds (the process and its workers) and their medians,
so a loaded machine shows as noise in both columns alike.

Needs `mesa` (pip install -e '.[bench]'). Writes benchmarks/results/simulate.json.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.sim import scenario as sc  # noqa: E402
from swarmgen.sim.machines import compile_machines  # noqa: E402
from swarmgen.sim.sweep import simulate  # noqa: E402

MODEL = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = ROOT / "benchmarks" / "results" / "simulate.json"
SIZES = (1, 2, 4, 8)
LEVELS = (0.5, 0.75, 0.875, 0.9375, 0.96875, 1.0)
NETLOGO_SECONDS = 4 * 60 + 40


# --- swarmgen ---------------------------------------------------------------------------------


def cpu_seconds() -> float:
    """CPU time of this process and of its reaped children (the pool's workers)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def swarmgen_runs(workers: int, reps: int) -> tuple[float, float, float, dict[int, list[float]]]:
    """(compile seconds, simulate seconds, simulate CPU seconds, size -> mean ticks to each
    level)."""
    started = time.perf_counter()
    machines = compile_machines(MODEL)
    compiled = time.perf_counter()
    cpu = cpu_seconds()
    scenario = sc.load("coverage").with_overrides({"UAV": list(SIZES)}, reps=reps)
    result = simulate(machines, scenario, workers=workers)
    finished = time.perf_counter()
    cpu = cpu_seconds() - cpu
    assert all(r.reason == "coverage" for r in result.runs)
    means = {}
    for index, config in enumerate(result.configs):
        runs = [r for r in result.runs if r.config == index]
        columns = zip(*(r.coverage for r in runs), strict=True)
        means[dict(config.counts)["UAV"]] = [
            statistics.fmean(v for v in c if v is not None) for c in columns
        ]
    return compiled - started, finished - compiled, cpu, means


def cli_seconds(workers: int) -> float:
    """Wall time of the whole command, process start-up and compiling the model included:
    `swarmgen simulate sar.xmi --scenario coverage --workers K` (tables to stdout)."""
    command = [sys.executable, "-m", "swarmgen", "simulate", str(MODEL), "--scenario", "coverage"]
    started = time.perf_counter()
    subprocess.run(
        [*command, "--workers", str(workers)],
        check=True,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return time.perf_counter() - started


# --- side by side with another tree -----------------------------------------------------------

# a fresh process that imports swarmgen from the tree given (not the installed one: an editable
# install's finder is dropped first) and prints the 200 runs' wall and CPU seconds
_PAIR = """
import json, resource, sys, time
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, sys.argv[1])
from pathlib import Path
from swarmgen.sim import scenario as sc
from swarmgen.sim.machines import compile_machines
from swarmgen.sim.sweep import simulate
import swarmgen
assert swarmgen.__file__.startswith(sys.argv[1]), swarmgen.__file__
def cpu():
    a, b = (resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime
machines = compile_machines(Path(sys.argv[2]))
scenario = sc.load("coverage").with_overrides({"UAV": [1, 2, 4, 8]}, reps=50)
c, w = cpu(), time.perf_counter()
simulate(machines, scenario, workers=int(sys.argv[3]))
print(json.dumps([time.perf_counter() - w, cpu() - c]))
"""


def tree_seconds(tree: Path, workers: int) -> tuple[float, float]:
    """Wall and CPU seconds of the 200 runs in a fresh process on `tree`."""
    out = subprocess.run(
        [sys.executable, "-c", _PAIR, str(tree), str(MODEL), str(workers)],
        check=True, capture_output=True, text=True, cwd=tree,
    )  # fmt: skip
    wall, cpu = json.loads(out.stdout.strip().splitlines()[-1])
    return wall, cpu


def side_by_side(before: Path, pairs: int) -> dict[str, Any]:
    """`pairs` alternating runs of the tree `before` and of this one, with 2 and 1 workers."""
    report: dict[str, Any] = {"before": _describe(before), "after": _describe(ROOT)}
    for workers in (2, 1):
        rows = []
        for _ in range(pairs):
            rows.append([*tree_seconds(before, workers), *tree_seconds(ROOT, workers)])
            print(f"pair ({workers} worker(s)): before {rows[-1][:2]}, after {rows[-1][2:]}")
        columns = list(zip(*rows, strict=True))
        report[f"workers_{workers}"] = {
            "pairs_wall_cpu_before_after": [[round(x, 3) for x in r] for r in rows],
            "median_wall_before": round(statistics.median(columns[0]), 3),
            "median_cpu_before": round(statistics.median(columns[1]), 3),
            "median_wall_after": round(statistics.median(columns[2]), 3),
            "median_cpu_after": round(statistics.median(columns[3]), 3),
            "median_cpu_ratio_after_over_before": round(
                statistics.median(r[3] / r[1] for r in rows), 3
            ),
        }
    return report


def _describe(tree: Path) -> str:
    """The tree's commit (or its path, when it is not a git checkout)."""
    found = subprocess.run(
        ["git", "-C", str(tree), "log", "-1", "--format=%h %s"], capture_output=True, text=True
    )
    return found.stdout.strip()[:100] if found.returncode == 0 else str(tree)


# --- Mesa reference ---------------------------------------------------------------------------


def mesa_run(args: tuple[int, int, int, int]) -> list[int]:
    """One coverage run with Mesa; returns the tick each level was reached."""
    import mesa

    uavs, width, height, seed = args

    class Uav(mesa.Agent):  # type: ignore[misc]
        def __init__(self, model: Any, x: float, y: float, heading: float) -> None:
            super().__init__(model)
            self.x, self.y = x, y
            self.dx, self.dy = math.cos(heading), math.sin(heading)

        def step(self) -> None:
            m = self.model
            x, y = self.x + self.dx, self.y + self.dy
            while not m.inside(x, y):  # at the boundary: a random direction that keeps it in
                angle = m.random.uniform(0.0, 2.0 * math.pi)
                self.dx, self.dy = math.cos(angle), math.sin(angle)
                x, y = self.x + self.dx, self.y + self.dy
            self.x, self.y = x, y
            m.see(x, y)

    class Coverage(mesa.Model):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__(seed=seed)
            self.seen = bytearray(width * height)
            self.count = 0
            self.tick = 0
            self.needs = [max(1, math.ceil(p * width * height - 1e-9)) for p in LEVELS]
            self.reached: list[int] = []
            spacing = min(4.0, (width - 1) / (uavs - 1)) if uavs > 1 else 0.0
            for i in range(uavs):
                x = (width - 1) / 2 + (i - (uavs - 1) / 2) * spacing
                heading = math.pi - math.pi * (i + 0.5) / uavs  # fan out over 180 degrees
                Uav(self, x, 0.0, heading)
                self.see(x, 0.0)
            self.record()

        def inside(self, x: float, y: float) -> bool:
            return -0.5 <= x < width - 0.5 and -0.5 <= y < height - 0.5

        def see(self, x: float, y: float) -> None:
            ix, iy = math.floor(x + 0.5), math.floor(y + 0.5)
            for cy in range(max(0, iy - 1), min(height, iy + 2)):
                row = cy * width
                for cx in range(max(0, ix - 1), min(width, ix + 2)):
                    if not self.seen[row + cx]:
                        self.seen[row + cx] = 1
                        self.count += 1

        def record(self) -> None:
            while (
                len(self.reached) < len(self.needs) and self.count >= self.needs[len(self.reached)]
            ):
                self.reached.append(self.tick)

        def step(self) -> None:
            self.tick += 1
            self.agents.do("step")
            self.record()

    model = Coverage()
    while len(model.reached) < len(LEVELS):
        model.step()
    return model.reached


def mesa_runs(reps: int, workers: int) -> tuple[float, float, dict[int, list[float]]]:
    jobs = [(n, 201, 201, 1000 * n + rep) for n in SIZES for rep in range(reps)]
    started = time.perf_counter()
    cpu = cpu_seconds()
    with ProcessPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(mesa_run, jobs, chunksize=1))
    elapsed = time.perf_counter() - started
    cpu = cpu_seconds() - cpu
    means = {}
    for n in SIZES:
        mine = [r for (size, *_), r in zip(jobs, results, strict=True) if size == n]
        means[n] = [statistics.fmean(column) for column in zip(*mine, strict=True)]
    return elapsed, cpu, means


# --- scale ------------------------------------------------------------------------------------


def scale_run(uavs: int, side: int) -> dict[str, Any]:
    """In a fresh process: 1,000 UAVs on a 2001 x 2001 grid to 100 percent coverage."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    started = time.perf_counter()
    machines = compile_machines(MODEL)
    scenario = sc.load("coverage").with_overrides({"UAV": [uavs]}, reps=1)
    scenario = sc.parse({**scenario.to_json(), "world": {"width": side, "height": side, "view": 1}})
    result = simulate(machines, scenario, workers=1)
    elapsed = time.perf_counter() - started
    (run,) = result.runs
    status = Path("/proc/self/status")
    hwm = next(
        (
            int(line.split()[1])
            for line in status.read_text().splitlines()
            if line.startswith("VmHWM")
        ),
        0,
    )
    return {
        "uavs": uavs,
        "grid": f"{side} x {side}",
        "completed": run.reason == "coverage",
        "coverage_final": run.coverage_final,
        "ticks_to_100_percent": run.coverage[-1],
        "ticks_to_levels": dict(zip([f"{p * 100:g}%" for p in LEVELS], run.coverage, strict=True)),
        "seconds": round(elapsed, 2),
        # Linux keeps ru_maxrss across fork + exec: it includes the parent's size at the
        # fork; VmHWM is this address space's own peak
        "ru_maxrss_mib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "ru_maxrss_mib_before_the_run": round(before / 1024, 1),
        "vm_hwm_mib": round(hwm / 1024, 1),
    }


def fresh_process(function: Any, *args: Any) -> Any:
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(function, *args).result()


# --- main -------------------------------------------------------------------------------------


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reps", type=int, default=50)
    parser.add_argument("--mesa-reps", type=int, default=50)
    parser.add_argument("--repeat", type=int, default=3, help="timed repeats of swarmgen")
    parser.add_argument("--skip-mesa", action="store_true")
    parser.add_argument("--skip-scale", action="store_true")
    parser.add_argument("--against", type=Path, help="another tree to time side by side")
    parser.add_argument("--pairs", type=int, default=7, help="side-by-side pairs per setting")
    parser.add_argument("--against-name", help="what --against is (default: its git commit)")
    args = parser.parse_args()
    runs = len(SIZES) * args.reps
    report: dict[str, Any] = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average_at_start": [round(x, 2) for x in os.getloadavg()],
        },
        "experiment": f"{runs} coverage runs: UAVs {list(SIZES)} x {args.reps} repetitions, "
        "201 x 201 patches, to 100 percent coverage",
        "netlogo_paper_seconds": NETLOGO_SECONDS,
    }
    if not args.skip_scale:  # first, while this process is small (see scale_run)
        scale = fresh_process(scale_run, 1000, 2001)
        print(f"scale: {json.dumps(scale)}", flush=True)
        report["scale"] = scale
    timings, cpus, compile_seconds = [], [], []
    means: dict[int, list[float]] = {}
    for _ in range(args.repeat):
        compiled, seconds, cpu, means = swarmgen_runs(2, args.reps)
        compile_seconds.append(round(compiled, 3))
        timings.append(round(seconds, 3))
        cpus.append(round(cpu, 3))
        print(
            f"swarmgen (2 workers): {seconds:.2f} s, {cpu:.2f} CPU s (+ {compiled:.2f} s compile)"
        )
    _, one_worker, one_cpu, _ = swarmgen_runs(1, args.reps)
    print(f"swarmgen (1 worker): {one_worker:.2f} s, {one_cpu:.2f} CPU s", flush=True)
    commands = [round(cli_seconds(2), 3) for _ in range(args.repeat)] if args.reps == 50 else []
    if commands:
        print(f"swarmgen simulate --scenario coverage --workers 2 (whole command): {commands} s")
    best = min(timings)
    report["swarmgen"] = {
        "simulate_seconds_2_workers": timings,
        "simulate_cpu_seconds_2_workers": cpus,
        "simulate_seconds_1_worker": round(one_worker, 3),
        "simulate_cpu_seconds_1_worker": round(one_cpu, 3),
        "compile_seconds": compile_seconds,
        "best_seconds_2_workers": best,
        "median_seconds_2_workers": statistics.median(timings),
        "command_seconds_2_workers": commands,
        "x_netlogo": round(NETLOGO_SECONDS / best, 1),
        "mean_ticks_to_levels": {str(n): [round(v, 1) for v in means[n]] for n in SIZES},
    }
    if args.against is not None:
        report["side_by_side"] = side_by_side(args.against.resolve(), args.pairs)
        if args.against_name:
            report["side_by_side"]["before"] = args.against_name
    if not args.skip_mesa:
        mesa_seconds, mesa_cpu, mesa_means = mesa_runs(args.mesa_reps, 2)
        mesa_total = len(SIZES) * args.mesa_reps
        print(f"Mesa (2 processes, {mesa_total} runs): {mesa_seconds:.1f} s, {mesa_cpu:.1f} CPU s")
        scale_to_200 = runs / mesa_total
        report["mesa"] = {
            "version": __import__("mesa").__version__,
            "runs": mesa_total,
            "seconds": round(mesa_seconds, 2),
            "cpu_seconds": round(mesa_cpu, 2),
            "seconds_for_the_same_runs": round(mesa_seconds * scale_to_200, 2),
            "mean_ticks_to_levels": {str(n): [round(v, 1) for v in mesa_means[n]] for n in SIZES},
        }
        report["x_mesa_wall"] = round(mesa_seconds * scale_to_200 / best, 1)
        report["x_mesa_cpu"] = round(mesa_cpu * scale_to_200 / min(cpus), 1)
    report["machine"]["load_average_at_end"] = [round(x, 2) for x in os.getloadavg()]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
