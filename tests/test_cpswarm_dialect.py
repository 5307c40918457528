"""The CPSwarm code generator's SCXML dialect (issue 15, item 4; swarmgen/frontend/scxml_cpswarm.py,
docs/scxml-input.md "CPSwarm dialect"): rosaction / rosservice states become library behaviours
bound to their ROS interface, rosmonitor states event sources on their topic; the 15 reference
files compile into every backend and run the same on the asyncio backend and in Qt SCXML."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path
from typing import Any

import pytest

from swarmgen import replay
from tests.conftest import REFERENCE as CORPUS
from tests.conftest import reference_absent, run_cli

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = CORPUS / "cpswarm_models" / "code-generator"
REFERENCE_FILES = sorted(REFERENCE.glob("*/*.xml")) if REFERENCE.is_dir() else []
BACKENDS = ("asyncio", "rclpy", "scxml", "smach")


def _compile(model: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return run_cli("compile", str(model), "-o", str(out))


def _codes(output: str) -> list[tuple[int, str, str]]:
    """(line, severity, code) of every diagnostic of the compile output."""
    found = re.findall(r":(\d+):\d+: (error|warning|note): .*\[(SG\d+)\]", output)
    return [(int(line), severity, code) for line, severity, code in found]


@pytest.mark.skipif(not REFERENCE_FILES, reason=reference_absent(REFERENCE))
@pytest.mark.parametrize(
    "model", REFERENCE_FILES, ids=[f"{p.parent.name}/{p.stem}" for p in REFERENCE_FILES]
)
def test_reference_file_compiles_into_every_backend_and_loads_in_qt(
    model: Path, tmp_path: Path
) -> None:
    result = _compile(model, tmp_path / "out")
    assert result.returncode == 0, result.stdout + result.stderr
    assert not [c for c in _codes(result.stderr + result.stdout) if c[1] == "error"]
    for backend in BACKENDS:
        assert any((tmp_path / "out" / backend).iterdir()), backend
    documents = sorted((tmp_path / "out" / "scxml").glob("*.scxml"))
    assert len(documents) == 1
    trace = replay.run_qt(documents[0], [])  # raises when Qt SCXML cannot load the document
    assert trace[0]["active"]


FSM2 = REFERENCE / "current" / "UAV_sar_FSM2.xml"
MISSION: list[dict[str, Any]] = [
    {"complete": "IdleEventMonitoring", "outcome": "succeeded"},  # bridge/events/mission_start
    {"complete": "TakeOff", "outcome": "succeeded"},
    {"complete": "Coverage", "outcome": "succeeded"},
]
ABORT: list[dict[str, Any]] = [
    {"event": "missionStart"},  # the station may send the monitored event itself
    {"complete": "AbortEventMonitoring", "outcome": "succeeded"},
    {"complete": "Land", "outcome": "succeeded"},
]


def _leaves(record: dict[str, Any]) -> set[str]:
    active = record["active"]
    assert isinstance(active, list)
    return {str(s) for s in active}


@pytest.mark.skipif(not FSM2.is_file(), reason=reference_absent(REFERENCE))
def test_sar_fsm2_replays_the_same_on_asyncio_and_in_qt() -> None:
    for steps in (MISSION, ABORT):
        ours = replay.replay(FSM2, "sar", steps, "asyncio")
        qt = replay.replay(FSM2, "sar", steps, "scxml")
        assert ours == qt
    mission = replay.replay(FSM2, "sar", MISSION, "asyncio")
    walked = [_leaves(r) & {"Idle__Idle", "TakeOff", "Coverage", "SelectRover"} for r in mission]
    assert walked == [{"Idle__Idle"}, {"TakeOff"}, {"Coverage"}, {"SelectRover"}]
    abort = replay.replay(FSM2, "sar", ABORT, "asyncio")
    assert "TakeOff" in _leaves(abort[1])
    assert "Land" in _leaves(abort[2]) and "SarThreads" not in _leaves(abort[2])
    assert "SarThreads" in _leaves(abort[3]) and "Idle__Idle" in _leaves(abort[3])


HEADER = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="{initial}" '
    'name="mission">\n'
)

CURRENT = (
    HEADER.format(initial="Threads")
    + """<parallel id="Threads">
