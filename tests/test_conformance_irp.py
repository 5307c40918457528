"""Issue 15 item 3: the W3C SCXML IRP tests on swarmgen's engine and in Qt SCXML, compared with
the checked-in results (tests/conformance/irp_expected.json). A test that passed and no longer
does is a regression; any other change means the results must be regenerated
(`python -m swarmgen.conformance --update`). docs/conformance.md is generated from the file."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
from lxml import etree

from swarmgen.conformance import irp, qt, report
from tests.conftest import REFERENCE, ROOT, reference_absent

IRP = REFERENCE / "w3c_irp"
RESULTS = ROOT / "tests" / "conformance" / "irp_expected.json"
DOC = ROOT / "docs" / "conformance.md"
needs_irp = pytest.mark.skipif(
    not (IRP / "manifest.xml").is_file(), reason=reference_absent(IRP / "manifest.xml")
)


def _expected() -> dict[str, Any]:
    content: dict[str, Any] = json.loads(RESULTS.read_text(encoding="utf-8"))
    return content


@pytest.fixture(scope="module")
def ours() -> dict[str, irp.Outcome]:
    return irp.run_all(IRP)


def _explain(changes: list[str]) -> str:
    return "\n".join(
        [*changes, "(a REGRESSION is a bug; otherwise: python -m swarmgen.conformance --update)"]
    )


@needs_irp
def test_swarmgen_results_are_the_checked_in_ones(ours: dict[str, irp.Outcome]) -> None:
    expected = _expected()
    qt_kept = {k: irp.Outcome(v["qt"], v["qt_detail"]) for k, v in expected["tests"].items()}
    got = report.results(irp.tests(IRP), ours, qt_kept)
    keys = ("swarmgen", "swarmgen_detail", "features")
    changes = report.differences(expected, got, keys)
    assert not changes, _explain(changes)


@needs_irp
def test_qt_results_are_the_checked_in_ones(qt_available: None) -> None:
    expected = _expected()
    theirs = qt.run_all(IRP)
    by_id = {
        k: irp.Outcome(v["swarmgen"], v["swarmgen_detail"], tuple(v["features"]))
        for k, v in expected["tests"].items()
    }
    got = report.results(irp.tests(IRP), by_id, theirs)
    changes = report.differences(expected, got, ("qt",))
    assert not changes, _explain(changes)


def test_the_page_and_the_file_are_generated() -> None:
    """docs/conformance.md is what the generator writes from the JSON, and the JSON is in the
    generator's own format (neither is edited by hand)."""
    text = RESULTS.read_text(encoding="utf-8")
    content = json.loads(text)
    assert report.dumps(content) == text
    assert DOC.read_text(encoding="utf-8") == report.markdown(content)


def test_the_totals_count_the_mandatory_automatic_tests() -> None:
    rows = _expected()["tests"]
    assert sum(r["mandatory"] for r in rows.values()) == 159
    assert len(rows) == 159 + 63
    page = DOC.read_text(encoding="utf-8")
    passed = sum(r["mandatory"] and r["swarmgen"] == "pass" for r in rows.values())
    assert f"| mandatory | {passed}/159 |" in page


def _swapped(txml: Path, out: Path) -> Path:
    """The template with conf:targetpass and conf:targetfail exchanged."""
    tree = etree.parse(str(txml))
    pass_, fail = f"{{{irp.CONF}}}targetpass", f"{{{irp.CONF}}}targetfail"
    for element in tree.iter():
        marks = {name: element.attrib.pop(name) for name in (pass_, fail) if name in element.attrib}
        for name, value in marks.items():
            element.set(fail if name == pass_ else pass_, value)
    swapped = out / txml.name
    tree.write(str(swapped))
    for data in txml.parent.glob(f"{txml.stem}*.txt"):  # its `<data src>` files go with it
        shutil.copy(data, out / data.name)
    return swapped


