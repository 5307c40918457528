"""Issue 15, item 2: the SCXML swarmgen writes, read back, is the same machine. Replays of the
source model and of its emitted SCXML document give the same traces on the generated scenarios
(seeded walks, aborts, behaviour failures), and `swarmgen convert` of that document gives XMI
that compiles to the same SCXML again."""

from __future__ import annotations

import zlib
from pathlib import Path

import pytest

from swarmgen import pipeline, replay
from swarmgen.chart.lower import lower
from tests.conftest import ROOT
from tests.scenarios import ScenarioMaker, failure_scenarios

SAMPLES = sorted((ROOT / "sample_models").glob("*/*.xmi"))
WALKS, WALK_LENGTH = 16, 40


def _members(model: Path) -> list[tuple[Path, str]]:
    validation = pipeline.validate(model)
    assert validation.model is not None
    return [(model, chart.member or chart.name) for chart in lower(validation.model)]


CASES = [case for model in SAMPLES for case in _members(model)]


def _emitted(model: Path, member: str, out: Path) -> Path:
    """The member type's SCXML document, compiled from `model` into `out`."""
    files = pipeline.compile_model(model, ["scxml"]).files
    (path, text) = next((p, t) for p, t in files.items() if p.name == f"{member}.scxml")
    document = out / path.name
    document.write_text(text, encoding="utf-8")
    return document


def _scenarios(model: Path, member: str) -> list[list[dict[str, object]]]:
    validation = pipeline.validate(model)
    assert validation.model is not None
    chart = next(c for c in lower(validation.model) if (c.member or c.name) == member)
    maker = ScenarioMaker(chart, seed=zlib.crc32(f"roundtrip:{model.name}:{member}".encode()))
    walks = [maker.walk(WALK_LENGTH) for _ in range(WALKS)]
    return walks + maker.aborts(walks) + failure_scenarios(chart, walks)


@pytest.mark.parametrize(("model", "member"), CASES, ids=[f"{m.stem}-{t}" for m, t in CASES])
def test_read_back_scxml_replays_like_its_source(model: Path, member: str, tmp_path: Path) -> None:
    document = _emitted(model, member, tmp_path)
    scenarios = _scenarios(model, member)
    assert len(scenarios) >= WALKS
    source = replay.replay_many(model, member, scenarios, "asyncio")
    read_back = replay.replay_many(document, member, scenarios, "asyncio")
    assert len(read_back) == len(source)
    for index, (expected, got) in enumerate(zip(source, read_back, strict=True)):
        assert got == expected, f"scenario {index}: {scenarios[index]}"


@pytest.mark.parametrize(("model", "member"), CASES, ids=[f"{m.stem}-{t}" for m, t in CASES])
def test_converted_scxml_compiles_to_the_same_scxml(
    model: Path, member: str, tmp_path: Path
) -> None:
    document = _emitted(model, member, tmp_path)
    xmi = pipeline.convert_model(document).xmi
    assert xmi is not None
    converted = tmp_path / "converted.xmi"
    converted.write_bytes(xmi)

    def body(path: Path) -> list[str]:
        files = pipeline.compile_model(path, ["scxml"]).files
        text = next(t for p, t in files.items() if p.suffix == ".scxml")
        return [line for line in text.splitlines() if "@generated" not in line]

    assert body(converted) == body(document)


def test_the_comparison_sees_a_changed_transition(tmp_path: Path) -> None:
    """The scenarios reach deep enough that one retargeted transition changes a trace."""
    model = ROOT / "sample_models" / "sar" / "sar.xmi"
    document = _emitted(model, "UAV", tmp_path)
    text = document.read_text(encoding="utf-8")
    original = '<transition event="missionStart" target="Coverage"/>'
    assert original in text
    document.write_text(text.replace(original, original.replace("Coverage", "Idle")), "utf-8")
    scenarios = _scenarios(model, "UAV")
    source = replay.replay_many(model, "UAV", scenarios, "asyncio")
    changed = replay.replay_many(document, "UAV", scenarios, "asyncio")
    assert any(a != b for a, b in zip(source, changed, strict=True))
