"""Bodies in swarmgen's languages: entry, exit and effect actions, and doActivity calls."""

from __future__ import annotations

from typing import Literal

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.frontend.raw import RawElement
from swarmgen.ir.build_context import (
    Builder,
    short,
)
from swarmgen.ir.nodes import (
    BehaviourCall,
    OpaqueCode,
)

# Languages whose bodies are swarmgen's expression language; anything else is kept opaque.
OWN_LANGUAGES = frozenset({"", "swarmgen", "sg"})


def bodies_of(element: RawElement) -> tuple[str, str]:
    """(language, text) of an OpaqueBehavior/OpaqueExpression; parallel lists joined."""
    languages = [lang.text for lang in element.kids("language")]
    bodies = [body.text for body in element.kids("body")]
    if not bodies and "body" in element.attrs:
        bodies = [element.attrs["body"]]
    return (languages[0].strip() if languages else ""), "\n".join(bodies)


def _is_own_language(language: str) -> bool:
    return language.strip().lower() in OWN_LANGUAGES


def actions_of(
    b: Builder,
    behaviour: RawElement | None,
    what: str,
    opaque: list[OpaqueCode],
    role: Literal["entry", "exit", "do", "effect"] = "effect",
) -> tuple[expr.Action, ...]:
    """The parsed actions of an entry, exit or effect behaviour; other languages kept opaque."""
    if behaviour is None:
        return ()
    language, text = bodies_of(behaviour)
    if not text.strip():
        return ()
    if not _is_own_language(language):
        opaque.append(OpaqueCode(language=language, body=text, role=role, span=behaviour.span))
        b.diags.append(
            dg.OPAQUE_CODE.at(behaviour.span, what=what, language=language, text=short(text))
        )
        return ()
    try:
        return b.actions(text)
    except expr.ExprError as err:
        error = quote_error(text, err)
        b.diags.append(dg.EFFECT_SYNTAX.at(behaviour.span, what=what, error=error, hint=err.hint))
        return ()


def activity_call(
    b: Builder, element: RawElement | None, opaque: list[OpaqueCode]
) -> BehaviourCall | None:
    """The library behaviour a doActivity calls, with its parsed argument bindings."""
    if element is None:
        return None
    operation = b.ref(element, "specification")
    language, text = bodies_of(element)
    if operation is None:
        if not element.ref_values("specification") and text.strip():
            opaque.append(OpaqueCode(language=language, body=text, role="do", span=element.span))
            b.diags.append(dg.OPAQUE_CODE.at(element.span, "no-behaviour", text=short(text)))
        return None
    behaviour = b.behaviours.get(operation.id or "")
    if behaviour is None:
        b.diags.append(dg.UNKNOWN_BEHAVIOUR.at(element.span, operation=operation.name))
        return None
    bindings: tuple[expr.Binding, ...] = ()
    if text.strip():
        try:
            bindings = b.bindings(text)
        except expr.ExprError as err:
            error = quote_error(text, err)
            b.diags.append(dg.BINDING_ERROR.at(element.span, error=error, hint=err.hint))
    return BehaviourCall(behaviour=behaviour.id, bindings=bindings, span=element.span)


def quote_error(text: str, err: expr.ExprError) -> str:
    """A syntax error as a message: the offending line quoted, then the error and its column."""
    lines = text.split("\n")  # ExprError counts lines by "\n" only
    line = lines[err.line] if err.line < len(lines) else text
    return f"{short(line)}: {err.message} (column {err.col + 1})"
