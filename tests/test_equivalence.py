"""Cross-backend equivalence: for every sample model and member type, and for generated
scenarios (seeded walks, abort in the middle of every state reached, behaviour failures,
inputs arriving back to back, and the edge families of tests/scenarios.py: outputs read by
guards, outcomes no transition takes, history re-entry, submachine completion, mixed bursts,
guards that raise, names a descriptor matches by token prefix and names it does not), the generated Python backends give exactly the trace of the emitted SCXML
run in Qt SCXML (an independent engine). A sample of those scenarios also runs on real rclpy.

The firewatch model (tests/fixtures/models/firewatch.xmi, written by make_firewatch.py) is the
bug report's: a behaviour's outputs must be written before its outcome is matched, so that
`fire_intensity > 0.5` on the `succeeded` transition sees the value the behaviour gave.
"""

from __future__ import annotations

import functools
import json
import zlib
from pathlib import Path
from typing import Any

import pytest

from swarmgen import pipeline, replay
from swarmgen.backends import names as backend_names
from swarmgen.chart.lower import lower
from tests.conftest import ROOT, SAMPLE_MODELS, XMI_SAMPLES, reference_absent
from tests.scenarios import ScenarioMaker, failure_scenarios
from tests.skips import need_rclpy

WALKS = 16
WALK_LENGTH = 40
FIREWATCH = ROOT / "tests" / "fixtures" / "models" / "firewatch.xmi"
# enumerations driving guards, a sequence through behaviours and an event, nested data types
DISPATCH = ROOT / "tests" / "fixtures" / "models" / "dispatch.xmi"
# if/elif/else over outputs, unset data and event fields; failing conditions and effects;
# transitions on error.execution (docs/semantics.md)
TRIAGE = ROOT / "tests" / "fixtures" / "models" / "triage.xmi"
SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
_ALL_MODELS = [
    *SAMPLE_MODELS,
    XMI_SAMPLES / "emfuml4_hets_atm.xmi",
    XMI_SAMPLES / "papyrus_spring-sm_simple-history-deep.uml",
    XMI_SAMPLES / "papyrus_spring-sm_simple-forkjoin.uml",
    XMI_SAMPLES / "papyrus_spring-sm_simple-connectionpointref.uml",
    FIREWATCH,
    DISPATCH,
    TRIAGE,
]
# The reference files live in ../shared, which a user's clone does not have.
MODELS = [m for m in _ALL_MODELS if m.exists()]
MISSING = [m for m in _ALL_MODELS if not m.exists()]


def test_reference_models_are_here() -> None:
    if MISSING:
        pytest.skip(reference_absent(", ".join(m.name for m in MISSING)))
    assert len(MODELS) == len(_ALL_MODELS)


PYTHON_BACKENDS = [b for b in backend_names() if b in replay.BACKENDS and b != "scxml"]
ALL_BACKENDS = ["asyncio", "smach", "scxml", "rclpy"]
RCLPY_CASES = [(FIREWATCH, "Scout"), (SAR, "UAV")]
RCLPY_SAMPLE = 6  # scenarios per case on rclpy (its replay is slow)

Trace = list[dict[str, Any]]


def _cases() -> list[tuple[Path, str]]:
    cases = []
    for model in MODELS:
        validation = pipeline.validate(model)
        assert validation.model is not None
        cases += [(model, chart.member or chart.name) for chart in lower(validation.model)]
    return cases


@functools.cache
def _families(model: Path, member: str) -> dict[str, list[list[dict[str, Any]]]]:
    """The generated scenarios of one member type, by family (deterministic for the pair)."""
    validation = pipeline.validate(model)
    assert validation.model is not None
    chart = next(c for c in lower(validation.model) if (c.member or c.name) == member)
    maker = ScenarioMaker(chart, seed=zlib.crc32(f"{model.name}:{member}".encode()))
    walks = [maker.walk(WALK_LENGTH) for _ in range(WALKS)]
    return {
        "walks": walks,
        "aborts": maker.aborts(walks),
        "failures": failure_scenarios(chart, walks),
        "guarded_triggers": maker.guarded_triggers(),
        "untaken_outcomes": maker.untaken_outcomes(),
        "history_reentry": maker.history_reentry(),
        "submachine_completion": maker.submachine_completion(),
        "mixed_bursts": maker.mixed_bursts(),
        "descriptor_names": maker.descriptor_names(),
    }


def _scenarios(model: Path, member: str) -> list[list[dict[str, object]]]:
    return [s for family in _families(model, member).values() for s in family]