@needs_irp
def test_a_pass_is_real_swapping_the_targets_makes_it_fail(
    ours: dict[str, irp.Outcome], tmp_path: Path
) -> None:
    """Every test swarmgen passes fails once its pass and fail targets are exchanged: the
    engine reaches `pass` because the test's transitions lead there, not by default."""
    transform = irp.stylesheet()
    passed = [t for t in irp.tests(IRP) if ours[t.id].result == "pass"]
    assert len(passed) >= 10
    for test in passed:
        for document in test.documents:  # the documents its `<invoke src>`s read, beside it
            for sub in sorted(document.parent.glob(f"{document.stem}sub*.txml")):
                _swapped(sub, tmp_path)
        mutated = irp.Test(
            test.id, test.mandatory, tuple(_swapped(d, tmp_path) for d in test.documents)
        )
        outcome = irp.run_test(transform, mutated, tmp_path)
        assert outcome.result == "fail", (test.id, outcome)


@needs_irp
def test_the_stylesheets_translate_every_conf_construct() -> None:
    """No conf:* element or attribute is left after either conversion (a leftover would be
    ignored by a reader and change the test's meaning)."""
    ours, ecma = irp.stylesheet(), irp.stylesheet(IRP / "confEcma.xsl")
    for txml in sorted((IRP / "txml").glob("*.txml")):
        assert irp.leftover(irp.convert(ours, txml)) is None, txml.name
        assert irp.leftover(qt.convert_ecma(ecma, txml)) is None, txml.name


@needs_irp
def test_the_xslt2_conditions_are_written_for_libxslt() -> None:
    """libxslt skips confEcma.xsl's analyze-string: without the fill, test 147's
    `conf:idVal="1=1"` comes out as an empty (true) cond; with it, as confEcma.xsl means."""
    ecma = irp.stylesheet(IRP / "confEcma.xsl")
    txml = IRP / "txml" / "test147.txml"
    plain = etree.fromstring(irp.convert(ecma, txml))
    filled = etree.fromstring(qt.convert_ecma(ecma, txml))
    ns = {"s": "http://www.w3.org/2005/07/scxml"}
    assert plain.xpath("//s:transition[@event='bar']/@cond", namespaces=ns) == [""]
    assert filled.xpath("//s:transition[@event='bar']/@cond", namespaces=ns) == ["Var1==1"]
    ours = etree.fromstring(irp.convert(irp.stylesheet(), txml))
    assert ours.xpath("//s:transition[@event='bar']/@cond", namespaces=ns) == ["Var1==1"]


def test_an_untranslated_construct_is_not_run(tmp_path: Path) -> None:
    document = (
        b'<scxml xmlns="http://www.w3.org/2005/07/scxml" '
        b'xmlns:conf="http://www.w3.org/2005/scxml-conformance" version="1.0">'
        b'<state id="s0"><transition conf:mystery="1" target="pass"/></state>'
        b'<final id="pass"/></scxml>'
    )
    outcome = irp.run_document(document, tmp_path / "t.scxml")
    named = "untranslated conf:mystery"
    assert outcome == irp.Outcome("not-run", named, (named,))


def test_timers_run_on_the_virtual_clock(tmp_path: Path) -> None:
    """swarmgen's timer pattern: the earlier timer fires first, without waiting."""
    document = b"""<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="s0">
      <state id="s0">
        <onentry>
          <send event="after.s0.1" id="after.s0.1" delay="50000ms"/>
          <send event="after.s0.2" id="after.s0.2" delay="20ms"/>
        </onentry>
        <onexit><cancel sendid="after.s0.1"/><cancel sendid="after.s0.2"/></onexit>
        <transition event="after.s0.1" target="fail"/>
        <transition event="after.s0.2" target="pass"/>
      </state>
      <final id="pass"/><final id="fail"/></scxml>"""
    assert irp.run_document(document, tmp_path / "t.scxml") == irp.Outcome("pass")
