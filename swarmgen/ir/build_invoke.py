"""A state's `<invoke>`s (SCXML input, docs/scxml-input.md): the raw `invoke` elements the
SCXML reader made, each with its child document's raw model (`RawModel.sessions`), into IR
`Invoke`s whose `session` is the child's whole model, built by the same `build`."""

from __future__ import annotations

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.frontend.raw import RawElement
from swarmgen.ir.build_bodies import actions_of, quote_error
from swarmgen.ir.build_context import Builder
from swarmgen.ir.nodes import Invoke, OpaqueCode


def invokes_of(b: Builder, state: RawElement) -> tuple[Invoke, ...]:
    """The invokes of a state, in document order (one whose document is missing: none)."""
    from swarmgen.ir.build import build  # the child is a model of its own: the same stages

    found: list[Invoke] = []
    for element in state.kids("invoke"):
        raw = b.raw.sessions.get(element.attrs.get("session", ""))
        if raw is None:
            continue
        session, diagnostics = build(raw)
        b.diags += diagnostics
        opaque: list[OpaqueCode] = []
        finalize = actions_of(b, element.first("finalize"), "finalize", opaque)
        attrs = element.attrs
        found.append(
            Invoke(
                invokeid=attrs.get("invokeid"),
                idlocation=attrs.get("idlocation"),
                kind=attrs.get("kind"),
                kind_expr=_expression(b, element, attrs.get("kindexpr")),
                autoforward=attrs.get("autoforward") == "true",
                params=tuple(
                    expr.Binding(name=p.name, value=value)
                    for p in element.kids("param")
                    if (value := _expression(b, p, p.attrs.get("value"))) is not None
                ),
                finalize=finalize,
                session=session,
                span=element.span,
            )
        )
    return tuple(found)


def _expression(b: Builder, element: RawElement, text: str | None) -> expr.Expr | None:
    if text is None:
        return None
    try:
        return b.expression(text)
    except expr.ExprError as err:
        error = quote_error(text, err)
        b.diags.append(dg.GUARD_SYNTAX.at(element.span, error=error, hint=err.hint))
        return None
