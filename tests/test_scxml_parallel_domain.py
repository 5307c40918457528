"""A transition out of (or into) a `<parallel>` child's own state leaves the whole `<parallel>`,
as W3C's transition domain says (the least common *compound* ancestor; a `<parallel>` is never
one) and Qt SCXML does, although the reader puts that child in a UML region of its own
(docs/scxml-input.md, "A transition out of a `<parallel>` child"). Found by the generated
charts' hunting mode (seed 21): every backend kept such a transition inside the child's region,
so the sibling regions' `onexit`/`onentry` did not run.

Each document counts entries and exits in its data, so a trace shows what was left and entered;
every backend and the emitted SCXML (in Qt) must give the trace Qt gives for the document as
written, and the one the W3C algorithm gives (written out by hand below)."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import replay
from tests.conftest import run_cli

HEAD = '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" datamodel="ecmascript"'
COUNTERS = '<datamodel><data id="ax" expr="0"/><data id="bx" expr="0"/><data id="bn" expr="0"/>'
B_REGION = """
    <state id="b">
      <onentry><assign location="bn" expr="bn + 1"/></onentry>
      <onexit><assign location="bx" expr="bx + 1"/></onexit>
      <state id="b1"><transition event="go" target="b2"/></state>
      <state id="b2"/>
    </state>"""


def _doc(name: str, a_region: str, initial: str = "p") -> str:
    return f"""{HEAD} initial="{initial}" name="{name}">
  {COUNTERS}</datamodel>
  <parallel id="p">{a_region}{B_REGION}
  </parallel>
</scxml>
"""


def _a(own: str = "", a2: str = "") -> str:
    """The `<parallel>`'s child `a`, with a transition of its own and one of `a2`'s."""
    return f"""
    <state id="a">
      <onexit><assign location="ax" expr="ax + 1"/></onexit>{own}
      <state id="a1"><transition event="go" target="a2"/></state>
      <state id="a2">{a2}</state>
    </state>"""


A_TO_CHILD = _a(own='<transition event="reset" target="a1"/>')
A_TO_ITSELF = _a(a2='<transition event="reset" target="a"/>')
A_SELF = _a(own='<transition event="reset" target="a"/>')
A_INTERNAL = _a(own='<transition event="reset" type="internal" target="a1"/>')
A_INSIDE = _a(a2='<transition event="reset" target="a1"/>')
HISTORY = '<history id="h"><transition target="a1"/></history>'
A_TO_HISTORY = _a(own=f'<transition event="reset" target="h"/>{HISTORY}')
A_INSIDE_TO_HISTORY = _a(a2='<transition event="reset" target="h"/>', own=HISTORY)

STEPS = [{"event": "go"}, {"event": "reset"}, {"event": "go"}]
START = {"ax": 0, "bx": 0, "bn": 1}
WHOLE = [START, START, {"ax": 1, "bx": 1, "bn": 2}, {"ax": 1, "bx": 1, "bn": 2}]  # p left
LOCAL_A = [START, START, START, START]  # only inside a: b stays in b2

CASES = {
    "to_child": (A_TO_CHILD, WHOLE),  # `a` -> a1: W3C leaves p (`a` is in the list)
    "to_itself": (A_TO_ITSELF, WHOLE),  # a2 -> `a`: the same
    "self": (A_SELF, WHOLE),  # `a` -> `a`: the same
    "internal": (A_INTERNAL, LOCAL_A),  # type="internal": stays in `a`, in W3C too
    "inside": (A_INSIDE, LOCAL_A),  # a2 -> a1: the domain is `a` in both
    # `a` -> its history: W3C's domain is that of the history's place, above p
    "to_history": (A_TO_HISTORY, WHOLE),
    # a2 -> a's history: the states it holds decide (here a2: the domain is `a`); kept
    "inside_to_history": (A_INSIDE_TO_HISTORY, LOCAL_A),
}


def _counters(trace: list[dict[str, object]]) -> list[dict[str, object]]:
    found = []
    for record in trace:
        data = record["data"]
        assert isinstance(data, dict)
        found.append({k: data[k] for k in ("ax", "bx", "bn")})
    return found


def _trace(
    tmp_path: Path, name: str, text: str, backend: str, steps: list[dict[str, object]]
) -> list[dict[str, object]]:
    """The document's trace in Qt (as written) or through a backend."""
    document = tmp_path / f"{name}.scxml"
    document.write_text(text, encoding="utf-8")
    if backend == "qt":
        return replay.run_qt(document, steps)
    (trace,) = replay.replay_many(document, name, [steps], backend)
    return trace


def _run(tmp_path: Path, name: str, text: str, backend: str) -> list[dict[str, object]]:
    """The counters after each of STEPS."""
    return _counters(_trace(tmp_path, name, text, backend, list(STEPS)))


@pytest.mark.parametrize("case", sorted(CASES))
def test_qt_runs_the_document_as_w3c_says(case: str, tmp_path: Path, qt_available: None) -> None:
    region, expected = CASES[case]
    assert _run(tmp_path, "Par", _doc("Par", region), "qt") == expected


