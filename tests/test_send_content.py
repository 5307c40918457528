"""Issue 15's send and data features, the same trace in asyncio, smach and the emitted SCXML
run in Qt SCXML: `_ioprocessors.scxml.location` (W3C's `_ioprocessors[<processor>].location`),
`raise (expr)` (`<send eventexpr>`), `raise e(expr)` (`<send>` with `<content>`: the event's
data is the value) and `<data src>` read when the document is compiled."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, pipeline, replay
from tests.skips import requires_rclpy

BACKENDS = ("asyncio", "smach", "scxml")

PROCESSORS = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Io">
  <datamodel>
    <data id="where" expr="_ioprocessors['http://www.w3.org/TR/scxml/#SCXMLEventProcessor'].location"/>
    <data id="own" expr="''"/>
  </datamodel>
  <state id="s0">
    <transition event="go" cond="where == '#_scxml_' + _sessionid" target="s1">
      <assign location="own" expr="_ioprocessors.scxml.location"/>
    </transition>
  </state>
  <state id="s1"><transition event="go" cond="own == where" target="pass"/></state>
  <final id="pass"/>
</scxml>
"""


def _agree(
    tmp_path: Path, document: str, name: str, steps: list[dict[str, object]]
) -> list[dict[str, object]]:
    source = tmp_path / f"{name}.scxml"
    source.write_text(document, encoding="utf-8")
    traces = {b: replay.replay(source, name, steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        if backend != "scxml":  # the session id is each engine's own string: compared apart
            assert _no_session(trace) == _no_session(traces["scxml"]), (
                f"{backend} differs from Qt SCXML:\n{trace}"
            )
    return traces["scxml"]


def _no_session(trace: list[dict[str, object]]) -> list[object]:
    return [{k: v for k, v in step.items() if k != "data"} for step in trace]


def test_the_language_reads_the_processor_location() -> None:
    value = expr.parse_expr("_ioprocessors.scxml.location")
    assert expr.to_text(value) == "_ioprocessors.scxml.location"
    # Qt SCXML names the processor `scxml` only (W3C's URI key is undefined there)
    assert expr.to_ecmascript(value) == "_ioprocessors.scxml.location"
    for bad in ("_ioprocessors.http", "_ioprocessors.scxml", "_ioprocessors.scxml.foo"):
        with pytest.raises(expr.ExprError):
            expr.parse_expr(bad)


def test_the_processor_location_is_this_session(tmp_path: Path, qt_available: None) -> None:
    # (sending to it is compared on the engine only: Qt SCXML drops what a document sends to its
    # own session in the replay harness, docs/semantics.md "Targets"; IRP test 501)
    trace = _agree(tmp_path, PROCESSORS, "Io", [{"event": "go"}, {"event": "go"}])
    assert trace[-1]["active"] == ["pass_"]


COMPUTED = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Ee">
  <datamodel>
    <data id="which" expr="'foo'"/><data id="got" expr="''"/><data id="n" expr="0"/>
    <data id="xs" expr="[0]"/>
  </datamodel>
  <state id="s0">
    <onentry><send eventexpr="which" delay="10ms"/></onentry>
    <transition event="foo" target="s1"><assign location="got" expr="_event.name"/></transition>
  </state>
  <state id="s1">
    <onentry><send event="bar" delay="10ms"><content expr="120 + 3"/></send></onentry>
    <transition event="bar" cond="_event.data == 123" target="s2"/>
  </state>
  <state id="s2">
    <onentry><send eventexpr="'ba' + 'z'" target="#_internal"><content>7</content></send></onentry>
    <transition event="baz" target="s3"><assign location="n" expr="_event.data"/></transition>
  </state>
  <state id="s3">
    <onentry><send eventexpr="'qu' + 'x'" target="#_internal"><content expr="[1, 2]"/></send></onentry>
    <transition event="qux" target="s4"><assign location="xs" expr="_event.data"/></transition>
  </state>
  <state id="s4"><transition event="go" target="pass"/></state>
  <final id="pass"/>
</scxml>
"""


def test_the_language_reads_computed_names_and_values() -> None:
    named, valued, fields = expr.parse_actions(
        "raise (which) after 1 s\nraise e(n + 1)\nraise e(n = 1)"
    )
    assert (
        isinstance(named, expr.Raise)
        and named.event is None
        and named.named == expr.Name(name="which")
    )
    assert isinstance(valued, expr.Raise) and valued.content is not None and not valued.args
    assert isinstance(fields, expr.Raise) and fields.content is None and fields.args
    assert expr.event_text(named) == "(which)"


def test_computed_names_and_content_agree_in_every_backend(
    tmp_path: Path, qt_available: None
) -> None:
    # (delayed sends: Qt SCXML has sent a `<send>` without a delay by the end of step 0, where
    # the engine's virtual clock waits for the replay's first `wait`)
    trace = _agree(tmp_path, COMPUTED, "Ee", [{"wait": 10}, {"wait": 10}, {"event": "go"}])
    assert [step["active"] for step in trace] == [["s0"], ["s1"], ["s4"], ["pass_"]]
    assert trace[2]["data"] == {
        "which": "foo",
        "got": "foo",
        "n": 7,
        "xs": [1, 2],
    }  # numbers stay numbers
    assert trace[-1]["active"] == ["pass_"]


SOURCED = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Src">
  <datamodel>
    <data id="level" src="file:level.json"/>
    <data id="tag" src="tag.txt"/>
  </datamodel>
  <state id="s0"><transition event="go" cond="level == 42 &amp;&amp; tag == 'alpha'" target="pass"/></state>
  <final id="pass"/>
</scxml>
"""


def test_data_src_is_read_when_compiled(tmp_path: Path, qt_available: None) -> None:
    (tmp_path / "level.json").write_text("42\n", encoding="utf-8")
    (tmp_path / "tag.txt").write_text(
        "'alpha'", encoding="utf-8"
    )  # as inline content: an expression
    trace = _agree(tmp_path, SOURCED, "Src", [{"event": "go"}])
    assert trace[0]["data"] == {"level": 42, "tag": "alpha"}
    assert trace[-1]["active"] == ["pass_"]


@pytest.mark.parametrize(
    ("src", "why"),
    [
        ("file:../secret.txt", "outside the document's directory"),
        ("file:///etc/hostname", "only a relative file: URI"),
        ("/etc/hostname", "an absolute path"),
        ("http://example.org/x", "only a relative file: URI"),
        ("file:missing.txt", "no such file"),
        ("file:big.txt", "at most 65536 bytes"),
        ("file:link.txt", "outside the document's directory"),
    ],
)
def test_data_src_reads_only_small_files_beside_the_document(
    tmp_path: Path, src: str, why: str
) -> None:
    home = tmp_path / "doc"
    home.mkdir()
    (tmp_path / "secret.txt").write_text("1", encoding="utf-8")
    (home / "big.txt").write_text("1" * 70_000, encoding="utf-8")
    (home / "link.txt").symlink_to(tmp_path / "secret.txt")
    source = home / "m.scxml"
    source.write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0">\n'
        f'  <datamodel>\n    <data id="x" src="{src}"/>\n  </datamodel>\n'
        '  <state id="s0"/>\n</scxml>\n',
        encoding="utf-8",
    )
    found = [d for d in pipeline.validate(source).diagnostics if d.code.id == "SG061"]
    assert len(found) == 1 and why in found[0].message, found
    assert (found[0].span.line, found[0].span.col) == (3, 5)  # at the <data>


FIELDED = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Js">
  <datamodel><data id="got" expr="''"/><data id="size" expr="0"/></datamodel>
  <state id="s0">
    <onentry><send event="foo" delay="10ms"><content>{"productName": "bar", "size": 27}</content></send></onentry>
    <transition event="foo" cond="_event.data.productName == 'bar'" target="s1">
      <assign location="got" expr="_event.data.productName"/><assign location="size" expr="_event.data.size"/>
    </transition>
  </state>
  <state id="s1"><transition event="go" target="pass"/></state>
  <final id="pass"/>
</scxml>
"""


def test_a_json_object_content_is_the_events_fields(tmp_path: Path, qt_available: None) -> None:
    """W3C B.2.2: JSON content is the value; an object's members are swarmgen's event fields."""
    trace = _agree(tmp_path, FIELDED, "Js", [{"wait": 20}, {"event": "go"}])
    assert trace[1]["data"] == {"got": "bar", "size": 27}
    assert trace[-1]["active"] == ["pass_"]


ROUND = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Rt">
  <datamodel><data id="which" expr="'foo'"/><data id="n" expr="0"/></datamodel>
  <state id="s0">
    <onentry>
      <send eventexpr="which" delay="10ms"/>
      <send event="bar" target="#_internal"><content expr="n + 1"/></send>
    </onentry>
    <transition event="foo" target="s1"><assign location="n" expr="_event.data"/></transition>
    <transition event="bar" target="s1"/>
  </state>
  <state id="s1"/>
</scxml>
"""


def test_emitted_computed_names_and_values_read_back(tmp_path: Path) -> None:
    """The emitted `eventexpr` and `$sg.content(...)` read back as `raise (n)`/`raise e(v)`:
    the document, and its XMI conversion, compile to the same SCXML again."""
    source = tmp_path / "Rt.scxml"
    source.write_text(ROUND, encoding="utf-8")

    def body(path: Path) -> list[str]:
        files = pipeline.compile_model(path, ["scxml"]).files
        text = next(t for p, t in files.items() if p.suffix == ".scxml")
        return [line for line in text.splitlines() if "@generated" not in line]

    emitted = tmp_path / "emitted.scxml"
    emitted.write_text("\n".join(body(source)), encoding="utf-8")
    assert 'eventexpr="which"' in emitted.read_text(encoding="utf-8")
    assert body(emitted) == body(source)
    xmi = pipeline.convert_model(emitted).xmi
    assert xmi is not None and b"raise (which)" in xmi and b"raise bar(n + 1)" in xmi
    converted = tmp_path / "converted.xmi"
    converted.write_bytes(xmi)
    assert body(converted) == body(source)


DONE_VALUE = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Dn">
  <datamodel><data id="n" expr="0"/></datamodel>
  <state id="s0" initial="a">
    <state id="a"><transition event="go" target="b"/></state>
    <final id="b"><donedata><content expr="40 + 2"/></donedata></final>
    <transition event="done.state.s0" target="s1"><assign location="n" expr="_event.data"/></transition>
  </state>
  <state id="s1"/>
</scxml>
"""


def test_done_values_stay_numbers_in_qt(tmp_path: Path, qt_available: None) -> None:
    """`done(value)` goes through `$sg.content` too: Qt SCXML gave the number 42 as "42"."""
    trace = _agree(tmp_path, DONE_VALUE, "Dn", [{"event": "go"}])
    assert trace[-1]["data"] == {"n": 42}


IMMEDIATE = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Rc">
  <datamodel><data id="n" expr="0"/><data id="got" expr="''"/></datamodel>
  <state id="s0">
    <onentry><send eventexpr="'ba' + 'z'" target="#_internal"><content expr="[1, 2]"/></send></onentry>
    <transition event="baz" target="s1"><assign location="got" expr="_event.name"/></transition>
  </state>
  <state id="s1">
    <onentry><send event="qux" target="#_internal"><content>7</content></send></onentry>
    <transition event="qux" target="s2"><assign location="n" expr="_event.data"/></transition>
  </state>
  <state id="s2"/>
</scxml>
"""


@requires_rclpy
def test_the_rclpy_host_agrees(tmp_path: Path, qt_available: None) -> None:
    """The ROS 2 node's host gives the same trace. Sends without a delay only: the rclpy
    replay is isolated, with timers off, so it runs no delayed send (`Node.start_delayed`)."""
    source = tmp_path / "Rc.scxml"
    source.write_text(IMMEDIATE, encoding="utf-8")
    traces = {b: replay.replay(source, "Rc", [{"wait": 10}], b) for b in ("rclpy", *BACKENDS)}
    assert all(trace == traces["scxml"] for trace in traces.values()), traces
    assert traces["rclpy"][0]["data"] == {"got": "baz", "n": 7}
