"""CLI start-up benchmark: whole-process wall time of short `swarmgen` commands, side by side.

    .venv/bin/python benchmarks/bench_startup.py [--reps 15] [--base /tmp/base]

Commands: `--version`, `--help`, `validate --help`, `compile --help`, `validate` SAR,
`compile` SAR `--backend scxml`, `compile` SAR with every backend, and `validate` on synthetic
models of 1,000, 3,000 and 10,000 states (benchmarks/synth_model.py, generated once per run into
the scratch directory; `--cases` runs a subset, e.g. `--cases validate_sar,validate_synth_10k`;
the JSON's `validate_growth` gives their median seconds per 1,000 states). Each runs as a subprocess
through the console script (`.venv/bin/swarmgen`), interpreter start included, output into a
fresh temporary directory.

`--base DIR` adds a baseline source tree (e.g. `git worktree add /tmp/base HEAD`, the code
before a change) and `--tree NAME=DIR` more trees, each run by the same interpreter with
`PYTHONPATH=DIR`: the trees alternate run by run (rep 1 of every case and tree, then rep 2, ...),
so a load that comes and goes on a shared machine falls on all alike. Read the ratios.

Two bytecode modes, measured in the same run:

- `cached`: compiled modules (`.pyc`) kept in a temporary `PYTHONPYCACHEPREFIX` (warmed by one
  uncounted run): what an installed wheel or a normal checkout does;
- `source`: `PYTHONDONTWRITEBYTECODE=1` and no `.pyc` for swarmgen's modules, so each run
  compiles them from source, as in an environment that sets it (this one does).

Wall time from fork to exit (`time.perf_counter`) and the child's CPU time (user + system, from
getrusage(RUSAGE_CHILDREN) around each run: on a loaded machine it grows less than the wall
time, which also counts waiting for a core), medians over `--reps` runs; peak resident
memory from one extra run per command under `/usr/bin/time -v` ("Maximum resident set size"),
when it exists. Prints a table and writes benchmarks/results/startup.json with the machine, the
load average at start and end, and every sample.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = HERE / "results" / "startup.json"
GNU_TIME = Path("/usr/bin/time")
OUT = "{out}"  # replaced by a fresh output directory per run
SYNTH_SIZES = (1000, 3000, 10000)  # states of the synthetic models `validate` is timed on


def synth(states: int) -> str:
    """The placeholder of the synthetic model of `states` states (see `synth_path`)."""
    return f"{{synth:{states}}}"


CASES: dict[str, list[str]] = {
    "version": ["--version"],
    "help": ["--help"],
    "validate_help": ["validate", "--help"],
    "compile_help": ["compile", "--help"],
    "validate_sar": ["validate", str(SAR)],
    "compile_sar_scxml": ["compile", str(SAR), "-o", OUT, "--backend", "scxml"],
    "compile_sar_all": ["compile", str(SAR), "-o", OUT],
    **{f"validate_synth_{n // 1000}k": ["validate", synth(n)] for n in SYNTH_SIZES},
}
TARGETS_S = {  # issue 14
    "version": 0.080,
    "help": 0.080,
    "validate_help": 0.080,
    "compile_help": 0.080,
    "validate_sar": 0.200,
    "compile_sar_all": 0.300,
    "validate_synth_10k": 2.0,  # the aim of issue 14's validate part (every backend: < 5 s)
}
MODES = ("cached", "source")


def script() -> list[str]:
    """The `swarmgen` console script beside this interpreter, else `python -m swarmgen`."""
    beside = Path(sys.executable).parent / "swarmgen"
    return [str(beside)] if beside.is_file() else [sys.executable, "-m", "swarmgen"]


def environment(tree: Path, mode: str, pycache: Path) -> dict[str, str]:
    """The environment of a run of `tree` in bytecode `mode`."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    env.pop("PYTHONPYCACHEPREFIX", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if mode == "cached":
        env["PYTHONPYCACHEPREFIX"] = str(pycache)
    else:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def synth_path(scratch: Path, states: int) -> Path:
    """Where the synthetic model of `states` states lives in this run's scratch directory."""
    return scratch / "synth" / f"synth_{states}.xmi"


def make_synth(scratch: Path) -> None:
    """Generate the synthetic models once (the same bytes for the same size)."""
    for states in SYNTH_SIZES:
        target = synth_path(scratch, states)
        target.parent.mkdir(parents=True, exist_ok=True)
        generator = [sys.executable, str(HERE / "synth_model.py"), "--states", str(states)]
        subprocess.run([*generator, "-o", str(target)], check=True, capture_output=True)


