"""The bad-input corpus (tests/fixtures/bad/): every broken or hostile input ends in one clear
diagnostic and the documented exit code, never a traceback, and `compile` then writes nothing.

The real entry point is run as a subprocess (`python -m swarmgen`), `validate` and `compile` of one
case side by side, in a fresh working directory.
"""

from __future__ import annotations

import ast
import difflib
import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from lxml import etree

from swarmgen.scxml.emit import SUPPORT_SCRIPT

ROOT = Path(__file__).resolve().parent.parent
BAD = ROOT / "tests" / "fixtures" / "bad"
BASE = BAD / "valid_base.xmi"
PASSWD = Path("/etc/passwd")
SCXML_NS = "http://www.w3.org/2005/07/scxml"
SG_NS = "urn:swarmgen:scxml:1"
# Raw control characters (tab and newline aside) in output: terminal escapes, binary junk.
CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")
PASSWD_ENTRY = re.compile(r"^\w[\w.-]*:[^:\n]*:\d+:\d+:", re.MULTILINE)  # name:x:0:0:
IDENTS = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*(?: [A-Za-z_][A-Za-z0-9_.]*)*")

HOSTILE_STATE = "</state><script>alert(1)</script>"
HOSTILE_EVENT = 'x"; import os; os.system("rm -rf /") #'
HOSTILE_DATA = "note\n\"quoted\" 'single'\n</data>"
HOSTILE_DEFAULT = '");alert(1);("\n-->'
HOSTILE_MEMBER = "Drone-->mk2-"


@dataclass(frozen=True)
class Case:
    file: str  # a fixture, or "<directory>" / "<missing>", made at test time
    exit: int
    code: str | None  # the diagnostic code expected; None for a clean model

    @property
    def id(self) -> str:
        return self.file.removesuffix(".xmi").strip("<>")


CASES = [
    Case("valid_base.xmi", 0, None),
    # unreadable input: exit 2
    Case("not_xml.xmi", 2, "SG002"),
    Case("truncated.xmi", 2, "SG002"),
    Case("binary.xmi", 2, "SG002"),
    Case("xml_bomb.xmi", 2, "SG003"),
    Case("xxe_external_entity.xmi", 2, "SG003"),
    Case("xxe_utf16.xmi", 2, "SG003"),
    Case("xinclude_passwd.xmi", 2, "SG003"),
    Case("wrong_root.xmi", 2, "SG004"),
    Case("empty.xmi", 2, "SG001"),
    Case("whitespace_only.xmi", 2, "SG001"),
    Case("<directory>", 2, "SG001"),
    Case("<missing>", 2, "SG001"),
    Case("too_deep.xmi", 2, "SG005"),
    # model errors: exit 1
    Case("duplicate_ids.xmi", 1, "SG010"),
    Case("dangling_transition_target.xmi", 1, "SG011"),
    Case("dangling_trigger_event.xmi", 1, "SG011"),
    Case("dangling_stereotype_base.xmi", 1, "SG011"),
    Case("submachine_cycle.xmi", 1, "SG104"),
    Case("missing_initial.xmi", 1, "SG101"),
    Case("two_initials.xmi", 1, "SG102"),
    Case("guard_syntax.xmi", 1, "SG107"),
    Case("send_undeclared_event.xmi", 1, "SG106"),
    Case("doactivity_not_behaviour.xmi", 1, "SG105"),
    Case("trigger_undeclared_name.xmi", 1, "SG106"),
    Case("name_collision.xmi", 1, "SG110"),
    Case("outcome_without_behaviour.xmi", 1, "SG111"),
    Case("undeclared_outcome.xmi", 1, "SG119"),
    Case("huge_integer_default.xmi", 1, "SG122"),
    Case("infinite_real_default.xmi", 1, "SG122"),
    # hostile but valid: compiles, the hostile text stays data
    Case("hostile_names.xmi", 0, None),
    Case("hostile_comment_dashes.xmi", 0, None),
]


@dataclass(frozen=True)
class Run:
    exit: int
    stdout: str
    stderr: str

    @property
    def output(self) -> str:
        return self.stdout + self.stderr


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "SWARMGEN_DEBUG"}
    env["PYTHONIOENCODING"] = "utf-8"
    return env


