"""Diagnostics as data: stable codes, severities, spans and hints, rendered as text or JSON.

Every stage returns its diagnostics instead of raising on model errors. Codes are registered
once here so that `docs/diagnostics.md` and the renderers agree.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from enum import IntEnum, StrEnum
from pathlib import Path

from swarmgen.span import Span


class Severity(StrEnum):
    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


class ExitCode(IntEnum):
    """Exit codes shared by every command (datamodel-codegen's OK/DIFF/ERROR split)."""

    OK = 0
    MODEL_ERRORS = 1  # the model has errors, or `--check` found drift
    INPUT_ERROR = 2  # the input could not be read, or the command was misused


@dataclass(frozen=True)
class Code:
    id: str
    name: str
    summary: str
    severity: Severity
    # Input problems end with exit code 2; model problems with 1.
    input_error: bool = False


CODES: dict[str, Code] = {}


def _code(
    id_: str,
    name: str,
    summary: str,
    severity: Severity = Severity.ERROR,
    *,
    input_error: bool = False,
) -> Code:
    code = Code(id_, name, summary, severity, input_error)
    assert id_ not in CODES, id_
    CODES[id_] = code
    return code


# --- input: the file could not be read as an XMI model (exit 2)
UNREADABLE = _code(
    "SG001", "unreadable-input", "the input is missing, not a file, or empty", input_error=True
)
NOT_XML = _code("SG002", "not-well-formed", "the input is not well-formed XML", input_error=True)
FORBIDDEN_XML = _code(
    "SG003", "forbidden-xml", "DTDs, entities and XInclude are refused", input_error=True
)
NOT_XMI = _code("SG004", "not-xmi", "the root element is not XMI or UML", input_error=True)
TOO_LARGE = _code(
    "SG005", "input-too-large", "the input exceeds a size or depth limit", input_error=True
)
# --- model structure (exit 1)
DUPLICATE_ID = _code("SG010", "duplicate-id", "two elements share one xmi:id")
DANGLING_REF = _code("SG011", "dangling-reference", "a reference names no element of the model")
UNKNOWN_STEREOTYPE = _code(
    "SG012", "unknown-stereotype", "a stereotype that swarmgen does not know", Severity.WARNING
)
UNKNOWN_TAG = _code(
    "SG013", "unknown-tag", "a tagged value that swarmgen does not know", Severity.WARNING
)
BAD_TAG_VALUE = _code("SG014", "bad-tag-value", "a tagged value outside its allowed values")
WRONG_REF_KIND = _code(
    "SG015", "wrong-reference-kind", "a reference names an element of the wrong kind"
)
NO_MACHINE = _code(
    "SG020", "no-state-machine", "the model holds no state machine", Severity.WARNING
)
MEMBER_WITHOUT_MACHINE = _code(
    "SG021", "member-without-machine", "a member type owns no state machine", Severity.WARNING
)
BAD_MULTIPLICITY = _code("SG022", "bad-multiplicity", "a multiplicity that is not a count")
# --- state machines
MISSING_INITIAL = _code(
    "SG101", "missing-initial", "a region with states has no initial pseudostate"
)
DUPLICATE_INITIAL = _code(
    "SG102", "duplicate-initial", "a region has more than one initial pseudostate"
)
BAD_TARGET = _code("SG103", "bad-transition-end", "a transition source or target is not a vertex")
SUBMACHINE_CYCLE = _code(
    "SG104", "submachine-cycle", "a state machine contains itself as a submachine"
)
UNKNOWN_BEHAVIOUR = _code("SG105", "unknown-behaviour", "a doActivity names no library behaviour")
UNKNOWN_EVENT = _code("SG106", "unknown-event", "a trigger names no declared event or outcome")
GUARD_SYNTAX = _code("SG107", "guard-syntax", "a guard is not in the expression language")
EFFECT_SYNTAX = _code("SG108", "effect-syntax", "an effect or entry/exit action does not parse")
BINDING_ERROR = _code("SG109", "binding-error", "a behaviour argument binding is wrong")
NAME_COLLISION = _code("SG110", "name-collision", "two names become the same identifier")
OUTCOME_WITHOUT_BEHAVIOUR = _code(
    "SG111",
    "outcome-without-behaviour",
    "a transition waits for an outcome but its state runs no behaviour",
)
UNKNOWN_NAME = _code("SG112", "unknown-name", "an expression uses a name that is not member data")
UNKNOWN_FIELD = _code(
    "SG113", "unknown-event-field", "an expression uses a field the event does not have"
)
OPAQUE_CODE = _code(
    "SG114", "opaque-code", "code in a foreign language is kept but not executed", Severity.WARNING
)
BAD_INITIAL_TRANSITION = _code(
    "SG115",
    "bad-initial-transition",
    "an initial transition has a trigger or guard, or is not single",
)
BAD_PSEUDOSTATE = _code("SG116", "bad-pseudostate", "a pseudostate used against its rules")
FINAL_WITH_OUTGOING = _code("SG117", "final-with-outgoing", "a transition leaves a final state")
UNSUPPORTED = _code(
    "SG118", "unsupported", "a UML construct that swarmgen does not translate", Severity.WARNING
)
UNKNOWN_OUTCOME = _code(
    "SG119", "unknown-outcome", "a transition waits for an outcome its behaviour cannot produce"
)
EVENT_ARGUMENT = _code(
    "SG120", "event-argument", "raise/send gives a field the event does not have"
)
MACHINE_TOO_DEEP = _code("SG121", "nesting-too-deep", "states nested deeper than the limit")
BAD_DEFAULT = _code(
    "SG122", "bad-default-value", "a default value generated code cannot represent exactly"
)
# --- limits on the work a small model may ask for (SG130-SG139)
MODEL_TOO_LARGE = _code(
    "SG130", "model-too-large", "a machine is too large once its submachines are inlined"
)
TOO_MANY_MEMBERS = _code(
    "SG131", "too-many-members", "a swarm has more members of one type than the limit"
)
NONDETERMINISM_UNDECIDED = _code(
    "SG132",
    "nondeterminism-undecided",
    "SG204 could not decide some pairs of guards within its budget",
    Severity.NOTE,
)
# --- well-formedness of machines and classes (SG140-SG159): models that would compile wrong
UNEXPECTED_ELEMENT = _code(
    "SG140", "unexpected-element", "an element of a kind that does not belong where it stands"
)
SEVERAL_REFS = _code(
    "SG141", "several-references", "a single-valued reference names more than one element"
)
INITIAL_LEAVES_REGION = _code(
    "SG142", "initial-leaves-region", "an initial or default history transition leaves its region"
)
ENTERS_INITIAL = _code("SG143", "enters-initial", "a transition targets an initial pseudostate")
BAD_FORK = _code(
    "SG144", "bad-fork", "fork targets that are not in distinct orthogonal regions of one state"
)
BAD_JOIN = _code(
    "SG145", "bad-join", "join sources not in distinct orthogonal regions, or no single way out"
)
SINGLE_BRANCH = _code(
    "SG146", "single-branch", "a fork or join with a single branch", Severity.WARNING
)
CHOICE_WITHOUT_ELSE = _code(
    "SG147", "choice-without-else", "a choice or junction whose guards can all be false"
)
BAD_OUTCOME_NAME = _code(
    "SG148", "bad-outcome-name", "an outcome name that is not a plain identifier"
)
GENERALISATION_CYCLE = _code(
    "SG149", "generalisation-cycle", "a class specialises itself, directly or not"
)
COMPOSITION_CYCLE = _code(
    "SG150", "composition-cycle", "a class is a part of itself or a data type contains itself"
)
RESERVED_FILE_NAME = _code(
    "SG151", "reserved-file-name", "a generated file name that Windows reserves", Severity.WARNING
)
PATH_TOO_LONG = _code(
    "SG152", "path-too-long", "a generated path too long for Windows", Severity.WARNING
)
BAD_FINAL_STATE = _code(
    "SG153", "bad-final-state", "a final state with regions, behaviours or a submachine"
)
UNKNOWN_KIND = _code(
    "SG154", "unknown-kind", "a pseudostate or transition kind that UML does not define"
)
BAD_INTERNAL = _code(
    "SG155", "bad-internal-transition", "an internal transition whose source and target differ"
)
SUBMACHINE_WITH_REGIONS = _code(
    "SG156", "submachine-with-regions", "a submachine state that has regions of its own"
)
DUPLICATE_REGION_NAME = _code(
    "SG157", "duplicate-region-name", "two regions of one state share a name", Severity.WARNING
)
LIVELOCK = _code("SG160", "livelock", "transitions that loop forever without an external event")
# --- analysis: swarm bugs before flight
UNREACHABLE_STATE = _code(
    "SG201",
    "unreachable-state",
    "no path from the initial state reaches the state",
    Severity.WARNING,
)
NO_WAY_OUT = _code(
    "SG202", "no-way-out", "a state that is not final has no way out", Severity.WARNING
)
NEVER_ENDS = _code(
    "SG203", "never-ends", "a member's machine can never reach a final state", Severity.WARNING
)
NONDETERMINISTIC = _code(
    "SG204",
    "nondeterministic",
    "two transitions on one trigger whose guards can both hold",
    Severity.WARNING,
)
UNHANDLED_OUTCOME = _code(
    "SG205",
    "unhandled-outcome",
    "a behaviour outcome that no transition of its state handles",
    Severity.WARNING,
)
NEVER_SENT = _code(
    "SG206", "event-never-sent", "a trigger on an event that nobody sends", Severity.WARNING
)
NEVER_HANDLED = _code(
    "SG207",
    "event-never-handled",
    "an event is sent but no member type reacts to it",
    Severity.WARNING,
)
TYPE_ERROR = _code("SG208", "type-error", "an expression combines values of incompatible types")
INPUT_MAYBE_UNSET = _code(
    "SG209",
    "input-maybe-unset",
    "a behaviour input may be unset when its state is entered",
    Severity.WARNING,
)
OUTPUT_UNUSED = _code(
    "SG210",
    "output-unused",
    "a behaviour output is written to member data nobody reads",
    Severity.NOTE,
)
MISSING_CAPABILITY = _code(
    "SG211", "missing-capability", "a behaviour requires hardware the member type does not have"
)
MISSING_PARAMETER = _code(
    "SG212",
    "missing-parameter",
    "a behaviour input is neither bound, member data nor a hardware parameter",
)
BAD_COUNT = _code("SG214", "bad-member-count", "a swarm has fewer than one member of a type")
ROS_NAME_COLLISION = _code("SG215", "ros-name-collision", "two elements get the same ROS name")


@dataclass(frozen=True)
class Diagnostic:
    """One finding: what, where, and how to fix it."""

    code: Code
    message: str
    span: Span
    severity: Severity | None = None  # None: the code's own severity
    hint: str | None = None
    notes: tuple[str, ...] = field(default=())

    @property
    def level(self) -> Severity:
        return self.severity or self.code.severity

    def sort_key(self) -> tuple[str, int, int, str, str]:
        return (self.span.file, self.span.line, self.span.col, self.code.id, self.message)

    def to_dict(self) -> dict[str, object]:
        return {
            "code": self.code.id,
            "name": self.code.name,
            "severity": self.level.value,
            "message": self.message,
            "file": self.span.file,
            "line": self.span.line,
            "col": self.span.col,
            "xmi_id": self.span.xmi_id,
            "path": self.span.path,
            "hint": self.hint,
            "notes": list(self.notes),
        }


def diag(
    code: Code, message: str, span: Span, *, hint: str | None = None, notes: Sequence[str] = ()
) -> Diagnostic:
    return Diagnostic(code, message, span, hint=hint, notes=tuple(notes))


def normalise(diagnostics: Iterable[Diagnostic]) -> list[Diagnostic]:
    """Sorted by position, duplicates removed (mypy's Errors does the same)."""
    seen: set[tuple[object, ...]] = set()
    unique: list[Diagnostic] = []
    for d in sorted(diagnostics, key=Diagnostic.sort_key):
        key = (*d.sort_key(), d.span.xmi_id)
        if key not in seen:
            seen.add(key)
            unique.append(d)
    return unique


def has_errors(diagnostics: Iterable[Diagnostic]) -> bool:
    return any(d.level is Severity.ERROR for d in diagnostics)


def exit_code_for(diagnostics: Sequence[Diagnostic]) -> ExitCode:
    errors = [d for d in diagnostics if d.level is Severity.ERROR]
    if any(d.code.input_error for d in errors):
        return ExitCode.INPUT_ERROR
    return ExitCode.MODEL_ERRORS if errors else ExitCode.OK


def render_text(diagnostics: Sequence[Diagnostic], *, excerpt: bool = True) -> str:
    """`model.xmi:42:7: error: message [SG102]`, then the path, a source excerpt and hints."""
    sources: dict[str, list[str] | None] = {}
    blocks = [_render_one(d, sources if excerpt else None) for d in diagnostics]
    return "".join(blocks)


def _render_one(d: Diagnostic, sources: dict[str, list[str] | None] | None) -> str:
    where = one_line(d.span.location())  # a file name with a line break must not split it
    lines = [f"{where}: {d.level.value}: {one_line(d.message)} [{d.code.id}]"]
    if d.span.path:
        lines.append(f"  in: {one_line(d.span.path)}")
    if sources is not None and d.span.line > 0:
        lines.extend(_excerpt(d.span, sources))
    lines.extend(f"  note: {one_line(n)}" for n in d.notes)
    if d.hint:
        lines.append(f"  hint: {one_line(d.hint)}")
    return "\n".join(lines) + "\n"


def one_line(text: str) -> str:
    """Model names with line breaks must not break the one-line-per-finding format."""
    if text.isprintable():
        return text
    return "".join(
        ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in text
    )


def _excerpt(span: Span, sources: dict[str, list[str] | None]) -> list[str]:
    if span.file not in sources:
        sources[span.file] = _read_lines(span.file)
    text = sources[span.file]
    if text is None or span.line > len(text):
        return []
    line = text[span.line - 1].rstrip("\n")
    if len(line) > 160:
        line = line[:157] + "..."
    line = _printable(line)
    caret = " " * (max(span.col, 1) - 1) + "^"
    return [f"  {span.line:>5} | {line}", f"        | {caret}"]


def _printable(line: str) -> str:
    """A source line safe to print: control and invisible characters (terminal escapes, bidi
    overrides, the bytes of a binary file) become U+FFFD, one for one, so the caret stays put."""
    return "".join(c if c.isprintable() or c == "\t" else "\ufffd" for c in line)


def _read_lines(file: str) -> list[str] | None:
    try:
        with Path(file).open(encoding="utf-8", errors="replace") as f:
            return f.readlines()
    except OSError:
        return None


def render_json(diagnostics: Sequence[Diagnostic]) -> str:
    errors = sum(d.level is Severity.ERROR for d in diagnostics)
    warnings = sum(d.level is Severity.WARNING for d in diagnostics)
    payload = {
        "diagnostics": [d.to_dict() for d in diagnostics],
        "summary": {"errors": errors, "warnings": warnings},
    }
    return json.dumps(payload, indent=2, ensure_ascii=False) + "\n"


def refusal_line(model: object, diagnostics: Sequence[Diagnostic]) -> str:
    """One line for a command that runs a model (simulate, replay) and cannot: the first error,
    located, and how to see them all."""
    model = one_line(str(model))
    errors = [d for d in diagnostics if d.level is Severity.ERROR]
    if not errors:
        return f"{model}: the model has errors; run `swarmgen validate {model}`"
    first = errors[0]
    where = "".join(f":{n}" for n in (first.span.line, first.span.col) if n)
    more = f" (and {len(errors) - 1} more error(s))" if len(errors) > 1 else ""
    return (
        f"{model}{where}: {one_line(first.message)} [{first.code.id}]{more}; "
        f"run `swarmgen validate {model}`"
    )


def summary_line(diagnostics: Sequence[Diagnostic]) -> str:
    errors = sum(d.level is Severity.ERROR for d in diagnostics)
    warnings = sum(d.level is Severity.WARNING for d in diagnostics)
    return f"{errors} error(s), {warnings} warning(s)"


SARIF_SCHEMA = "https://json.schemastore.org/sarif-2.1.0.json"
_SARIF_LEVEL = {Severity.ERROR: "error", Severity.WARNING: "warning", Severity.NOTE: "note"}


def render_sarif(diagnostics: Sequence[Diagnostic], version: str) -> str:
    """SARIF 2.1.0, as code-scanning services read it: one run, the rules used, one result per
    diagnostic with its physical location (relative path when under the current directory)."""
    used = sorted({d.code.id for d in diagnostics})
    rules = [
        {
            "id": CODES[code].id,
            "name": CODES[code].name,
            "shortDescription": {"text": CODES[code].summary},
            "defaultConfiguration": {"level": _SARIF_LEVEL[CODES[code].severity]},
            "help": {"text": f"see docs/diagnostics.md, code {code}"},
        }
        for code in used
    ]
    results = [_sarif_result(d, used.index(d.code.id)) for d in diagnostics]
    log = {
        "$schema": SARIF_SCHEMA,
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "swarmgen",
                        "version": version,
                        "rules": rules,
                    }
                },
                "columnKind": "unicodeCodePoints",
                "results": results,
            }
        ],
    }
    return json.dumps(log, indent=2, ensure_ascii=False) + "\n"