@pytest.mark.parametrize(("model", "member"), _cases(), ids=[f"{m.stem}-{t}" for m, t in _cases()])
def test_backends_agree_with_qt_scxml(model: Path, member: str, qt_available: None) -> None:
    scenarios = _scenarios(model, member)
    assert len(scenarios) >= WALKS
    reference = replay.replay_many(model, member, scenarios, "scxml")
    configurations = {str(r["active"]) for trace in reference for r in trace}
    assert len(configurations) >= 2, (
        f"the walks should visit several configurations: {configurations}"
    )
    for backend in sorted(PYTHON_BACKENDS, key=lambda b: b == "rclpy"):
        if backend == "rclpy":
            need_rclpy()  # last: without the `ros` extra, the others were still compared
        traces = replay.replay_many(model, member, scenarios, backend)
        for number, (ours, theirs) in enumerate(zip(traces, reference, strict=True)):
            assert ours == theirs, _first_difference(
                backend, number, scenarios[number], ours, theirs
            )


def test_firewatch_edge_families_are_generated() -> None:
    """The generator reaches what the firewatch model is for (else the equivalence above
    proves little): every family yields scenarios for the scout."""
    families = _families(FIREWATCH, "Scout")
    assert all(families.values()), {k: len(v) for k, v in families.items()}
    steps = [i for s in _scenarios(FIREWATCH, "Scout") for st in s for i in st.get("burst", [st])]
    intensities = {
        i["outputs"].get("fire_intensity") for i in steps if i.get("complete") == "Patrol"
    }
    assert {0.49, 0.5, 0.51, 0.9, 0.91} <= intensities  # both sides of both guards
    batteries = {
        i["outputs"].get("battery") for i in steps if i.get("complete") == "MonitorBattery"
    }
    assert {19.99, 20.01, 29.99, 30.0, 49.99, 50.0} <= batteries  # raise lowBattery, consume it
    assert any(i.get("outcome") == "unplanned" for i in steps)  # an undeclared outcome
    assert any(i.get("complete") == "Patrol" and i["outputs"] == {} for i in steps)  # zeros
    relay = [i for s in _scenarios(FIREWATCH, "Relay") for st in s for i in st.get("burst", [st])]
    fires = [i["data"] for i in relay if i.get("event") == "fireFound"]
    assert any(d.get("fire_id") == 0 for d in fires)  # a zero divisor in the guard
    assert any("fire_id" not in d for d in fires)  # a missing field in the guard


# --- rclpy, on a sample


def _rclpy_sample(model: Path, member: str) -> list[list[dict[str, Any]]]:
    """A few scenarios from different families (edge families first), the shorter first."""
    families = _families(model, member)
    order = [
        "guarded_triggers",
        "untaken_outcomes",
        "history_reentry",
        "mixed_bursts",
        "descriptor_names",
        "submachine_completion",
        "failures",
        "walks",
    ]
    pools = [sorted(families[f], key=len) for f in order if families[f]]
    sample: list[list[dict[str, Any]]] = []
    while len(sample) < RCLPY_SAMPLE and any(pools):
        for pool in pools:
            if pool and len(sample) < RCLPY_SAMPLE:
                sample.append(pool.pop(0))
    return sample


# Focused firewatch scout scenarios: what the bug report is about.
_START = [
    {"event": "missionStart", "data": {}},
    {"complete": "TakeOff", "outcome": "succeeded", "outputs": {}},
]
FOCUSED: dict[str, list[dict[str, Any]]] = {
    "high": [
        *_START,
        {
            "complete": "Patrol",
            "outcome": "succeeded",
            "outputs": {"fire_id": 4, "fire_intensity": 0.9},
        },
    ],
    "low": [
        *_START,
        {
            "complete": "Patrol",
            "outcome": "succeeded",
            "outputs": {"fire_id": 5, "fire_intensity": 0.2},
        },
    ],
    "untaken": [
        *_START,
        # `smoke` is taken only above 0.9, so nothing leaves Patrolling
        {
            "complete": "Patrol",
            "outcome": "smoke",
            "outputs": {"fire_id": 7, "fire_intensity": 0.3},
        },
        # 40 is in neither [0, 30) nor [50, ...): no transition takes this `succeeded`
        {"complete": "MonitorBattery", "outcome": "succeeded", "outputs": {"battery": 40.0}},
    ],
    "preempted": [
        *_START,
        # no transition waits for `preempted`
        {
            "complete": "Patrol",
            "outcome": "preempted",
            "outputs": {"fire_id": 8, "fire_intensity": 0.6},
        },
    ],
    "omitted": [
        *_START,
        # `aborted` re-enters Patrolling (the behaviour starts again) with outputs written
        {
            "complete": "Patrol",
            "outcome": "aborted",
            "outputs": {"fire_id": 7, "fire_intensity": 0.3},
        },
        # an output the behaviour does not give is written as its type's zero
        {"complete": "Patrol", "outcome": "smoke", "outputs": {"fire_intensity": 0.95}},
    ],
}
FOCUSED_NAMES = list(FOCUSED)


