"""The registry's codes of the SCXML reader (SG060-SG079): documents swarmgen cannot read, or reads with a caveat.

Registered after `codes_ros`, in the same `CODES`, the same way. Every one is an input error
(exit 2, nothing written): an SCXML construct is never silently dropped.
"""

from __future__ import annotations

from swarmgen.diagnostics.codes import NOTE, WARNING, M, register

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

CPSWARM_INVOKE = register(
    "SG064",
    "cpswarm-invoke",
    "a CPSwarm code-generator state (rosaction, rosservice, rosmonitor) swarmgen cannot read",
    input_error=True,
    message='<invoke type="{type}"> in state \'{state}\' has no <data id="invoke"> payload',
    hint='add <datamodel><data id="invoke"><{payload}>...</{payload}></data></datamodel> '
    "(docs/scxml-input.md, CPSwarm dialect)",
    variants={
        "missing": M(
            "<{element}> needs <{child}>", "add it (docs/scxml-input.md, CPSwarm dialect)"
        ),
        "policy": M(
            '<{element} type="{value}"> is not one of: {allowed}',
            "use one of them (docs/scxml-input.md, CPSwarm dialect)",
        ),
        "mismatch": M(
            "<invoke type=\"{type}\"> in state '{state}' holds <{payload}>",
            "ROS_ACTION holds <rosaction>, ROS_SERVICE <rosservice>, ROS_MONITOR <rosmonitor>",
        ),
        "no-invoke": M(
            "state '{state}' has a <{payload}> payload but no <invoke type=\"{type}\"/>",
            'add <invoke type="{type}"/> to the state',
        ),
        "several": M(
            "state '{state}' has {count} <invoke> elements; a CPSwarm state calls one interface",
            "split the state",
        ),
    },
)
CPSWARM_CAVEAT = register(
    "SG065",
    "cpswarm-caveat",
    "a CPSwarm construct the dialect allows but does not define, read by a documented rule",
    WARNING,
    message="{what} '{value}' has no package; read as '{read}'",
    hint="write the full name (pkg/Name) to choose another package",
    variants={
        "legacy": M(
            "{what} is the 2019 spelling; read as {read}",
            "write the current form (docs/scxml-input.md, CPSwarm dialect)",
        ),
        "mapping": M(
            "<map> names '{name}', which is no goal, request, result or response var of "
            "state '{state}'; the mapping is ignored",
            'list the var in <goal>/<result> (or <request>/<response>) with type="userdata"',
        ),
        "outcome": M(
            "'{state}' waits for outcome '{outcome}', but no state inside it calls a ROS "
            "action or service that could end with it; the transition is dropped",
            "move the transition to the state that runs the behaviour",
        ),
    },
)
CPSWARM_NOTE = register(
    "SG066",
    "cpswarm-note",
    "how swarmgen reads a CPSwarm construct whose meaning lived outside the SCXML",
    NOTE,
    message="{element} type=\"callback\" in state '{state}' was user code in the CPSwarm "
    "tool; swarmgen runs no callback",
    hint="supply the behaviour through a plug-in (docs/plugins.md)",
    variants={
        "declared": M(
            "'{name}' is not in the document's <datamodel>; declared as member data",
            'declare it (<data id="{name}" expr=...>) to give it a type and a value',
        ),
        "ignored": M(
            '<data id="{id}"> in a CPSwarm state is not read: {why}',
            "the ROS interface is the one <rosaction>/<rosservice> names",
        ),
        "monitor": M(
            "the topic '{topic}' raises the event '{event}' ({why})",
            "name the event on the <parallel>'s transition to choose another",
        ),
    },
)
SCXML_INVOKE = register(
    "SG070",
    "scxml-invoke",
    "an SCXML `<invoke>` of an SCXML session swarmgen cannot run: a document it cannot read "
    "safely or computes only at run time, a namelist naming no data, nesting too deep",
    input_error=True,
    message="<invoke> has no document to run: {why}",
    hint="give src, or <content> holding one <scxml> element (docs/scxml-input.md, Invoke)",
    variants={
        "src": M(
            '<invoke src="{src}"> is not read: {why}',
            "give a file beside the document or below its folder, or the document inline "
            "in <content>",
        ),
        "nesting": M(
            "invoked documents nest deeper than {limit} (a document that invokes itself?)",
            "invoke fewer levels of documents",
        ),
        "many": M(
            "a document and the documents it invokes invoke more than {limit} documents",
            "invoke fewer documents",
        ),
        "convert": M(
            "<invoke> has no form in UML XMI: the swarm profile has no invoked sessions",
            "keep the SCXML document as the model (compile reads it); convert writes no XMI for it",
        ),
        "attribute": M(
            "{attribute} on <invoke> is not read: {why}",
            "docs/scxml-input.md, Invoke, lists what the reader accepts",
        ),
    },
)

__all__ = [
    "CPSWARM_CAVEAT",
    "CPSWARM_INVOKE",
    "CPSWARM_NOTE",
    "SCXML_BAD_DOCUMENT",
    "SCXML_DATAMODEL",
    "SCXML_EXPRESSION",
    "SCXML_INVOKE",
    "SCXML_UNSUPPORTED",
]