def command(case: str, out: Path) -> list[str]:
    """The command line of `case`, writing (if it writes) into `out`; a synthetic model's
    placeholder becomes its path in the scratch directory (`out`'s grandparent)."""
    scratch = out.parent.parent
    placeholders = {OUT: str(out)} | {synth(n): str(synth_path(scratch, n)) for n in SYNTH_SIZES}
    return [*script(), *(placeholders.get(a, a) for a in CASES[case])]


def cpu_of_children() -> float:
    """User + system CPU seconds of every child reaped so far."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def run_once(case: str, env: dict[str, str], scratch: Path) -> tuple[float, float]:
    """One run of `case`: its wall time and CPU time (user + system, which waiting for a busy
    core does not add to); fails loudly if swarmgen does."""
    out = Path(tempfile.mkdtemp(dir=scratch)) / "out"
    args = command(case, out)
    cpu = cpu_of_children()
    start = time.perf_counter()
    done = subprocess.run(args, cwd=scratch, env=env, capture_output=True, check=False)
    seconds = time.perf_counter() - start
    cpu = cpu_of_children() - cpu
    shutil.rmtree(out.parent, ignore_errors=True)
    if done.returncode != 0:
        sys.exit(f"failed ({done.returncode}): {' '.join(args)}\n{done.stderr.decode()}")
    return seconds, cpu


def peak_mb(case: str, env: dict[str, str], scratch: Path) -> float | None:
    """Peak resident memory of one run of `case`, from `/usr/bin/time -v` (None without it)."""
    if not (GNU_TIME.is_file() and os.access(GNU_TIME, os.X_OK)):
        return None
    out = Path(tempfile.mkdtemp(dir=scratch)) / "out"
    done = subprocess.run(
        [str(GNU_TIME), "-v", *command(case, out)],
        cwd=scratch,
        env=env,
        capture_output=True,
        check=False,
    )
    shutil.rmtree(out.parent, ignore_errors=True)
    found = re.search(rb"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    return round(int(found.group(1)) / 1024, 1) if found else None


def origin(tree: Path, env: dict[str, str], scratch: Path) -> str:
    """Where `import swarmgen` comes from with `env` (outside any tree): it must be `tree`."""
    code = "import swarmgen; print(swarmgen.__file__)"
    found = subprocess.run(
        [sys.executable, "-c", code],
        cwd=scratch,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    if not Path(found).resolve().is_relative_to(tree.resolve()):
        sys.exit(f"PYTHONPATH={tree} imports swarmgen from {found}")
    return found


def revision(tree: Path) -> dict[str, Any]:
    """The tree's git commit and whether it has uncommitted changes."""
    git = ["git", "-C", str(tree)]
    head = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True).stdout
    dirty = subprocess.run([*git, "status", "--porcelain"], capture_output=True, text=True).stdout
    return {"path": str(tree), "commit": head.strip(), "uncommitted_changes": bool(dirty.strip())}


def machine() -> dict[str, Any]:
    """Interpreter, platform, CPUs and CPU model."""
    model = ""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        found = re.search(r"^model name\s*:\s*(.+)$", cpuinfo.read_text(), re.MULTILINE)
        model = found.group(1) if found else ""
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "cpu_model": model,
    }


def summary(samples: list[tuple[float, float]]) -> dict[str, Any]:
    """Median, min and p90 of the wall times, the median CPU time (seconds), and the samples."""
    walls = [wall for wall, _ in samples]
    ordered = sorted(walls)
    return {
        "runs": len(samples),
        "median_s": round(statistics.median(walls), 4),
        "min_s": round(ordered[0], 4),
        "p90_s": round(ordered[min(len(ordered) - 1, int(0.9 * len(ordered)))], 4),
        "cpu_median_s": round(statistics.median(cpu for _, cpu in samples), 4),
        "samples_s": [round(s, 4) for s in walls],
    }


def measure(trees: dict[str, Path], reps: int, scratch: Path, cases: list[str]) -> dict[str, Any]:
    """Every case, tree and mode, interleaved rep by rep; then one peak-memory run of each."""
    pycache = scratch / "pycache"
    if any(CASES[case][-1].startswith("{synth:") for case in cases):
        make_synth(scratch)
    envs = {(t, m): environment(p, m, pycache) for t, p in trees.items() for m in MODES}
    warm_up = "compile_sar_all" if "compile_sar_all" in cases else cases[0]
    for (tree, _), env in envs.items():
        origin(trees[tree], env, scratch)
        run_once(warm_up, env, scratch)  # warm-up: the disk cache, the .pyc (cached)
    samples: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    for rep in range(reps):
        for case in cases:
            for (tree, mode), env in envs.items():
                samples.setdefault((case, tree, mode), []).append(run_once(case, env, scratch))
        print(f"  rep {rep + 1}/{reps}", file=sys.stderr)
    results: dict[str, Any] = {}
    for (case, tree, mode), values in samples.items():
        entry = summary(values)
        entry["peak_mb"] = peak_mb(case, envs[tree, mode], scratch)
        results.setdefault(mode, {}).setdefault(case, {})[tree] = entry
    return results


