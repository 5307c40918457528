"""User properties, from the model and from `--property`, to checked trees, and their
verdicts to findings (SG407) with counterexamples (docs/verify.md, "User properties")."""

from __future__ import annotations

import re
from collections.abc import Sequence

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import codes_verify as cv
from swarmgen.ir.nodes import Model
from swarmgen.props.check import diagnostics, model_properties, parse_checked, vocabulary
from swarmgen.span import Span
from swarmgen.verify import liveness
from swarmgen.verify.counterexample import rerun
from swarmgen.verify.explore import Budget, Search
from swarmgen.verify.observe import Checked, Observer
from swarmgen.verify.properties import Finding
from swarmgen.verify.system import System

LIVENESS = frozenset({"eventually", "leads to", "until"})
FAIRNESS = (
    " (under the fairness assumption: deliveries, behaviour ends, outcomes and timers are fair; "
    "the abort discharges what is pending; docs/verify.md)"
)


def gather(model: Model, texts: Sequence[str]) -> tuple[list[Checked], list[dg.Diagnostic]]:
    """The model's properties (validation reported their errors) and `--property` texts, the
    latter's errors as diagnostics on `--property`."""
    vocab = vocabulary(model)
    checked: list[Checked] = []
    for prop in model_properties(model):
        tree, problems = parse_checked(prop.text, vocab)
        if tree is not None and not problems:
            checked.append(Checked(prop.name, prop.text, prop.span, tree))
    errors: list[dg.Diagnostic] = []
    for number, text in enumerate(texts, start=1):
        name = f"--property {number}"
        span = Span(file="--property")
        tree, problems = parse_checked(text, vocab)
        if tree is None or problems:
            errors.extend(diagnostics(name, text, span, problems))
        else:
            checked.append(Checked(name, text, span, tree))
    return checked, errors


def needs_graph(props: Sequence[Checked]) -> bool:
    """Whether some property is a liveness property (the search records the graph)."""
    return any(p.tree.kind in LIVENESS for p in props)


def needs_whole_abort(props: Sequence[Checked]) -> bool:
    """Whether some property must be checked after the abort too (`always`, `never`): the
    search then expands every state after the abort instead of stopping at decoupled ones."""
    return any(p.tree.kind not in LIVENESS for p in props)


def evaluate(system: System, search: Search, observer: Observer, budget: Budget) -> list[Finding]:
    """Each violated property's finding with its trace; liveness only on a whole search."""
    found: list[Finding] = []
    for index, prop in enumerate(observer.props):
        if prop.tree.kind in LIVENESS:
            if search.bounded:
                continue
            lasso = liveness.check(observer, prop.tree)
            if lasso is None:
                found.extend(_vacuous(prop, observer, search))
                continue
            trace = rerun(system, lasso.stem + lasso.cycle, budget.symmetry)
            trace.loop = len(lasso.stem) if lasso.cycle else None
            how, fairness = lasso.how, FAIRNESS
        else:
            if index not in observer.safety:
                continue
            number, step = observer.safety[index]
            steps = search.path(number) + ([step] if step is not None else [])
            trace = rerun(system, steps, budget.symmetry)
            how = "it holds" if prop.tree.kind == "never" else "it fails"
            how, fairness = f"{how} at the end of the trace", ""
        diagnostic = cv.VERIFY_PROPERTY.at(
            prop.span, name=prop.name, text=prop.text, how=how, length=trace.length,
            fairness=fairness,
        )  # fmt: skip
        found.append(Finding(diagnostic, trace))
    return found


def _vacuous(prop: Checked, observer: Observer, search: Search) -> list[Finding]:
    """SG409 for a `P leads to Q` that holds because P never does."""
    tree = prop.tree
    if tree.kind != "leads to" or tree.left is None or liveness.premise_seen(observer, tree):
        return []
    premise = re.split(r"\bleads\s+to\b", prop.text, maxsplit=1)[0].strip()
    diagnostic = cv.VERIFY_VACUOUS.at(
        prop.span, name=prop.name, text=prop.text, premise=premise, states=search.states
    )
    return [Finding(diagnostic)]
