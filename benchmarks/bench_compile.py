"""Compile-time benchmarks: wall time and peak memory of the real command, interpreter start included.

    .venv/bin/python benchmarks/bench_compile.py        (or: make bench)

1. `swarmgen compile sample_models/sar/sar.xmi -o <tmp>`: 15 runs (after one warm-up run that is
   not counted), median and p90.
2. Synthetic models (benchmarks/synth_model.py) of 1,000, 3,000 and 10,000 states (`--sizes`, e.g.
   `--sizes 1000 3000 10000 30000`): `swarmgen validate` and `swarmgen compile` (which validates
   too, then renders and writes), 3 runs each, medians; peak resident memory of each command; the
   growth from each size to the next (time ratio over size ratio: 1.0 is linear), and every
   backend over SCXML only at each size. benchmarks/results/compile.png and .svg plot time against
   states for both.

`compile` is measured as a user runs it (SCXML and every backend) and, when the CLI has
`--backend`, also as `compile --backend scxml` (the compiler core: validate, lower, SCXML). The
targets are checked for both. swarmgen keeps no cache between processes, so every run does the
whole work.
Every command runs as a subprocess; peak memory comes from
`/usr/bin/time -v` ("Maximum resident set size") when it exists, else from
getrusage(RUSAGE_CHILDREN) (a maximum over all children so far: only an upper bound). Prints a
table and writes benchmarks/results/compile.json.
"""

from __future__ import annotations

import argparse
import itertools
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
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
RESULTS = HERE / "results" / "compile.json"
GNU_TIME = Path("/usr/bin/time")
ENV = dict(os.environ)
FIGURE = HERE / "results" / "compile"
TARGETS = {
    "sar_median_s": 0.3,  # SAR compile, median, process start included
    "large_s": 5.0,  # 10,000 states (or the largest size below it): compile, median
    "large_peak_mb": 500.0,
    "growth": 1.2,  # per step between sizes: (time ratio) / (size ratio), startup floor removed
    "all_over_scxml": 2.0,  # every backend over SCXML only, at every size
}

sys.path.insert(0, str(HERE))
import synth_model  # noqa: E402  (a sibling script, not a package)


@dataclass(frozen=True)
class Sample:
    seconds: float
    peak_mb: float | None
    cpu_s: float | None = None  # user + system of the command: what others' load adds least to


def swarmgen() -> list[str]:
    """The `swarmgen` console script beside this interpreter, else `python -m swarmgen`."""
    script = Path(sys.executable).parent / "swarmgen"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "swarmgen"]


def run(args: list[str], cwd: Path) -> Sample:
    """One command, timed from fork to exit; fails loudly if swarmgen does."""
    command = [*swarmgen(), *args]
    gnu_time = GNU_TIME.is_file() and os.access(GNU_TIME, os.X_OK)
    if gnu_time:
        command = [str(GNU_TIME), "-v", *command]
    start = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, env=ENV, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"benchmark command failed ({done.returncode}): {' '.join(args)}\n{done.stderr}")
    peak_mb = cpu_s = None
    if gnu_time:
        found = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
        peak_mb = int(found.group(1)) / 1024 if found else None
        used = re.findall(r"(?:User|System) time \(seconds\): ([0-9.]+)", done.stderr)
        cpu_s = sum(float(u) for u in used) if len(used) == 2 else None
    else:  # ru_maxrss is in KiB on Linux: the largest child so far
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return Sample(seconds, peak_mb, cpu_s)


def variants(work: Path) -> dict[str, list[str]]:
    """How `compile` is run: as is, and SCXML only when the CLI can be told so."""
    found: dict[str, list[str]] = {"all": []}
    helptext = subprocess.run(
        [*swarmgen(), "compile", "--help"], cwd=work, capture_output=True, text=True, check=False
    ).stdout
    if "--backend" in helptext:
        found["scxml"] = ["--backend", "scxml"]
    return found


def compile_into_fresh_dir(model: Path, work: Path, options: list[str]) -> Sample:
    out = Path(tempfile.mkdtemp(prefix="out.", dir=work)) / "out"
    sample = run(["compile", str(model), "-o", str(out), *options], cwd=work)
    shutil.rmtree(out.parent)
    return sample


def summary(samples: list[Sample]) -> dict[str, Any]:
    times = [s.seconds for s in samples]
    values = [s.peak_mb for s in samples if s.peak_mb is not None]
    cpu = [s.cpu_s for s in samples if s.cpu_s is not None]
    return {
        "median_s": statistics.median(times),
        "cpu_median_s": statistics.median(cpu) if cpu else None,
        "p90_s": statistics.quantiles(times, n=10, method="inclusive")[8]
        if len(times) > 1
        else times[0],
        "peak_mb": max(values) if values else None,
        "samples_s": [round(t, 4) for t in times],
    }


def bench_sar(work: Path, runs: int, options: list[str]) -> dict[str, Any]:
    compile_into_fresh_dir(SAR, work, options)  # warm-up: .pyc files and the page cache
    return {
        "runs": runs,
        **summary([compile_into_fresh_dir(SAR, work, options) for _ in range(runs)]),
    }


