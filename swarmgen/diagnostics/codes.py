"""The registry of diagnostic codes, each with its severity and the messages it is reported with.

A message is a str.format template with named fields, and usually a hint template; a stage
passes the span and the field values only (`dg.UNREACHABLE_STATE.at(span, state=..., ...)`), so
the wording of every finding lives here, beside its code (as mypy's message registry does).
Where one code is reported in really different situations, each wording is a named variant
(`dg.BAD_PSEUDOSTATE.at(span, "no-outgoing", label=...)`). `docs/diagnostics.md` lists them.
"""

from __future__ import annotations

from swarmgen.diagnostics.model import DEFAULT, Code, Message, Severity

CODES: dict[str, Code] = {}  # every id ever assigned, the retired ones too
M = Message
ERROR, WARNING, NOTE = Severity.ERROR, Severity.WARNING, Severity.NOTE


def register(
    id_: str,
    name: str,
    summary: str,
    severity: Severity = ERROR,
    *,
    input_error: bool = False,
    message: str | None = None,
    hint: str | None = None,
    variants: dict[str, Message] | None = None,
    notes: dict[str, str] | None = None,
) -> Code:
    """Register a code with its default message (`message`, `hint`), named `variants` and the
    templates of the `notes` its diagnostics may carry."""
    messages = {DEFAULT: Message(message, hint)} if message is not None else {}
    messages.update(variants or {})
    note_templates = {key: Message(text) for key, text in (notes or {}).items()}
    code = Code(id_, name, summary, severity, input_error, messages, note_templates)
    assert id_ not in CODES, id_
    CODES[id_] = code
    return code


def retire(id_: str, name: str, summary: str, severity: Severity, why: str) -> None:
    """Withdraw a code that is never reported: it keeps its id, so that an old `--disable` still
    works and the id is never reused for another meaning, but it has no messages to report."""
    assert id_ not in CODES, id_
    CODES[id_] = Code(id_, name, summary, severity, retired=why)


def active_codes() -> list[Code]:
    """The codes a stage may report, in registry order (the retired ones left out)."""
    return [code for code in CODES.values() if code.retired is None]


# Hints that more than one variant shares.
_DECLARE_DATA = "declare it as an attribute of the member type"
# Notes that list what an element has, in their two forms (some, or none at all).
_FIELDS = {"fields": "its fields are: {fields}", "no-fields": "its fields are: none"}

