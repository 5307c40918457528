"""The swarm's network settings: each communication interface's `communicationParams` readable
by the network transport, and the member types agreeing on them (SG230, SG231)."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.network import swarm_network
from swarmgen.ir.nodes import Model


def check_network(model: Model) -> list[Diagnostic]:
    """`communicationParams of 'Radio': port 70000 is not in 1-65535`, and the like."""
    found = []
    for problem in swarm_network(model).problems:
        misspelt = problem.variant == "misspelt"
        code = dg.MISSPELT_COMMUNICATION_PARAM if misspelt else dg.BAD_COMMUNICATION_PARAMS
        variant = dg.DEFAULT if problem.variant in ("misspelt", "value") else problem.variant
        found.append(code.at(problem.span, variant, **problem.fields))
    return found
