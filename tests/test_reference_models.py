"""Every reference XMI file (Eclipse UML2 4, Papyrus UML2 5, Modelio EMF/OMG) and every sample
model loads with the counts its README gives, and compiles to SCXML that the W3C schema accepts
and Qt SCXML loads and starts."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest
import xmlschema
from lxml import etree

from swarmgen import pipeline
from swarmgen.diagnostics import Severity
from swarmgen.ir.nodes import FinalState, Model, Pseudostate, State
from swarmgen.ir.query import walk
from tests.conftest import (
    HAS_SHARED,
    SAMPLE_MODELS,
    XMI_SAMPLES,
    qt_load,
    requires_shared,
    xmi_sample_files,
)


@dataclass(frozen=True)
class Counts:
    machines: int
    regions: int
    states: int  # uml:State, final states not included (as the README counts them)
    finals: int
    pseudostates: dict[str, int]
    transitions: int
    triggers: int
    guards: int = 0


# From ../shared/reference/xmi_samples/README.md.
EXPECTED = {
    "emfuml4_hets_atm.xmi": Counts(
        2, 5, 15, 3, {"initial": 3, "choice": 3, "fork": 1, "join": 2}, 32, 5, 4
    ),
    "papyrus_spring-sm_simple-connectionpointref.uml": Counts(
        2, 2, 6, 0, {"initial": 2, "entryPoint": 1, "exitPoint": 1}, 8, 4
    ),
    "papyrus_spring-sm_simple-forkjoin.uml": Counts(
        1, 3, 6, 1, {"initial": 3, "fork": 1, "join": 1}, 11, 3
    ),
    "papyrus_spring-sm_simple-history-deep.uml": Counts(
        1, 3, 6, 0, {"initial": 3, "deepHistory": 1}, 7, 4
    ),
    "papyrus_spring-sm_simple-timers.uml": Counts(1, 1, 5, 0, {"initial": 1}, 5, 4),
    "modelio_hets_review_omg211.xmi": Counts(0, 0, 0, 0, {}, 0, 0),
    "modelio_portaless_test_profile.xmi": Counts(0, 0, 0, 0, {}, 0, 0),
}


def _counts(model: Model) -> Counts:
    regions = states = finals = 0
    kinds: dict[str, int] = {}
    for machine in model.machines:
        regions += len(machine.regions)
        for placed in walk(machine):
            vertex = placed.vertex
            if isinstance(vertex, State):
                states += 1
                regions += len(vertex.regions)
            elif isinstance(vertex, FinalState):
                finals += 1
            elif isinstance(vertex, Pseudostate):
                kinds[vertex.kind.value] = kinds.get(vertex.kind.value, 0) + 1
    transitions = [t for m in model.machines for t in m.transitions]
    return Counts(
        machines=len(model.machines),
        regions=regions,
        states=states,
        finals=finals,
        pseudostates=kinds,
        transitions=len(transitions),
        triggers=sum(len(t.triggers) for t in transitions),
        guards=sum(t.guard_text is not None for t in transitions),
    )


@requires_shared
def test_every_reference_file_is_covered() -> None:
    assert sorted(EXPECTED) == sorted(p.name for p in xmi_sample_files())


@requires_shared
@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_reference_file_loads_with_readme_counts(name: str) -> None:
    result = pipeline.validate(XMI_SAMPLES / name)
    errors = [d for d in result.diagnostics if d.level is Severity.ERROR]
    assert not errors, errors
    assert result.model is not None
    assert _counts(result.model) == EXPECTED[name]


@requires_shared
def test_spans_point_at_the_element() -> None:
    """Every IR node keeps file, line, column and xmi:id of its XMI element."""
    path = XMI_SAMPLES / "emfuml4_hets_atm.xmi"
    model = pipeline.validate(path).model
    assert model is not None
    lines = path.read_text(encoding="utf-8").splitlines()
    for machine in model.machines:
        for transition in machine.transitions:
            span = transition.span
            assert span.file == str(path) and span.xmi_id == transition.id
            assert lines[span.line - 1][span.col - 1 :].startswith("<transition")
            assert f'xmi:id="{transition.id}"' in lines[span.line - 1]


def _all_models() -> list[Path]:
    return [*SAMPLE_MODELS, *xmi_sample_files()]


@pytest.fixture(scope="module")
def emitted(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Every SCXML document of every model, written once for the schema and Qt tests."""
    out = tmp_path_factory.mktemp("scxml")
    paths = []
    for model in _all_models():
        result = pipeline.compile_model(model)
        assert result.files or not pipeline.dg.has_errors(result.validation.diagnostics)
        for relative, text in result.files.items():
            if relative.suffix == ".scxml":
                target = out / f"{model.stem}__{relative.name}"
                target.write_text(text, encoding="utf-8")
                paths.append(target)
    assert len(paths) >= (10 if HAS_SHARED else 4)  # the samples give 4 documents
    return paths


def test_scxml_is_valid_against_w3c_schema(
    emitted: list[Path], scxml_schema: xmlschema.XMLSchema
) -> None:
    invalid = {
        p.name: str(next(iter(scxml_schema.iter_errors(str(p)))))
        for p in emitted
        if not scxml_schema.is_valid(str(p))
    }
    assert not invalid, invalid


def test_scxml_loads_and_starts_in_qt(emitted: list[Path], qt_available: None) -> None:
    reports = qt_load(emitted)
    assert len(reports) == len(emitted)
    failures = {r["file"]: r["errors"] for r in reports if r["errors"]}
    assert not failures, failures
    not_started = [r["file"] for r in reports if not r["active"]]
    assert not not_started, f"no active state after start: {not_started}"


def test_sample_uav_starts_in_its_three_parallel_regions(
    qt_available: None, tmp_path: Path
) -> None:
    """The SAR UAV's L1 machine: SarBehavior, swarm functions and hardware functions in parallel."""
    result = pipeline.compile_model(Path("sample_models/sar/sar.xmi").resolve())
    uav = tmp_path / "UAV.scxml"
    uav.write_text(result.files[pipeline.PurePosixPath("scxml/UAV.scxml")], encoding="utf-8")
    (report,) = qt_load([uav])
    # targets are monitored once the UAV is launched (its swarm functions wait in Standby)
    assert report["active"] == ["Idle", "Positioning", "Standby"]
    root = etree.parse(str(uav)).getroot()
    assert root.get("initial") == "Mission"
