"""The registry's codes of the SCXML reader (SG060-SG079): documents swarmgen cannot read, or reads with a caveat.

Registered after `codes_ros`, in the same `CODES`, the same way. Every one is an input error
(exit 2, nothing written): an SCXML construct is never silently dropped.
"""

from __future__ import annotations

from swarmgen.diagnostics.codes import M, register

SCXML_UNSUPPORTED = register(
    "SG060",
    "scxml-unsupported",
    "an SCXML construct swarmgen's IR cannot express yet (`<invoke>`, `<if>`, `<script>`, ...)",
    input_error=True,
    message="<{element}> is not supported by swarmgen's SCXML reader: {why}",
    hint="remove it, or express it with states and transitions (docs/scxml-input.md)",
    variants={
        "attribute": M(
            '{attribute}="{value}" on <{element}> is not supported: {why}',
            "docs/scxml-input.md lists what the reader accepts",
        ),
        "event": M(
            "the event descriptor '{event}' is not supported: {why}",
            "name the events the transition takes (docs/scxml-input.md)",
        ),
    },
)
SCXML_BAD_DOCUMENT = register(
    "SG061",
    "scxml-bad-document",
    "an SCXML document that breaks SCXML 1.0's rules (unknown element, missing or duplicate id)",
    input_error=True,
    message="<{element}> is not an element of SCXML 1.0 (or of swarmgen's sg: extension)",
    hint="fix the element's name or move it into another namespace",
    variants={
        "duplicate-id": M(
            "the id '{id}' is used twice (first at {where})", "give every state its own id"
        ),
        "unknown-target": M(
            "{attribute} names '{id}', which is no state of this document",
            "name the id of a state, parallel, final or history element",
        ),
        "bad-initial": M(
            "initial '{id}' is not a descendant of <{element}>",
            "name a descendant of the state (W3C SCXML 3.3)",
        ),
        "missing": M("<{element}> needs the attribute {attribute}", "add it (W3C SCXML 1.0)"),
        "bad-value": M(
            '{attribute}="{value}" on <{element}> is not valid: {why}',
            "see W3C SCXML 1.0 for the attribute's values",
        ),
    },
)
SCXML_EXPRESSION = register(
    "SG062",
    "scxml-expression",
    "an expression outside the ECMAScript subset swarmgen translates",
    input_error=True,
    message="cannot translate '{text}' into swarmgen's expression language: {why}",
    hint="use literals, data names, comparisons, &&, ||, !, arithmetic, _event.data.<field> "
    "(docs/scxml-input.md)",
)
SCXML_DATAMODEL = register(
    "SG063",
    "scxml-datamodel",
    "a datamodel swarmgen cannot run (xpath, or a name it does not know)",
    input_error=True,
    message='datamodel "{datamodel}" is not one swarmgen reads',
    hint='use datamodel="ecmascript" (its subset), "null" or "swarmgen"',
)

__all__ = ["SCXML_BAD_DOCUMENT", "SCXML_DATAMODEL", "SCXML_EXPRESSION", "SCXML_UNSUPPORTED"]
