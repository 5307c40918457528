"""Cross-backend equivalence: for every sample model and member type, and for generated
scenarios (seeded walks, abort in the middle of every state reached, behaviour failures,
inputs arriving back to back), the generated Python backends give exactly the trace of the
emitted SCXML run in Qt SCXML (an independent engine)."""

from __future__ import annotations

import zlib
from pathlib import Path

import pytest

from swarmgen import pipeline, replay
from swarmgen.backends import names as backend_names
from swarmgen.chart.lower import lower
from tests.conftest import SAMPLE_MODELS, XMI_SAMPLES
from tests.scenarios import ScenarioMaker, failure_scenarios

WALKS = 16
WALK_LENGTH = 40
MODELS = [
    *SAMPLE_MODELS,
    XMI_SAMPLES / "emfuml4_hets_atm.xmi",
    XMI_SAMPLES / "papyrus_spring-sm_simple-history-deep.uml",
    XMI_SAMPLES / "papyrus_spring-sm_simple-forkjoin.uml",
    XMI_SAMPLES / "papyrus_spring-sm_simple-connectionpointref.uml",
]
PYTHON_BACKENDS = [b for b in backend_names() if b in replay.BACKENDS and b != "scxml"]


def _cases() -> list[tuple[Path, str]]:
    cases = []
    for model in MODELS:
        validation = pipeline.validate(model)
        assert validation.model is not None
        cases += [(model, chart.member or chart.name) for chart in lower(validation.model)]
    return cases


def _scenarios(model: Path, member: str) -> list[list[dict[str, object]]]:
    validation = pipeline.validate(model)
    assert validation.model is not None
    chart = next(c for c in lower(validation.model) if (c.member or c.name) == member)
    maker = ScenarioMaker(chart, seed=zlib.crc32(f"{model.name}:{member}".encode()))
    walks = [maker.walk(WALK_LENGTH) for _ in range(WALKS)]
    return walks + maker.aborts(walks) + failure_scenarios(chart, walks)


@pytest.mark.parametrize(("model", "member"), _cases(), ids=[f"{m.stem}-{t}" for m, t in _cases()])
def test_backends_agree_with_qt_scxml(model: Path, member: str, qt_available: None) -> None:
    scenarios = _scenarios(model, member)
    assert len(scenarios) >= WALKS
    reference = replay.replay_many(model, member, scenarios, "scxml")
    configurations = {str(r["active"]) for trace in reference for r in trace}
    assert len(configurations) >= 2, (
        f"the walks should visit several configurations: {configurations}"
    )
    for backend in PYTHON_BACKENDS:
        traces = replay.replay_many(model, member, scenarios, backend)
        for number, (ours, theirs) in enumerate(zip(traces, reference, strict=True)):
            assert ours == theirs, _first_difference(
                backend, number, scenarios[number], ours, theirs
            )


def _first_difference(
    backend: str,
    number: int,
    steps: object,
    ours: list[dict[str, object]],
    theirs: list[dict[str, object]],
) -> str:
    for mine, reference in zip(ours, theirs, strict=False):
        if mine != reference:
            return (
                f"{backend} differs from Qt SCXML in scenario {number} at step {mine['step']} "
                f"({mine['input']}):\n  {backend}: {mine}\n  qt:     {reference}\n  scenario: {steps}"
            )
    return f"{backend}: trace lengths differ ({len(ours)} vs {len(theirs)})"