@pytest.mark.parametrize("backend", ["asyncio", "smach", "scxml"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_every_backend_leaves_what_w3c_leaves(
    case: str, backend: str, tmp_path: Path, qt_available: None
) -> None:
    region, expected = CASES[case]
    assert _run(tmp_path, "Par", _doc("Par", region), backend) == expected


NESTED = f"""{HEAD} initial="top" name="Nest">
  {COUNTERS}</datamodel>
  <parallel id="top">
    <parallel id="p">
      <state id="a">
        <onexit><assign location="ax" expr="ax + 1"/></onexit>
        <transition event="reset" target="a1"/>
        <state id="a1"><transition event="go" target="a2"/></state>
        <state id="a2"/>
      </state>
      <state id="c"/>
    </parallel>{B_REGION}
  </parallel>
</scxml>
"""


@pytest.mark.parametrize("backend", ["qt", "asyncio", "scxml"])
def test_nested_parallels_are_all_left(backend: str, tmp_path: Path, qt_available: None) -> None:
    """`a` is a child of `p`, itself a child of `top`: W3C's domain is the root, so `b` (a
    child of `top`) is left too; the reader re-enters `top`, the outermost `<parallel>`."""
    assert _run(tmp_path, "Nest", NESTED, backend) == WHOLE


SIBLINGS = f"""{HEAD} initial="p" name="Siblings">
  <datamodel><data id="x" expr="0"/></datamodel>
  <parallel id="p">
    <onexit><assign location="x" expr="x + 1"/></onexit>
    <parallel id="q">
      <onexit><assign location="x" expr="x + 10"/></onexit>
      <state id="b"/>
      <state id="c"><transition event="e" target="b"/></state>
    </parallel>
    <state id="d"><onexit><assign location="x" expr="x + 100"/></onexit></state>
  </parallel>
</scxml>
"""


@pytest.mark.parametrize("backend", ["qt", "asyncio", "smach", "scxml"])
def test_a_transition_between_regions_of_a_nested_parallel_leaves_both(
    backend: str, tmp_path: Path, qt_available: None
) -> None:
    """`c` to `b`, two children of `q`, itself a child of `p`: W3C's domain is the root (no
    `<parallel>` is compound), so `p`, `q` and `d` are all exited (x = 111); the reader's region
    around `q` would have kept `p` and `d`. Found by the hunting mode."""
    trace = _trace(tmp_path, "Siblings", SIBLINGS, backend, [{"event": "e"}])
    assert [record["data"] for record in trace] == [{"x": 0}, {"x": 111}]


TOP = f"""{HEAD} initial="Top" name="Top">
  {COUNTERS}</datamodel>
  <parallel id="Top">{A_TO_CHILD}{B_REGION}
  </parallel>
</scxml>
"""


@pytest.mark.parametrize("backend", ["qt", "asyncio", "smach", "scxml"])
def test_the_machines_own_parallel_is_left(
    backend: str, tmp_path: Path, qt_available: None
) -> None:
    """A top `<parallel>` named after the document is the machine's own regions (docs/scxml.md):
    the transition re-enters the machine's parallel node."""
    assert _run(tmp_path, "Top", TOP, backend) == WHOLE


def test_the_emitted_document_says_it_and_reads_back_alike(tmp_path: Path) -> None:
    """swarmgen writes `target="a1 p"` (W3C's own way to say it), reads it back as the same
    transition, and `convert` keeps it in XMI as `reenters`."""
    document = tmp_path / "Par.scxml"
    document.write_text(_doc("Par", A_TO_CHILD), encoding="utf-8")
    first, second = tmp_path / "first", tmp_path / "second"
    assert run_cli("compile", str(document), "-o", str(first), "--backend", "scxml").returncode == 0
    emitted = (first / "scxml" / "Par.scxml").read_text(encoding="utf-8")
    assert '<transition event="reset" target="a1 p"/>' in emitted
    again = first / "scxml" / "Par.scxml"
    assert run_cli("compile", str(again), "-o", str(second), "--backend", "scxml").returncode == 0
    assert (second / "scxml" / "Par.scxml").read_text(encoding="utf-8") == emitted
    xmi = tmp_path / "Par.xmi"
    assert run_cli("convert", str(document), "-o", str(xmi)).returncode == 0
    assert 'target="a1" reenters="p"' in xmi.read_text(encoding="utf-8")
    third = tmp_path / "third"
    assert run_cli("compile", str(xmi), "-o", str(third), "--backend", "scxml").returncode == 0
    assert 'event="reset" target="a1 p"' in (third / "scxml" / "Par.scxml").read_text()


def test_a_reentered_state_that_does_not_hold_the_transition_is_reported(tmp_path: Path) -> None:
    document = tmp_path / "Par.scxml"
    document.write_text(_doc("Par", A_TO_CHILD), encoding="utf-8")
    xmi = tmp_path / "Par.xmi"
    assert run_cli("convert", str(document), "-o", str(xmi)).returncode == 0
    text = xmi.read_text(encoding="utf-8").replace('reenters="p"', 'reenters="b2"')
    xmi.write_text(text, encoding="utf-8")
    result = run_cli("validate", str(xmi))
    assert result.returncode == 1
    err = result.stdout + result.stderr
    assert "re-enters 'b2', which does not hold both its ends [SG103]" in err
    assert "Par.xmi:" in err
