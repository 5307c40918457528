"""One verification, end to end: load the model, explore its swarm, evaluate the properties,
and decide the exit status (0 verified, 1 violated, 4 bounded without a verdict; the model's
own errors exit as `validate` does)."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import field, replace
from pathlib import Path

from swarmgen import diagnostics as dg
from swarmgen.records import dataclass
from swarmgen.verify import userprops
from swarmgen.verify.explore import Budget, Search, explore
from swarmgen.verify.load import Loaded, load
from swarmgen.verify.observe import Observer
from swarmgen.verify.properties import Finding, evaluate

VERIFIED, VIOLATED, BAD_PROPERTY, BOUNDED = 0, 1, 2, 4


@dataclass
class Result:
    """A verification's diagnostics (validation's, then the properties'), its findings with
    their traces, the search and the exit status."""

    loaded: Loaded
    budget: Budget = field(default_factory=Budget)
    findings: list[Finding] = field(default_factory=list)
    search: Search | None = None
    seconds: float = 0.0
    exit_code: int = VERIFIED

    @property
    def diagnostics(self) -> list[dg.Diagnostic]:
        """Validation's diagnostics and the properties' ones, in that order."""
        return [*self.loaded.diagnostics, *(f.diagnostic for f in self.findings)]


def verify(
    path: Path,
    budget: Budget,
    members: Mapping[str, int] | None = None,
    abort: Sequence[str] = (),
    emit_bound: int = 1,
    progress: Callable[[str], None] | None = None,
    *,
    station_bound: int = 1,
    properties: Sequence[str] = (),
) -> Result:
    """Verify the model's swarm within the budget (see the module docstring): the built-in
    properties, the model's own properties and `properties` (texts, as `--property`)."""
    loaded = load(path, members, abort, emit_bound, station_bound=station_bound)
    result = Result(loaded, budget)
    if loaded.system is None or loaded.model is None:
        result.exit_code = int(dg.exit_code_for(loaded.diagnostics)) or VIOLATED
        return result
    props, errors = userprops.gather(loaded.model, properties)
    if errors:
        loaded.diagnostics.extend(errors)
        result.exit_code = BAD_PROPERTY
        return result
    observer = None
    if props:
        observer = Observer(loaded.system, props, userprops.needs_graph(props))
        if userprops.needs_whole_abort(props):
            budget = replace(budget, decouple=False)
            result.budget = budget
    started = time.perf_counter()
    result.search = explore(loaded.system, budget, progress, observer)
    result.findings = evaluate(loaded.model, loaded.system, result.search, budget)
    if observer is not None:
        result.findings.extend(userprops.evaluate(loaded.system, result.search, observer, budget))
    result.seconds = time.perf_counter() - started
    if any(f.diagnostic.level is dg.Severity.ERROR for f in result.findings):
        result.exit_code = VIOLATED
    elif result.search.bounded:
        result.exit_code = BOUNDED
    return result


def summary(result: Result) -> str:
    """The one verdict line: verified, violated or bounded, with the search's size."""
    search = result.search
    if search is None and result.exit_code == BAD_PROPERTY:
        return "not verified: a --property has errors"
    if search is None:
        return "not verified: the model has errors"
    size = f"{search.states:,} states, depth {search.max_depth}"
    if result.exit_code == VIOLATED:
        count = sum(f.diagnostic.level is dg.Severity.ERROR for f in result.findings)
        return f"violated: {count} propert{'y' if count == 1 else 'ies'} ({size})"
    if result.exit_code == BOUNDED:
        return f"bounded: {size}"
    return f"verified: {size}"