@pytest.fixture(scope="module")
def rclpy_traces() -> dict[tuple[str, str], tuple[list[list[dict[str, Any]]], list[Trace]]]:
    """One rclpy replay per case (a subprocess; the interfaces are built once and kept in the
    venv): the sampled scenarios, and for the firewatch scout also the focused ones.
    Replay runs with ROS discovery off (swarmgen.ros_harness), so no DDS traffic leaves it."""
    need_rclpy()
    runs: dict[tuple[str, str], tuple[list[list[dict[str, Any]]], list[Trace]]] = {}
    for model, member in RCLPY_CASES:
        scenarios = _rclpy_sample(model, member)
        if model == FIREWATCH and member == "Scout":
            scenarios = [*(FOCUSED[n] for n in FOCUSED_NAMES), *scenarios]
        runs[(model.stem, member)] = (
            scenarios,
            replay.replay_many(model, member, scenarios, "rclpy"),
        )
    return runs


@pytest.mark.parametrize(
    ("model", "member"), RCLPY_CASES, ids=[f"{m.stem}-{t}" for m, t in RCLPY_CASES]
)
def test_rclpy_agrees_with_qt_scxml(
    model: Path,
    member: str,
    qt_available: None,
    rclpy_traces: dict[tuple[str, str], tuple[list[list[dict[str, Any]]], list[Trace]]],
) -> None:
    scenarios, ours = rclpy_traces[(model.stem, member)]
    assert 0 < len(scenarios) <= RCLPY_SAMPLE + len(FOCUSED)
    reference = replay.replay_many(model, member, scenarios, "scxml")
    for number, (mine, theirs) in enumerate(zip(ours, reference, strict=True)):
        assert mine == theirs, _both_traces("rclpy", number, scenarios[number], mine, theirs)


# --- focused: outputs are written before the outcome is matched


@functools.cache
def _focused_traces(backend: str) -> tuple[Trace, ...]:
    scenarios = [FOCUSED[n] for n in FOCUSED_NAMES]
    return tuple(replay.replay_many(FIREWATCH, "Scout", scenarios, backend))


def _focused(backend: str, name: str, request: pytest.FixtureRequest) -> Trace:
    if backend == "rclpy":
        runs = request.getfixturevalue("rclpy_traces")
        _, traces = runs[(FIREWATCH.stem, "Scout")]
        return traces[FOCUSED_NAMES.index(name)]
    if backend == "scxml":
        request.getfixturevalue("qt_available")
    return _focused_traces(backend)[FOCUSED_NAMES.index(name)]


def _show(trace: Trace) -> str:
    return "\n".join(f"    {json.dumps(r, sort_keys=True)}" for r in trace)


@pytest.mark.parametrize("backend", ALL_BACKENDS)
def test_firewatch_patrol_outputs_choose_the_target(
    backend: str, request: pytest.FixtureRequest
) -> None:
    """Patrol ends `succeeded` with fire_intensity 0.9: `> 0.5` holds (Extinguishing); with
    0.2: `<= 0.5` holds (Observing), and its effect `reports = reports + 1` reads `reports`,
    never written before: 0 (Integer's zero), so 1."""
    high = _focused(backend, "high", request)
    assert "Extinguishing" in high[-1]["active"] and "Observing" not in high[-1]["active"], (
        f"{backend}: fire_intensity 0.9 must enter Extinguishing:\n{_show(high)}"
    )
    assert high[-1]["data"]["fire_intensity"] == 0.9 and high[-1]["data"]["fire_id"] == 4, (
        f"{backend}:\n{_show(high)}"
    )
    low = _focused(backend, "low", request)
    assert "Observing" in low[-1]["active"] and "Extinguishing" not in low[-1]["active"], (
        f"{backend}: fire_intensity 0.2 must enter Observing:\n{_show(low)}"
    )
    assert low[-1]["data"]["fire_intensity"] == 0.2 and low[-1]["data"]["reports"] == 1, (
        f"{backend}:\n{_show(low)}"
    )


