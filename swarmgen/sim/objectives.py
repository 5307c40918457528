"""Optimisation objectives: `minimize mean(rescue_100%)`, parsed without eval and computed over
the runs of one trial.

    objective := ["minimize" | "maximize"] expr          (default: minimize)
    expr      := term (("+" | "-") term)*
    term      := factor (("*" | "/") factor)*
    factor    := NUMBER | "-" factor | "(" expr ")" | FUNC "(" METRIC ")"
    FUNC      := mean | median | min | max | sd | count | pNN (p50, p90, p99, ...)

A metric is a column of `runs.csv` (`coverage_50%`, `coverage_96.875%`, `search_first`,
`rescue_100%`, `end_tick`, `events`, `coverage_final`), `members` (the run's total member
count) or `targets`. A time the run did not reach (within `max_ticks`, or a run that stalled)
counts as `max_ticks` (the horizon: a censored time is at least that bad), except in
`count(...)`, the number of runs that reached it.
"""

from __future__ import annotations

import math
import re
import statistics
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, cast

from swarmgen.console import shown
from swarmgen.errors import SwarmgenError
from swarmgen.records import dataclass
from swarmgen.sim.stats import kth, level_name

if TYPE_CHECKING:
    from swarmgen.sim.batch import Config, RunResult
    from swarmgen.sim.scenario import Scenario

_TOKEN = re.compile(r"\s*(?:(\d+(?:\.\d*)?(?:[eE][+-]?\d+)?)|([A-Za-z_][\w.%]*)|(.))")
_FUNCS = {"mean", "median", "min", "max", "sd", "count"}
_PERCENTILE = re.compile(r"p(\d{1,2}(?:\.\d+)?)")
MAX_TEXT = 500  # characters of one objective


class ObjectiveError(SwarmgenError):
    """An objective that cannot be parsed or names an unknown metric (exit 2)."""


@dataclass(frozen=True)
class Node:
    """One node of an objective's tree: a number, an aggregate of a metric, or an operation."""

    op: str  # "num", "agg", "+", "-", "*", "/", "neg"
    value: float = 0.0
    func: str = ""
    metric: str = ""
    args: tuple[Node, ...] = ()


@dataclass(frozen=True)
class Objective:
    """A parsed objective: its direction, its tree and its text (the column name of reports)."""

    direction: str  # "minimize" or "maximize"
    tree: Node
    text: str

    def metrics(self) -> set[str]:
        """Every metric the objective reads."""
        found: set[str] = set()
        stack = [self.tree]
        while stack:
            node = stack.pop()
            if node.op == "agg":
                found.add(node.metric)
            stack += node.args
        return found


class _Parser:
    """Recursive descent over the tokens of one objective."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.tokens: list[tuple[str, str]] = []
        for match in _TOKEN.finditer(text):
            number, word, other = match.groups()
            if number is not None:
                self.tokens.append(("num", number))
            elif word is not None:
                self.tokens.append(("word", word))
            elif other is not None and not other.isspace():
                self.tokens.append(("op", other))
        self.at = 0

    def fail(self, what: str) -> ObjectiveError:
        return ObjectiveError(f"--objective {shown(self.text)!r}: {what}")

    def peek(self) -> tuple[str, str] | None:
        return self.tokens[self.at] if self.at < len(self.tokens) else None

    def take(self, op: str) -> bool:
        if self.peek() == ("op", op):
            self.at += 1
            return True
        return False

    def expr(self) -> Node:
        node = self.term()
        while (token := self.peek()) in (("op", "+"), ("op", "-")):
            self.at += 1
            node = Node(token[1], args=(node, self.term()))
        return node

    def term(self) -> Node:
        node = self.factor()
        while (token := self.peek()) in (("op", "*"), ("op", "/")):
            self.at += 1
            node = Node(token[1], args=(node, self.factor()))
        return node

    def factor(self) -> Node:
        token = self.peek()
        if token is None:
            raise self.fail("ends too early")
        self.at += 1
        kind, text = token
        if kind == "num":
            return Node("num", value=float(text))
        if token == ("op", "-"):
            return Node("neg", args=(self.factor(),))
        if token == ("op", "("):
            node = self.expr()
            if not self.take(")"):
                raise self.fail("a `(` is not closed")
            return node
        if kind == "word":
            return self.aggregate(text)
        raise self.fail(f"unexpected {text!r}")

    def aggregate(self, func: str) -> Node:
        if func not in _FUNCS and not _PERCENTILE.fullmatch(func):
            raise self.fail(
                f"unknown function {shown(func)!r} (mean, median, min, max, sd, count, pNN)"
            )
        token = self.peek() if self.take("(") else None
        if token is None or token[0] != "word":
            raise self.fail(f"write {func}(METRIC), e.g. {func}(rescue_100%)")
        self.at += 1
        if not self.take(")"):
            raise self.fail(f"write {func}(METRIC): one metric, then `)`")
        return Node("agg", func=func, metric=token[1])


def parse(text: str) -> Objective:
    """An objective from its text; ObjectiveError for bad syntax (metrics are checked later,
    against the scenario: `check`)."""
    if len(text) > MAX_TEXT:
        raise ObjectiveError(f"--objective: longer than {MAX_TEXT} characters")
    body = text.strip()
    direction = "minimize"
    for word in ("minimize", "maximize", "minimise", "maximise"):
        if body.lower().startswith(word + " ") or body.lower().startswith(word + "("):
            direction = "minimize" if word.startswith("mini") else "maximize"
            body = body[len(word) :]
            break
    parser = _Parser(text)
    parser.tokens = _Parser(body).tokens
    if not parser.tokens:
        raise parser.fail("empty: write e.g. 'minimize mean(coverage_100%)'")
    tree = parser.expr()
    if parser.peek() is not None:
        raise parser.fail(f"unexpected {parser.peek()[1]!r}")  # type: ignore[index]
    return Objective(direction, tree, " ".join(text.split()))


def metric_names(scenario: Scenario) -> list[str]:
    """The metrics a scenario's runs have (the columns of runs.csv, `members`, `targets`)."""
    names = ["end_tick", "events", "coverage_final", "members", "targets"]
    names += [f"coverage_{level_name(v, 'coverage')}" for v in scenario.coverage_levels]
    for kind in ("search", "rescue"):
        names += [f"{kind}_{level_name(v, 'targets')}" for v in scenario.target_levels]
    return names


