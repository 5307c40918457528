"""`raise e via <type>` and `raise e ... into <datum>` (W3C's `<send type|typeexpr>` and
`idlocation`): the SCXML event processor (its URI or "scxml") is the only I/O processor, any
other value raises error.execution and sends nothing; `into` writes a send id made for the send
to the datum, also when the send fails, and the failure's error event carries it (W3C 5.10.1).
The same in asyncio, smach and the emitted SCXML in Qt SCXML (docs/semantics.md, "Targets")."""

from __future__ import annotations

from pathlib import Path

from swarmgen import expr, replay
from swarmgen.conformance import irp

BACKENDS = ("asyncio", "smach", "scxml")
PROCESSOR = "http://www.w3.org/TR/scxml/#SCXMLEventProcessor"

DOCUMENT = f"""<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0" name="Types">
  <datamodel>
    <data id="kind" expr="'{PROCESSOR}'"/><data id="got" expr="''"/><data id="seen" expr="''"/>
  </datamodel>
  <state id="s0">
    <onentry>
      <send event="never" type="27"/>
      <raise event="skipped"/>
    </onentry>
    <transition event="error.execution" target="s1"/>
    <transition event="*" target="bad"/>
  </state>
  <state id="s1">
    <onentry><send event="ok" typeexpr="kind"><param name="k" expr="5"/></send></onentry>
    <transition event="ok" cond="_event.data.k == 5" target="s2"/>
    <transition event="*" target="bad"/>
  </state>
  <state id="s2">
    <onentry><send event="lost" target="nowhere" idlocation="got"/></onentry>
    <transition event="error.execution" target="s3"><assign location="seen" expr="_event.sendid"/></transition>
    <transition event="*" target="bad"/>
  </state>
  <state id="s3">
    <transition cond="got != '' &amp;&amp; got == seen" target="good"/>
    <transition target="bad"/>
  </state>
  <final id="good"/><final id="bad"/>
</scxml>
"""


def test_the_language_reads_types_and_id_locations() -> None:
    (action,) = expr.parse_actions('raise e(k = 1) to t via "scxml" after 1 s into v')
    assert isinstance(action, expr.Raise) and action.via == expr.Const(value="scxml")
    assert (action.into, action.sendid) == ("v", None)


def test_types_and_id_locations_agree_in_every_backend(tmp_path: Path, qt_available: None) -> None:
    """Every backend ends in `pass` with the same errors; the send ids themselves are each
    engine's own (as `_sessionid`), so only their agreement inside a run is compared."""
    source = tmp_path / "types.scxml"
    source.write_text(DOCUMENT, encoding="utf-8")
    ends = {b: replay.replay(source, "Types", [{"wait": 50}], b)[-1] for b in BACKENDS}
    for backend, end in ends.items():
        assert (end["active"], end["errors"]) == (["good"], 2), f"{backend}: {end}"
        assert end["data"]["got"] == end["data"]["seen"] != ""


def test_the_engine_passes_on_its_virtual_clock(tmp_path: Path) -> None:
    """The IRP runner's way (pass/fail finals) on the same document."""
    document = DOCUMENT.replace('"good"', '"pass"').replace('"bad"', '"fail"')
    outcome = irp.run_document(document.encode(), tmp_path / "types.scxml")
    assert outcome == irp.Outcome("pass")
