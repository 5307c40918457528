"""W3C `<invoke>` of SCXML sessions (docs/semantics.md, "Invoked sessions"; docs/scxml-input.md,
"Invoke"): a child document inline or from a file run by the runtime engine as a session of its
own, the same trace in asyncio, smach and the emitted SCXML in Qt SCXML; id and idlocation,
params and namelist, finalize, autoforward, #_parent and #_<id> targets, done.invoke, the
cancellation of a session whose state is exited; the documents the reader refuses, located."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest

from swarmgen import pipeline, replay
from swarmgen.conformance import irp
from tests.conftest import run_cli
from tests.skips import need_rclpy

BACKENDS = ("asyncio", "smach", "scxml")
FIXTURES = Path(__file__).parent / "fixtures" / "invoke"
# parent.scxml: s0 invokes `kid` (param y = 21), which sends hello(v = y + 1) to its parent
# (finalize: x = v), gets `go` from it and ends (done.invoke.kid); s1 invokes an echo with
# idlocation and autoforward, which answers the forwarded `ping` with `pong`; s2 invokes a
# session that would send `late` to its parent after 300 ms, but s2 is left first (`leave`):
# the session is cancelled and `late` never comes.
STEPS: list[dict[str, Any]] = [
    {"wait": 50},
    {"event": "ping"},
    {"event": "leave"},
    {"wait": 500},
    {"event": "finish"},
]


def _normalised(trace: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """A made invoke id is the platform's own (W3C 6.4: `stateid.platformid`): only its form
    is compared."""
    for step in trace:
        where = step["data"]["where"]
        step["data"]["where"] = where.startswith("s1.") if where else where
    return trace


def test_sessions_agree_in_every_backend(tmp_path: Path, qt_available: None) -> None:
    source = tmp_path / "parent.scxml"
    shutil.copy(FIXTURES / "parent.scxml", source)
    traces = {b: _normalised(replay.replay(source, "Parent", STEPS, b)) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    first, pinged, left, waited, finished = traces["scxml"][1:]
    assert first["active"] == ["s1"]  # kid ended: done.invoke.kid
    assert first["data"] == {"r": 44, "same": False, "where": True, "x": 22}
    assert pinged["active"] == ["s2"] and pinged["data"]["same"] is True  # autoforwarded
    assert left["active"] == waited["active"] == ["s3"]  # `late` was cancelled with s2
    assert finished["active"] == ["pass_"]
    assert all(step["errors"] == 0 for step in traces["scxml"])


def test_sessions_run_the_same_on_rclpy(tmp_path: Path) -> None:
    """The ROS node processes an event as it arrives: a child's first events reach its parent
    while the parent is still starting it, and wait for the parent's macrostep to end."""
    need_rclpy()
    source = tmp_path / "parent.scxml"
    shutil.copy(FIXTURES / "parent.scxml", source)
    ours = _normalised(replay.replay(source, "Parent", STEPS, "asyncio"))
    assert _normalised(replay.replay(source, "Parent", STEPS, "rclpy")) == ours


