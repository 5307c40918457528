"""The diagnostic registry: every code has its messages, templates fill exactly their fields,
stages report through the templates, and docs/diagnostics.md lists every message."""

from __future__ import annotations

import ast
import keyword
from pathlib import Path

import pytest

from swarmgen import diagnostics as dg
from swarmgen.diagnostics.render import messages_markdown
from swarmgen.span import Span

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "diagnostics.md"
BEGIN, END = "<!-- messages: begin -->", "<!-- messages: end -->"
SPAN = Span(file="m.xmi", line=3, col=5)
VARIANTS = [(c, v) for c in dg.CODES.values() for v in c.messages]
NOTES = [(c, n) for c in dg.CODES.values() for n in c.note_templates]


def test_every_code_has_a_message() -> None:
    assert [c.id for c in dg.active_codes() if not c.messages] == []


def test_retired_codes_keep_their_ids_and_nothing_else() -> None:
    """A retired code cannot be reported (no messages), and docs list it as retired."""
    retired = [c for c in dg.CODES.values() if c.retired is not None]
    assert [c.id for c in retired] == ["SG020", "SG121"]
    assert all(not c.messages and not c.note_templates for c in retired)
    assert set(dg.CODES) - {c.id for c in dg.active_codes()} == {c.id for c in retired}
    doc = DOC.read_text()
    section = doc.split("| code | name | why retired |", 1)[1].split("\n\n", 1)[0]
    for code in retired:
        assert f"| {code.id} | `{code.name}` | {code.retired} |" in section
    with pytest.raises(AssertionError):
        dg.retire("SG020", "again", "reused", dg.Severity.NOTE, "an id is never reused")


@pytest.mark.parametrize(("code", "variant"), VARIANTS, ids=[f"{c.id}-{v}" for c, v in VARIANTS])
def test_template_fields_are_names_and_render(code: dg.Code, variant: str) -> None:
    message = code.messages[variant]
    assert message.text.strip()
    for name in message.fields:
        assert name.isidentifier() and not keyword.iskeyword(name), (code.id, name)
    values = dict.fromkeys(message.fields, 1)  # 1 fits every format spec used (`:,`, `:.0f`)
    d = code.at(SPAN, variant, notes=["n"], **values)
    assert d.code is code and d.span == SPAN and d.notes == ("n",)
    assert "{" not in d.message.replace("{{", "")
    assert (d.hint is None) == (message.hint is None)


@pytest.mark.parametrize(("code", "note"), NOTES, ids=[f"{c.id}-{n}" for c, n in NOTES])
def test_note_templates_render(code: dg.Code, note: str) -> None:
    template = code.note_templates[note]
    assert template.text.strip() and template.hint is None
    text = code.note(note, **dict.fromkeys(template.fields, 1))
    assert text and "{" not in text.replace("{{", "")


def test_a_note_with_a_missing_field_fails() -> None:
    with pytest.raises(TypeError, match="missing fields \\['where'\\]"):
        dg.DUPLICATE_ID.note("first-used")
    assert dg.DUPLICATE_ID.note("first-used", where="m.xmi:3:5") == "first used at m.xmi:3:5"


def test_a_missing_or_unknown_field_fails() -> None:
    with pytest.raises(TypeError, match="missing fields \\['machine'\\]"):
        dg.UNREACHABLE_STATE.at(SPAN, state="Idle")
    with pytest.raises(TypeError, match="unknown \\['extra'\\]"):
        dg.UNREACHABLE_STATE.at(SPAN, state="Idle", machine="M", extra=1)
    with pytest.raises(KeyError):
        dg.UNREACHABLE_STATE.at(SPAN, "no-such-variant", state="Idle", machine="M")


def test_rendering_is_the_template_filled() -> None:
    d = dg.UNREACHABLE_STATE.at(SPAN, state="Idle", machine="M")
    assert d.message == "state 'Idle' of 'M' can never be entered"
    assert d.hint == "add a transition to it, or remove it"
    big = dg.MODEL_TOO_LARGE.at(SPAN, machine="M", total=12345, limit=10000)
    assert "has 12,345 states" in big.message and "the limit is 10,000" in big.message


def test_a_hint_with_an_unknown_field_is_left_out() -> None:
    assert dg.GUARD_SYNTAX.at(SPAN, error="x", hint=None).hint is None
    assert dg.GUARD_SYNTAX.at(SPAN, error="x", hint="use ==").hint == "use =="


def test_stages_report_through_the_registry() -> None:
    """No stage builds a message at the call site with `dg.diag`: every one uses `Code.at`."""
    offenders = []
    for path in sorted((ROOT / "swarmgen").rglob("*.py")):
        if "diagnostics" in path.relative_to(ROOT / "swarmgen").parts[:1]:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "diag"
            ):
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == []


def _literal_text(node: ast.AST) -> bool:
    """Whether an expression writes message text: an f-string, or a string as a list item or
    an operand of `+` (a note's name, or the separator of a `.join`, is no text)."""
    if isinstance(node, ast.JoinedStr):
        return True
    if isinstance(node, ast.List | ast.Tuple):
        parts = node.elts
    elif isinstance(node, ast.BinOp):
        parts = [node.left, node.right]
    else:
        return False
    return any(isinstance(p, ast.Constant) and isinstance(p.value, str) for p in parts)


def test_notes_come_from_the_registry() -> None:
    """No stage writes a note's text at the call site: notes are `code.note(name, ...)`."""
    offenders = []
    for path in sorted((ROOT / "swarmgen").rglob("*.py")):
        if "diagnostics" in path.relative_to(ROOT / "swarmgen").parts[:1]:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
                continue
            if node.func.attr != "at":
                continue
            for keyword_ in node.keywords:
                if keyword_.arg == "notes" and any(
                    _literal_text(n) for n in ast.walk(keyword_.value)
                ):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == []


def test_docs_list_every_message() -> None:
    text = DOC.read_text()
    assert BEGIN in text and END in text, f"docs/diagnostics.md needs {BEGIN} ... {END}"
    shown = text.split(BEGIN, 1)[1].split(END, 1)[0].strip() + "\n"
    assert shown == messages_markdown(), (
        "docs/diagnostics.md is stale: replace its messages table with "
        "swarmgen.diagnostics.render.messages_markdown()"
    )
