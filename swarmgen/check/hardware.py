"""Hardware capability: every behaviour a member type runs must find the hardware it requires
(following UML generalisation) and the inputs it is not given (hardware parameters)."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Behaviour, MemberType, Model, State
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
                        dg.MISSING_CAPABILITY.at(
                            state.activity.span,
                            notes=_capability_notes(member, behaviour),
                            state=state.name,
                            member=member.name,
                            behaviour=behaviour.name,
                            need=need,
                        )
                    )
    return found


def _capability_notes(member: MemberType, behaviour: Behaviour) -> list[str]:
    """What the member type has and what the behaviour requires, for SG211's notes."""
    code = dg.MISSING_CAPABILITY
    parts = sorted(f"{p.name}: {p.type_name}" for p in member.hardware)
    has = (
        code.note("has", member=member.name, hardware=", ".join(parts))
        if parts
        else code.note("has-nothing", member=member.name)
    )
    needs = ", ".join(behaviour.requires)
    return [has, code.note("requires", behaviour=behaviour.name, needs=needs)]


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
                        dg.MISSING_PARAMETER.at(
                            state.activity.span,
                            input=prop.name,
                            behaviour=behaviour.name,
                            state=state.name,
                            member=member.name,
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
                            dg.MISSING_PARAMETER.at(
                                state.activity.span,
                                "no-hardware",
                                input=prop.name,
                                behaviour=behaviour.name,
                            )
                        )
    return found
