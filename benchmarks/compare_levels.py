"""The paper's verification step: one coverage scenario at both levels, compared cell by cell.

Runs `swarmgen simulate` twice, as whole processes, with the same scenario, member counts,
seed and repetitions: once at the abstract level (the grid world) and once at the detailed
level (the SAR sample's generated rclpy nodes, unmodified, against the behaviour library and
the world node on real ROS 2). Both write times in abstract ticks from the clock origin, so the
two `results.json` compare per swarm size and coverage level.

    .venv/bin/python benchmarks/compare_levels.py --reps 10 --members UAV=1,2,4,8
    .venv/bin/python benchmarks/compare_levels.py --scenario paper-coverage-matched --reps 2
    .venv/bin/python benchmarks/compare_levels.py --markdown     # the table of the last run

Writes `benchmarks/results/compare_levels.json` (`compare_levels.<scenario>.json` for a
scenario other than `paper-coverage`) and the figure next to it (PNG and SVG): per swarm size
and coverage level the abstract and detailed means with 95 percent confidence intervals
(Student's t), n, and the relative difference (detailed - abstract) / abstract with a Welch
interval; per swarm size the detailed runs' real-time factor (median, min, max) and wall times.
Each level's own output directory (tables, results.json, figures) is kept under
`benchmarks/results/compare_levels.runs/<scenario>/<level>/`; `--reuse` takes a level's
results from there when they were made with the same sweep.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from swarmgen.sim.stats import t975  # noqa: E402

MODEL = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = ROOT / "benchmarks" / "results"


def swarmgen_command(*args: str) -> list[str]:
    """`swarmgen ARGS` as a whole process (its detailed runs lease ROS domains machine-wide,
    swarmgen/ros/domains.py, so a test suite beside the benchmark never shares one)."""
    return [sys.executable, "-m", "swarmgen", *args]


LEVELS = ("abstract", "detailed")


def child_cpu() -> float:
    """CPU seconds of the reaped child processes (each `swarmgen simulate` and its runs)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def simulate(level: str, args: argparse.Namespace, out: Path) -> dict[str, Any]:
    """One `swarmgen simulate` process; its results.json, wall and CPU seconds, exit code."""
    command = swarmgen_command(
        "simulate", str(args.model),
        "--scenario", args.scenario, "--level", level, "--reps", str(args.reps),
        "--seed", str(args.seed), "--members", args.members,
        "--workers", str(args.workers), "-o", str(out),
    )  # fmt: skip
    started, cpu = time.perf_counter(), child_cpu()
    done = subprocess.run(command, cwd=ROOT, check=False)  # the progress bar goes to stderr
    wall, cpu = time.perf_counter() - started, child_cpu() - cpu
    if done.returncode not in (0, 1):  # 1: some detailed runs failed; they are marked so
        raise SystemExit(f"{level}: swarmgen simulate exited with {done.returncode}")
    results = json.loads((out / "results.json").read_text(encoding="utf-8"))
    return {"results": results, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
            "exit": done.returncode, "command": "swarmgen " + " ".join(command[4:])}  # fmt: skip


def matches(results: dict[str, Any], args: argparse.Namespace, swept: str) -> bool:
    """Whether an earlier results.json was made with this sweep (for --reuse)."""
    scenario = results.get("scenario", {})
    sizes = sorted(c["members"].get(swept, 0) for c in results.get("configurations", []))
    wanted = sorted(int(n) for n in args.members.split("=", 1)[1].split(","))
    return (
        scenario.get("reps") == args.reps
        and scenario.get("seed") == args.seed
        and sizes == wanted
        and Path(args.scenario).stem in (scenario.get("name"), args.scenario)
    )


def level_results(level: str, args: argparse.Namespace, out: Path, swept: str) -> dict[str, Any]:
    """A level's results: reused from `out` when --reuse and they match, else run."""
    previous = out / "results.json"
    if args.reuse and previous.is_file():
        results = json.loads(previous.read_text(encoding="utf-8"))
        if matches(results, args, swept):
            print(f"{level}: reusing {previous}", file=sys.stderr)
            return {"results": results, "wall_s": None, "cpu_s": None, "exit": None,
                    "command": "reused"}  # fmt: skip
    out.parent.mkdir(parents=True, exist_ok=True)
    return simulate(level, args, out)


