"""Robustness: a corpus of 200+ mutations of the sample models (deleted, duplicated and
retargeted elements and references, wrong types, truncations, huge names, deep nesting) each
ends in diagnostics with the right exit code and never a crash; property tests with random valid
models (they compile, the SCXML validates, the generated code imports, the bytes are stable) and
random corruptions (never a crash)."""

from __future__ import annotations

import copy
import importlib.util
import random
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
import xmlschema
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from lxml import etree

from swarmgen import pipeline
from swarmgen.diagnostics import ExitCode, Severity
from tests.conftest import ROOT, SAMPLE_MODELS
from tests.modelkit import ModelKit

XMI = "{http://schema.omg.org/spec/XMI/2.1}"
# References the compiler resolves (and so must report when they break).
CHECKED_REFS = (
    "source",
    "target",
    "event",
    "signal",
    "specification",
    "submachine",
    "classifierBehavior",
    "guard",
)


@dataclass(frozen=True)
class Mutation:
    name: str
    text: bytes
    expected: frozenset[int]  # acceptable exit codes


def _tree(model: Path) -> etree._ElementTree:
    return etree.parse(str(model))


def _ids(tree: etree._ElementTree) -> dict[str, etree._Element]:
    return {e.get(f"{XMI}id"): e for e in tree.iter(etree.Element) if e.get(f"{XMI}id")}


def _referrers(tree: etree._ElementTree) -> list[tuple[etree._Element, str, str]]:
    ids = _ids(tree)
    found = []
    for element in tree.iter(etree.Element):
        for attribute in CHECKED_REFS:
            value = element.get(attribute)
            if value in ids:
                found.append((element, attribute, value))
    return found


def _bytes(tree: etree._ElementTree) -> bytes:
    return etree.tostring(tree, xml_declaration=True, encoding="UTF-8")


def _deleted(model: Path, rng: random.Random, count: int) -> list[Mutation]:
    base = _tree(model)
    references = _referrers(base)
    ids = _ids(base)
    mutations = []
    for number in range(count):
        tree = copy.deepcopy(base)
        element, _attribute, value = rng.choice(references)
        target = _ids(tree)[value]
        referrer = next(
            e for e in tree.iter(etree.Element) if e.get(f"{XMI}id") == element.get(f"{XMI}id")
        )
        if target in referrer.iterancestors() or referrer in target.iter():
            continue  # deleting it would delete the reference too
        target.getparent().remove(target)
        mutations.append(
            Mutation(
                f"{model.parent.name}-delete-{number}-{ids[value].get('name')}",
                _bytes(tree),
                frozenset({1}),
            )
        )
    return mutations


def _duplicated(model: Path, rng: random.Random, count: int) -> list[Mutation]:
    base = _tree(model)
    candidates = [
        e for e in base.iter(etree.Element) if e.get(f"{XMI}id") and e.getparent() is not None
    ]
    mutations = []
    for number in range(count):
        tree = copy.deepcopy(base)
        chosen = rng.choice(candidates).get(f"{XMI}id")
        element = _ids(tree)[chosen]
        element.addnext(copy.deepcopy(element))
        mutations.append(
            Mutation(f"{model.parent.name}-duplicate-{number}", _bytes(tree), frozenset({1}))
        )
    return mutations


def _retargeted(model: Path, rng: random.Random, count: int) -> list[Mutation]:
    base = _tree(model)
    packages = [
        e.get(f"{XMI}id") for e in base.iter(etree.Element) if e.get(f"{XMI}type") == "uml:Package"
    ]
    references = _referrers(base)
    mutations = []
    for number in range(count):
        tree = copy.deepcopy(base)
        element, attribute, _ = rng.choice(references)
        twin = _ids(tree)[element.get(f"{XMI}id")]
        twin.set(attribute, rng.choice(packages))  # a package is never the right kind
        mutations.append(
            Mutation(
                f"{model.parent.name}-retarget-{number}-{attribute}", _bytes(tree), frozenset({1})
            )
        )
    return mutations


def _wrong_types(model: Path, rng: random.Random, count: int) -> list[Mutation]:
    base = _tree(model)
    used = {value for _, _, value in _referrers(base)}
    kinds = {"uml:Signal", "uml:SignalEvent", "uml:StateMachine", "uml:Operation", "uml:Constraint"}
    candidates = [
        e.get(f"{XMI}id")
        for e in base.iter(etree.Element)
        if e.get(f"{XMI}type") in kinds and e.get(f"{XMI}id") in used
    ]
    mutations = []
    for number in range(count):
        tree = copy.deepcopy(base)
        element = _ids(tree)[rng.choice(candidates)]
        element.set(f"{XMI}type", "uml:Package")
        mutations.append(
            Mutation(f"{model.parent.name}-wrongtype-{number}", _bytes(tree), frozenset({1}))
        )
    return mutations


