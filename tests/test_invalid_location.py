"""Locations an SCXML document reads or assigns that are none (W3C 5.4, 5.9.2, 6.2, 6.4): an
`<assign>` to a datum no `<data>` declares, a `<param location>` or namelist entry that names
none, or text that is no location. W3C raises error.execution when such a location is used and
the block ends; the SCXML reader keeps each as `invalid("...")` (SG158 warns of it), and
asyncio, smach, rclpy and the emitted SCXML run in Qt SCXML fail alike. A UML model's
undeclared name stays an error (SG112): only the SCXML reader makes `invalid(...)`."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, pipeline, replay
from tests.modelkit import ModelKit
from tests.skips import requires_rclpy

BACKENDS = ("asyncio", "smach", "scxml")


def test_the_language_reads_and_renders_an_invalid_location() -> None:
    (action,) = expr.parse_actions('invalid("foo.bar") = n + 1')
    bad = expr.Invalid(location="foo.bar")
    assert action == expr.Assign(target=bad, value=expr.parse_expr("n + 1"))
    read = expr.parse_expr('invalid("\\"foo") + 1')
    assert expr.parse_expr(expr.to_text(read)) == read
    assert expr.to_text(bad) == 'invalid("foo.bar")'
    assert expr.to_ecmascript(bad) == '$sg.invalid("foo.bar")'  # throws in the SCXML
    assert expr.to_python(bad, str, str) == "ctx.invalid('foo.bar')"  # raises in Python
    for wrong in ("invalid(x) = 1", 'invalid("") + 1', 'invalid("a", "b")'):
        with pytest.raises(expr.ExprError):
            expr.parse_actions(wrong)
    with pytest.raises(expr.ExprError):  # a binding sets a behaviour input, never a location
        expr.parse_bindings('invalid("x") = 1')


DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Iv">
  <datamodel><data id="n" expr="0"/><data id="errs" expr="0"/></datamodel>
  <state id="s0">
    <onentry>
      <assign location="nope" expr="1"/>
      <assign location="n" expr="100"/>
    </onentry>
    <onentry><assign location="n" expr="n + 1"/></onentry>
    <transition event="error.execution" target="s1">
      <assign location="errs" expr="errs + 1"/>
    </transition>
  </state>
  <state id="s1">
    <onentry>
      <assign location="n" expr="n + 10"/>
      <send event="leaked" namelist="n &quot;ghost"/>
    </onentry>
    <transition event="error.execution" target="s2">
      <assign location="errs" expr="errs + 1"/>
    </transition>
    <transition event="leaked" target="fail"/>
  </state>
  <state id="s2" initial="s21">
    <state id="s21"><transition target="s22"/></state>
    <final id="s22"><donedata><param name="x" location="ghost.field"/></donedata></final>
    <transition event="error.execution" target="s3">
      <assign location="errs" expr="errs + 1"/>
    </transition>
    <transition event="done.state.s2" target="fail"/>
  </state>
  <state id="s3"><transition event="go" cond="errs == 3" target="pass"/></state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""


def _write(tmp_path: Path, document: str, name: str) -> Path:
    source = tmp_path / f"{name}.scxml"
    source.write_text(document, encoding="utf-8")
    return source


def test_the_reader_keeps_them_with_a_warning(tmp_path: Path) -> None:
    found = pipeline.validate(_write(tmp_path, DOCUMENT, "Iv")).diagnostics
    warned = sorted((d.code.id, d.level.value, d.span.line) for d in found)
    assert [w for w in warned if w[0] != "SG202"] == [  # (SG202: `pass`/`fail` end the run)
        ("SG158", "warning", 3),
        ("SG158", "warning", 13),
        ("SG158", "warning", 25),
    ]
    messages = " ".join(d.message for d in found)
    assert "assigns `nope`" in messages and 'reads `"ghost`' in messages
    assert "reads `ghost.field`" in messages


def test_they_fail_alike_everywhere(tmp_path: Path, qt_available: None) -> None:
    """The assignment to `nope` ends its `<onentry>` (n is not 100), the next block runs; the
    send with an invalid namelist sends nothing (`leaked` never comes), the done data raises
    error.execution before done.state.s2: three errors, n = 11, then `go` reaches `pass`."""
    source = _write(tmp_path, DOCUMENT, "Iv")
    traces = {b: replay.replay(source, "Iv", [{"event": "go"}], b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    first, last = traces["scxml"]
    assert first["active"] == ["s3"] and first["data"] == {"errs": 3, "n": 11}
    assert first["errors"] == 3 and last["active"] == ["pass_"]


@requires_rclpy
def test_the_rclpy_host_agrees(tmp_path: Path, qt_available: None) -> None:
    source = _write(tmp_path, DOCUMENT, "Iv")
    traces = {b: replay.replay(source, "Iv", [{"event": "go"}], b) for b in ("rclpy", "scxml")}
    assert traces["rclpy"] == traces["scxml"]


INVOKE = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Ik">
  <datamodel><data id="errs" expr="0"/></datamodel>
  <state id="s0">
    <invoke type="http://www.w3.org/TR/scxml/" namelist="ghost">
      <content>
        <scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="f">
          <datamodel><data id="ghost" expr="0"/></datamodel>
          <final id="f"/>
        </scxml>
      </content>
    </invoke>
    <transition event="error.execution" target="s1">
      <assign location="errs" expr="errs + 1"/>
    </transition>
    <transition event="done.invoke" target="fail"/>
  </state>
  <state id="s1"><transition event="go" target="s2"/></state>
  <state id="s2"><transition event="done.invoke" target="fail"/></state>
  <final id="fail"/>
</scxml>
"""


