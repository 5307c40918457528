"""Hardware capability: every behaviour a member type runs must find the hardware it requires
(following UML generalisation) and the inputs it is not given (hardware parameters)."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model, State
from swarmgen.ir.query import ModelIndex, walk


def check_capabilities(model: Model) -> list[Diagnostic]:
    """`state Coverage of UGV runs Coverage, which requires Camera; UGV has no Camera`."""
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    for member in model.member_types:
        provided = index.capabilities(member)
        for machine in index.member_machines(member):
            for placed in walk(machine):
                state = placed.vertex
                if not isinstance(state, State) or state.activity is None:
                    continue
                behaviour = index.behaviours[state.activity.behaviour]
                for need in behaviour.requires:
                    if need in provided:
                        continue
                    found.append(
                        dg.diag(
                            dg.MISSING_CAPABILITY,
                            f"state '{state.name}' of '{member.name}' runs '{behaviour.name}', which "
                            f"requires {need}; '{member.name}' has no {need}",
                            state.activity.span,
                            notes=[
                                f"'{member.name}' has: {', '.join(sorted(p.name + ': ' + p.type_name for p in member.hardware)) or 'no hardware'}",
                                f"'{behaviour.name}' requires: {', '.join(behaviour.requires)}",
                            ],
                            hint=f"give '{member.name}' a part whose class is or specialises {need}, "
                            f"or run another behaviour in '{state.name}'",
                        )
                    )
    return found


def check_parameters(model: Model) -> list[Diagnostic]:
    """An input that is not bound is read from member data, else from a hardware parameter."""
    index = ModelIndex(model)
    found: list[Diagnostic] = []
    for member in model.member_types:
        parameters = index.hardware_parameters(member)
        for machine in index.member_machines(member):
            scope = index.data_scope[machine.id]
            for placed in walk(machine):
                state = placed.vertex
                if not isinstance(state, State) or state.activity is None:
                    continue
                behaviour = index.behaviours[state.activity.behaviour]
                bound = {b.name for b in state.activity.bindings}
                for prop in behaviour.inputs:
                    if prop.name in bound or prop.name in scope or prop.name in parameters:
                        continue
                    found.append(
                        dg.diag(
                            dg.MISSING_PARAMETER,
                            f"input '{prop.name}' of '{behaviour.name}' (state '{state.name}' of "
                            f"'{member.name}') is neither bound, member data nor a hardware parameter",
                            state.activity.span,
                            hint=f"bind it in the doActivity (`{prop.name} = ...`), declare member data "
                            f"'{prop.name}', or give a hardware part the parameter '{prop.name}'",
                        )
                    )
    # machines no member runs (plain UML models): inputs must come from bindings or data
    for machine in model.machines:
        if index.members_running(machine):
            continue
        scope = index.data_scope[machine.id]
        for placed in walk(machine):
            state = placed.vertex
            if isinstance(state, State) and state.activity is not None:
                behaviour = index.behaviours[state.activity.behaviour]
                bound = {b.name for b in state.activity.bindings}
                for prop in behaviour.inputs:
                    if prop.name not in bound and prop.name not in scope:
                        found.append(
                            dg.diag(
                                dg.MISSING_PARAMETER,
                                f"input '{prop.name}' of '{behaviour.name}' is neither bound nor member data",
                                state.activity.span,
                                hint=f"bind it in the doActivity body (`{prop.name} = ...`)",
                            )
                        )
    return found