def rows_by_cell(results: dict[str, Any], swept: str) -> dict[tuple[int, str], dict[str, Any]]:
    """The summary's coverage rows keyed by (swarm size, level name)."""
    return {(r["members"][swept], r["level"]): r for r in results["summary"]["coverage"]}


def welch(a: dict[str, Any], d: dict[str, Any]) -> list[float] | None:
    """95 percent interval of (detailed - abstract) / abstract mean (Welch, Satterthwaite df);
    the abstract mean is taken as exact, so this slightly understates the width."""
    if a["mean"] is None or d["mean"] is None or not a["mean"]:
        return None
    if a["sd"] is None or d["sd"] is None:
        return None
    va, vd = a["sd"] ** 2 / a["n"], d["sd"] ** 2 / d["n"]
    if va + vd == 0:
        return [(d["mean"] - a["mean"]) / a["mean"]] * 2
    df = (va + vd) ** 2 / (va**2 / (a["n"] - 1) + vd**2 / (d["n"] - 1))
    half = t975(max(1, math.floor(df))) * math.sqrt(va + vd)
    return [round((d["mean"] - a["mean"] + s * half) / a["mean"], 4) for s in (-1, 1)]


def cells(abstract: dict[str, Any], detailed: dict[str, Any], swept: str) -> list[dict[str, Any]]:
    """Per swarm size and coverage level: both levels' estimates and their relative difference."""
    a_rows, d_rows = rows_by_cell(abstract, swept), rows_by_cell(detailed, swept)
    out = []
    for key in sorted(a_rows, key=lambda k: (k[0], float(k[1].rstrip("%")))):
        a, d = a_rows[key], d_rows.get(key)
        if d is None:
            continue
        rel = None if a["mean"] in (None, 0) or d["mean"] is None else d["mean"] / a["mean"] - 1
        out.append({
            "members": key[0], "level": key[1],
            "abstract": {"mean": a["mean"], "ci95": a["ci95"], "n": a["n"], "sd": a["sd"]},
            "detailed": {"mean": d["mean"], "ci95": d["ci95"], "n": d["n"], "sd": d["sd"],
                         "missing": d["missing"]},
            "relative_difference": None if rel is None else round(rel, 4),
            "relative_difference_ci95": welch(a, d),
        })  # fmt: skip
    return out


def speed(detailed: dict[str, Any], swept: str) -> list[dict[str, Any]]:
    """Per swarm size: the detailed runs' real-time factor and wall seconds."""
    sizes = [c["members"].get(swept, 0) for c in detailed["configurations"]]
    out = []
    for index, size in enumerate(sizes):
        mine = [r for r in detailed["detailed"]["runs"] if r["config"] == index]
        rtf = [r["real_time_factor"] for r in mine if r.get("real_time_factor")]
        wall = [r["wall_s"] for r in mine]
        out.append({
            "members": size, "runs": len(mine),
            "failed": sum(1 for r in mine if r.get("failure")),
            "real_time_factor": None if not rtf else {
                "median": round(statistics.median(rtf), 1),
                "min": round(min(rtf), 1), "max": round(max(rtf), 1)},
            "wall_s_per_run": {"median": round(statistics.median(wall), 1),
                               "min": round(min(wall), 1), "max": round(max(wall), 1)},
            "wall_s_total": round(sum(wall), 1),
            "sim_s_median": statistics.median(r["sim_s"] or 0.0 for r in mine),
            "timeouts": sum(r.get("timeouts") or 0 for r in mine),
            # answers for another step: a sign of a loaded machine or of another run's
            # messages in the same ROS domain
            "stale": sum(r.get("stale") or 0 for r in mine),
        })  # fmt: skip
    return out


