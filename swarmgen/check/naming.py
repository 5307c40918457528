"""Identifier collisions: two model names that become one identifier in generated code."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Protocol

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Model
from swarmgen.span import Span


class _Named(Protocol):
    @property
    def name(self) -> str: ...
    @property
    def ident(self) -> str: ...
    @property
    def span(self) -> Span: ...


def check_collisions(model: Model) -> list[Diagnostic]:
    found: list[Diagnostic] = []
    found += _collisions("member type", model.member_types)
    found += _collisions("behaviour", model.behaviours)
    found += _collisions("event", model.events)
    found += _collisions("state machine", model.machines)
    for event in model.events:
        found += _collisions(f"field of event '{event.name}'", event.fields)
    for member in model.member_types:
        found += _collisions(f"member data of '{member.name}'", member.data)
    for behaviour in model.behaviours:
        found += _collisions(f"input of '{behaviour.name}'", behaviour.inputs)
        found += _collisions(f"output of '{behaviour.name}'", behaviour.outputs)
    return found


def _collisions(what: str, items: Iterable[_Named]) -> list[Diagnostic]:
    first: dict[str, _Named] = {}
    found = []
    for item in items:
        other = first.setdefault(item.ident, item)
        if other is item:
            continue
        same = other.name == item.name
        message = (
            f"{what} '{item.name}' is declared twice"
            if same
            else f"{what} '{item.name}' and '{other.name}' both become the identifier '{item.ident}'"
        )
        found.append(
            dg.diag(
                dg.NAME_COLLISION,
                message,
                item.span,
                notes=[f"the other is at {other.span.location()}"],
                hint="rename one of them" if not same else "remove or rename the duplicate",
            )
        )
    return found