<state id="Work">
<state id="TakeOff">
<datamodel><data id="adf"><name>uav_mavros_takeoff</name></data>
<data id="invoke"><rosaction><name>cmd/takeoff</name><action>uav_mavros_takeoff/TakeOff</action>
<goal type="fixed"><param>1.5</param><param>'high'</param></goal><result type="callback"/>
</rosaction></data></datamodel>
<invoke type="ROS_ACTION"/>
<transition event="succeeded" target="Coverage"/>
</state>
<state id="Coverage">
<datamodel><data id="invoke"><rosaction><name>uav_coverage</name>
<action>cpswarm_msgs/Coverage</action><goal type="empty"/>
<result type="userdata"><var>target_id</var><var>target_pose</var></result></rosaction>
<mappings><map><x>target_id</x><y>found_id</y></map>
<map><x>target_pose</x><y>target_pose</y></map></mappings></data></datamodel>
<invoke type="ROS_ACTION"/>
<transition event="succeeded" target="Tracking"/>
</state>
<state id="Tracking">
<datamodel><data id="invoke"><rosaction><name>uav_tracking</name><action>cpswarm_msgs/Tracking</action>
<goal type="userdata"><var>target</var></goal><result type="empty"/></rosaction>
<mappings><map><x>target</x><y>found_id</y></map></mappings></data></datamodel>
<invoke type="ROS_ACTION"/>
</state>
</state>
<state id="AbortMonitoring">
<datamodel><data id="invoke"><rosmonitor><topic>bridge/events/mission_abort</topic>
<msg>swarmros/SimpleEvent</msg></rosmonitor></data></datamodel>
<invoke type="ROS_MONITOR"/>
</state>
<transition event="missionAbort" target="Abort"/>
</parallel>
<state id="Abort">
<state id="Land">
<datamodel><data id="invoke"><rosservice><name>cmd/land</name><srv>cpswarm_msgs/Land</srv>
<request type="userdata"><var>height</var></request><response type="empty"/></rosservice>
</data></datamodel>
<invoke type="ROS_SERVICE"/>
</state>
<transition event="succeeded" target="Threads"/>
</state>
</scxml>
"""
)

LEGACY = (
    HEADER.format(initial="Threads")
    + """<parallel id="Threads">
