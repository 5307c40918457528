"""Diagnostics as text (a compiler's lines with a source excerpt), JSON and SARIF 2.1.0."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from swarmgen.diagnostics.codes import CODES, active_codes
from swarmgen.diagnostics.model import Diagnostic, Severity
from swarmgen.span import Span


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
    """`{"diagnostics": [...], "summary": {errors, warnings}}`, as `--format json` prints it."""
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
    """`2 error(s), 1 warning(s)`."""
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


def messages_markdown() -> str:
    """The table of every code's messages and notes for docs/diagnostics.md (a test keeps it
    current); retired codes have none."""
    rows = ["| code | variant | message | hint |", "|---|---|---|---|"]
    for code in active_codes():
        for variant, message in code.messages.items():
            cells = (_template(message.text), _template(message.hint or ""))
            rows.append(f"| {code.id} | {variant} | {' | '.join(cells)} |")
        for key, note in code.note_templates.items():
            rows.append(f"| {code.id} | note: {key} | {_template(note.text)} |  |")
    return "\n".join(rows) + "\n"


def _template(text: str) -> str:
    """A template as a Markdown code cell (backticks become quotes, pipes are escaped)."""
    return "`" + text.replace("`", "'").replace("|", "\\|") + "`" if text else ""
