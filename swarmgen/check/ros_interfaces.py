"""Declared ROS interface types: every behaviour with a `rosType` is resolved in the interface
index the pipeline loaded, and its inputs and outputs are checked against the type's fields
(`swarmgen.ros.idl_bind`, docs/ros2.md "Declared interface types")."""

from __future__ import annotations

from typing import Any

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic
from swarmgen.ir.nodes import Behaviour, Model
from swarmgen.ros.idl_bind import INTERFACE_KIND, Issue, analyse, split_type
from swarmgen.ros.idl_index import InterfaceIndex, Problem, Root
from swarmgen.span import Span

_EXPECTED = {"action": "action", "srv": "service", "msg": "topic"}
_WANTED = {"action": "action", "service": "srv", "topic": "msg"}


def check_ros_interfaces(model: Model, index: InterfaceIndex) -> list[Diagnostic]:
    """SG301-SG309 for every behaviour that declares a rosType."""
    found: list[Diagnostic] = []
    for behaviour in model.behaviours:
        if behaviour.ros is None or not behaviour.ros.type:
            continue
        _, issues = analyse(behaviour, index, model.datatypes, model.enumerations)
        found.extend(_diagnostic(behaviour, issue, index) for issue in issues)
    return found


def _diagnostic(behaviour: Behaviour, issue: Issue, index: InterfaceIndex) -> Diagnostic:
    values: dict[str, Any] = dict(issue.values)
    notes = [_quote(q, values) for q in issue.quote]
    if issue.problem is not None:
        return _problem(behaviour, issue.problem, index)
    if issue.key == "shadowed":
        return dg.ROS_TYPE_SHADOWED.at(behaviour.span, **values)
    name = behaviour.name
    if issue.key == "bad-form":
        return dg.ROS_TYPE_FORM.at(behaviour.span, behaviour=name, **values)
    if issue.key == "kind":
        assert behaviour.ros is not None
        expected, wanted = _EXPECTED[str(values["kind"])], _WANTED[behaviour.ros.kind]
        return dg.ROS_KIND_MISMATCH.at(
            behaviour.span, behaviour=name, expected=expected, wanted=wanted, notes=notes, **values
        )
    if issue.key == "direction":
        return dg.ROS_TOPIC_DIRECTION.at(behaviour.span, behaviour=name, notes=notes, **values)
    if issue.key == "unknown-field":
        return dg.ROS_UNKNOWN_FIELD.at(behaviour.span, behaviour=name, notes=notes, **values)
    detail = values.pop("detail")
    code = dg.ROS_FIELD_TYPE if issue.key == "type" else dg.ROS_DATATYPE_UNMAPPED
    return code.at(behaviour.span, behaviour=name, detail=detail, notes=notes, **values)


def _quote(quote: tuple[str, int, str], values: dict[str, object]) -> str:
    file, line, text = quote
    section = values.get("section", "definition")
    return dg.ROS_UNKNOWN_FIELD.note(
        "definition", type=values.get("type", ""), section=section, where=f"{file}:{line}",
        text=text.strip(),
    )  # fmt: skip


def _root_text(root: Root) -> str:
    """A root as the user knows it; no absolute paths of the machine (expected outputs)."""
    if root.origin == "installed":
        return "the installed packages (AMENT_PREFIX_PATH, the Python prefix)"
    if root.origin == "bundled":
        return "swarmgen's bundled Kilted standard definitions"
    return str(root.path)


def _problem(behaviour: Behaviour, problem: Problem, index: InterfaceIndex) -> Diagnostic:
    """A type that does not resolve: SG301 at the behaviour when the declared type itself is
    missing, else SG303 at the definition line (or file) that fails."""
    needed = dg.BAD_INTERFACE.note(
        "needed-by", behaviour=behaviour.name, where=behaviour.span.location()
    )
    if problem.kind == "missing" and not problem.file:
        assert behaviour.ros is not None and behaviour.ros.type is not None
        triple = split_type(behaviour.ros.type, behaviour.ros.kind)
        package, kind, name = triple or ("pkg", INTERFACE_KIND[behaviour.ros.kind], "Name")
        roots = ", ".join(dict.fromkeys(_root_text(r) for r in index.roots))
        return dg.ROS_TYPE_NOT_FOUND.at(
            behaviour.span,
            type=problem.type,
            behaviour=behaviour.name,
            path=f"{package}/{kind}/{name}.{kind}",
            notes=[dg.ROS_TYPE_NOT_FOUND.note("searched", roots=roots)],
        )
    span = Span(file=problem.file, line=problem.line, col=problem.col)
    if problem.kind == "missing":
        package, _, name = problem.type.split("/")
        return dg.BAD_INTERFACE.at(
            span, "nested-missing", type=problem.type, path=f"{package}/msg/{name}.msg",
            notes=[needed],
        )  # fmt: skip
    variant = dg.DEFAULT if problem.kind == "syntax" else problem.kind
    return dg.BAD_INTERFACE.at(
        span, variant, type=problem.type, error=problem.error, notes=[needed]
    )
