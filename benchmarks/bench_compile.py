"""Compile-time benchmarks: wall time and peak memory of the real command, interpreter start included.

    .venv/bin/python benchmarks/bench_compile.py        (or: make bench)

1. `swarmgen compile sample_models/sar/sar.xmi -o <tmp>`: 15 runs (after one warm-up run that is
   not counted), median and p90.
2. Synthetic models (benchmarks/synth_model.py) of 1,000 and 10,000 states: `swarmgen validate` and
   `swarmgen compile` (which validates too, then renders and writes), 3 runs each, medians; peak
   resident memory of each command; the ratio time(10k) / time(1k) of `compile`.

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
TARGETS = {
    "sar_median_s": 0.5,  # SAR compile, median
    "large_s": 5.0,  # 10,000 states: compile (validate + render + write), median
    "large_peak_mb": 500.0,
    "ratio": 12.0,  # compile time(10k) / time(1k)
}

sys.path.insert(0, str(HERE))
import synth_model  # noqa: E402  (a sibling script, not a package)


@dataclass(frozen=True)
class Sample:
    seconds: float
    peak_mb: float | None


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
    peak_mb = None
    if gnu_time:
        found = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
        peak_mb = int(found.group(1)) / 1024 if found else None
    else:  # ru_maxrss is in KiB on Linux: the largest child so far
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return Sample(seconds, peak_mb)


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
    return {
        "median_s": statistics.median(times),
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
    parser.add_argument(
        "--sizes", type=int, nargs=2, default=[1000, 10000], metavar=("SMALL", "LARGE")
    )
    parser.add_argument("-o", "--output", type=Path, default=RESULTS)
    args = parser.parse_args(argv)
    small, large = args.sizes

    with tempfile.TemporaryDirectory(prefix="swarmgen-bench.") as tmp:
        work = Path(tmp)
        compile_variants = variants(work)
        floor = startup(work, 5)
        sar = {name: bench_sar(work, args.sar_runs, o) for name, o in compile_variants.items()}
        synthetic = {
            str(n): bench_synthetic(work, n, args.runs, compile_variants) for n in (small, large)
        }

    verdicts: dict[str, Any] = {}
    for name in compile_variants:
        t_small = synthetic[str(small)][f"compile_{name}"]["median_s"]
        t_large = synthetic[str(large)][f"compile_{name}"]["median_s"]
        large_peak = synthetic[str(large)][f"compile_{name}"]["peak_mb"]
        verdicts[name] = {
            "ratio": t_large / t_small,
            "ratio_without_startup": (t_large - floor) / (t_small - floor)
            if t_small > floor
            else None,
            "met": {
                "sar_median_s": sar[name]["median_s"] < TARGETS["sar_median_s"],
                "large_s": t_large < TARGETS["large_s"],
                "large_peak_mb": large_peak is not None and large_peak < TARGETS["large_peak_mb"],
                "ratio": t_large / t_small <= TARGETS["ratio"],
            },
        }
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
        "sizes": {"small": small, "large": large},
        "targets": TARGETS,
        "verdicts": verdicts,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    print(table(results))
    print(f"\nwritten to {args.output}")
    met = [ok for v in verdicts.values() for ok in v["met"].values()]
    return 0 if all(met) else 1


def _s(value: float | None, unit: str = "s") -> str:
    return "n/a" if value is None else f"{value:.3f} {unit}"


def table(r: dict[str, Any]) -> str:
    small, large = r["sizes"]["small"], r["sizes"]["large"]
    sar, syn, verdicts = r["sar_compile"], r["synthetic"], r["verdicts"]
    rows = [
        ("measure", "value", "target"),
        ("startup (swarmgen --version), median", _s(r["startup_median_s"]), ""),
    ]
    for n in (small, large):
        v = syn[str(n)]["validate"]
        rows.append((f"{n} states: validate, median", _s(v["median_s"]), ""))
        rows.append((f"{n} states: validate, peak RSS", _s(v["peak_mb"], "MB"), ""))
    for name, options in r["compile_variants"].items():
        label = "compile " + " ".join(options) if options else "compile (all backends)"
        met = verdicts[name]["met"]

        def target(key: str, text: str, met: dict[str, bool] = met) -> str:
            return f"{text} {'ok' if met[key] else 'MISSED'}"

        s = sar[name]
        rows += [
            (
                f"SAR {label}, median of {s['runs']}",
                _s(s["median_s"]),
                target("sar_median_s", "< 0.5 s"),
            ),
            (f"SAR {label}, p90", _s(s["p90_s"]), ""),
            (f"SAR {label}, peak RSS", _s(s["peak_mb"], "MB"), ""),
        ]
        for n in (small, large):
            c = syn[str(n)][f"compile_{name}"]
            is_large = n == large
            rows += [
                (
                    f"{n} states ({syn[str(n)]['model_mib']} MiB): {label}, median",
                    _s(c["median_s"]),
                    target("large_s", "< 5 s") if is_large else "",
                ),
                (
                    f"{n} states: {label}, peak RSS",
                    _s(c["peak_mb"], "MB"),
                    target("large_peak_mb", "< 500 MB") if is_large else "",
                ),
            ]
        ratio_net = verdicts[name]["ratio_without_startup"]
        rows += [
            (
                f"{label}: time({large}) / time({small})",
                f"{verdicts[name]['ratio']:.2f}",
                target("ratio", "<= 12"),
            ),
            (
                "  the same without the startup floor",
                "n/a" if ratio_net is None else f"{ratio_net:.2f}",
                "",
            ),
        ]
    widths = [max(len(row[i]) for row in rows) for i in range(3)]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(line.rstrip() for line in lines)


if __name__ == "__main__":
    sys.exit(main())