def test_a_src_document_runs_as_its_inline_copy_in_qt(tmp_path: Path, qt_available: None) -> None:
    """`src` below the document's folder; namelist gives the child's `step`; the emitted
    SCXML carries the child inline, which Qt SCXML runs with the same trace."""
    for name in ("from_file.scxml", "counter.scxml"):
        shutil.copy(FIXTURES / name, tmp_path / name)
    source = tmp_path / "from_file.scxml"
    steps: list[dict[str, Any]] = [{"wait": 50}, {"event": "again"}, {"wait": 50}]
    traces = {b: replay.replay(source, "FromFile", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    # ticks at n = 0 and 2 (step 2 from the parent), the last n written by finalize
    assert traces["scxml"][0]["active"] == ["idle"]
    assert traces["scxml"][0]["data"] == {"last": 2, "step": 2, "ticks": 2}
    assert traces["scxml"][-1]["data"] == {"last": 2, "step": 2, "ticks": 4}


def test_the_emitted_document_reads_back_to_itself(tmp_path: Path) -> None:
    first = run_cli("compile", str(FIXTURES / "parent.scxml"), "-o", str(tmp_path / "first"))
    assert first.returncode == 0, first.stdout + first.stderr
    document = tmp_path / "first" / "scxml" / "Parent.scxml"
    text = document.read_text()
    assert text.count("<invoke ") == 3 and text.count("<scxml ") == 4
    again = run_cli("compile", str(document), "-o", str(tmp_path / "again"))
    assert again.returncode == 0, again.stdout + again.stderr
    written = (tmp_path / "again" / "scxml" / "Parent.scxml").read_text()
    assert written.splitlines()[2:] == text.splitlines()[2:]


def _outcome(tmp_path: Path, document: str) -> irp.Outcome:
    path = tmp_path / "doc.scxml"
    return irp.run_document(document.encode(), path)


def _doc(body: str) -> str:
    return (
        '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="D">'
        f'{body}<final id="pass"/><final id="fail"/></scxml>'
    )


CHILD = '<content><scxml version="1.0" initial="f"><final id="f">{}</final></scxml></content>'


def test_done_invoke_carries_the_childs_done_data(tmp_path: Path) -> None:
    """W3C: the done.invoke event of a child that reached a top-level final state with
    `<donedata>` carries it (Qt SCXML's carries none: docs/semantics.md)."""
    done = CHILD.format('<donedata><param name="k" expr="7"/></donedata>')
    body = (
        '<datamodel><data id="k" expr="0"/></datamodel><state id="s0">'
        f'<invoke type="scxml" id="c">{done}</invoke>'
        '<transition event="done.invoke.c" cond="_event.data.k == 7" target="pass"/>'
        '<transition event="*" target="fail"/></state>'
    )
    assert _outcome(tmp_path, _doc(body)).result == "pass"


def test_a_failed_typeexpr_is_an_execution_error(tmp_path: Path) -> None:
    """A type computed at run time that is no SCXML session: error.execution, nothing runs."""
    body = (
        '<datamodel><data id="t" expr="\'http\'"/></datamodel><state id="s0">'
        f'<invoke typeexpr="t">{CHILD.format("")}</invoke>'
        '<transition event="error.execution" target="pass"/>'
        '<transition event="done.invoke" target="fail"/></state>'
    )
    assert _outcome(tmp_path, _doc(body)).result == "pass"


def test_a_session_that_invokes_itself_is_bounded_when_read(tmp_path: Path) -> None:
    source = tmp_path / "again.scxml"
    source.write_text(_doc('<state id="s0"><invoke type="scxml" src="again.scxml"/></state>'))
    found = pipeline.validate(source).diagnostics
    nested = [d for d in found if "nest deeper than 8" in d.message]
    assert [d.code.id for d in nested] == ["SG070"], found
    assert nested[0].span.line == 1 and nested[0].span.file.endswith("again.scxml")
    compiled = run_cli("compile", str(source), "-o", str(tmp_path / "out"))
    assert compiled.returncode == 2 and "SG070" in compiled.stdout + compiled.stderr
    assert not (tmp_path / "out").exists()  # nothing written


# (a namelist entry that is no datum, `&quot;x`, is no error: W3C 6.4 cancels the invoke with
# error.execution when it runs, as the engine does; tests/test_invalid_location.py)
BAD = {
    "other type": ('<invoke type="http://example.org/x"/>', "SG060"),
    "outside the folder": ('<invoke src="../outside.scxml"/>', "SG070"),
    "absolute": ('<invoke src="/etc/hostname"/>', "SG070"),
    "url": ('<invoke src="http://example.org/c.scxml"/>', "SG070"),
    "no document": ("<invoke/>", "SG070"),
    "two documents": (f'<invoke src="c.scxml">{CHILD.format("")}</invoke>', "SG070"),
    "srcexpr": ("<invoke srcexpr=\"'c.scxml'\"/>", "SG070"),
    "not scxml": ('<invoke src="c.xml"/>', "SG070"),
    "missing": ('<invoke src="none.scxml"/>', "SG001"),
    "finalize outside": ("<finalize/>", "SG060"),
    "bad child": (
        '<invoke><content><scxml version="1.0" initial="nowhere"><state id="a"/></scxml>'
        "</content></invoke>",
        "SG061",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_invokes_are_located_errors(case: str, tmp_path: Path) -> None:
    invoke, code = BAD[case]
    (tmp_path / "c.xml").write_text("<notscxml/>")
    (tmp_path / "outside.scxml").write_text(_doc('<state id="s0"/>'))
    folder = tmp_path / "model"
    folder.mkdir()
    source = folder / "bad.scxml"
    source.write_text(_doc(f'<state id="s0">\n{invoke}</state>').replace("c.xml", "../c.xml"))
    (folder / "c.scxml").write_text(_doc('<state id="s0"/>'))
    if case == "not scxml":
        (folder / "c.xml").write_text("<notscxml/>")
        source.write_text(_doc(f'<state id="s0">\n{invoke}</state>'))
    found = [d for d in pipeline.validate(source).diagnostics if d.code.id == code]
    assert found, (case, pipeline.validate(source).diagnostics)
    assert found[0].span.line == 2 or code in ("SG001", "SG061")


def test_invoked_documents_are_bounded_in_number(tmp_path: Path) -> None:
    """Fan-out times nesting: 3 invokes of itself per document would be 3^8 documents."""
    source = tmp_path / "many.scxml"
    three = '<invoke type="scxml" src="many.scxml"/>' * 3
    source.write_text(_doc(f'<state id="s0">{three}</state>'))
    found = pipeline.validate(source).diagnostics
    assert any(d.code.id == "SG070" and "more than 64" in d.message for d in found), found


def test_an_invoke_in_a_final_state_is_refused(tmp_path: Path) -> None:
    source = tmp_path / "final.scxml"
    invoke = f'<invoke type="scxml">{CHILD.format("")}</invoke>'
    source.write_text(_doc(f'<state id="s0"/><final id="f">\n{invoke}</final>'))
    found = pipeline.validate(source).diagnostics
    assert [(d.code.id, d.span.line) for d in found] == [("SG060", 2)]
    assert "read in a <state> or <parallel> only" in found[0].message


def test_convert_and_verify_refuse_a_document_with_invokes(tmp_path: Path) -> None:
    """The swarm profile has no invoke: convert writes nothing (SG070 at the invoke); the
    verifier does not explore child sessions and says so."""
    converted = run_cli("convert", str(FIXTURES / "parent.scxml"), "-o", str(tmp_path / "p.xmi"))
    assert converted.returncode == 2
    assert "parent.scxml:7:5: error: <invoke> has no form in UML XMI" in converted.stderr
    assert not (tmp_path / "p.xmi").exists()
    verified = run_cli("verify", str(FIXTURES / "parent.scxml"))
    assert verified.returncode == 2
    assert "invokes SCXML sessions (<invoke>), which the verifier does not explore" in (
        verified.stderr
    )