@pytest.mark.parametrize("backend", ALL_BACKENDS)
def test_firewatch_outputs_written_when_no_transition_fires(
    backend: str, request: pytest.FixtureRequest
) -> None:
    trace = _focused(backend, "untaken", request)
    smoke, battery = trace[3], trace[4]
    assert "Patrolling" in smoke["active"], f"{backend}: smoke at 0.3 is not taken:\n{_show(trace)}"
    assert smoke["data"]["fire_id"] == 7 and smoke["data"]["fire_intensity"] == 0.3, (
        f"{backend}: the outputs of an outcome no transition takes are member data:\n{_show(trace)}"
    )
    assert "Monitoring" in battery["active"] and battery["data"]["battery"] == 40, (
        f"{backend}: battery 40 is written though no guard holds:\n{_show(trace)}"
    )
    trace = _focused(backend, "preempted", request)
    preempted = trace[3]
    assert "Patrolling" in preempted["active"], f"{backend}:\n{_show(trace)}"
    assert preempted["data"]["fire_id"] == 8 and preempted["data"]["fire_intensity"] == 0.6, (
        f"{backend}: `preempted` (no transition) writes its outputs too:\n{_show(trace)}"
    )


@pytest.mark.parametrize("backend", ALL_BACKENDS)
def test_firewatch_omitted_outputs_are_zero(backend: str, request: pytest.FixtureRequest) -> None:
    trace = _focused(backend, "omitted", request)
    aborted, smoke = trace[3], trace[4]
    assert aborted["data"]["fire_id"] == 7, f"{backend}:\n{_show(trace)}"
    assert "Observing" in smoke["active"], f"{backend}: smoke at 0.95 is taken:\n{_show(trace)}"
    assert smoke["data"]["fire_id"] == 0 and smoke["data"]["fire_intensity"] == 0.95, (
        f"{backend}: an output the behaviour does not give is written as 0:\n{_show(trace)}"
    )


@pytest.mark.parametrize("backend", ALL_BACKENDS)
def test_firewatch_data_start_typed(backend: str, request: pytest.FixtureRequest) -> None:
    """Member data without a default hold their type's zero from the start."""
    start = _focused(backend, "high", request)[0]["data"]
    expected = {
        "alert": False,
        "battery": 0,
        "fire_id": 0,
        "fire_intensity": 0,
        "home": {"x": 0, "y": 0},
        "label": "",
        "last_fire": 0,
        "reports": 0,
    }
    assert start == expected, f"{backend}: {start}"


# --- messages


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


def _both_traces(backend: str, number: int, steps: object, ours: Trace, theirs: Trace) -> str:
    """The first difference, then both traces in full (one record a line)."""
    return (
        f"{_first_difference(backend, number, steps, ours, theirs)}\n"
        f"  {backend} trace:\n{_show(ours)}\n  qt trace:\n{_show(theirs)}"
    )


# Dispatch's Plan gives only `route` and `zone`, then `mode` too: an enumeration-typed output
# the behaviour does not give is written as the enumeration's first literal, not "" (the value
# rule, docs/semantics.md); Planning's `mode != Mode.track` then holds and sets `home`.
DISPATCH_OMITTED = [
    {"event": "missionStart"},
    {"complete": "Plan", "outcome": "succeeded", "outputs": {"route": [1.0], "zone": {}}},
    {"event": "missionStart"},
    {"complete": "Plan", "outcome": "aborted", "outputs": {}},
]


@pytest.mark.parametrize("backend", ALL_BACKENDS)
def test_dispatch_omitted_enum_output_is_its_first_literal(
    backend: str, request: pytest.FixtureRequest
) -> None:
    if backend == "scxml":
        request.getfixturevalue("qt_available")
    if backend == "rclpy":
        need_rclpy()
    (trace,) = replay.replay_many(DISPATCH, "Rover", [DISPATCH_OMITTED], backend)
    planned, aborted = trace[2], trace[4]
    assert planned["data"]["mode"] == "home" and planned["data"]["route"] == [1.0], (
        f"{backend}: the omitted mode is `search`, so `mode != Mode.track` sets home:\n{_show(trace)}"
    )
    assert aborted["data"]["mode"] == "search" and aborted["data"]["route"] == [], (
        f"{backend}: outputs not given are the zeros `search` and []:\n{_show(trace)}"
    )