def _sarif_result(d: Diagnostic, rule_index: int) -> dict[str, object]:
    message = d.message
    if d.notes:
        message += "\n" + "\n".join(f"note: {n}" for n in d.notes)
    if d.hint:
        message += f"\nhint: {d.hint}"
    region: dict[str, int] = {}
    if d.span.line > 0:
        region = {"startLine": d.span.line, "startColumn": max(d.span.col, 1)}
    location: dict[str, object] = {"artifactLocation": {"uri": _sarif_uri(d.span.file)}}
    if region:
        location["region"] = region
    result: dict[str, object] = {
        "ruleId": d.code.id,
        "ruleIndex": rule_index,
        "level": _SARIF_LEVEL[d.level],
        "message": {"text": message},
        "locations": [{"physicalLocation": location}],
    }
    if d.span.path or d.span.xmi_id:
        logical = {"fullyQualifiedName": d.span.path or "", "name": d.span.xmi_id or ""}
        result["locations"][0]["logicalLocations"] = [logical]  # type: ignore[index]
    return result


def _sarif_uri(file: str) -> str:
    path = Path(file)
    try:
        return path.resolve().relative_to(Path.cwd().resolve()).as_posix()
    except ValueError:
        return path.resolve().as_uri()


def apply_options(
    diagnostics: Sequence[Diagnostic], *, strict: bool = False, disabled: Iterable[str] = ()
) -> list[Diagnostic]:
    """`--disable CODE` drops a code (input errors cannot be disabled); `--strict` makes
    warnings errors."""
    off = {c.upper() for c in disabled}
    kept = [d for d in diagnostics if d.code.id not in off or d.code.input_error]
    if strict:
        kept = [
            Diagnostic(d.code, d.message, d.span, Severity.ERROR, d.hint, d.notes)
            if d.level is Severity.WARNING
            else d
            for d in kept
        ]
    return kept
