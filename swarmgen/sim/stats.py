"""Results as the paper reports them: coverage times to p percent per swarm size, SAR search and
rescue times of the first, 50, 75, 90 and 100 percent of the targets, as means with 95 percent
confidence intervals (Student's t), and the CSV tables. Standard library only.
"""

from __future__ import annotations

import csv
import io
import math
import statistics
from collections.abc import Sequence
from dataclasses import field
from typing import Any

from swarmgen.records import dataclass

# Student's t quantile t(0.975, df) for df = 1..30 (two-sided 95 percent).
_T975 = (
    12.706204736, 4.302652730, 3.182446305, 2.776445105, 2.570581836, 2.446911851,
    2.364624252, 2.306004135, 2.262157163, 2.228138852, 2.200985160, 2.178812830,
    2.160368656, 2.144786688, 2.131449546, 2.119905299, 2.109815578, 2.100922040,
    2.093024054, 2.085963447, 2.079613845, 2.073873068, 2.068657610, 2.063898562,
    2.059538553, 2.055529439, 2.051830516, 2.048407142, 2.045229642, 2.042272456,
)  # fmt: skip
_Z975 = 1.959963984540054


def t975(df: int) -> float:
    """The 0.975 quantile of Student's t with `df` degrees of freedom: a table up to 30, then
    the Cornish-Fisher expansion around the normal quantile (error below 1e-6 from df 31)."""
    if df < 1:
        raise ValueError("t975 needs df >= 1")
    if df <= len(_T975):
        return _T975[df - 1]
    z = _Z975
    g1 = (z**3 + z) / 4
    g2 = (5 * z**5 + 16 * z**3 + 3 * z) / 96
    g3 = (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / 384
    g4 = (79 * z**9 + 776 * z**7 + 1482 * z**5 - 1920 * z**3 - 945 * z) / 92160
    return z + g1 / df + g2 / df**2 + g3 / df**3 + g4 / df**4


@dataclass(frozen=True)
class Estimate:
    """Mean, standard deviation and 95 percent confidence half-width over the runs that got there."""

    n: int  # runs that reached it
    missing: int  # runs that did not (within max_ticks)
    mean: float | None
    sd: float | None
    half: float | None  # half-width of the 95 percent confidence interval

    @property
    def low(self) -> float | None:
        """The confidence interval's lower end."""
        return None if self.mean is None or self.half is None else self.mean - self.half

    @property
    def high(self) -> float | None:
        """The confidence interval's upper end."""
        return None if self.mean is None or self.half is None else self.mean + self.half


def estimate(values: Sequence[float | None]) -> Estimate:
    """Mean and 95 percent confidence interval of the values that are not None."""
    seen = [float(v) for v in values if v is not None]
    missing = len(values) - len(seen)
    if not seen:
        return Estimate(0, missing, None, None, None)
    mean = statistics.fmean(seen)
    if len(seen) == 1:
        return Estimate(1, missing, mean, None, None)
    sd = statistics.stdev(seen)
    return Estimate(len(seen), missing, mean, sd, t975(len(seen) - 1) * sd / math.sqrt(len(seen)))


def kth(values: Sequence[int | None], share: float, count: int) -> int | None:
    """The time by which `share` of `count` items happened (share 0: the first), or None."""
    times = sorted(v for v in values if v is not None)
    need = max(1, math.ceil(share * count - 1e-9))
    return times[need - 1] if len(times) >= need else None


def level_name(share: float, kind: str) -> str:
    """A level as reports show it: `50%`, or `first` for the first target."""
    if kind == "targets" and share == 0:
        return "first"
    return f"{share * 100:g}%"


@dataclass(frozen=True)
class Row:
    """One estimate of one configuration at one level."""

    counts: tuple[tuple[str, int], ...]
    targets: int
    level: float
    estimate: Estimate
    params: tuple[tuple[str, Any], ...] = ()  # the configuration's swept parameters


@dataclass(frozen=True)
class Summary:
    """Every estimate of a simulation: coverage, search and rescue rows."""

    coverage: list[Row]
    search: list[Row]
    rescue: list[Row]
    types: list[str]
    swept: str | None  # the member type whose count is swept (the x axis), if any
    params: list[str] = field(default_factory=list)  # swept parameters: columns, plot facets


def summarise(sim: Any) -> Summary:
    """Per configuration and level: coverage, search and rescue estimates over repetitions."""
    scenario = sim.scenario
    by_config: dict[int, list[Any]] = {}
    for run in sim.runs:
        by_config.setdefault(run.config, []).append(run)
    coverage, search, rescue = [], [], []
    for index, config in enumerate(sim.configs):
        runs = by_config.get(index, [])

        def row(level: float, value: Estimate, config: Any = config) -> Row:
            return Row(config.counts, config.targets, level, value, config.params)

        for number, level in enumerate(scenario.coverage_levels):
            values = [r.coverage[number] for r in runs]
            coverage.append(row(level, estimate(values)))
        if config.targets:
            for level in scenario.target_levels:
                found = [kth(r.found, level, config.targets) for r in runs]
                saved = [kth(r.rescued, level, config.targets) for r in runs]
                search.append(row(level, estimate(found)))
                rescue.append(row(level, estimate(saved)))
    types = [kind for kind, _ in sim.configs[0].counts] if sim.configs else []
    swept = next(
        (k for k in types if len({dict(c.counts)[k] for c in sim.configs}) > 1),
        next((k for k in types if any(dict(c.counts)[k] for c in sim.configs)), None),
    )
    return Summary(coverage, search, rescue, types, swept, param_names(sim.configs))


def param_names(configs: Sequence[Any]) -> list[str]:
    """The swept parameters of the configurations, in the order the sweep names them."""
    names: dict[str, None] = {}
    for config in configs:
        names.update((k, None) for k, _ in config.params)
    return list(names)


def _cell(value: Any) -> Any:
    """A parameter's value in a table: JSON's spelling for booleans (`true`), else as is."""
    return ("true" if value else "false") if isinstance(value, bool) else value


def _number(value: float | None, digits: int = 3) -> str:
    return "" if value is None else f"{value:.{digits}f}"


def table(rows: list[Row], types: list[str], kind: str, params: Sequence[str] = ()) -> str:
    """CSV: member counts, targets, swept parameters, level, runs reaching it, mean, sd, 95
    percent CI."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(
        [
            *types,
            "targets",
            *params,
            "level",
            "n",
            "missing",
            "mean",
            "sd",
            "ci95_half",
            "ci95_low",
            "ci95_high",
        ]
    )
    for row in rows:
        e = row.estimate
        writer.writerow(
            [
                *(dict(row.counts).get(k, 0) for k in types),
                row.targets,
                *(_cell(dict(row.params).get(k, "")) for k in params),
                level_name(row.level, kind),
                e.n,
                e.missing,
                _number(e.mean),
                _number(e.sd),
                _number(e.half),
                _number(e.low),
                _number(e.high),
            ]
        )
    return out.getvalue()


def runs_table(sim: Any) -> str:
    """CSV: one line per run with its raw times."""
    scenario = sim.scenario
    types = [kind for kind, _ in sim.configs[0].counts] if sim.configs else []
    params = param_names(sim.configs)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    cov = [f"coverage_{level_name(v, 'coverage')}" for v in scenario.coverage_levels]
    search = [f"search_{level_name(v, 'targets')}" for v in scenario.target_levels]
    rescue = [f"rescue_{level_name(v, 'targets')}" for v in scenario.target_levels]
    writer.writerow(
        [
            *types,
            "targets",
            *params,
            "rep",
            "reason",
            "end_tick",
            "events",
            "coverage_final",
            *cov,
            *search,
            *rescue,
        ]
    )
    for run in sim.runs:
        config = sim.configs[run.config]
        counts = dict(config.counts)
        writer.writerow(
            [
                *(counts[k] for k in types),
                config.targets,
                *(_cell(dict(config.params).get(k, "")) for k in params),
                run.rep,
                run.reason,
                run.end_tick,
                run.events,
                f"{run.coverage_final:.6f}",
                *("" if v is None else v for v in run.coverage),
                *(
                    _blank(kth(run.found, v, config.targets)) if config.targets else ""
                    for v in scenario.target_levels
                ),
                *(
                    _blank(kth(run.rescued, v, config.targets)) if config.targets else ""
                    for v in scenario.target_levels
                ),
            ]
        )
    return out.getvalue()


def _blank(value: int | None) -> str | int:
    return "" if value is None else value


def to_json(summary: Summary) -> dict[str, Any]:
    """The summary as JSON-ready data (levels named, confidence intervals as pairs)."""

    def rows(items: list[Row], kind: str) -> list[dict[str, Any]]:
        return [
            {
                "members": dict(r.counts),
                "targets": r.targets,
                **({"params": dict(r.params)} if r.params else {}),
                "level": level_name(r.level, kind),
                "n": r.estimate.n,
                "missing": r.estimate.missing,
                "mean": r.estimate.mean,
                "sd": r.estimate.sd,
                "ci95": [r.estimate.low, r.estimate.high],
            }
            for r in items
        ]

    return {
        "swept": summary.swept,
        "coverage": rows(summary.coverage, "coverage"),
        "search": rows(summary.search, "targets"),
        "rescue": rows(summary.rescue, "targets"),
    }
