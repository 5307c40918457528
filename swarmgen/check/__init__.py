"""Checks: one module per family of rules, each `Model -> list[Diagnostic]`, run in order."""

from __future__ import annotations

from collections.abc import Callable

from swarmgen.check.expressions import check_expressions
from swarmgen.check.naming import check_collisions
from swarmgen.check.structure import (
    check_initial_states,
    check_outcomes,
    check_pseudostates,
    check_submachines,
)
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model

Rule = Callable[[Model], list[Diagnostic]]

RULES: tuple[Rule, ...] = (
    check_submachines,
    check_initial_states,
    check_pseudostates,
    check_outcomes,
    check_expressions,
    check_collisions,
)


def run(model: Model) -> list[Diagnostic]:
    """Every rule's findings, in rule order (the pipeline sorts them by position)."""
    found: list[Diagnostic] = []
    for rule in RULES:
        found.extend(rule(model))
    return found
