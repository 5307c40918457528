"""Diagrams of a model: one per state machine (submachines included, each in its own diagram)
and one of the swarm composition and hardware, as Mermaid, Graphviz DOT or SVG.

    files = graph.files(model, "mermaid")            # {PurePosixPath("UavMission.mmd"): text, ...}
    files = graph.files(model, "svg", member="UAV")  # needs Graphviz `dot`

`view` computes what is shown once; `mermaid` and `dot` only write it. Output is deterministic:
model order, safe ids, no timestamps (SVG: see `dot.svg`).
"""

from __future__ import annotations

from pathlib import PurePosixPath
from typing import TYPE_CHECKING

from swarmgen.graph import mermaid, structure, view
from swarmgen.graph.view import GraphError

if TYPE_CHECKING:
    from swarmgen.graph.dot import GraphvizError
from swarmgen.ir.nodes import Machine, MemberType, Model
from swarmgen.ir.query import ModelIndex

FORMATS = ("mermaid", "dot", "svg")
Files = dict[PurePosixPath, str]

__all__ = ["FORMATS", "GraphError", "GraphvizError", "files", "select"]


def select(model: Model, member: str | None) -> tuple[list[Machine], MemberType | None]:
    """The machines to draw (all, or the member type's machine and its submachines, in model
    order) and the member type; GraphError for an unknown member type."""
    if member is None:
        return list(model.machines), None
    found = next((m for m in model.member_types if m.name == member), None)
    if found is None:
        names = ", ".join(sorted(m.name for m in model.member_types)) or "(none)"
        raise GraphError(f"no member type '{member}'; choose one of: {names}")
    reachable = {m.id for m in ModelIndex(model).member_machines(found)}
    return [m for m in model.machines if m.id in reachable], found


def files(model: Model, fmt: str = "mermaid", member: str | None = None) -> Files:
    """Relative path -> text: `<machine>.<ext>` per machine and `swarm.<ext>`."""
    if fmt not in FORMATS:
        raise GraphError(f"unknown diagram format '{fmt}'; choose one of: {', '.join(FORMATS)}")
    machines, chosen = select(model, member)
    diagrams = view.diagrams(model, machines)
    comp = structure.composition(model, chosen)
    out: Files = {}
    if fmt == "mermaid":
        for diagram in diagrams:
            out[PurePosixPath(diagram.stem + mermaid.SUFFIX)] = mermaid.state_diagram(diagram)
        out[PurePosixPath(structure.COMPOSITION_STEM + mermaid.SUFFIX)] = mermaid.composition(comp)
        return out
    from swarmgen.graph import dot  # Graphviz (subprocess): not for the Mermaid diagrams

    link = dot.SVG_SUFFIX if fmt == "svg" else dot.SUFFIX
    for diagram in diagrams:
        out[PurePosixPath(diagram.stem + dot.SUFFIX)] = dot.state_diagram(diagram, link)
    out[PurePosixPath(structure.COMPOSITION_STEM + dot.SUFFIX)] = dot.composition(comp)
    if fmt == "svg":
        return {path.with_suffix(dot.SVG_SUFFIX): dot.svg(text) for path, text in out.items()}
    return out


def __getattr__(name: str) -> object:
    """`GraphvizError`, from `graph.dot`, imported when first asked for (compile's Mermaid
    diagrams do not need Graphviz's module)."""
    if name == "GraphvizError":
        from swarmgen.graph.dot import GraphvizError

        return GraphvizError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
