"""Modelio's native files as input (issue 15 item 5; swarmgen/frontend/modelio*.py,
docs/modelio-input.md): `.exml` files and `.ramc` archives validate, compile into every backend
and run; hostile archives and malformed object graphs are located diagnostics, never a
traceback, and nothing of an archive is written to disk."""

from __future__ import annotations

import io
import re
import stat
import subprocess
import zipfile
from pathlib import Path
from typing import Any

import pytest

from swarmgen import pipeline, replay
from swarmgen.frontend import modelio_zip
from tests.conftest import REFERENCE as CORPUS
from tests.conftest import reference_absent, run_cli

MODELIO = CORPUS / "cpswarm_models" / "modelio"
RAMC = MODELIO / "CPSWarmLibrary_2019_modelio38.ramc"
EXML = MODELIO / "exml_2019_sar"
REFERENCE_FILES = [EXML / f"{n}.exml" for n in ("SarBehavior", "SarThreads", "IdleThreads")]
REFERENCE_FILES = [p for p in [*REFERENCE_FILES, RAMC] if p.is_file()]
BACKENDS = ("asyncio", "diagrams", "rclpy", "scxml", "smach")
needs_reference = pytest.mark.skipif(not RAMC.is_file(), reason=reference_absent(MODELIO))


def _codes(output: str) -> list[tuple[str, str]]:
    """(severity, code) of every diagnostic in the CLI's output."""
    return re.findall(r": (error|warning|note): .*\[(SG\d+)\]", output)