def _swarmgen(*commands: list[str], cwd: Path) -> list[Run]:
    """Run several `swarmgen` command lines at once; their results in order."""
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "swarmgen", *args],
            cwd=cwd,
            env=_env(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for args in commands
    ]
    runs = []
    for proc in procs:
        out, err = proc.communicate(timeout=60)
        runs.append(
            Run(proc.returncode, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"))
        )
    return runs


def _model_path(case: Case, tmp_path: Path) -> Path:
    if case.file == "<directory>":
        path = tmp_path / "model_dir.xmi"
        path.mkdir()
        return path
    if case.file == "<missing>":
        return tmp_path / "no_such_model.xmi"
    return BAD / case.file


def _assert_no_crash(run: Run) -> None:
    assert "Traceback" not in run.output, run.output
    assert "internal error" not in run.output.lower(), run.output
    assert not CONTROL.search(run.output), f"raw control characters in output: {run.output!r}"


def _assert_nothing_of_passwd(text: str, *, code: bool = False) -> None:
    """No line of /etc/passwd; in diagnostics not even "root:" (generated code may say `root:`)."""
    assert not PASSWD_ENTRY.search(text)
    if not code:
        assert "root:" not in text
    if PASSWD.is_file():
        for line in PASSWD.read_text(encoding="utf-8", errors="replace").splitlines():
            if len(line.strip()) > 4:
                assert line not in text


def _assert_single_diagnostic(stdout: str, shown: str, code: str) -> None:
    """`file[:line:col]: error: message [SG00x]`, then only indented lines."""
    lines = stdout.rstrip("\n").split("\n")
    pattern = rf"{re.escape(shown)}(:\d+:\d+)?: error: .+ \[{code}\]"
    assert re.fullmatch(pattern, lines[0]), stdout
    assert all(line.startswith("  ") for line in lines[1:]), stdout


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_bad_input(case: Case, tmp_path: Path) -> None:
    model = _model_path(case, tmp_path)
    work = tmp_path / "cwd"
    work.mkdir()
    out = tmp_path / "out"
    validate, compile_ = _swarmgen(
        ["validate", str(model)], ["compile", str(model), "-o", str(out)], cwd=work
    )
    for run in (validate, compile_):
        _assert_no_crash(run)
        _assert_nothing_of_passwd(run.output)
    assert validate.exit == case.exit, validate.output
    assert compile_.exit == case.exit, compile_.output
    assert list(work.iterdir()) == []  # nothing written to the working directory
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".out")]
    assert leftovers == []  # no staging directory left behind

    if case.code is None:
        assert ": error: " not in validate.stdout, validate.stdout  # warnings are allowed
        assert "0 error(s)" in validate.stderr
        _assert_clean_output(out)
        return

    assert not out.exists(), "compile wrote output for a model with errors"
    assert f"[{case.code}]" in validate.stdout, validate.output
    assert f"[{case.code}]" in compile_.stderr, compile_.output
    assert "nothing written" in compile_.stderr
    if case.exit == 2:
        _assert_single_diagnostic(validate.stdout, str(model), case.code)


