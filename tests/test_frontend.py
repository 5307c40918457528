"""The XMI reader is tolerant like a real tool: the same model written by other producers and in
Modelio's OMG formats gives the same IR and the same SCXML."""

from __future__ import annotations

from pathlib import Path

import pytest
from lxml import etree

from swarmgen import pipeline
from swarmgen.frontend import load
from swarmgen.ir.nodes import Model
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
XMI_NS = "http://schema.omg.org/spec/XMI/2.1"
OMG_UML = {
    "2.1.1": "http://schema.omg.org/spec/UML/2.1.1",
    "2.2": "http://schema.omg.org/spec/UML/2.2",
    "2.3": "http://www.omg.org/spec/UML/20090901",
    "2.4.1": "http://www.omg.org/spec/UML/20110701",
}
# What Modelio's export XSLT adds to elements EMF leaves untyped (formats.md 1.1).
EXPLICIT_TYPES = {
    "region": "uml:Region",
    "transition": "uml:Transition",
    "trigger": "uml:Trigger",
    "ownedAttribute": "uml:Property",
    "generalization": "uml:Generalization",
    "ownedParameter": "uml:Parameter",
    "ownedRule": "uml:Constraint",
}


def _without_spans(model: Model) -> dict[str, object]:
    data = model.model_dump(mode="json", exclude={"source", "exporter"})

    def strip(node: object) -> object:
        if isinstance(node, dict):
            return {k: strip(v) for k, v in node.items() if k != "span" and not k.endswith("_span")}
        if isinstance(node, list):
            return [strip(v) for v in node]
        return node

    result = strip(data)
    assert isinstance(result, dict)
    return result


def _scxml_bodies(path: Path) -> dict[str, str]:
    files = pipeline.compile_model(path).files
    # the header comment names the source file: compare everything after it
    return {str(p): t.split("-->", 1)[1] for p, t in files.items() if p.suffix == ".scxml"}


def _rewrite(tmp_path: Path, name: str, change: object) -> Path:
    tree = etree.parse(str(SAR))
    change(tree)  # type: ignore[operator]
    path = tmp_path / name
    path.write_bytes(etree.tostring(tree, xml_declaration=True, encoding="UTF-8"))
    return path


def _reference() -> Model:
    model = pipeline.validate(SAR).model
    assert model is not None
    return model


@pytest.mark.parametrize("version", sorted(OMG_UML))
def test_omg_uml_formats_read_like_emf(version: str, tmp_path: Path) -> None:
    """Modelio's 'UML 2.x' export options: OMG namespace, explicit xmi:type, OMG hrefs."""

    def to_omg(tree: etree._ElementTree) -> None:
        root = tree.getroot()
        for element in root.iter(tag=etree.Element):
            local = etree.QName(element).localname
            if local in EXPLICIT_TYPES and f"{{{XMI_NS}}}type" not in element.attrib:
                element.set(f"{{{XMI_NS}}}type", EXPLICIT_TYPES[local])
            href = element.get("href", "")
            if href.startswith("pathmap://UML_LIBRARIES/"):
                element.set("href", f"{OMG_UML[version]}/uml.xml#{href.rsplit('#', 1)[1]}")
        text = etree.tostring(root, encoding="unicode").replace(
            "http://www.eclipse.org/uml2/3.0.0/UML", OMG_UML[version]
        )
        tree._setroot(etree.fromstring(text))

    variant = _rewrite(tmp_path, f"sar_omg_{version}.xmi", to_omg)
    result = pipeline.validate(variant)
    assert not pipeline.dg.has_errors(result.diagnostics), result.diagnostics
    assert result.model is not None
    assert _without_spans(result.model) == _without_spans(_reference())
    assert _scxml_bodies(variant) == _scxml_bodies(SAR)


def test_idref_children_and_missing_types(tmp_path: Path) -> None:
    """MagicDraw-style `<source xmi:idref=.../>` children and no xmi:type on subvertices."""

    def to_idrefs(tree: etree._ElementTree) -> None:
        for transition in tree.getroot().iter("transition"):
            for feature in ("source", "target"):
                value = transition.attrib.pop(feature)
                etree.SubElement(transition, feature).set(f"{{{XMI_NS}}}idref", value)
        for vertex in tree.getroot().iter("subvertex"):
            if vertex.get(f"{{{XMI_NS}}}type") == "uml:State":
                del vertex.attrib[f"{{{XMI_NS}}}type"]

    variant = _rewrite(tmp_path, "sar_idrefs.xmi", to_idrefs)
    model = pipeline.validate(variant).model
    assert model is not None
    assert _without_spans(model) == _without_spans(_reference())


def test_missing_sidecar_profile_is_fine() -> None:
    """The sample names CPSwarm.profile.xmi, which is not there: stereotypes still apply."""
    raw, diagnostics = load(SAR)
    assert raw is not None and not diagnostics
    assert not (SAR.parent / "CPSwarm.profile.xmi").exists()
    names = {s.name for s in raw.stereotypes}
    assert {"Swarm", "SwarmMember", "SwarmEvent", "HardwareFunction"} <= names


def test_stereotypes_match_by_local_name_in_any_namespace(tmp_path: Path) -> None:
    def rename_profile(tree: etree._ElementTree) -> None:
        text = etree.tostring(tree.getroot(), encoding="unicode")
        start = text.index('xmlns:CPSwarm="') + len('xmlns:CPSwarm="')
        uri = text[start : text.index('"', start)]
        tree._setroot(etree.fromstring(text.replace(uri, "http://example.invalid/other/profile")))

    variant = _rewrite(tmp_path, "sar_other_profile_uri.xmi", rename_profile)
    model = pipeline.validate(variant).model
    assert model is not None
    assert _without_spans(model) == _without_spans(_reference())


def test_every_element_keeps_file_line_and_id() -> None:
    raw, _ = load(SAR)
    assert raw is not None
    lines = SAR.read_text(encoding="utf-8").splitlines()
    for element in raw.elements():
        if element.id is None:
            continue
        assert element.span.xmi_id == element.id
        line = lines[element.span.line - 1]
        assert line[element.span.col - 1 :].startswith("<"), (element.feature, element.span)
        assert element.id in line or element.feature in line