def test_an_invalid_namelist_cancels_the_invoke(tmp_path: Path, qt_available: None) -> None:
    """W3C 6.4: the invoke does not start (no done.invoke ever comes) and error.execution is
    raised. The engine raises it in the macrostep that starts the invoke (W3C's main loop
    handles the internal queue again after the invokes); Qt SCXML 5.15 handles it only with
    the next external event, so Qt is compared where the run ends."""
    source = _write(tmp_path, INVOKE, "Ik")
    steps: list[dict[str, object]] = [{"event": "go"}, {"wait": 100}]
    traces = {b: replay.replay(source, "Ik", steps, b) for b in BACKENDS}
    assert traces["asyncio"] == traces["smach"]
    assert [r["active"] for r in traces["asyncio"]] == [["s1"], ["s2"], ["s2"]]
    assert traces["scxml"][-1] == traces["asyncio"][-1]
    assert traces["asyncio"][-1]["data"] == {"errs": 1}


def test_the_emitted_document_reads_back_to_itself(tmp_path: Path) -> None:
    """`invalid(...)` is written as `$sg.invalid("...")` (a read) or the location as it was (an
    `<assign>`), both read back as the same `invalid(...)`; the XMI conversion keeps it as
    written in the action language, and compiles to the same SCXML."""

    def body(path: Path) -> list[str]:
        files = pipeline.compile_model(path, ["scxml"]).files
        text = next(t for p, t in files.items() if p.suffix == ".scxml")
        return [line for line in text.splitlines() if "@generated" not in line]

    for name, document in (("Iv", DOCUMENT), ("Ik", INVOKE)):
        source = _write(tmp_path, document, name)
        emitted = tmp_path / f"emitted{name}.scxml"
        emitted.write_text("\n".join(body(source)), encoding="utf-8")
        assert "$sg.invalid(" in emitted.read_text(encoding="utf-8")
        assert body(emitted) == body(source)
        codes = [d.code.id for d in pipeline.validate(emitted).diagnostics]
        assert "SG158" in codes and "SG112" not in codes
    xmi = pipeline.convert_model(tmp_path / "Iv.scxml").xmi  # (an invoke has no XMI)
    assert xmi is not None and b'invalid("nope") = 1' in xmi
    converted = tmp_path / "converted.xmi"
    converted.write_bytes(xmi)
    assert body(converted) == body(tmp_path / "Iv.scxml")


def _machine_model(
    tmp_path: Path, effect: str, data: dict[str, tuple[str, object]] | None = None
) -> Path:
    kit = ModelKit("Iv")
    kit.event("go", sender="station")
    machine = kit.machine("BotMachine")
    machine.initial("Idle")
    machine.state("Idle")
    machine.final("Done")
    machine.transition("Idle", "Done", "go", effect=effect)
    kit.member("Bot", machine, data=data)
    kit.swarm("Swarm", {"Bot": 1})
    model = tmp_path / "iv.xmi"
    model.write_text(kit.xmi(), encoding="utf-8")
    return model


def test_an_xmi_models_undeclared_name_stays_an_error(tmp_path: Path) -> None:
    """The same assignment in a UML model is SG112, an error: only the SCXML reader reads an
    undeclared location as one that fails when it runs."""
    found = pipeline.validate(_machine_model(tmp_path, "nope = 1")).diagnostics
    assert [(d.code.id, d.level.value) for d in found if "nope" in d.message] == [
        ("SG112", "error")
    ]
    found = pipeline.validate(_machine_model(tmp_path, "x = ghost.field")).diagnostics
    assert {d.code.id for d in found if d.level.value == "error"} == {"SG112"}


def test_an_invalid_location_names_no_member_data(tmp_path: Path) -> None:
    """Written by hand, `invalid("x") = e` on member data x would be assigned by the emitted
    `<assign location="x">` in Qt SCXML where Python fails: SG159, an error. A location that
    is none (`ghost`) is only the warning."""
    data = {"count": ("Integer", 0)}
    found = pipeline.validate(_machine_model(tmp_path, 'invalid("count.x") = 1', data))
    assert [(d.code.id, d.level.value) for d in found.diagnostics if "count" in d.message] == [
        ("SG158", "warning"),
        ("SG159", "error"),
    ]
    found = pipeline.validate(_machine_model(tmp_path, 'invalid("ghost") = 1', data))
    assert [d.code.id for d in found.diagnostics if "ghost" in d.message] == ["SG158"]