def figure(report: dict[str, Any], stem: Path) -> None:
    """Time to each coverage level against the swarm size at both levels (left), and the
    relative difference with its interval (right); PNG and SVG, reproducible (no dates)."""
    import matplotlib

    matplotlib.rcParams["svg.hashsalt"] = "swarmgen"
    matplotlib.rcParams["svg.fonttype"] = "none"
    from matplotlib.figure import Figure
    from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, NullLocator

    fig = Figure(figsize=(9.0, 3.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    levels = list(dict.fromkeys(c["level"] for c in report["cells"]))
    sizes = sorted({c["members"] for c in report["cells"]})
    for number, level in enumerate(levels):
        mine = [c for c in report["cells"] if c["level"] == level]
        colour = f"C{number}"
        for name, style in (("abstract", "o-"), ("detailed", "s--")):
            points = [(c["members"], c[name]) for c in mine if c[name]["mean"] is not None]
            left.errorbar(
                [x for x, _ in points], [e["mean"] for _, e in points],
                yerr=[_half(e) for _, e in points], fmt=style, color=colour,
                markersize=3, capsize=2, linewidth=1,
                label=f"{level}" if name == "abstract" else ("detailed" if number == 0 else None),
            )  # fmt: skip
        rels = [c for c in mine if c["relative_difference"] is not None]
        right.errorbar(
            [c["members"] * (1 + 0.04 * (number - 2)) for c in rels],
            [100 * c["relative_difference"] for c in rels],
            yerr=_rel_errors(rels), fmt="o", color=colour, markersize=3, capsize=2,
            label=level,
        )  # fmt: skip
    for ax in (left, right):
        ax.set_xscale("log", base=2)
        ax.xaxis.set_major_locator(FixedLocator(sizes))
        ax.xaxis.set_minor_locator(NullLocator())
        ax.set_xticklabels([str(s) for s in sizes])
        ax.set_xlabel(f"number of {report['swept']}s")
        ax.grid(True, linewidth=0.3)
    left.set_yscale("log")
    left.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    left.yaxis.set_minor_locator(NullLocator())
    left.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    left.set_ylabel(f"time to coverage (ticks of {report['tick_s']:.3g} s)")
    left.set_title("abstract (solid) and detailed (dashed)", fontsize=9)
    left.legend(fontsize=6, ncol=2)
    for edge in (-10, 10):
        right.axhline(edge, color="grey", linewidth=0.6, linestyle=":")
    right.axhline(0, color="black", linewidth=0.6)
    right.set_ylabel("(detailed - abstract) / abstract (%)")
    right.set_title("relative difference, 95% interval", fontsize=9)
    right.legend(title="coverage", fontsize=6, title_fontsize=6)
    fig.suptitle(report["scenario"], fontsize=10)
    for fmt, metadata in (("png", {"Software": "swarmgen"}),
                          ("svg", {"Date": None, "Creator": "swarmgen"})):  # fmt: skip
        fig.savefig(_file(stem, fmt), format=fmt, dpi=120, metadata=metadata)


def _file(stem: Path, ext: str) -> Path:
    """`stem.ext` (with_suffix would replace a scenario name's dots)."""
    return stem.parent / f"{stem.name}.{ext}"


def _half(estimate: dict[str, Any]) -> float:
    ci = estimate["ci95"]
    return 0.0 if not ci or ci[0] is None else (ci[1] - ci[0]) / 2


def _rel_errors(points: list[dict[str, Any]]) -> list[list[float]]:
    low, high = [], []
    for c in points:
        ci, rel = c["relative_difference_ci95"], c["relative_difference"]
        low.append(0.0 if ci is None else 100 * (rel - ci[0]))
        high.append(0.0 if ci is None else 100 * (ci[1] - rel))
    return [low, high]


def markdown(report: dict[str, Any]) -> str:
    """The comparison and speed tables of a report, as Markdown (for docs/simulate.md)."""

    def est(e: dict[str, Any]) -> str:
        if e["mean"] is None:
            return "-"
        ci = e["ci95"]
        interval = "" if not ci or ci[0] is None else f" [{ci[0]:,.0f}, {ci[1]:,.0f}]"
        return f"{e['mean']:,.0f}{interval}"

    def rel(c: dict[str, Any]) -> str:
        if c["relative_difference"] is None:
            return "-"
        ci = c["relative_difference_ci95"]
        interval = "" if ci is None else f" [{100 * ci[0]:+.1f}, {100 * ci[1]:+.1f}]"
        return f"{100 * c['relative_difference']:+.1f}%{interval}"

    swept = report["swept"]
    lines = [
        f"| {swept}s | coverage | abstract (ticks, 95% CI) | detailed (ticks, 95% CI) | "
        "detailed vs abstract [95% CI] | n (abstract / detailed) |",
        "|---|---|---|---|---|---|",
    ]
    for c in report["cells"]:
        lines.append(
            f"| {c['members']} | {c['level']} | {est(c['abstract'])} | {est(c['detailed'])} | "
            f"{rel(c)} | {c['abstract']['n']} / {c['detailed']['n']} |"
        )
    lines += ["", f"| {swept}s | detailed runs | real-time factor: median (min-max) | "
              "wall s per run: median | wall s, all runs | timeouts | stale |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for s in report["speed"]:
        rtf = s["real_time_factor"] or {"median": 0, "min": 0, "max": 0}
        lines.append(
            f"| {s['members']} | {s['runs']} ({s['failed']} failed) | {rtf['median']:g} "
            f"({rtf['min']:g}-{rtf['max']:g}) | {s['wall_s_per_run']['median']:g} | "
            f"{s['wall_s_total']:g} | {s['timeouts']} | {s.get('stale', 0)} |"
        )
    return "\n".join(lines)


def report_of(
    args: argparse.Namespace, runs: dict[str, dict[str, Any]], swept: str
) -> dict[str, Any]:
    """The comparison report (the JSON written to benchmarks/results/)."""
    abstract, detailed = runs["abstract"]["results"], runs["detailed"]["results"]
    params = detailed.get("detailed", {}).get("params", {})
    return {
        "scenario": detailed["scenario"]["name"],
        "model": str(Path(args.model).resolve().relative_to(ROOT))
        if Path(args.model).resolve().is_relative_to(ROOT) else str(args.model),
        "swept": swept, "reps": args.reps, "seed": args.seed, "workers": args.workers,
        "tick_s": params.get("tick_s", 0.5), "detailed_params": params,
        "cells": cells(abstract, detailed, swept),
        "speed": speed(detailed, swept),
        "processes": {level: {k: v for k, v in run.items() if k != "results"}
                      for level, run in runs.items()},
    }  # fmt: skip


def main() -> None:
    """Run (or reuse) both levels, write the JSON and figures, print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", default=str(MODEL))
    parser.add_argument("--scenario", default="paper-coverage", help="shipped name or file")
    parser.add_argument("--reps", type=int, default=10)
    parser.add_argument("--members", default="UAV=1,2,4,8", help="TYPE=N[,N...]: the sweep")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--workers", type=int, default=1, help="concurrent detailed runs")
    parser.add_argument("--out", type=Path, default=RESULTS)
    parser.add_argument("--reuse", action="store_true", help="reuse a level's matching results")
    parser.add_argument("--markdown", action="store_true", help="print the last report's tables")
    args = parser.parse_args()
    name = Path(args.scenario).stem
    stem = args.out / ("compare_levels" if name == "paper-coverage" else f"compare_levels.{name}")
    if args.markdown:
        print(markdown(json.loads(_file(stem, "json").read_text(encoding="utf-8"))))
        return
    swept = args.members.split("=", 1)[0]
    load = [round(x, 2) for x in os.getloadavg()]
    runs = {level: level_results(level, args, args.out / "compare_levels.runs" / name / level,
                                 swept) for level in LEVELS}  # fmt: skip
    report = report_of(args, runs, swept)
    report["machine"] = {"cpus": os.cpu_count(), "python": platform.python_version(),
                         "load_average_at_start": load,
                         "load_average_at_end": [round(x, 2) for x in os.getloadavg()]}  # fmt: skip
    stem.parent.mkdir(parents=True, exist_ok=True)
    _file(stem, "json").write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    figure(report, stem)
    print(markdown(report))


if __name__ == "__main__":
    main()