def ratios(results: dict[str, Any], trees: dict[str, Path]) -> None:
    """Add, per tree, the base/tree median ratio (how many times faster than base it is)."""
    if "base" not in trees:
        return
    for by_case in results.values():
        for entry in by_case.values():
            entry["speedup_over_base"] = {
                tree: round(entry["base"]["median_s"] / entry[tree]["median_s"], 2)
                for tree in trees
                if tree != "base"
            }
            entry["cpu_speedup_over_base"] = {
                tree: round(entry["base"]["cpu_median_s"] / entry[tree]["cpu_median_s"], 2)
                for tree in trees
                if tree != "base"
            }


def growth(results: dict[str, Any], trees: dict[str, Path]) -> dict[str, Any]:
    """Per mode and tree, the median wall and CPU seconds of `validate` per 1,000 states of
    each synthetic model measured (linear growth: the same figure at every size)."""
    found: dict[str, Any] = {}
    for mode, by_case in results.items():
        for tree in trees:
            rows = {}
            for states in SYNTH_SIZES:
                entry = by_case.get(f"validate_synth_{states // 1000}k", {}).get(tree)
                if entry is not None:
                    rows[str(states)] = {
                        "wall_s_per_1k_states": round(entry["median_s"] * 1000 / states, 4),
                        "cpu_s_per_1k_states": round(entry["cpu_median_s"] * 1000 / states, 4),
                    }
            if rows:
                found.setdefault(mode, {})[tree] = rows
    return found


def table(results: dict[str, Any], trees: dict[str, Path]) -> str:
    """A plain-text table of the medians (ms) and peaks (MB)."""
    lines = []
    for mode, by_case in results.items():
        lines.append(f"bytecode {mode}:")
        for case, entry in by_case.items():
            cells = [
                f"{tree} {entry[tree]['median_s'] * 1000:6.0f} ms"
                f" (cpu {entry[tree]['cpu_median_s'] * 1000:4.0f}) {entry[tree]['peak_mb']} MB"
                for tree in trees
            ]
            speedups = entry.get("speedup_over_base", {})
            tail = "".join(f"  {tree} x{ratio}" for tree, ratio in speedups.items())
            lines.append(f"  {case:18} " + " | ".join(cells) + tail)
    return "\n".join(lines)


def main() -> None:
    """Measure, print, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--reps", type=int, default=15, help="runs per case, tree and mode")
    parser.add_argument("--base", type=Path, help="a baseline source tree, e.g. /tmp/base")
    parser.add_argument(
        "--tree",
        action="append",
        default=[],
        metavar="NAME=PATH",
        help="another source tree to compare (repeatable)",
    )
    parser.add_argument(
        "--without-current",
        action="store_true",
        help="leave out this checkout (e.g. while others edit it); needs --base or --tree",
    )
    parser.add_argument("--output", type=Path, default=RESULTS, help="the JSON written")
    parser.add_argument(
        "--cases", help=f"comma-separated cases to run (default: all of {', '.join(CASES)})"
    )
    args = parser.parse_args()
    cases = args.cases.split(",") if args.cases else list(CASES)
    unknown = [case for case in cases if case not in CASES]
    if unknown:
        parser.error(f"unknown case(s): {', '.join(unknown)}")
    trees = {"base": args.base.resolve()} if args.base is not None else {}
    for item in args.tree:
        name, _, path = item.partition("=")
        trees[name] = Path(path).resolve()
    if not args.without_current:
        trees["current"] = ROOT
    if not trees:
        parser.error("--without-current needs --base or --tree")
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="swarmgen-bench-startup-") as scratch:
        results = measure(trees, args.reps, Path(scratch), cases)
    ratios(results, trees)
    last = list(trees)[-1]  # the tree the targets are checked on: this checkout, else the last
    cached = results["cached"]
    payload = {
        "when": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": {
            **machine(),
            "load_average_at_start": [round(x, 2) for x in load_start],
            "load_average_at_end": [round(x, 2) for x in os.getloadavg()],
            "peak_memory_from": "/usr/bin/time -v" if GNU_TIME.is_file() else None,
        },
        "trees": {name: revision(path) for name, path in trees.items()},
        "cases": {name: case for name, case in CASES.items() if name in cases},
        "targets_s": TARGETS_S,
        "targets_checked_on": last,
        "targets_met_cached": {
            case: cached[case][last]["median_s"] < limit
            for case, limit in TARGETS_S.items()
            if case in cached
        },
        "validate_growth": growth(results, trees),
        "results": results,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(payload, indent=2) + "\n")
    print(table(results, trees))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