def _truncated(model: Path, rng: random.Random, count: int) -> list[Mutation]:
    text = model.read_bytes()
    cuts = sorted(rng.sample(range(200, len(text) - 20), count))
    return [
        Mutation(f"{model.parent.name}-truncate-{cut}", text[:cut], frozenset({2})) for cut in cuts
    ]


def _huge_names(model: Path, rng: random.Random, count: int) -> list[Mutation]:
    base = _tree(model)
    named = [
        e.get(f"{XMI}id") for e in base.iter(etree.Element) if e.get("name") and e.get(f"{XMI}id")
    ]
    mutations = []
    for number in range(count):
        tree = copy.deepcopy(base)
        element = _ids(tree)[rng.choice(named)]
        element.set("name", "N" * 200_000 + str(number))
        # renaming may break name-based links (an outcome, a requirement): 0 or 1, never a crash
        mutations.append(
            Mutation(f"{model.parent.name}-hugename-{number}", _bytes(tree), frozenset({0, 1}))
        )
    return mutations


def _deep(model: Path) -> Mutation:
    base = _tree(model)
    state = next(e for e in base.iter("subvertex") if e.get(f"{XMI}type") == "uml:State")
    holder = state
    for level in range(120):
        region = etree.SubElement(holder, "region", {f"{XMI}id": f"_deep_r{level}"})
        holder = etree.SubElement(
            region,
            "subvertex",
            {f"{XMI}type": "uml:State", f"{XMI}id": f"_deep_s{level}", "name": f"L{level}"},
        )
    return Mutation(f"{model.parent.name}-deep-120", _bytes(base), frozenset({2}))


def corpus() -> list[Mutation]:
    mutations: list[Mutation] = []
    for model in SAMPLE_MODELS:
        rng = random.Random(f"{model.parent.name}-mutations")
        mutations += _deleted(model, rng, 40)
        mutations += _duplicated(model, rng, 20)
        mutations += _retargeted(model, rng, 20)
        mutations += _wrong_types(model, rng, 10)
        mutations += _truncated(model, rng, 12)
        mutations += _huge_names(model, rng, 3)
        mutations.append(_deep(model))
    return mutations


CORPUS = corpus()


def test_corpus_is_large_enough() -> None:
    assert len(CORPUS) >= 200
    assert len({m.name for m in CORPUS}) == len(CORPUS)


@pytest.mark.parametrize("mutation", CORPUS, ids=[m.name for m in CORPUS])
def test_mutation_ends_in_diagnostics(mutation: Mutation, tmp_path: Path) -> None:
    path = tmp_path / "mutant.xmi"
    path.write_bytes(mutation.text)
    result = pipeline.compile_model(path)  # any exception here is a crash
    code = result.validation.exit_code
    assert code in mutation.expected, pipeline.dg.render_text(result.validation.diagnostics)[:2000]
    if code != ExitCode.OK:
        assert result.validation.diagnostics and not result.files
        for d in result.validation.diagnostics:
            assert d.span.file == str(path) and d.code.id.startswith("SG")


