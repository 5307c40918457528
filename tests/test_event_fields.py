"""W3C's `_event` fields and system variables (`_event.name`, `.type`, `.sendid`, `.origin`,
`.origintype`, `.invokeid`, `.data`; `_sessionid`, `_name`, `_ioprocessors`): read-only words
of the expression language, the same values in asyncio, smach and the emitted SCXML in Qt SCXML
(docs/semantics.md, "The event and system variables"), `<data expr>` computed at the start."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmgen import expr, replay

BACKENDS = ("asyncio", "smach", "scxml")

DOCUMENT = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Ev">
  <datamodel>
    <data id="me" expr="_name"/><data id="n" expr="''"/><data id="t" expr="''"/>
    <data id="s" expr="''"/><data id="o" expr="''"/><data id="ot" expr="''"/>
    <data id="k" expr="0"/><data id="blank" expr="'x'"/>
  </datamodel>
  <state id="s0">
    <onentry>
      <raise event="a"/>
      <send event="c" delay="10ms" id="cid"/>
      <send event="b" target="#_internal"><param name="k" expr="7"/></send>
    </onentry>
    <transition event="a" cond="_sessionid != ''" target="s1">
      <assign location="n" expr="_event.name"/><assign location="t" expr="_event.type"/>
      <assign location="blank" expr="_event.sendid + _event.origin + _event.invokeid"/>
    </transition>
  </state>
  <state id="s1">
    <transition event="b" target="s2"><assign location="k" expr="_event.data.k"/>
      <assign location="t" expr="_event.type"/><assign location="o" expr="_event.origin"/>
    </transition>
  </state>
  <state id="s2">
    <transition event="c" cond="_event.sendid == 'cid'" target="s3">
      <assign location="s" expr="_event.sendid"/><assign location="ot" expr="_event.origintype"/>
    </transition>
  </state>
  <state id="s3"><transition event="go" target="pass"/></state>
  <final id="pass"/>
</scxml>
"""


def test_the_language_reads_system_variables() -> None:
    value = expr.parse_expr("_event.name == _name and _event.data == _ioprocessors")
    assert expr.to_text(value) == "_event.name == _name and _event.data == _ioprocessors"
    assert expr.free_names(value) == frozenset()  # no member data
    for bad in ("_event", "_event.foo", "_name.x = 1"):  # `_name = 1`: tests/test_system_assign.py
        with pytest.raises(expr.ExprError):
            expr.parse_actions(bad) if "=" in bad else expr.parse_expr(bad)


def test_event_fields_agree_in_every_backend(tmp_path: Path, qt_available: None) -> None:
    source = tmp_path / "ev.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    steps = [{"wait": 60}, {"event": "go"}]
    traces = {b: replay.replay(source, "Ev", steps, b) for b in BACKENDS}
    for backend, trace in traces.items():
        assert trace == traces["scxml"], f"{backend} differs from Qt SCXML:\n{trace}"
    data = traces["scxml"][1]["data"]
    assert traces["scxml"][-1]["active"] == ["pass_"]
    assert data == {
        "me": "Ev",
        "n": "a",
        "t": "external",  # a send to #_internal goes to the external queue (as in Qt)
        "blank": "",  # W3C's blank fields: "" in every backend
        "k": 7,
        "o": "#_internal",
        "s": "cid",
        "ot": "http://www.w3.org/TR/scxml/#SCXMLEventProcessor",
    }