def bench_synthetic(
    work: Path, states: int, runs: int, compile_variants: dict[str, list[str]]
) -> dict[str, Any]:
    model = work / f"synth_{states}.xmi"
    text = synth_model.generate(states)
    model.write_text(text, encoding="utf-8")
    run(["validate", str(model)], cwd=work)  # warm-up
    result: dict[str, Any] = {
        "states": states,
        "model_mib": round(len(text.encode("utf-8")) / 2**20, 2),
        "runs": runs,
        "validate": summary([run(["validate", str(model)], cwd=work) for _ in range(runs)]),
    }
    for name, options in compile_variants.items():
        samples = [compile_into_fresh_dir(model, work, options) for _ in range(runs)]
        result[f"compile_{name}"] = summary(samples)
    return result


def startup(work: Path, runs: int) -> float:
    """`swarmgen --version`: interpreter start and imports, the floor of every command."""
    return statistics.median(run(["--version"], cwd=work).seconds for _ in range(runs))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sar-runs", type=int, default=15)
    parser.add_argument("--runs", type=int, default=3, help="runs per synthetic model")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 3000, 10000])
    parser.add_argument("-o", "--output", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    sizes = sorted(set(args.sizes))
    small = sizes[0]
    large = max([n for n in sizes if n <= 10000] or [sizes[-1]])

    with tempfile.TemporaryDirectory(prefix="swarmgen-bench.") as tmp:
        work = Path(tmp)
        compile_variants = variants(work)
        floor = startup(work, 5)
        sar = {name: bench_sar(work, args.sar_runs, o) for name, o in compile_variants.items()}
        synthetic = {str(n): bench_synthetic(work, n, args.runs, compile_variants) for n in sizes}

    verdicts = {
        name: verdict(name, sar[name], synthetic, sizes, large, floor) for name in compile_variants
    }
    if "scxml" in compile_variants:
        over = {
            str(n): synthetic[str(n)]["compile_all"]["median_s"]
            / synthetic[str(n)]["compile_scxml"]["median_s"]
            for n in sizes
        }
        verdicts["all"]["all_over_scxml"] = over
        cpu = {n: [synthetic[str(n)][f"compile_{v}"]["cpu_median_s"] for v in ("all", "scxml")]
               for n in sizes}  # fmt: skip
        verdicts["all"]["all_over_scxml_cpu"] = {
            str(n): a / b for n, (a, b) in cpu.items() if a is not None and b
        }
        verdicts["all"]["met"]["all_over_scxml"] = all(
            r <= TARGETS["all_over_scxml"] for r in over.values()
        )
    results: dict[str, Any] = {
        "when": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": {
            "python": platform.python_version(),
            "platform": platform.platform(),
            "cpus": os.cpu_count(),
            "load_average_at_end": [round(x, 2) for x in os.getloadavg()],
            "peak_memory_from": "/usr/bin/time -v" if GNU_TIME.is_file() else "getrusage",
        },
        "compile_variants": compile_variants,
        "startup_median_s": floor,
        "sar_compile": sar,
        "synthetic": synthetic,
        "sizes": {"small": small, "large": large, "all": sizes},
        "targets": TARGETS,
        "verdicts": verdicts,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    print(table(results))
    print(f"\nwritten to {args.output}")
    if len(sizes) > 1:
        figure(results, FIGURE if args.output == RESULTS else args.output.with_suffix(""))
    met = [ok for v in verdicts.values() for ok in v["met"].values()]
    return 0 if all(met) else 1


def verdict(
    name: str,
    sar: dict[str, Any],
    synthetic: dict[str, Any],
    sizes: list[int],
    large: int,
    floor: float,
) -> dict[str, Any]:
    """The targets of one compile variant: SAR, the large model, growth between sizes."""
    times = {n: synthetic[str(n)][f"compile_{name}"]["median_s"] for n in sizes}
    large_peak = synthetic[str(large)][f"compile_{name}"]["peak_mb"]
    growth = {}
    for a, b in itertools.pairwise(sizes):
        net = (times[b] - floor) / (times[a] - floor) if times[a] > floor else None
        growth[f"{a}->{b}"] = {
            "time_ratio": times[b] / times[a],
            "size_ratio": b / a,
            "over_linear": times[b] / times[a] / (b / a),
            "over_linear_without_startup": None if net is None else net / (b / a),
        }
    return {
        "growth": growth,
        "met": {
            "sar_median_s": sar["median_s"] < TARGETS["sar_median_s"],
            "large_s": times[large] < TARGETS["large_s"],
            "large_peak_mb": large_peak is not None and large_peak < TARGETS["large_peak_mb"],
            "growth": all(
                (g["over_linear_without_startup"] or g["over_linear"]) <= TARGETS["growth"]
                for g in growth.values()
            ),
        },
    }


def figure(r: dict[str, Any], stem: Path) -> None:
    """Compile time (median) against states for every variant, log-log with a linear guide
    through the first point of each; PNG and SVG, reproducible (no dates)."""
    import matplotlib

    matplotlib.rcParams["svg.hashsalt"] = "swarmgen"
    matplotlib.rcParams["svg.fonttype"] = "none"
    from matplotlib.figure import Figure
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    fig = Figure(figsize=(5.5, 3.8), layout="constrained")
    ax = fig.subplots()
    sizes = r["sizes"]["all"]
    for number, (name, options) in enumerate(r["compile_variants"].items()):
        times = [r["synthetic"][str(n)][f"compile_{name}"]["median_s"] for n in sizes]
        label = "compile " + " ".join(options) if options else "compile (every backend)"
        ax.plot(sizes, times, "o-", color=f"C{number}", label=label, markersize=4)
        ax.plot(
            sizes, [times[0] * n / sizes[0] for n in sizes], ":", color=f"C{number}", linewidth=0.8
        )
        cpu = [r["synthetic"][str(n)][f"compile_{name}"].get("cpu_median_s") for n in sizes]
        if all(c is not None for c in cpu):
            ax.plot(sizes, cpu, "x--", color=f"C{number}", label=f"{label}, CPU", markersize=4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.xaxis.set_major_locator(FixedLocator(sizes))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}"))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xlabel("states (synthetic model)")
    ax.set_ylabel("wall / CPU time, median (s)")
    ax.set_title("compile time against model size (dotted: linear)", fontsize=9)
    ax.grid(True, linewidth=0.3)
    ax.legend(fontsize=7)
    for fmt, metadata in (("png", {"Software": "swarmgen"}),
                          ("svg", {"Date": None, "Creator": "swarmgen"})):  # fmt: skip
        fig.savefig(stem.parent / f"{stem.name}.{fmt}", format=fmt, dpi=120, metadata=metadata)


def _s(value: float | None, unit: str = "s") -> str:
    return "n/a" if value is None else f"{value:.3f} {unit}"


def table(r: dict[str, Any]) -> str:
    """The results as a text table, one row per measure, with the targets met or missed."""
    sizes, large = r["sizes"]["all"], r["sizes"]["large"]
    syn, verdicts = r["synthetic"], r["verdicts"]
    rows = [
        ("measure", "value", "target"),
        ("startup (swarmgen --version), median", _s(r["startup_median_s"]), ""),
    ]
    for n in sizes:
        v = syn[str(n)]["validate"]
        rows.append((f"{n} states: validate, median", _s(v["median_s"]), ""))
        rows.append((f"{n} states: validate, CPU median", _s(v.get("cpu_median_s")), ""))
    for name, options in r["compile_variants"].items():
        label = "compile " + " ".join(options) if options else "compile (all backends)"
        rows += _variant_rows(r, name, label, sizes, large)
    over = verdicts["all"].get("all_over_scxml", {})
    for n, ratio in over.items():
        # this size's own verdict (the JSON's `met` keeps the one over every size)
        met = ratio <= TARGETS["all_over_scxml"]
        rows.append((f"{n} states: every backend / SCXML only", f"{ratio:.2f}", "<= 2 " + _ok(met)))
    widths = [max(len(row[i]) for row in rows) for i in range(3)]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(line.rstrip() for line in lines)


def _ok(met: bool) -> str:
    return "ok" if met else "MISSED"


def _variant_rows(
    r: dict[str, Any], name: str, label: str, sizes: list[int], large: int
) -> list[tuple[str, str, str]]:
    met = r["verdicts"][name]["met"]
    s = r["sar_compile"][name]
    rows = [
        (f"SAR {label}, median of {s['runs']}", _s(s["median_s"]), "< 0.3 s " + _ok(met["sar_median_s"])),
        (f"SAR {label}, p90", _s(s["p90_s"]), ""),
        (f"SAR {label}, peak RSS", _s(s["peak_mb"], "MB"), ""),
    ]  # fmt: skip
    for n in sizes:
        c = r["synthetic"][str(n)][f"compile_{name}"]
        is_large = n == large
        rows += [
            (
                f"{n} states ({r['synthetic'][str(n)]['model_mib']} MiB): {label}, median",
                _s(c["median_s"]),
                "< 5 s " + _ok(met["large_s"]) if is_large else "",
            ),
            (f"{n} states: {label}, CPU (user + system), median", _s(c.get("cpu_median_s")), ""),
            (
                f"{n} states: {label}, peak RSS",
                _s(c["peak_mb"], "MB"),
                "< 500 MB " + _ok(met["large_peak_mb"]) if is_large else "",
            ),
        ]
    for step, g in r["verdicts"][name]["growth"].items():
        net = g["over_linear_without_startup"]
        rows.append(
            (
                f"{label}: growth {step} over linear (without startup)",
                f"{g['over_linear']:.2f} ({'n/a' if net is None else f'{net:.2f}'})",
                "<= 1.2 " + _ok(met["growth"]),
            )
        )
    return rows


if __name__ == "__main__":
    sys.exit(main())