@pytest.mark.parametrize("mutation", CORPUS[::12], ids=[m.name for m in CORPUS[::12]])
def test_mutation_through_the_cli(mutation: Mutation, tmp_path: Path) -> None:
    """The real entry point: no traceback, the documented exit code, nothing written."""
    path = tmp_path / "mutant.xmi"
    path.write_bytes(mutation.text)
    out = tmp_path / "out"
    completed = subprocess.run(
        [sys.executable, "-m", "swarmgen", "compile", str(path), "-o", str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=120, check=False,
    )  # fmt: skip
    assert completed.returncode in mutation.expected
    assert "Traceback" not in completed.stderr and "internal error" not in completed.stderr
    if completed.returncode != 0:
        assert not out.exists()


def test_a_100_mib_model_fails_fast(tmp_path: Path) -> None:
    path = tmp_path / "huge.xmi"
    with path.open("wb") as handle:
        handle.write(
            b'<?xml version="1.0"?><xmi:XMI xmlns:xmi="http://schema.omg.org/spec/XMI/2.1">'
        )
        handle.truncate(100 * 1024 * 1024)  # sparse: 100 MiB without writing them
    completed = subprocess.run(
        [sys.executable, "-m", "swarmgen", "validate", str(path)],
        capture_output=True, text=True, cwd=ROOT, timeout=60, check=False,
    )  # fmt: skip
    assert completed.returncode == 2
    assert "[SG005]" in completed.stdout and "limit is 64 MiB" in completed.stdout


# --- property tests ----------------------------------------------------------------------------

EVENTS = ["go", "stop", "ping", "pong"]


@st.composite
def models(draw: st.DrawFn) -> ModelKit:
    """Random valid swarms: nested and parallel states, events, behaviours, guards, effects."""
    kit = ModelKit(draw(st.sampled_from(["Alpha", "Beta swarm", "Gamma-Ω"])))
    kit.hardware("Sensor", "Sensor")
    kit.behaviour("Work", outputs={"result": "Integer"}, outcomes=["found"], requires=["Sensor"])
    for event in EVENTS:
        kit.event(event, {"value": "Integer"}, sender="station")
    m = kit.machine("Main")
    names = [f"S{i}" for i in range(draw(st.integers(2, 6)))]
    composite = draw(st.booleans())
    for name in names:
        m.state(name, do="Work" if draw(st.booleans()) else None)
    m.initial(names[0])
    if composite:
        regions = m.composite("Box", ["left", "right"] if draw(st.booleans()) else ["only"])
        for region in regions:
            inner = f"{region.replace('/', '_')}_A"
            m.state(inner, region=region)
            m.initial(inner, region=region)
            m.final(f"{inner}_end", region=region)
            m.transition(inner, f"{inner}_end", draw(st.sampled_from(EVENTS)))
        m.transition(names[0], "Box", draw(st.sampled_from(EVENTS)))
        m.transition("Box", names[-1])
    for _ in range(draw(st.integers(1, 8))):
        source, target = draw(st.sampled_from(names)), draw(st.sampled_from(names))
        state = next(s for s in m.states if s.name == source)
        trigger = draw(st.sampled_from([*EVENTS, "succeeded", "found"] if state.do else EVENTS))
        guard = draw(st.sampled_from(["", "count < 3", "event.value > count or flag", "not flag"]))
        effect = draw(
            st.sampled_from(["", "count = count + 1", "flag = not flag\nraise ping(value = count)"])
        )
        if trigger in {"succeeded", "found"} and "event." in guard:
            guard = ""  # outcome data is the behaviour's outputs, not `value`
        m.transition(source, target, trigger, guard=guard, effect=effect)
    m.final("End")
    m.transition(names[-1], "End", "stop")
    kit.member(
        "Bot",
        machine=m,
        parts={"eye": "Sensor"},
        data={"count": ("Integer", 0), "flag": ("Boolean", False), "result": ("Integer", 0)},
    )
    kit.swarm("Swarm", {"Bot": draw(st.integers(1, 5))})
    return kit


@settings(
    max_examples=12,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(kit=models())
def test_random_models_compile_validate_import_and_are_stable(
    kit: ModelKit, tmp_path: Path, scxml_schema: xmlschema.XMLSchema
) -> None:
    path = tmp_path / "random.xmi"
    path.write_text(kit.xmi(), encoding="utf-8")
    first = pipeline.compile_model(path, backends=["asyncio"])
    errors = [d for d in first.validation.diagnostics if d.level.value == "error"]
    assert not errors, pipeline.dg.render_text(errors)
    assert first.files == pipeline.compile_model(path, backends=["asyncio"]).files  # same bytes
    for relative, text in first.files.items():
        if relative.suffix == ".scxml":
            scxml_schema.validate(text)
    out = tmp_path / "out"
    pipeline.write_tree(first.files, out)
    package = next((out / "asyncio").iterdir())
    _import_and_build(package)


def _import_and_build(package: Path) -> None:
    name = f"_random_{abs(hash(package))}"
    spec = importlib.util.spec_from_file_location(
        name, package / "__init__.py", submodule_search_locations=[str(package)]
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
        for member in module.MEMBER_TYPES.values():
            chart = member.build()
            assert chart.root.initial is not None
    finally:
        for key in [k for k in sys.modules if k == name or k.startswith(name + ".")]:
            del sys.modules[key]


SAR_TEXT = (ROOT / "sample_models" / "sar" / "sar.xmi").read_bytes()


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    edits=st.lists(
        st.tuples(st.integers(0, len(SAR_TEXT) - 1), st.integers(0, 40), st.binary(max_size=8)),
        min_size=1,
        max_size=4,
    )
)
@example(edits=[(0, 0, b"PK\x03\x04")])  # a zip's magic: read as a .ramc, refused (SG067)
def test_random_corruptions_never_crash(
    edits: list[tuple[int, int, bytes]], tmp_path: Path
) -> None:
    text = bytearray(SAR_TEXT)
    for at, length, insert in edits:
        text[at : at + length] = insert
    path = tmp_path / "corrupt.xmi"
    path.write_bytes(bytes(text))
    result = pipeline.validate(path)  # any exception here is a crash
    errors = {d.code.id for d in result.diagnostics if d.level is Severity.ERROR}
    # the registry's input errors: the file could not be read in the format its content named
    # (XML, XMI, SCXML, or a Modelio archive when the corruption wrote a zip's magic bytes)
    unreadable = {d.code.id for d in result.diagnostics if d.code.input_error}
    for d in result.diagnostics:
        assert d.span.file == str(path) and d.code.id.startswith("SG"), d
    if result.exit_code == ExitCode.INPUT_ERROR:  # the file could not be read as XMI
        assert unreadable, errors
    elif result.exit_code == ExitCode.MODEL_ERRORS:  # read, and the model has errors
        assert errors and not unreadable and result.model is not None, errors
    else:
        assert result.exit_code == ExitCode.OK and not errors and result.model is not None
