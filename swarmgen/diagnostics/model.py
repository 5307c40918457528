"""The data of a diagnostic: severities, exit codes, codes with their message templates, findings."""

from __future__ import annotations

import string
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import field
from enum import IntEnum, StrEnum

from swarmgen.records import dataclass
from swarmgen.span import Span

DEFAULT = "default"  # the name of a code's usual message; other wordings are named variants


class Severity(StrEnum):
    """How bad a finding is; errors stop the pipeline."""

    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


class ExitCode(IntEnum):
    """Exit codes shared by every command (datamodel-codegen's OK/DIFF/ERROR split)."""

    OK = 0
    MODEL_ERRORS = 1  # the model has errors, or `--check` found drift
    INPUT_ERROR = 2  # the input could not be read, or the command was misused


def template_fields(template: str) -> frozenset[str]:
    """The named fields a str.format template uses (`{total:,}` uses `total`)."""
    return frozenset(name for _, name, _, _ in string.Formatter().parse(template) if name)


@dataclass(frozen=True)
class Message:
    """A message template and its hint template, str.format-style with named fields. A hint
    whose fields include a None value is left out (a parse error without a hint of its own)."""

    text: str
    hint: str | None = None

    @property
    def fields(self) -> frozenset[str]:
        """Every field the message and its hint need."""
        return template_fields(self.text) | template_fields(self.hint or "")

    def render(self, values: Mapping[str, object]) -> tuple[str, str | None]:
        """The message and hint with `values` filled in; every field exactly once, no extras,
        so a site that forgets a field or passes a stale one fails at once (in the tests)."""
        given = set(values)
        if given != self.fields:
            missing = sorted(self.fields - given)
            extra = sorted(given - self.fields)
            raise TypeError(f"message {self.text!r}: missing fields {missing}, unknown {extra}")
        hint = None
        if self.hint is not None and all(values[f] is not None for f in template_fields(self.hint)):
            hint = self.hint.format_map(values)
        return self.text.format_map(values), hint


@dataclass(frozen=True)
class Code:
    """A stable diagnostic code, its default severity and the messages it is reported with."""

    id: str
    name: str
    summary: str
    severity: Severity
    # Input problems end with exit code 2; model problems with 1.
    input_error: bool = False
    # Keyed by variant name, DEFAULT first; not part of equality (a code is its id).
    messages: Mapping[str, Message] = field(default_factory=dict, compare=False, hash=False)
    # The notes its diagnostics may carry, keyed by name (their `hint` is unused).
    note_templates: Mapping[str, Message] = field(default_factory=dict, compare=False, hash=False)
    # Why a withdrawn code is never reported (None: the code is in use); see `codes.retire`.
    retired: str | None = field(default=None, compare=False)

    def at(
        self,
        span: Span,
        variant: str = DEFAULT,
        /,
        *,
        notes: Sequence[str] = (),
        **values: object,
    ) -> Diagnostic:
        """The diagnostic of this code at `span`, its message (`variant`) filled with `values`."""
        text, hint = self.messages[variant].render(values)
        return Diagnostic(self, text, span, hint=hint, notes=tuple(notes))

    def note(self, name: str, /, **values: object) -> str:
        """The note `name` of this code with `values` filled in (for `at(..., notes=[...])`)."""
        return self.note_templates[name].render(values)[0]


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
        """The severity it is reported with."""
        return self.severity or self.code.severity

    def sort_key(self) -> tuple[str, int, int, str, str]:
        """Position first, then code and message: the order diagnostics are printed in."""
        return (self.span.file, self.span.line, self.span.col, self.code.id, self.message)

    def to_dict(self) -> dict[str, object]:
        """The JSON form (`--format json`)."""
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
    """A diagnostic with a ready message; stages use `Code.at` and the registered templates."""
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
    """Whether any diagnostic is an error."""
    return any(d.level is Severity.ERROR for d in diagnostics)


def exit_code_for(diagnostics: Sequence[Diagnostic]) -> ExitCode:
    """2 for input errors, 1 for model errors, else 0."""
    errors = [d for d in diagnostics if d.level is Severity.ERROR]
    if any(d.code.input_error for d in errors):
        return ExitCode.INPUT_ERROR
    return ExitCode.MODEL_ERRORS if errors else ExitCode.OK


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
