"""Enumerations, sequences and «RosMessage» data types on real XMI, through the IR, the value
rule, the type check, the SCXML datamodel and the generated typed module (docs/semantics.md,
"Enumerations and sequences")."""

# no `from __future__ import annotations`: the dataclasses below need real type hints, as the
# generated `behaviour_types` module has
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from swarmgen import pipeline
from swarmgen.chart.lower import lower
from swarmgen.runtime.plugins import outcome_of, request_of
from swarmgen.scxml.emit import emit
from tests.conftest import ROOT
from tests.fixtures.models.make_dispatch import build

DISPATCH = ROOT / "tests" / "fixtures" / "models" / "dispatch.xmi"


def _validate(text: str, tmp_path: Path) -> pipeline.Validation:
    path = tmp_path / "m.xmi"
    path.write_text(text, encoding="utf-8")
    return pipeline.validate(path)


def test_the_fixture_is_what_its_script_writes() -> None:
    assert DISPATCH.read_text(encoding="utf-8") == build().xmi()


def test_enumerations_and_sequences_are_read() -> None:
    model = pipeline.validate(DISPATCH).model
    assert model is not None
    (mode,) = model.enumerations
    assert (mode.name, mode.literals) == ("Mode", ("search", "track", "home"))
    data = {p.name: p for m in model.member_types for p in m.data}
    assert (data["mode"].type, data["mode"].default, data["mode"].many) == ("Mode", None, False)
    assert data["last"].default == "home"
    assert (data["route"].type, data["route"].many) == ("Real", True)
    plan = next(b for b in model.behaviours if b.name == "Plan")
    assert {p.name: p.many for p in plan.outputs} == {"mode": False, "route": True, "zone": False}
    report = next(e for e in model.events if e.name == "report")
    assert [f.many for f in report.fields] == [False, True]


def test_initial_values_follow_the_value_rule() -> None:
    model = pipeline.validate(DISPATCH).model
    assert model is not None
    (chart,) = lower(model)
    initial = {d.name: d.initial for d in chart.data}
    assert initial == {
        "last": "home",
        "mode": "search",  # an enumeration's zero is its first literal
        "route": [],  # a sequence's is empty
        "zone": {"centre": {"x": 0.0, "y": 0.0}, "label": ""},  # nested data types
    }


def test_literals_are_strings_in_the_scxml() -> None:
    model = pipeline.validate(DISPATCH).model
    assert model is not None
    text = emit(model)[0].text
    assert 'cond="(mode == &quot;track&quot;)"' in text
    assert '<data id="route" expr="[]"' in text


def test_an_instance_value_names_the_default_literal(tmp_path: Path) -> None:
    text = build().xmi()
    literal = re.search(r'<ownedLiteral xmi:id="([^"]+)" name="track"/>', text)
    assert literal is not None
    text, count = re.subn(
        r'<defaultValue xmi:type="uml:LiteralString" (xmi:id="[^"]+") value="home"/>',
        rf'<defaultValue xmi:type="uml:InstanceValue" \1 instance="{literal.group(1)}"/>',
        text,
    )
    assert count == 1
    model = _validate(text, tmp_path).model
    assert model is not None
    data = {p.name: p.default for m in model.member_types for p in m.data}
    assert data["last"] == "track"


def test_a_default_that_is_no_literal_is_sg122(tmp_path: Path) -> None:
    kit = build()
    machine, parts, data = kit.members["Rover"]
    kit.members["Rover"] = (machine, parts, {**data, "last": ("Mode", "away")})
    result = _validate(kit.xmi(), tmp_path)
    found = [d for d in result.diagnostics if d.code.id == "SG122"]
    assert len(found) == 1
    assert "is not a literal of Mode" in found[0].message
    assert found[0].hint == "write one of search, track, home"


def test_a_ros_message_data_type_keeps_its_type(tmp_path: Path) -> None:
    text = build().xmi()
    pose = re.search(
        r'<packagedElement xmi:type="uml:DataType" xmi:id="([^"]+)" name="Pose">', text
    )
    assert pose is not None
    stereo = f'  <CPSwarm:RosMessage xmi:id="_rosmsg" base_DataType="{pose.group(1)}" rosType="geometry_msgs/msg/Point"/>\n'
    text = text.replace("</xmi:XMI>", stereo + "</xmi:XMI>")
    result = _validate(text, tmp_path)
    assert result.model is not None
    types = {d.name: d.ros_type for d in result.model.datatypes}
    assert types == {"Pose": "geometry_msgs/msg/Point", "Zone": None}
    assert not [d for d in result.diagnostics if d.code.id in {"SG012", "SG013"}]


@dataclass(frozen=True, slots=True)
class _Point:
    x: float


@dataclass(frozen=True, slots=True)
class _Request:
    route: tuple[float, ...]
    points: tuple[_Point, ...]
    mode: Literal["search", "track"]


@dataclass(frozen=True, slots=True)
class _Result:
    outcome: str
    points: tuple[_Point, ...] | None = None


def test_plugins_convert_sequences_at_the_boundary() -> None:
    request = request_of(_Request, {"route": [1, 2.5], "points": [{"x": 1}], "mode": "track"})
    assert request == _Request((1, 2.5), (_Point(1.0),), "track")
    assert request_of(_Request, {}).route == ()
    outcome = outcome_of(_Result("succeeded", (_Point(2.0),)))
    assert outcome.outputs == {"points": [{"x": 2.0}]}  # lists of dicts, as the member holds