# --- input: the file could not be read as an XMI model (exit 2)
UNREADABLE = register(
    "SG001",
    "unreadable-input",
    "the input is missing, not a file, or empty",
    input_error=True,
    message="{error}",
    variants={"empty": M("file is empty")},
)
NOT_XML = register(
    "SG002",
    "not-well-formed",
    "the input is not well-formed XML",
    input_error=True,
    message="not well-formed XML: {error}",
    variants={
        "encoding": M(
            "the XML declaration names unsupported encoding {encoding}",
            'save the model as UTF-8 (<?xml version="1.0" encoding="UTF-8"?>)',
        ),
        "empty-encoding": M(
            "the XML declaration names an empty encoding name",
            'save the model as UTF-8 (<?xml version="1.0" encoding="UTF-8"?>)',
        ),
    },
)
FORBIDDEN_XML = register(
    "SG003",
    "forbidden-xml",
    "DTDs, entities and XInclude are refused",
    input_error=True,
    message="document type declarations and entities are not allowed in model files",
    hint="XMI exports never need a DTD; remove the <!DOCTYPE ...> block",
    variants={
        "xinclude": M(
            "XInclude is not allowed in model files; the included file is not read",
            "remove the xi:include element; a model is exported as one file",
        )
    },
)
NOT_XMI = register(
    "SG004",
    "not-xmi",
    "the root element is not one of a format swarmgen reads",
    input_error=True,
    message="root element <{tag}> is not a model swarmgen reads "
    "(xmi:XMI, uml:Model, scxml, Modelio's EXT)",
    hint="export the model from Modelio with File > Export > XMI, or give an SCXML document, "
    "a Modelio .exml file or a .ramc model component",
)
TOO_LARGE = register(
    "SG005",
    "input-too-large",
    "the input exceeds a size or depth limit",
    input_error=True,
    variants={
        "file": M(
            "file is {mib:.0f} MiB; the limit is {limit} MiB", "split the model into smaller files"
        ),
        "file-unknown-size": M(
            "file is too large; the limit is {limit} MiB", "split the model into smaller files"
        ),
        "depth": M("model has nesting deeper than {limit}"),
        "elements": M("model has more than {limit} elements"),
        "attributes": M(
            "element <{element}> has {count} attributes; the limit is {limit} per element",
            "XMI exports use a few attributes per element; this file was not exported",
        ),
    },
)
# --- model structure (exit 1)
DUPLICATE_ID = register(
    "SG010",
    "duplicate-id",
    "two elements share one xmi:id",
    message="xmi:id '{id}' is used twice",
    hint="ids must be unique; re-export the model or rename one id",
    notes={"first-used": "first used at {where}"},
)
DANGLING_REF = register(
    "SG011",
    "dangling-reference",
    "a reference names no element of the model",
    message="{kind} '{name}': {feature} '{value}' names no element of the model",
    hint="the referenced element was deleted or lives in a file that was not exported",
    variants={
        "stereotype-base": M("«{stereotype}» is applied to '{base}', which names no element")
    },
)
UNKNOWN_STEREOTYPE = register(
    "SG012",
    "unknown-stereotype",
    "a stereotype that swarmgen does not know",
    WARNING,
    message="stereotype '{stereotype}' is not part of the swarm profile; ignored",
)
UNKNOWN_TAG = register(
    "SG013",
    "unknown-tag",
    "a tagged value that swarmgen does not know",
    WARNING,
    message="«{stereotype}» has no tag '{tag}'; ignored",
)
BAD_TAG_VALUE = register(
    "SG014",
    "bad-tag-value",
    "a tagged value outside its allowed values",
    message="«{stereotype}» {tag}='{value}' is not one of {allowed}",
)
WRONG_REF_KIND = register(
    "SG015",
    "wrong-reference-kind",
    "a reference names an element of the wrong kind",
    message="{feature} of '{name}' is a {kind} '{target}', expected {expected}",
)
retire(
    "SG020",
    "no-state-machine",
    "the model holds no state machine",
    WARNING,
    "a model without machines is valid (a library, a hardware catalogue); a member type "
    "without one is SG021",
)
MEMBER_WITHOUT_MACHINE = register(
    "SG021",
    "member-without-machine",
    "a member type owns no state machine",
    WARNING,
    message="member type '{member}' owns no state machine, so it has no behaviour",
    hint="add a state machine to the class (its classifierBehavior)",
)
BAD_MULTIPLICITY = register(
    "SG022",
    "bad-multiplicity",
    "a multiplicity that is not a count",
    message="part '{part}' has multiplicity {multiplicity}; a swarm needs a fixed count",
    hint="set the upper multiplicity to the number of members, e.g. 4",
)
# --- state machines
MISSING_INITIAL = register(
    "SG101",
    "missing-initial",
    "a region with states has no initial pseudostate",
    message="region '{region}' has states but no initial pseudostate",
    hint="add an initial pseudostate with a transition to the first state (e.g. '{first}')",
)
DUPLICATE_INITIAL = register(
    "SG102",
    "duplicate-initial",
    "a region has more than one initial pseudostate",
    message="region '{region}' has {count} initial pseudostates",
    hint="keep one initial pseudostate per region",
    notes={"first-at": "the first is at {where}"},
)
BAD_TARGET = register(
    "SG103",
    "bad-transition-end",
    "a transition source or target is not a vertex",
    message="transition '{name}' lacks a source or a target",
    variants={
        "not-a-state": M("transition {end} '{name}' is a {kind}, not a state of this machine"),
        "reenters": M(
            "transition '{name}' re-enters '{state}', which does not hold both its ends",
            hint="`reenters` names a state that holds the source and the target (or the "
            "machine); the SCXML reader sets it",
        ),
    },
)
SUBMACHINE_CYCLE = register(
    "SG104",
    "submachine-cycle",
    "a state machine contains itself as a submachine",
    message="state machine '{machine}' contains itself: {cycle}",
    hint="a submachine state must not (even indirectly) reuse the machine it belongs to",
)
UNKNOWN_BEHAVIOUR = register(
    "SG105",
    "unknown-behaviour",
    "a doActivity names no library behaviour",
    message="doActivity calls '{operation}', which is not a library behaviour",
    hint="apply «ComplexBehavior», «SwarmBehavior», «SwarmFunction» or «HardwareFunction» to the "
    "operation",
)
UNKNOWN_EVENT = register(
    "SG106",
    "unknown-event",
    "a trigger names no declared event or outcome",
    message="trigger '{name}' names no «SwarmEvent» signal and no outcome",
    hint="declare a Signal «SwarmEvent» named '{name}', or check the spelling",
    variants={
        "unnamed": M("trigger names no event"),
        "action": M(
            "{what} {verb} '{event}', which is not a declared event",
            "declare a Signal «SwarmEvent» named '{event}'",
        ),
    },
)
# A parse error's own hint, when it has one (None: no hint).
GUARD_SYNTAX = register(
    "SG107",
    "guard-syntax",
    "a guard is not in the expression language",
    message="guard {error}",
    hint="{hint}",
)
EFFECT_SYNTAX = register(
    "SG108",
    "effect-syntax",
    "an effect or entry/exit action does not parse",
    message="{what} {error}",
    hint="{hint}",
)
BINDING_ERROR = register(
    "SG109",
    "binding-error",
    "a behaviour argument binding is wrong",
    message="argument binding {error}",
    hint="{hint}",
    variants={"no-input": M("'{behaviour}' has no input '{name}'")},
    notes={"inputs": "its inputs are: {inputs}", "no-inputs": "its inputs are: none"},
)
NAME_COLLISION = register(
    "SG110",
    "name-collision",
    "two names become the same identifier",
    message="{what} '{name}' and '{other}' both become the identifier '{ident}'",
    hint="rename one of them",
    variants={"twice": M("{what} '{name}' is declared twice", "remove or rename the duplicate")},
    notes={"other-at": "the other is at {where}"},
)
OUTCOME_WITHOUT_BEHAVIOUR = register(
    "SG111",
    "outcome-without-behaviour",
    "a transition waits for an outcome but its state runs no behaviour",
    message="transition waits for outcome '{outcome}', but '{state}' runs no behaviour",
    hint="give the state a doActivity, or use a triggerless (completion) transition",
)
UNKNOWN_NAME = register(
    "SG112",
    "unknown-name",
    "an expression uses a name that is not member data",
    message="{what} uses '{name}', which is not member data",
    hint=_DECLARE_DATA,
    variants={
        "near": M("{what} uses '{name}', which is not member data", "did you mean '{near}'?"),
        "assigns": M("{what} assigns '{name}', which is not member data", _DECLARE_DATA),
        "state": M(
            "{what} tests In('{name}'), but no state has that name",
            "name a state of the machine (or its id in the SCXML document)",
        ),
        "assigns-near": M(
            "{what} assigns '{name}', which is not member data", "did you mean '{near}'?"
        ),
    },
)
UNKNOWN_FIELD = register(
    "SG113",
    "unknown-event-field",
    "an expression uses a field the event does not have",
    message="{what} reads event.{name}, but the triggering event has no field '{name}'",
    notes=_FIELDS,
)
OPAQUE_CODE = register(
    "SG114",
    "opaque-code",
    "code in a foreign language is kept but not executed",
    WARNING,
    message="{what} in language '{language}' is kept as text but not executed: {text}",
    hint="write it in swarmgen's action language (no <language>) to have it run",
    variants={
        "no-behaviour": M(
            "doActivity {text} calls no library behaviour; kept as text, not executed",
            "set the doActivity's specification to a behaviour operation of the library",
        )
    },
)
BAD_INITIAL_TRANSITION = register(
    "SG115",
    "bad-initial-transition",
    "an initial transition has a trigger or guard, or is not single",
    message="{label} has {count} outgoing transitions; it needs exactly one",
    variants={
        "trigger": M(
            "the transition from {label} has a trigger or guard",
            "an initial transition fires at once; move the trigger to the next transition",
        )
    },
)
BAD_PSEUDOSTATE = register(
    "SG116",
    "bad-pseudostate",
    "a pseudostate used against its rules",
    variants={
        "no-outgoing": M("{label} has no outgoing transition"),
        "several-defaults": M("{label} has more than one default transition"),
        "trigger": M(
            "a transition leaving {label} has a trigger",
            "transitions out of choice, junction, fork and join pseudostates fire at once",
        ),
        "terminate": M(
            "a transition leaves {label}; a terminate pseudostate ends the machine",
            "remove the transition, or use a state instead of the terminate pseudostate",
        ),
    },
)
FINAL_WITH_OUTGOING = register(
    "SG117",
    "final-with-outgoing",
    "a transition leaves a final state",
    message="transition leaves final state '{state}'",
    hint="a final state ends its region; use an ordinary state instead",
)
UNSUPPORTED = register(
    "SG118",
    "unsupported",
    "a UML construct that swarmgen does not translate",
    WARNING,
    variants={
        "change-event": M("change events are not supported; trigger ignored"),
        "time-event": M(
            "time event '{event}' has no constant delay; trigger ignored",
            "give the TimeEvent a TimeExpression with a LiteralInteger in milliseconds",
        ),
    },
)
UNKNOWN_OUTCOME = register(
    "SG119",
    "unknown-outcome",
    "a transition waits for an outcome its behaviour cannot produce",
    message="'{behaviour}' cannot end with outcome '{outcome}'",
    hint="add the outcome to the behaviour's `outcomes` tag, or fix the trigger",
    notes={"outcomes": "its outcomes are: {outcomes}"},
)
EVENT_ARGUMENT = register(
    "SG120",
    "event-argument",
    "raise/send gives a field the event does not have",
    message="{what} {verb} '{event}' with field '{field}', which the event does not have",
    notes=_FIELDS,
)
retire(
    "SG121",
    "nesting-too-deep",
    "states nested deeper than the limit",
    ERROR,
    "the reader's depth limit (SG005) refuses deep nesting first",
)
BAD_DEFAULT = register(
    "SG122",
    "bad-default-value",
    "a default value generated code cannot represent exactly",
    message="default value {value} of '{name}' {problem}",
    hint="{hint}",
)

