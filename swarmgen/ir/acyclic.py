"""Generalisation and composition must be acyclic (UML): a class that specialises itself has
every capability of a loop, and a class that is a part of itself (or a data type that contains
itself) has no finite instance. Both used to be accepted in silence; `ir.build` reports them
(SG149, SG150) with the cycle spelled out."""

from __future__ import annotations

from collections.abc import Iterator

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.frontend.raw import RawElement, RawModel

Edge = tuple[RawElement, RawElement]  # (the generalization or attribute, the class it leads to)
_CONTAINERS = {"Class", "Component", "DataType"}


def class_cycles(raw: RawModel, elements: list[RawElement], hardware: set[str]) -> list[Diagnostic]:
    """Cycles of generalisation, and of composition: composite attributes, attributes typed by
    a hardware class (a member's hardware is its parts whatever the aggregation) and the fields
    of data types (held by value)."""
    generals: dict[str, list[Edge]] = {}
    parts: dict[str, list[Edge]] = {}
    for element in elements:
        if not element.id:
            continue
        generals[element.id] = [
            (g, t) for g in element.kids("generalization") for t in _targets(raw, g, "general")
        ]
        if element.uml_type in _CONTAINERS:
            parts[element.id] = [
                (a, t)
                for a in element.kids("ownedAttribute")
                for t in _targets(raw, a, "type")
                if t.uml_type in _CONTAINERS
                and (
                    a.attrs.get("aggregation") == "composite"
                    or t.id in hardware
                    or element.uml_type == "DataType"
                )
            ]
    found = []
    for cycle in _cycles(generals):
        names = " -> ".join(e[1].name for e in [cycle[-1], *cycle])
        found.append(
            dg.GENERALISATION_CYCLE.at(cycle[0][0].span, name=cycle[-1][1].name, cycle=names)
        )
    for cycle in _cycles(parts):
        path = " -> ".join(f"{e[0].parent.name if e[0].parent else ''}.{e[0].name}" for e in cycle)
        found.append(dg.COMPOSITION_CYCLE.at(cycle[0][0].span, name=cycle[-1][1].name, cycle=path))
    return found


def _targets(raw: RawModel, element: RawElement, feature: str) -> list[RawElement]:
    """The elements a reference names, without reporting (the builders do that)."""
    return [t for v in element.ref_values(feature) if (t := raw.resolve(v)) is not None]


def _cycles(graph: dict[str, list[Edge]]) -> list[list[Edge]]:
    """One cycle (its edges, from where the search entered it) per set of elements that form
    one, in model order; iterative, so that a long chain cannot exhaust the stack."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    found: list[list[Edge]] = []
    seen: set[frozenset[str]] = set()
    for root in graph:
        if root in state:
            continue
        path: list[Edge] = []  # path[i] leads from stack[i] to stack[i + 1]
        stack: list[tuple[str, Iterator[Edge]]] = [(root, iter(graph[root]))]
        state[root] = 1
        while stack:
            node, edges = stack[-1]
            edge = next(edges, None)
            if edge is None:
                state[node] = 2
                stack.pop()
                if path:
                    path.pop()
                continue
            target = edge[1].id or ""
            if state.get(target) == 1:
                start = next(i for i, (n, _) in enumerate(stack) if n == target)
                cycle = [*path[start:], edge]
                if (key := frozenset(e[1].id or "" for e in cycle)) not in seen:
                    seen.add(key)
                    found.append(cycle)
            elif target not in state and target in graph:
                state[target] = 1
                path.append(edge)
                stack.append((target, iter(graph[target])))
    return found