<state id="Work">
<state id="SelectRover">
<datamodel>
<data id="invoke"><rosaction><name>cmd/compute_cost</name><action>ComputeCost</action><goal type="slot"><var>target_id</var></goal></rosaction>
</data>
</datamodel>
<invoke type="ROS_ACTION" />
<transition event="aborted" target="SelectRover"/>
</state>
</state>
<state id="GoHomeMonitoring">
<datamodel>
<data id="invoke"><rosmonitor><topic>bridge/events/go_home</topic><msg>SimpleEvent</msg></rosmonitor>
</data>
</datamodel>
<invoke type="ROS_MONITOR" />
</state>
<transition event="goHome" target="Land"/>
</parallel>
<state id="Land">
<datamodel>
<data id="invoke"><rosservice><name>cmd/land</name><srv>std_srvs.srv.Empty</srv><request empty="true"/></rosservice>
</data>
</datamodel>
<invoke type="ROS_SERVICE" />
</state>
</scxml>
"""
)


def _line(text: str, needle: str) -> int:
    return next(n for n, line in enumerate(text.splitlines(), 1) if needle in line)


def _declared(out: Path) -> str:
    return "\n".join(p.read_text() for p in sorted((out / "rclpy").rglob("*.py")))


def test_current_variant_every_construct(tmp_path: Path) -> None:
    source = tmp_path / "current.xml"
    source.write_text(CURRENT)
    result = _compile(source, tmp_path / "out")
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    codes = _codes(output)
    assert (_line(CURRENT, 'data id="adf"'), "note", "SG066") in codes  # ADF not read
    assert (_line(CURRENT, '<result type="callback"/>'), "note", "SG066") in codes
    assert (_line(CURRENT, "<var>height</var>"), "note", "SG066") in codes  # declared
    assert (_line(CURRENT, "<topic>bridge"), "note", "SG066") in codes  # monitor's event
    assert not [c for c in codes if c[2] in ("SG060", "SG061", "SG064", "SG065")]
    ros = _declared(tmp_path / "out")
    for declared in (
        '("action", "cmd/takeoff", "uav_mavros_takeoff/action/TakeOff")',
        '("action", "uav_coverage", "cpswarm_msgs/action/Coverage")',
        '("topic", "bridge/events/mission_abort", "swarmros/msg/SimpleEvent")',
        '("service", "cmd/land", "cpswarm_msgs/srv/Land")',
    ):
        assert declared in ros
    scxml = (tmp_path / "out" / "scxml" / "mission.scxml").read_text()
    assert '<sg:arg name="arg1" expr="1.5"/>' in scxml  # fixed params: bound literals
    assert '<sg:arg name="arg2" expr="&quot;high&quot;"/>' in scxml
    assert '<sg:arg name="target" expr="found_id"/>' in scxml  # an input mapping
    assert '<data id="height"' in scxml and '<data id="found_id"' in scxml
    assert '<data id="target"' not in scxml  # bound by its mapping, so not read from data


def test_current_variant_runs_outcomes_mappings_and_monitor(tmp_path: Path) -> None:
    source = tmp_path / "current.xml"
    source.write_text(CURRENT)
    steps: list[dict[str, Any]] = [
        {"complete": "TakeOff", "outcome": "succeeded"},
        {"complete": "Coverage", "outcome": "succeeded", "outputs": {"target_id": 7}},
        {"complete": "AbortMonitoring", "outcome": "succeeded"},
        {"complete": "Land", "outcome": "succeeded"},
    ]
    ours = replay.replay(source, "mission", steps, "asyncio")
    assert ours == replay.replay(source, "mission", steps, "scxml")
    assert "Coverage" in _leaves(ours[1])
    assert "Tracking" in _leaves(ours[2]) and ours[2]["data"]["found_id"] == 7
    assert "Land" in _leaves(ours[3])
    assert "TakeOff" in _leaves(ours[4])  # Abort's succeeded is Land's (SMACH's container rule)


def test_2019_variant(tmp_path: Path) -> None:
    source = tmp_path / "legacy.xml"
    source.write_text(LEGACY)
    result = _compile(source, tmp_path / "out")
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    codes = _codes(output)
    for needle in ("<action>ComputeCost", "<msg>SimpleEvent", "std_srvs.srv.Empty"):
        assert (_line(LEGACY, needle), "warning", "SG065") in codes, needle
    assert "read as 'cpswarm_msgs/action/ComputeCost'" in output  # the default package
    assert 'type="slot"' in output and 'empty="true"' in output  # 2019 spellings, read
    ros = _declared(tmp_path / "out")
    assert '("topic", "bridge/events/go_home", "swarmros/msg/SimpleEvent")' in ros
    assert '("service", "cmd/land", "std_srvs/srv/Empty")' in ros
    steps: list[dict[str, Any]] = [{"complete": "GoHomeMonitoring", "outcome": "succeeded"}]
    ours = replay.replay(source, "mission", steps, "asyncio")
    assert ours == replay.replay(source, "mission", steps, "scxml")
    assert "Land" in _leaves(ours[1])  # go_home raised goHome, the parallel's event


def _state(payload: str, invoke: str = '<invoke type="ROS_ACTION"/>') -> str:
    return (
        HEADER.format(initial="A")
        + f'<state id="A">\n<datamodel><data id="invoke">\n{payload}\n</data></datamodel>\n'
        + f"{invoke}\n</state>\n</scxml>\n"
    )


_ACTION = "<rosaction><name>cmd/a</name><action>p/A</action>{goal}</rosaction>"
BAD = {
    "rosaction-without-name": (
        _state("<rosaction><action>p/A</action></rosaction>"),
        "<rosaction>",
        "<rosaction> needs <name>",
    ),
    "unknown-goal-type": (
        _state(_ACTION.format(goal='<goal type="bogus"/>')),
        "<rosaction>",
        '<goal type="bogus"> is not one of: empty, fixed, callback, userdata',
    ),
    "unknown-result-type": (
        _state(_ACTION.format(goal='<result type="fixed"/>')),
        "<rosaction>",
        '<result type="fixed"> is not one of: empty, callback, userdata',
    ),
    "invoke-without-data": (
        HEADER.format(initial="A") + '<state id="A">\n<invoke type="ROS_SERVICE"/>\n</state>\n'
        "</scxml>\n",
        "<invoke",
        'has no <data id="invoke"> payload',
    ),
    "payload-without-invoke": (
        _state("<rosmonitor><topic>t</topic><msg>p/M</msg></rosmonitor>", ""),
        "<rosmonitor>",
        'no <invoke type="ROS_MONITOR"/>',
    ),
    "payload-of-another-type": (
        _state("<rosmonitor><topic>t</topic><msg>p/M</msg></rosmonitor>"),
        "<rosmonitor>",
        "<invoke type=\"ROS_ACTION\"> in state 'A' holds <rosmonitor>",
    ),
    "several-invokes": (
        _state(
            _ACTION.format(goal=""),
            '<invoke type="ROS_ACTION"/>\n<invoke type="ROS_ACTION" id="b"/>',
        ),
        'id="b"',
        "state 'A' has 2 <invoke> elements",
    ),
    "monitor-without-topic": (
        _state("<rosmonitor><msg>p/M</msg></rosmonitor>", '<invoke type="ROS_MONITOR"/>'),
        "<rosmonitor>",
        "<rosmonitor> needs <topic>",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_dialect_files_are_located_errors(case: str, tmp_path: Path) -> None:
    text, needle, message = BAD[case]
    source = tmp_path / "bad.xml"
    source.write_text(text)
    result = _compile(source, tmp_path / "out")
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    assert f"bad.xml:{_line(text, needle)}:" in output
    assert "[SG064]" in output and message in output
    assert not (tmp_path / "out").exists()


CAVEATS = (
    HEADER.format(initial="Box")
    + """<state id="Box">
