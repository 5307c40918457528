"""`swarmgen convert`: what is read is written back as EMF XMI that validates with the same
diagnostics, builds the same IR and compiles to the same SCXML as its source."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from lxml import etree

from swarmgen import pipeline
from swarmgen.frontend import load
from swarmgen.frontend.xmi_write import write_xmi
from tests.conftest import ROOT, XMI_SAMPLES, run_cli

SAMPLES = sorted((ROOT / "sample_models").glob("*/*.xmi"))
SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
REFERENCE = XMI_SAMPLES
CLEAN_CASES = sorted((ROOT / "tests" / "check_cases").glob("*.xmi"))


def _without_spans(node: Any) -> Any:
    if isinstance(node, dict):
        return {
            k: _without_spans(v)
            for k, v in node.items()
            if k not in {"span", "source"} and not k.endswith("_span")
        }
    if isinstance(node, list):
        return [_without_spans(v) for v in node]
    return node


def _scxml(path: Path, interfaces: list[Path]) -> dict[str, list[str]]:
    """The SCXML documents compiled from `path`, without the header naming the source."""
    files = pipeline.compile_model(path, ["scxml"], interfaces=interfaces).files
    return {
        str(p): [line for line in text.splitlines() if "@generated" not in line]
        for p, text in files.items()
        if p.suffix == ".scxml"
    }


def _interfaces(source: Path) -> list[Path]:
    beside = source.parent / "interfaces"
    return [beside] if beside.is_dir() else []


def _convertible() -> list[Path]:
    found = SAMPLES + CLEAN_CASES
    if REFERENCE.is_dir():
        found += sorted(REFERENCE.glob("*.xmi"))
    return found


@pytest.mark.parametrize("source", _convertible(), ids=lambda p: p.name)
def test_converted_model_is_the_same_model(source: Path, tmp_path: Path) -> None:
    interfaces = _interfaces(source)
    original = pipeline.validate(source, interfaces)
    converted = tmp_path / "model.xmi"
    result = pipeline.convert_model(source, interfaces)
    if original.model is None or original.exit_code != 0:
        assert result.xmi is None  # an unreadable model, or one with errors, is not written
        return
    assert result.xmi is not None
    converted.write_bytes(result.xmi)
    again = pipeline.validate(converted, interfaces)
    assert again.model is not None
    assert _without_spans(again.model.model_dump(mode="json")) == _without_spans(
        original.model.model_dump(mode="json")
    )
    assert [(d.code.id, d.message) for d in again.diagnostics] == [
        (d.code.id, d.message) for d in original.diagnostics
    ]
    assert _scxml(converted, interfaces) == _scxml(source, interfaces)


@pytest.mark.parametrize("source", SAMPLES, ids=lambda p: p.name)
def test_conversion_is_deterministic_and_a_fixpoint(source: Path, tmp_path: Path) -> None:
    first = pipeline.convert_model(source, _interfaces(source)).xmi
    assert first is not None
    assert pipeline.convert_model(source, _interfaces(source)).xmi == first
    converted = tmp_path / "model.xmi"
    converted.write_bytes(first)
    raw, _ = load(converted)
    assert raw is not None
    assert write_xmi(raw) == first


def test_the_output_is_emf_xmi_with_the_profile_applied() -> None:
    xmi = pipeline.convert_model(SAMPLES[0], _interfaces(SAMPLES[0])).xmi
    assert xmi is not None
    root = etree.fromstring(xmi)
    assert root.tag == "{http://schema.omg.org/spec/XMI/2.1}XMI"
    assert root[0].tag == "{http://www.eclipse.org/uml2/3.0.0/UML}Model"
    members = [e for e in root if etree.QName(e).localname == "SwarmMember"]
    assert members and all(e.get("base_Class") for e in members)
    typed = [e for e in root.iter() if e.get("{http://schema.omg.org/spec/XMI/2.1}id")]
    untyped = [
        e
        for e in typed[1:]
        if e.getparent() is not root
        and etree.QName(e).localname != "eAnnotations"
        and not e.get("{http://schema.omg.org/spec/XMI/2.1}type")
    ]
    assert not untyped


def test_markup_in_names_cannot_break_the_document(tmp_path: Path) -> None:
    source = SAR.read_text(encoding="utf-8")
    hostile = "A&quot;&lt;/x&gt;&amp;&lt;!--"
    model = tmp_path / "model.xmi"
    model.write_text(source.replace('name="SearchAndRescue"', f'name="{hostile}"', 1))
    raw, _ = load(model)
    assert raw is not None
    again = tmp_path / "again.xmi"
    again.write_bytes(write_xmi(raw))
    raw2, _ = load(again)
    assert raw2 is not None and raw2.roots[0].name == raw.roots[0].name == 'A"</x>&<!--'


def test_cli_writes_the_file_and_refuses_bad_input_writing_nothing(tmp_path: Path) -> None:
    out = tmp_path / "new" / "model.xmi"
    done = run_cli("convert", str(SAMPLES[0]), "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == pipeline.convert_model(SAMPLES[0], _interfaces(SAMPLES[0])).xmi
    bad = ROOT / "tests" / "fixtures" / "bad" / "wrong_root.xmi"
    refused = tmp_path / "other" / "model.xmi"
    done = run_cli("convert", str(bad), "-o", str(refused))
    assert done.returncode == 2
    assert "SG004" in done.stderr and "nothing written" in done.stderr
    assert "Traceback" not in done.stderr
    assert not refused.parent.exists()
