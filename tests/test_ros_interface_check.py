"""The ROS interface check (SG301-SG309): each diagnostic on a model that has the problem and on
the same model without it, the binding it computes, and `--interfaces` on the command line."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path, PurePosixPath
from typing import Any

import pytest

from swarmgen import pipeline
from swarmgen.backends.rclpy_declared import declared_bindings, user_packages
from swarmgen.ros.idl_bind import WHOLE, bind
from swarmgen.ros.idl_index import BUNDLED, InterfaceIndex, Root
from tests.modelkit import ModelKit

GO = "float64 altitude\nint32 zone\n---\nstring outcome\nint64 count\n---\nstring status\n"


def _model(
    tmp_path: Path,
    tags: dict[str, str],
    inputs: dict[str, str] | None = None,
    outputs: dict[str, str] | None = None,
    files: dict[str, str] | None = None,
    ros_messages: dict[str, str] | None = None,
) -> Path:
    """A one-behaviour model with the ROS tags `tags` and definitions `files` beside it; the
    data types named in `ros_messages` are «RosMessage»s of the rosType given."""
    kit = ModelKit("Ros")
    kit.datatypes["Point"] = {"x": "Real", "y": "Real", "z": "Real"}
    kit.datatypes["Vec"] = {"x": "Real", "y": "Real", "z": "Real"}  # geometry_msgs/msg/Point
    kit.datatypes["Flat"] = {"x": "Real", "w": "Real"}  # no message has these fields
    kit.datatypes["Goal"] = {"altitude": "Real", "zone": "Integer"}  # p/action/Go_Goal
    kit.datatypes["Spot"] = {"posX": "Real", "posY": "Real"}  # p/msg/Spot: pos_x, pos_y
    kit.enumeration("Mode", "search", "track")
    kit.behaviour("Go", inputs=inputs or {}, outputs=outputs or {})
    kit.event("launch", sender="station")
    m = kit.machine("Mission")
    m.initial("Idle")
    m.state("Idle")
    m.state("Run", do="Go")
    m.final("Done")
    m.transition("Idle", "Run", "launch")
    for outcome in ("succeeded", "aborted", "preempted"):
        m.transition("Run", "Done", outcome)
    defaults = {"Real": 0.0, "Integer": 0, "Boolean": False, "String": ""}
    data = {n: (t, defaults.get(t)) for n, t in {**(inputs or {}), **(outputs or {})}.items()}
    kit.member("UAV", m, data=data)
    kit.swarm("S", {"UAV": 1})
    text = kit.xmi()
    op = re.search(r'xmi:id="([^"]+)" name="Go"', text)
    assert op is not None
    attrs = "".join(f' {k}="{v}"' for k, v in tags.items())
    text = re.sub(f'(base_Operation="{op.group(1)}")', rf"\1{attrs}", text, count=1)
    for number, (datatype, ros_type) in enumerate((ros_messages or {}).items()):
        found = re.search(f'xmi:type="uml:DataType" xmi:id="([^"]+)" name="{datatype}"', text)
        assert found is not None
        stereo = f'  <CPSwarm:RosMessage xmi:id="_rm{number}" base_DataType="{found.group(1)}" rosType="{ros_type}"/>\n'
        text = text.replace("</xmi:XMI>", stereo + "</xmi:XMI>")
    tmp_path.mkdir(parents=True, exist_ok=True)
    path = tmp_path / "model.xmi"
    path.write_text(text, encoding="utf-8")
    for rel, content in (files or {}).items():
        (tmp_path / "interfaces" / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "interfaces" / rel).write_text(content)
    return path


def _codes(path: Path) -> list[str]:
    """The SG3xx codes (the data-flow notes SG209/SG210 of the tiny model are not the point)."""
    return [d.code.id for d in pipeline.validate(path).diagnostics if d.code.id.startswith("SG3")]


ACTION = {"rosKind": "action", "rosType": "p/action/Go"}


@pytest.mark.parametrize(
    ("tags", "inputs", "outputs", "files", "code"),
    [
        (ACTION, {"altitude": "Real"}, {}, {}, "SG301"),
        ({"rosKind": "action", "rosType": "p/x/Go"}, {}, {}, {}, "SG302"),
        (ACTION, {}, {}, {"p/action/Go.action": "floatt x\n---\n---\n"}, "SG303"),
        (ACTION, {}, {}, {"p/action/Go.action": "R r\n---\n---\n", "p/msg/R.msg": "R[] r\n"}, "SG303"),
        (ACTION, {}, {}, {"p/action/Go.action": "q/Gone g\n---\n---\n"}, "SG303"),
        ({"rosKind": "service", "rosType": "p/action/Go"}, {}, {}, {"p/action/Go.action": GO}, "SG304"),
        (ACTION, {"altitud": "Real"}, {}, {"p/action/Go.action": GO}, "SG305"),
        (ACTION, {}, {"counts": "Integer"}, {"p/action/Go.action": GO}, "SG305"),
        (ACTION, {"altitude": "String"}, {}, {"p/action/Go.action": GO}, "SG306"),
        (ACTION, {}, {"count": "Boolean"}, {"p/action/Go.action": GO}, "SG306"),
        (ACTION, {"zone": "Real"}, {}, {"p/action/Go.action": GO}, "SG306"),
        ({"rosKind": "topic", "rosType": "geometry_msgs/msg/Pose"}, {"position": "Point"}, {}, {}, None),
        ({"rosKind": "topic", "rosType": "geometry_msgs/msg/PoseStamped"}, {"pose": "Point"}, {}, {}, "SG307"),
        ({"rosKind": "topic", "rosType": "geometry_msgs/msg/Point"}, {"x": "Real"}, {"y": "Real"}, {}, "SG308"),
        ({"rosKind": "service", "rosType": "std_srvs/msg/Trigger"}, {}, {}, {}, "SG301"),
        ({"rosKind": "service", "rosType": "std_srvs/Trigger"}, {}, {"success": "Boolean"}, {}, None),
        (ACTION, {"altitude": "Real", "zone": "Integer"}, {"count": "Real"}, {"p/action/Go.action": GO}, None),
    ],
)  # fmt: skip
def test_each_code_fails_and_passes(
    tmp_path: Path,
    tags: dict[str, str],
    inputs: dict[str, str],
    outputs: dict[str, str],
    files: dict[str, str],
    code: str | None,
) -> None:
    found = _codes(_model(tmp_path, tags, inputs, outputs, files))
    assert found == ([code] if code else []), found


def test_passing_variants_of_each_failing_model(tmp_path: Path) -> None:
    ok = {"p/action/Go.action": GO}
    for index, (tags, inputs, outputs) in enumerate(
        [
            (ACTION, {"altitude": "Real"}, {}),  # SG301 fixed by the definition, SG305 by the name
            (
                {"rosKind": "action", "rosType": "p/Go"},
                {},
                {},
            ),  # SG302/SG304: the kind from rosKind
            (ACTION, {"zone": "Integer"}, {"count": "Integer"}),  # SG306: converting types
            (
                {"rosKind": "topic", "rosType": "geometry_msgs/msg/Point"},
                {},
                {"y": "Real"},
            ),  # SG308
        ]
    ):
        path = _model(tmp_path / str(index), tags, inputs, outputs, ok)
        assert _codes(path) == [], (tags, inputs, outputs)


def test_diagnostics_are_located_with_quote_and_hint(tmp_path: Path) -> None:
    path = _model(tmp_path, ACTION, {"altitud": "Real"}, {}, {"p/action/Go.action": GO})
    (d,) = [d for d in pipeline.validate(path).diagnostics if d.code.id == "SG305"]
    assert d.span.file == str(path) and d.span.line > 0
    assert d.hint is not None and "did you mean `altitude`?" in d.hint
    assert any("Go.action:1: float64 altitude" in n for n in d.notes), d.notes
    bad = _model(
        tmp_path / "b", ACTION, {}, {}, {"p/action/Go.action": "int32 x\nfloatt y\n---\n---\n"}
    )
    (e,) = [d for d in pipeline.validate(bad).diagnostics if d.code.id.startswith("SG3")]
    assert (
        e.code.id == "SG303"
        and e.span.file.endswith("Go.action")
        and (e.span.line, e.span.col) == (2, 1)
    )
    assert any("needed by behaviour 'Go'" in n for n in e.notes)


def test_binding_maps_fields_and_outcome(tmp_path: Path) -> None:
    path = _model(
        tmp_path, ACTION, {"altitude": "Real"}, {"count": "Integer"}, {"p/action/Go.action": GO}
    )
    model = pipeline.validate(path).model
    assert model is not None
    index = InterfaceIndex([Root(tmp_path / "interfaces", "user"), Root(BUNDLED, "bundled")])
    binding = bind(model.behaviours[0], index, model.datatypes)
    assert binding is not None and binding.type == "p/action/Go"
    assert binding.inputs == (("altitude", "altitude"),) and binding.outputs == (
        ("count", "count"),
    )
    assert binding.outcome_field == "outcome" and binding.direction == "call"
    assert "p/action/Go" in binding.definitions


def test_cli_interfaces_option(tmp_path: Path) -> None:
    path = _model(tmp_path, ACTION, {"altitude": "Real"})
    user = tmp_path / "defs" / "p" / "action"
    user.mkdir(parents=True)
    (user / "Go.action").write_text(GO)
    run = [sys.executable, "-m", "swarmgen", "validate", str(path)]
    assert subprocess.run(run, capture_output=True, timeout=60).returncode == 0  # SG301 warning
    assert "SG301" in subprocess.run(run, capture_output=True, text=True, timeout=60).stdout
    clean = subprocess.run(
        [*run, "--interfaces", str(tmp_path / "defs")], capture_output=True, text=True, timeout=60
    )
    assert clean.returncode == 0 and clean.stdout == ""
    missing = subprocess.run(
        [*run, "--interfaces", str(tmp_path / "nope")], capture_output=True, text=True, timeout=60
    )
    assert missing.returncode == 2 and len(missing.stderr.strip().splitlines()) == 1


# issue 12 item 3: sequences, enumerations and «RosMessage» data types in the mapping
ARRAYS = "float64[] route\nint32[<=4] zones\nstring mode\nfloat64 speed\n---\nstring outcome\nfloat64[3] last\n---\n"
ARRAY_FILES = {"p/action/Go.action": ARRAYS}
POSE_TOPIC = {"rosKind": "topic", "rosType": "geometry_msgs/msg/Pose"}
POINT_TOPIC = {"rosKind": "topic", "rosType": "geometry_msgs/msg/Point"}
VEC = {"Vec": "geometry_msgs/msg/Point"}


@pytest.mark.parametrize(
    ("tags", "inputs", "outputs", "files", "messages", "code"),
    [
        # a sequence maps to an array (unbounded, bounded, fixed), element types by the same rules
        (ACTION, {"route": "Real[*]", "zones": "Integer[*]"}, {"last": "Real[*]"}, ARRAY_FILES, {}, None),
        (ACTION, {"route": "Real"}, {}, ARRAY_FILES, {}, "SG306"),  # single value into T[]
        (ACTION, {"speed": "Real[*]"}, {}, ARRAY_FILES, {}, "SG306"),  # sequence into a single
        (ACTION, {"route": "String[*]"}, {}, ARRAY_FILES, {}, "SG306"),  # element type
        (ACTION, {}, {"last": "Boolean[*]"}, ARRAY_FILES, {}, "SG306"),
        # an enumeration maps like a String
        (ACTION, {"mode": "Mode"}, {}, ARRAY_FILES, {}, None),
        (ACTION, {"speed": "Mode"}, {}, ARRAY_FILES, {}, "SG306"),
        (ACTION, {"mode": "Mode[*]"}, {}, ARRAY_FILES, {}, "SG306"),
        # a «RosMessage» data type fits only a field of exactly its message, then field by field
        (POSE_TOPIC, {"position": "Vec"}, {}, {}, VEC, None),
        (POSE_TOPIC, {"orientation": "Vec"}, {}, {}, VEC, "SG306"),  # a Quaternion field
        (POSE_TOPIC, {"position": "Flat"}, {}, {}, {"Flat": "geometry_msgs/msg/Point"}, "SG306"),
        (POSE_TOPIC, {"position": "Flat"}, {}, {}, {}, "SG307"),  # plain data type: a warning
        # ... or is the whole message (goal, result) when it is that type
        (POINT_TOPIC, {"p": "Vec"}, {}, {}, VEC, None),
        (POINT_TOPIC, {}, {"p": "Vec"}, {}, VEC, None),
        (POINT_TOPIC, {"p": "Flat"}, {}, {}, {"Flat": "geometry_msgs/msg/Point"}, "SG306"),
        (ACTION, {"g": "Goal"}, {}, {"p/action/Go.action": GO}, {"Goal": "p/action/Go_Goal"}, None),
        (ACTION, {"g": "Goal"}, {}, {"p/action/Go.action": GO}, {}, "SG305"),  # not declared
    ],
)  # fmt: skip
def test_structured_data_fails_and_passes(
    tmp_path: Path,
    tags: dict[str, str],
    inputs: dict[str, str],
    outputs: dict[str, str],
    files: dict[str, str],
    messages: dict[str, str],
    code: str | None,
) -> None:
    found = _codes(_model(tmp_path, tags, inputs, outputs, files, messages))
    assert found == ([code] if code else []), found


def test_structured_diagnostics_say_why(tmp_path: Path) -> None:
    def only(path: Path) -> str:
        (d,) = [d for d in pipeline.validate(path).diagnostics if d.code.id.startswith("SG3")]
        return d.message

    single = only(_model(tmp_path / "a", ACTION, {"route": "Real"}, {}, ARRAY_FILES))
    assert "(float64[])" in single and "the field is an array" in single, single
    many = only(_model(tmp_path / "b", ACTION, {"speed": "Real[*]"}, {}, ARRAY_FILES))
    assert "(Real[*])" in many and "the model's value is a sequence" in many, many
    other = only(_model(tmp_path / "c", POSE_TOPIC, {"orientation": "Vec"}, {}, {}, VEC))
    assert "Vec is geometry_msgs/msg/Point, not geometry_msgs/Quaternion" in other, other
    flat = {"Flat": "geometry_msgs/msg/Point"}
    shape = only(_model(tmp_path / "d", POSE_TOPIC, {"position": "Flat"}, {}, {}, flat))
    assert "has no field `w`" in shape, shape


def test_binding_of_sequences_enums_and_whole_messages(tmp_path: Path) -> None:
    def binding(path: Path) -> Any:
        model = pipeline.validate(path).model
        assert model is not None
        index = InterfaceIndex([Root(path.parent / "interfaces", "user"), Root(BUNDLED, "bundled")])
        return bind(model.behaviours[0], index, model.datatypes, model.enumerations)

    arrays = binding(
        _model(tmp_path / "a", ACTION, {"route": "Real[*]", "mode": "Mode"}, {}, ARRAY_FILES)
    )
    assert arrays is not None and arrays.inputs == (("route", "route"), ("mode", "mode"))
    whole = binding(_model(tmp_path / "b", POINT_TOPIC, {}, {"p": "Vec"}, {}, VEC))
    assert whole is not None and whole.outputs == ((WHOLE, "p"),) and whole.direction == "subscribe"


SPOT_FILES = {
    "p/msg/Spot.msg": "float64 pos_x\nfloat64 pos_y\n",
    "p/action/Go.action": "p/Spot target\n---\nstring outcome\np/Spot reached\n---\n",
}


def _index(path: Path) -> InterfaceIndex:
    return InterfaceIndex([Root(path.parent / "interfaces", "user"), Root(BUNDLED, "bundled")])


def test_renamed_keys_bind_and_the_backend_decides_as_the_check(tmp_path: Path) -> None:
    """`posX` maps to `pos_x` (ros_name): no diagnostic, a binding with the renames, and the
    rclpy backend binds exactly the behaviours the check passes."""
    cases = [
        ({"target": "Spot"}, {"reached": "Spot"}, SPOT_FILES, True),
        ({"target": "Flat"}, {}, SPOT_FILES, False),  # SG306/SG307: no such fields
        ({"altitude": "Real"}, {}, {}, False),  # SG301: the private fallback
    ]
    for number, (inputs, outputs, files, binds) in enumerate(cases):
        path = _model(tmp_path / str(number), ACTION, inputs, outputs, files)
        model = pipeline.validate(path).model
        assert model is not None
        assert (_codes(path) == []) is binds, (inputs, _codes(path))
        found = declared_bindings(model, ["Go"], _index(path), ())
        assert ("Go" in found) is binds, inputs
    path = tmp_path / "0" / "model.xmi"
    model = pipeline.validate(path).model
    assert model is not None
    binding = bind(model.behaviours[0], _index(path), model.datatypes, model.enumerations)
    assert binding is not None
    spot = (("posX", "pos_x", ()), ("posY", "pos_y", ()))
    assert binding.renames == (("input", "target", spot), ("output", "reached", spot))
    literal = declared_bindings(model, ["Go"], _index(path), ())["Go"].literal("go")
    assert "renames=(('input', 'target', (('posX', 'pos_x', ())" in literal, literal


def test_user_definition_changed_after_the_check_is_no_error(tmp_path: Path) -> None:
    """The workspace copies the text the check read: a file edited, then removed, after the
    check gives the checked text, never an exception (exit 3)."""
    path = _model(tmp_path, ACTION, {"target": "Spot"}, {}, SPOT_FILES)
    model = pipeline.validate(path).model
    assert model is not None
    index = _index(path)
    declared = declared_bindings(model, ["Go"], index, ())
    assert "Go" in declared
    spot = tmp_path / "interfaces" / "p" / "msg" / "Spot.msg"
    spot.write_bytes(b"\xff\xfe not text")
    files = user_packages(declared.values(), index)["p"]
    assert files[PurePosixPath("msg/Spot.msg")] == SPOT_FILES["p/msg/Spot.msg"]
    spot.unlink()
    files = user_packages(declared.values(), index)["p"]
    assert files[PurePosixPath("msg/Spot.msg")] == SPOT_FILES["p/msg/Spot.msg"]


def test_shadowed_definition_warns_and_an_equal_one_does_not(tmp_path: Path) -> None:
    """SG309: the same type defined otherwise in a later directory (`--interfaces` first,
    then `interfaces/` beside the model); an equal text (but for line ends) is no warning."""
    for other, codes in ((GO + "int8 extra\n", ["SG309"]), (GO.replace("\n", "\r\n"), [])):
        path = _model(tmp_path / str(len(codes)), ACTION, {}, {}, {"p/action/Go.action": GO})
        first = path.parent / "first"
        (first / "p" / "action").mkdir(parents=True)
        (first / "p" / "action" / "Go.action").write_text(other, newline="")
        found = pipeline.validate(path, [first]).diagnostics
        assert [d.code.id for d in found if d.code.id.startswith("SG3")] == codes