def _compile(model: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return run_cli("compile", str(model), "-o", str(out))


# --- the reference files ---------------------------------------------------------------------


@pytest.mark.skipif(not REFERENCE_FILES, reason=reference_absent(MODELIO))
@pytest.mark.parametrize("model", REFERENCE_FILES, ids=[p.name for p in REFERENCE_FILES])
def test_reference_file_validates_and_compiles_into_every_backend(
    model: Path, tmp_path: Path
) -> None:
    checked = run_cli("validate", str(model))
    assert checked.returncode == 0, checked.stdout + checked.stderr
    result = _compile(model, tmp_path / "out")
    assert result.returncode == 0, result.stdout + result.stderr
    found = _codes(result.stdout + result.stderr)
    assert ("note", "SG069") in found  # the profile the native files lack
    assert not [c for c in found if c[0] == "error"]
    for backend in BACKENDS:
        assert any((tmp_path / "out" / backend).iterdir()), backend
    assert "Traceback" not in result.stderr


def _machine(model: Path, name: str) -> Any:
    validation = pipeline.validate(model)
    assert validation.model is not None
    return next(m for m in validation.model.machines if m.name == name), validation


def _vertex_names(machine: Any) -> list[str]:
    return [v.name for r in machine.regions for v in r.vertices]


@needs_reference
def test_sar_behavior_machine_has_the_states_and_transitions_of_the_file() -> None:
    machine, validation = _machine(EXML / "SarBehavior.exml", "SarBehavior")
    assert _vertex_names(machine) == [
        "Initial State", "IdleThreads", "TakeOff", "Coverage", "Local Coverage",
        "Select Rover", "Tracking",
    ]  # fmt: skip
    names = {v.id: v.name for r in machine.regions for v in r.vertices}
    edges = sorted(
        (names[t.source], tuple(x.name for x in t.triggers), names[t.target])
        for t in machine.transitions
    )
    assert len(edges) == 10
    assert ("IdleThreads", ("missionStart",), "TakeOff") in edges
    assert ("Select Rover", ("aborted",), "Select Rover") in edges
    assert ("Tracking", ("aborted",), "Local Coverage") in edges
    events = {e.name for e in validation.model.events}
    assert events == {
        "succeeded", "aborted", "missionStart", "targetFound", "targetLost", "targetUpdate",
        "targetRescued",
    }  # fmt: skip
    # the submachines are in other files: a note each, the states stay simple
    notes = [d for d in validation.diagnostics if d.code.id == "SG069"]
    assert sorted(d.span.path.rsplit("::", 1)[1] for d in notes if "submachine" in d.message) == [
        "Coverage", "IdleThreads", "Local Coverage", "Tracking",
    ]  # fmt: skip


@needs_reference
def test_the_archive_resolves_submachines_across_its_files() -> None:
    machine, validation = _machine(RAMC, "SarThreads")
    assert _vertex_names(machine) == [
        "Initial State", "SarBehavior", "Final State", "MissionAbort", "Final State1",
    ]  # fmt: skip
    sar = next(v for r in machine.regions for v in r.vertices if v.name == "SarBehavior")
    behaviour = next(m for m in validation.model.machines if m.name == "SarBehavior")
    assert sar.submachine == behaviour.id  # a uid of another member of the archive
    assert {c.name for c in validation.charts} == {
        "SarThreads", "BeeCluster", "Fish_schooling", "Random_direction",
    }  # fmt: skip
    assert [p.name for p in machine.data] == ["w_0", "w_max", "rssi_thr"]  # Drone Controller's
    located = next(d for d in validation.diagnostics if "IdleEventMonitoring" in d.message)
    assert located.span.file == f"{RAMC}!model/model/Standard.StateMachine/{behaviour_file()}"
    assert located.span.xmi_id == "80f0763b-2242-4082-8ee0-d8a5717fa4e4"  # the region's uid
    assert located.span.path.endswith("Drone Controller::IdleThreads")


def behaviour_file() -> str:
    return "081ed592-0ef7-472c-867d-fe812fbbe888.exml"  # IdleThreads, entered at its one state


MISSION = [
    {"event": "missionStart"},
    {"event": "succeeded"},
    {"event": "succeeded"},
    {"event": "aborted"},
    {"event": "succeeded"},
    {"event": "aborted"},
    {"event": "missionAbort"},
]


@needs_reference
def test_sar_threads_replays_the_same_on_asyncio_and_in_qt() -> None:
    ours = replay.replay(RAMC, "SarThreads", MISSION, "asyncio")
    assert ours == replay.replay(RAMC, "SarThreads", MISSION, "scxml")
    leaves = [set(r["active"]) - {"SarBehavior"} for r in ours]
    assert leaves == [
        {"IdleThreads", "IdleEventMonitoring"},
        {"TakeOff"},
        {"Coverage"},
        {"Select_Rover"},
        {"Select_Rover"},
        {"Tracking"},
        {"Local_Coverage"},
        {"Final_State1"},  # MissionAbort left at once on completion
    ]


# --- a model component made here -------------------------------------------------------------

CLASS_UID = "c0000000-0000-0000-0000-000000000001"
MACHINE_UID = "c0000000-0000-0000-0000-000000000002"
SUB_UID = "c0000000-0000-0000-0000-000000000003"


def _att(name: str, value: str) -> str:
    return f'<ATT name="{name}"><![CDATA[{value}]]></ATT>'


def _obj(mc: str, uid: str, name: str, atts: str = "", deps: str = "", pid: str = "") -> str:
    return (
        f'<OBJECT><ID name="{name}" mc="Standard.{mc}" uid="{uid}"/>{pid}'
        f"<ATTRIBUTES>{_att('Name', name)}{atts}</ATTRIBUTES>"
        f"<DEPENDENCIES>{deps}</DEPENDENCIES></OBJECT>"
    )


def _ext(body: str) -> bytes:
    return f'<?xml version="1.0" ?>\n<EXT object="x" version="4">\n{body}\n</EXT>\n'.encode()


def _link(relation: str, mc: str, uid: str, name: str = "x") -> str:
    ref = f'<REFOBJ><ID name="{name}" mc="Standard.{mc}" uid="{uid}"/></REFOBJ>'
    return f'<LINK relation="{relation}">{ref}</LINK>'


def _transition(uid: str, target: str, guard: str = "", effect: str = "", event: str = "") -> str:
    atts = _att("Guard", guard) + _att("Effect", effect)
    deps = _link("Target", "State", target)
    if event:
        deps = _link("Trigger", "Event", event) + deps
    return f'<COMP relation="OutGoing">{_obj("Transition", uid, "T" + uid[-2:], atts, deps)}</COMP>'


PID = f'<PID name="Counter" mc="Standard.Class" uid="{CLASS_UID}"/>'
CLASS = _ext(
    _obj(
        "Class",
        CLASS_UID,
        "Counter",
        deps='<COMP relation="OwnedAttribute">'
        + _obj(
            "Attribute",
            "a0000000-0000-0000-0000-000000000001",
            "count",
            _att("Value", "3"),
            '<LINK relation="Type"><FOREIGNID name="integer" mc="Standard.DataType" '
            'uid="00000004-0000-0009-0000-000000000000"/></LINK>',
        )
        + "</COMP>",
    )
)
SUB = _ext(
    _obj(
        "StateMachine",
        SUB_UID,
        "Inner",
        pid=PID,
        deps='<COMP relation="Top">'
        + _obj("Region", "r0000000-0000-0000-0000-000000000009", "", deps="")
        + "</COMP>",
    )
)


def _machine_file(
    target: str = "s0000000-0000-0000-0000-000000000002",
    guard: str = "count > 2",
    effect: str = "count = count + 1",
) -> bytes:
    """Counter: Initial -> Idle; Idle --go [count > 2] / count = count + 1--> Busy (a
    submachine state of Inner); Busy --go--> Done."""
    initial = _obj(
        "InitialPseudoState",
        "s0000000-0000-0000-0000-000000000000",
        "Initial",
        deps=_transition(
            "t0000000-0000-0000-0000-000000000001", "s0000000-0000-0000-0000-000000000001"
        ),
    )
    idle = _obj(
        "State",
        "s0000000-0000-0000-0000-000000000001",
        "Idle",
        deps=_transition(
            "t0000000-0000-0000-0000-000000000002",
            target,
            guard=guard,
            effect=effect,
            event="e0000000-0000-0000-0000-000000000001",
        ),
    )
    busy = _obj(
        "State",
        "s0000000-0000-0000-0000-000000000002",
        "Busy",
        deps=f'<LINK relation="SubMachine"><ID name="Inner" mc="Standard.StateMachine" '
        f'uid="{SUB_UID}"/></LINK>'
        + _transition(
            "t0000000-0000-0000-0000-000000000003",
            "s0000000-0000-0000-0000-000000000003",
            event="e0000000-0000-0000-0000-000000000001",
        ),
    )
    done = _obj("FinalState", "s0000000-0000-0000-0000-000000000003", "Done")
    region = _obj(
        "Region",
        "r0000000-0000-0000-0000-000000000001",
        "",
        deps=f'<COMP relation="Sub">{initial}{idle}{busy}{done}</COMP>',
    )
    event = _obj("Event", "e0000000-0000-0000-0000-000000000001", "go", _att("Kind", "SignalEvent"))
    return _ext(
        _obj(
            "StateMachine",
            MACHINE_UID,
            "Counting",
            pid=PID,
            deps=f'<COMP relation="Top">{region}</COMP><COMP relation="EComponent">{event}</COMP>',
        )
    )


def _ramc(path: Path, members: dict[str, bytes], method: int = zipfile.ZIP_DEFLATED) -> Path:
    with zipfile.ZipFile(path, "w", method) as archive:
        archive.writestr("metadatas.xml", b"<ram-component/>")
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def _component(tmp_path: Path, machine: bytes | None = None) -> Path:
    return _ramc(
        tmp_path / "counter.ramc",
        {
            f"model/model/Standard.Class/{CLASS_UID}.exml": CLASS,
            f"model/model/Standard.StateMachine/{MACHINE_UID}.exml": machine or _machine_file(),
            f"model/model/Standard.StateMachine/{SUB_UID}.exml": SUB,
        },
    )


def test_a_component_made_here_compiles_and_runs_guards_effects_and_data(tmp_path: Path) -> None:
    model = _component(tmp_path)
    result = _compile(model, tmp_path / "out")
    assert result.returncode == 0, result.stdout + result.stderr
    for backend in BACKENDS:
        assert any((tmp_path / "out" / backend).iterdir()), backend
    steps = [{"event": "go"}, {"event": "go"}]
    ours = replay.replay(model, "Counting", steps, "asyncio")
    assert ours == replay.replay(model, "Counting", steps, "scxml")
    assert [(r["active"], r["data"]["count"]) for r in ours] == [
        (["Idle"], 3),
        (["Busy"], 4),  # the guard held (3 > 2), the effect ran; Inner's region is empty
        (["Done"], 4),
    ]


def test_a_lone_exml_file_reads_without_its_archive(tmp_path: Path) -> None:
    model = tmp_path / "Counting.exml"
    model.write_bytes(_machine_file(guard="", effect=""))  # no class here: no data to use
    result = run_cli("validate", str(model))
    assert result.returncode == 0, result.stdout + result.stderr
    assert (
        "the submachine 'Inner' of state 'Busy' is not in the files read"
        in result.stderr + result.stdout
    )


# --- hostile archives --------------------------------------------------------------------------


def _zip_bytes(
    entries: list[tuple[zipfile.ZipInfo | str, bytes]], method: int = zipfile.ZIP_DEFLATED
) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", method) as archive:
        for info, data in entries:
            archive.writestr(info, data)
    return buffer.getvalue()


def _symlink() -> zipfile.ZipInfo:
    info = zipfile.ZipInfo("model/model/link.exml")
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info


def _valid() -> bytes:
    return _zip_bytes([(f"model/model/Standard.StateMachine/{MACHINE_UID}.exml", _machine_file())])


ZEROS = b"\0" * (2 * 1024 * 1024)
HOSTILE: dict[str, tuple[Any, str, str]] = {
    # case: (archive bytes or a builder, expected text, the member the span names or "")
    "bomb-ratio": (
        lambda: _zip_bytes([("model/model/bomb.exml", ZEROS)]),
        "expands",
        "model/model/bomb.exml",
    ),
    "member-too-large": (
        lambda: _zip_bytes([("model/model/big.exml", b"\0" * (modelio_zip.MAX_MEMBER_BYTES + 1))]),
        "the limit is 16,777,216",
        "model/model/big.exml",
    ),
    "total-too-large": (
        lambda: _zip_bytes([(f"model/model/{i}.exml", b"\0" * (15 * 2**20)) for i in range(5)]),
        "the archive expands to",
        "",
    ),
    "too-many-members": (
        lambda: _zip_bytes([(f"d{i}/", b"") for i in range(modelio_zip.MAX_MEMBERS + 1)]),
        "the limit is 10,000",
        "",
    ),
    "parent-path": (
        lambda: _zip_bytes([("model/../x.exml", b"<EXT/>")]),
        "'..' component",
        "model/../x.exml",
    ),
    "absolute-path": (
        lambda: _zip_bytes([("/x.exml", b"<EXT/>")]),
        "absolute path",
        "/x.exml",
    ),
    "backslash": (
        lambda: _zip_bytes([("model\\..\\x.exml", b"<EXT/>")]),
        "backslash",
        "model\\..\\x.exml",
    ),
    "duplicate-member": (
        lambda: _zip_bytes([("model/a.exml", b"<EXT/>"), ("model/a.exml", b"<EXT/>")]),
        "twice",
        "model/a.exml",
    ),
    "symlink": (
        lambda: _zip_bytes([(_symlink(), b"/etc/passwd")]),
        "symbolic link",
        "model/model/link.exml",
    ),
    "nested-ramc": (
        lambda: _zip_bytes([("model/inner.ramc", _valid())]),
        "nested archives are not read",
        "model/inner.ramc",
    ),
    "bzip2": (
        lambda: _zip_bytes([("model/model/a.exml", _machine_file())], zipfile.ZIP_BZIP2),
        "compressed with method 12",
        "model/model/a.exml",
    ),
    "pk-magic-not-zip": (lambda: b"PK\x03\x04" + b"garbage" * 20, "not a readable zip", ""),
    "truncated": (lambda: _valid()[: len(_valid()) // 2], "not a readable zip", ""),
    "no-exml": (lambda: _zip_bytes([("metadatas.xml", b"<ram-component/>")]), "no .exml", ""),
}


@pytest.mark.filterwarnings("ignore:Duplicate name")  # zipfile warns when writing one
@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_hostile_archive_is_a_located_error(case: str, tmp_path: Path) -> None:
    build, expected, member = HOSTILE[case]
    path = tmp_path / "hostile.ramc"
    path.write_bytes(build())
    before = sorted(tmp_path.rglob("*"))
    result = run_cli("validate", str(path))
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    assert "Traceback" not in output and "internal error" not in output
    assert ("error", "SG067") in _codes(output), output
    assert expected in output
    where = f"{path}!{member}" if member else f"{path}: error"
    assert where in output
    assert sorted(tmp_path.rglob("*")) == before  # nothing extracted, nothing written


# --- malformed object graphs -------------------------------------------------------------------

DANGLING = "s9999999-0000-0000-0000-000000000000"
MALFORMED: dict[str, tuple[bytes, str, str]] = {
    # case: (the machine file, code, expected text)
    "bad-xml": (b"<EXT><OBJECT></EXT>", "SG002", "not well-formed"),
    "dangling-target": (_machine_file(DANGLING), "SG068", f"names uid {DANGLING}"),
    "no-uid": (
        _ext('<OBJECT><ID name="M" mc="Standard.StateMachine"/></OBJECT>'),
        "SG068",
        "has no <ID> with a uid",
    ),
    "duplicate-uid": (
        _machine_file().replace(
            b"t0000000-0000-0000-0000-000000000003", b"t0000000-0000-0000-0000-000000000002"
        ),
        "SG068",
        "is used twice",
    ),
    "not-ext": (b"<OBJECT/>", "SG004", "<OBJECT>"),
    "dtd": (b'<!DOCTYPE EXT [<!ENTITY x "y">]><EXT/>', "SG003", ""),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
@pytest.mark.parametrize("container", ["exml", "ramc"])
def test_malformed_exml_is_a_located_error(case: str, container: str, tmp_path: Path) -> None:
    data, code, expected = MALFORMED[case]
    member = f"model/model/Standard.StateMachine/{MACHINE_UID}.exml"
    if container == "exml":
        path = tmp_path / "m.exml"
        path.write_bytes(data)
        where = f"{path}:"
    else:
        path = _component(tmp_path, data)
        where = f"{path}!{member}"
        code = "SG068" if code == "SG004" else code  # a member is an .exml by its place
    result = run_cli("validate", str(path))
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    assert "Traceback" not in output
    assert ("error", code) in _codes(output), output
    assert expected in output and where in output