def _assert_clean_output(out: Path) -> None:
    """SCXML that parses, holds no <script> and keeps model text out of element content and
    identifiers; generated Python that parses and calls nothing the model's names spell."""
    for path in sorted(out.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        _assert_nothing_of_passwd(source, code=True)
        for node in ast.walk(ast.parse(source, filename=str(path))):
            if isinstance(node, ast.Call):
                callee = node.func
                name = (
                    callee.attr if isinstance(callee, ast.Attribute) else getattr(callee, "id", "")
                )
                assert name not in {"system", "alert"}, f"{path}: model text became code"
    documents = sorted((out / "scxml").glob("*.scxml"))
    assert documents
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    for path in documents:
        raw = path.read_text(encoding="utf-8")
        _assert_nothing_of_passwd(raw)
        # one <script>: swarmgen's own support script, exactly
        assert raw.lower().count("<script") == 1
        root = etree.fromstring(raw.encode("utf-8"), parser)
        scripts = list(root.iter("{http://www.w3.org/2005/07/scxml}script"))
        assert len(scripts) == 1 and scripts[0].text == SUPPORT_SCRIPT
        assert scripts[0].getparent() is root
        for element in root.iter():
            if not isinstance(element.tag, str):  # the header comment
                text = element.text or ""
                assert "--" not in text, text
                continue
            if element is scripts[0]:
                continue
            for text in (element.text, element.tail):  # hostile names only in attributes
                assert not text or text.strip() == "", (element.tag, text)
            if etree.QName(element).namespace == SCXML_NS:
                for attribute in ("id", "target", "initial", "event", "location"):
                    value = element.get(attribute)
                    if attribute == "target" and value == "#_internal":
                        continue  # <send target="#_internal">: raise with data
                    assert value is None or IDENTS.fullmatch(value), (attribute, value)


def test_hostile_names_stay_escaped_attribute_text(tmp_path: Path) -> None:
    """The hostile names arrive intact as attribute values, and never as markup or code."""
    out = tmp_path / "out"
    (run,) = _swarmgen(["compile", str(BAD / "hostile_names.xmi"), "-o", str(out)], cwd=tmp_path)
    assert run.exit == 0, run.output
    raw = (out / "scxml" / "Drone.scxml").read_text(encoding="utf-8")
    assert "&lt;/state&gt;&lt;script&gt;" in raw
    root = etree.fromstring(raw.encode("utf-8"))
    by_name = {e.get(f"{{{SG_NS}}}name"): e for e in root.iter(f"{{{SCXML_NS}}}*")}
    assert etree.QName(by_name[HOSTILE_STATE]).localname == "state"
    data = by_name[HOSTILE_DATA]
    assert etree.QName(data).localname == "data"
    assert json.loads(data.get("expr", "")) == HOSTILE_DEFAULT  # one string literal, no code
    events = {e.get("name"): e for e in root.iter(f"{{{SG_NS}}}event")}
    assert HOSTILE_EVENT in events
    ident = events[HOSTILE_EVENT].get("id")
    assert ident and IDENTS.fullmatch(ident)
    assert [t.get("event") for t in root.iter(f"{{{SCXML_NS}}}transition")].count(ident) == 1


def test_dashes_in_file_and_member_names(tmp_path: Path) -> None:
    """File and member type names go into the header comment, where `--` is not allowed."""
    model = tmp_path / "my--model-.xmi"
    shutil.copyfile(BAD / "hostile_comment_dashes.xmi", model)
    out = tmp_path / "out"
    (run,) = _swarmgen(["compile", str(model), "-o", str(out)], cwd=tmp_path)
    _assert_no_crash(run)
    assert run.exit == 0, run.output
    (document,) = (out / "scxml").glob("*.scxml")
    root = etree.parse(str(document)).getroot()
    assert root.get(f"{{{SG_NS}}}member") == HOSTILE_MEMBER
    _assert_clean_output(out)


def test_json_format_on_a_model_error(tmp_path: Path) -> None:
    (run,) = _swarmgen(
        ["validate", str(BAD / "guard_syntax.xmi"), "--format", "json"], cwd=tmp_path
    )
    _assert_no_crash(run)
    assert run.exit == 1
    payload = json.loads(run.stdout)
    assert "SG107" in [d["code"] for d in payload["diagnostics"]]
    assert payload["summary"]["errors"] >= 1


def test_failed_compile_leaves_previous_output_alone(tmp_path: Path) -> None:
    out = tmp_path / "out"
    (first,) = _swarmgen(["compile", str(BASE), "-o", str(out)], cwd=tmp_path)
    assert first.exit == 0, first.output
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    (second,) = _swarmgen(["compile", str(BAD / "guard_syntax.xmi"), "-o", str(out)], cwd=tmp_path)
    _assert_no_crash(second)
    assert second.exit == 1
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


MODEL_ERRORS = [c for c in CASES if c.exit == 1]


@pytest.mark.parametrize("case", MODEL_ERRORS, ids=lambda c: c.id)
def test_model_fixture_is_the_base_with_one_change(case: Case) -> None:
    """Each model-level fixture differs from valid_base.xmi in at most two lines each way."""
    base = BASE.read_text(encoding="utf-8").splitlines()
    fixture = (BAD / case.file).read_text(encoding="utf-8").splitlines()
    diff = [d for d in difflib.ndiff(base, fixture) if d[:1] in "+-" and d[:2] != "? "]
    removed = [d for d in diff if d.startswith("- ")]
    added = [d for d in diff if d.startswith("+ ")]
    assert diff and len(removed) <= 2 and len(added) <= 2, diff


def test_readme_table_matches_the_cases() -> None:
    rows = re.findall(
        r"^\| `([^`]+)` \| .+ \| (\d) \|\s*(SG\d{3})?\s*\|$",
        (BAD / "README.md").read_text(encoding="utf-8"),
        flags=re.MULTILINE,
    )
    documented = {(file, int(exit_), code or None) for file, exit_, code in rows}
    assert documented == {(c.file, c.exit, c.code) for c in CASES}
    on_disk = {p.name for p in BAD.glob("*.xmi")}
    assert on_disk == {c.file for c in CASES if not c.file.startswith("<")}