__all__ = [
    "BAD_DEFAULT",
    "BAD_INITIAL_TRANSITION",
    "BAD_MULTIPLICITY",
    "BAD_PSEUDOSTATE",
    "BAD_TAG_VALUE",
    "BAD_TARGET",
    "BINDING_ERROR",
    "DANGLING_REF",
    "DUPLICATE_ID",
    "DUPLICATE_INITIAL",
    "EFFECT_SYNTAX",
    "EVENT_ARGUMENT",
    "FINAL_WITH_OUTGOING",
    "FORBIDDEN_XML",
    "GUARD_SYNTAX",
    "MEMBER_WITHOUT_MACHINE",
    "MISSING_INITIAL",
    "NAME_COLLISION",
    "NOT_XMI",
    "NOT_XML",
    "OPAQUE_CODE",
    "OUTCOME_WITHOUT_BEHAVIOUR",
    "SUBMACHINE_CYCLE",
    "TOO_LARGE",
    "UNKNOWN_BEHAVIOUR",
    "UNKNOWN_EVENT",
    "UNKNOWN_FIELD",
    "UNKNOWN_NAME",
    "UNKNOWN_OUTCOME",
    "UNKNOWN_STEREOTYPE",
    "UNKNOWN_TAG",
    "UNREADABLE",
    "UNSUPPORTED",
    "WRONG_REF_KIND",
]
