"""Model-level checks: one module per family of rules, each `Model -> list[Diagnostic]`, run in
order. Rules over the lowered charts run later, as their own stage (`swarmgen.chart.checks`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from swarmgen import diagnostics as dg
from swarmgen.check.determinism import check_determinism
from swarmgen.check.events import check_events, check_unhandled_outcomes
from swarmgen.check.expressions import check_expressions
from swarmgen.check.hardware import check_capabilities, check_parameters
from swarmgen.check.livelock import check_livelocks
from swarmgen.check.naming import check_collisions, check_output_paths
from swarmgen.check.network import check_network
from swarmgen.check.reachability import check_reachability
from swarmgen.check.ros_interfaces import check_ros_interfaces
from swarmgen.check.size import check_size
from swarmgen.check.structure import (
    check_initial_states,
    check_outcomes,
    check_pseudostates,
    check_submachines,
)
from swarmgen.check.swarm import check_counts, check_ros_names
from swarmgen.check.types import check_types
from swarmgen.check.wellformed import check_wellformed
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model
from swarmgen.props.check import check_properties
from swarmgen.ros.idl_index import InterfaceIndex

Rule = Callable[[Model], list[Diagnostic]]

RULES: tuple[Rule, ...] = (
    check_submachines,
    check_size,
    check_initial_states,
    check_pseudostates,
    check_wellformed,
    check_outcomes,
    check_expressions,
    check_collisions,
    check_output_paths,
    check_reachability,
    check_livelocks,
    check_determinism,
    check_unhandled_outcomes,
    check_events,
    check_capabilities,
    check_parameters,
    check_counts,
    check_ros_names,
    check_types,
    check_network,
    check_properties,
)


def run(model: Model, interfaces: InterfaceIndex | None = None) -> list[Diagnostic]:
    """Every rule's findings, in rule order (the pipeline sorts them by position), then the
    declared ROS types against `interfaces` when the pipeline loaded an index."""
    found: list[Diagnostic] = []
    for rule in RULES:
        findings = rule(model)
        found.extend(findings)
        if rule is check_size and findings:
            return found  # the later rules would walk the inlined machine; `may_lower` is False
    if interfaces is not None:
        found.extend(check_ros_interfaces(model, interfaces))
    return found


def may_lower(found: Sequence[Diagnostic]) -> bool:
    """Whether a model with these findings may be lowered: only one without errors, since lowering
    assumes a well-formed model (SG143's initial transitions, SG104's cycles would break it), and
    never one too large to inline (SG130), whatever its severity."""
    too_large = any(d.code is dg.MODEL_TOO_LARGE for d in found)
    return not too_large and not dg.has_errors(found)