def check(objective: Objective, scenario: Scenario) -> None:
    """ObjectiveError when the objective names a metric the scenario's runs do not have."""
    known = metric_names(scenario)
    for metric in sorted(objective.metrics()):
        if metric not in known:
            raise ObjectiveError(
                f"--objective {shown(objective.text)!r}: unknown metric {shown(metric)!r} "
                f"(this scenario has: {', '.join(known)})"
            )


def run_metric(run: RunResult, config: Config, scenario: Scenario, metric: str) -> float | None:
    """One run's value of a metric, None when the run did not reach it."""
    fixed = {
        "end_tick": run.end_tick,
        "events": run.events,
        "coverage_final": run.coverage_final,
        "members": sum(n for _, n in config.counts),
        "targets": config.targets,
    }
    if metric in fixed:
        return float(fixed[metric])
    for i, level in enumerate(scenario.coverage_levels):
        if metric == f"coverage_{level_name(level, 'coverage')}":
            value = run.coverage[i]
            return None if value is None else float(value)
    for level in scenario.target_levels:
        for kind, times in (("search", run.found), ("rescue", run.rescued)):
            if metric == f"{kind}_{level_name(level, 'targets')}":
                hit = (
                    kth(cast(Sequence[Any], times), level, config.targets)
                    if config.targets
                    else None
                )
                return None if hit is None else float(hit)
    raise ObjectiveError(f"unknown metric {shown(metric)!r}")


def _aggregate(func: str, values: Sequence[float | None], horizon: float) -> float:
    """`func` over the runs' values; a value not reached counts as the horizon."""
    if func == "count":
        return float(sum(1 for v in values if v is not None))
    filled = sorted(horizon if v is None else v for v in values)
    if not filled:
        return math.nan
    if func == "mean":
        return statistics.fmean(filled)
    if func == "min":
        return filled[0]
    if func == "max":
        return filled[-1]
    if func == "sd":
        return statistics.stdev(filled) if len(filled) > 1 else 0.0
    share = 50.0 if func == "median" else float(func[1:])
    # the nearest-rank percentile: a value some run really had
    rank = max(1, math.ceil(share / 100 * len(filled) - 1e-9))
    return filled[min(rank, len(filled)) - 1]


def evaluate(
    objective: Objective,
    runs: Sequence[RunResult],
    configs: Sequence[Config],
    scenario: Scenario,
) -> float:
    """The objective's value over the runs (each with its configuration, by `run.config`)."""
    horizon = float(scenario.max_ticks)

    def value(node: Node) -> float:
        if node.op == "num":
            return node.value
        if node.op == "agg":
            values = [run_metric(r, configs[r.config], scenario, node.metric) for r in runs]
            return _aggregate(node.func, values, horizon)
        if node.op == "neg":
            return -value(node.args[0])
        left, right = (value(a) for a in node.args)
        if node.op == "+":
            return left + right
        if node.op == "-":
            return left - right
        if node.op == "*":
            return left * right
        return left / right if right != 0 else math.nan  # a trial optuna then marks failed

    return value(objective.tree)