<state id="Idle"/>
<transition event="succeeded" target="Other"/>
</state>
<state id="Other">
<datamodel><data id="invoke"><rosaction><name>cmd/a</name><action>p/A</action>
<result type="userdata"><var>r</var></result></rosaction>
<mappings><map><x>nothing</x><y>z</y></map></mappings></data></datamodel>
<invoke type="ROS_ACTION"/>
</state>
</scxml>
"""
)


def test_what_the_dialect_leaves_open_is_a_located_warning(tmp_path: Path) -> None:
    source = tmp_path / "caveats.xml"
    source.write_text(CAVEATS)
    result = _compile(source, tmp_path / "out")
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    codes = _codes(output)
    assert (_line(CAVEATS, 'event="succeeded"'), "warning", "SG065") in codes
    assert "no state inside it calls a ROS action or service" in output
    assert (_line(CAVEATS, "<map>"), "warning", "SG065") in codes
    assert "<map> names 'nothing'" in output


def test_plain_scxml_is_untouched(tmp_path: Path) -> None:
    """A document without the dialect reads as before (the rewrite does nothing)."""
    source = tmp_path / "plain.scxml"
    source.write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" name="P" initial="A">'
        '<state id="A"><invoke type="http"/></state></scxml>'
    )
    result = _compile(source, tmp_path / "out")
    assert result.returncode == 2
    assert "[SG060]" in result.stdout + result.stderr  # an unknown invoke type: unsupported
    assert "[SG064]" not in result.stdout + result.stderr
