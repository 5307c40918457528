"""`startswith(text, prefix)`: whether a string begins with another (IRP test 224's
`conf:varPrefix`). Both operands are strings: the checker refuses another type (SG208) and an
untyped value that is no string fails when it runs (error.execution), the same in asyncio,
smach and the emitted SCXML in Qt SCXML (`$sg.startswith`). The SCXML reader reads
ECMAScript's `t.startsWith(p)` as it."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, pipeline, replay
from swarmgen.frontend.scxml_expr import translate
from tests.skips import requires_rclpy

BACKENDS = ("asyncio", "smach", "scxml")


def test_the_language_reads_and_renders_it() -> None:
    found = expr.parse_expr('startswith(id, "s0.") and not startswith(event.f, id)')
    assert expr.parse_expr(expr.to_text(found)) == found
    one = expr.parse_expr('startswith(a, "x")')
    assert one == expr.StartsWith(text=expr.Name(name="a"), prefix=expr.Const(value="x"))
    assert expr.to_ecmascript(one) == '$sg.startswith(a, "x")'
    assert expr.to_python(one, str, str) == "ctx.startswith(a, 'x')"
    assert translate("a.startsWith('x')", lambda n: n) == one  # ECMAScript's method
    assert translate('$sg.startswith(a, "x")', lambda n: n) == one  # as the emitter writes it
    for wrong in ("startswith(a)", "startswith(a, b, c)", "startswith a, b"):
        with pytest.raises(expr.ExprError):
            expr.parse_expr(wrong)
    assert expr.parse_expr("startswith + 1") == expr.parse_expr("startswith + 1")  # still a name


DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Sw">
  <datamodel>
    <data id="id" expr="'s0.abc'"/><data id="pre" expr="'s0.'"/><data id="n" expr="0"/>
    <data id="u" expr="n + 1"/>
  </datamodel>
  <state id="s0">
    <transition event="go" cond="id.startsWith(pre) &amp;&amp; !pre.startsWith(id)" target="s1">
      <assign location="n" expr="n + 1"/>
    </transition>
  </state>
  <state id="s1">
    <transition event="go" cond="u.startsWith('x')" target="fail"/>
    <transition event="error.execution" target="s2"/>
  </state>
  <state id="s2"><transition event="go" cond="id.startsWith('')" target="pass"/></state>
  <final id="pass"/>
  <final id="fail"/>
</scxml>
"""


def test_it_agrees_everywhere(tmp_path: Path, qt_available: None) -> None:
    """A prefix holds and the reverse does not; an untyped number fails (error.execution, the
    cond is false); every string starts with ""."""
    source = tmp_path / "sw.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    steps: list[dict[str, object]] = [{"event": "go"}] * 3
    traces = {b: replay.replay(source, "Sw", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    assert [r["active"] for r in traces["scxml"]] == [["s0"], ["s1"], ["s2"], ["pass_"]]
    assert traces["scxml"][-1]["errors"] == 1 and traces["scxml"][-1]["data"]["n"] == 1


@requires_rclpy
def test_the_rclpy_host_agrees(tmp_path: Path, qt_available: None) -> None:
    source = tmp_path / "sw.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    steps: list[dict[str, object]] = [{"event": "go"}] * 3
    traces = {b: replay.replay(source, "Sw", steps, b) for b in ("rclpy", "scxml")}
    assert traces["rclpy"] == traces["scxml"]


def test_the_emitted_document_reads_back_to_itself(tmp_path: Path) -> None:
    def body(path: Path) -> list[str]:
        files = pipeline.compile_model(path, ["scxml"]).files
        text = next(t for p, t in files.items() if p.suffix == ".scxml")
        return [line for line in text.splitlines() if "@generated" not in line]

    source = tmp_path / "sw.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    emitted = tmp_path / "emitted.scxml"
    emitted.write_text("\n".join(body(source)), encoding="utf-8")
    assert "$sg.startswith = function" in emitted.read_text(encoding="utf-8")
    assert body(emitted) == body(source)


def test_both_operands_are_strings(tmp_path: Path) -> None:
    source = tmp_path / "sw.scxml"
    source.write_text(DOCUMENT.replace("u.startsWith('x')", "n.startsWith(1)"), encoding="utf-8")
    found = [d for d in pipeline.validate(source).diagnostics if d.code.id == "SG208"]
    assert len(found) == 1 and "'startswith' takes strings, not a number" in found[0].message
