"""Traces as ROS 2 bags and the event timeline (docs/trace.md): bags recorded by `swarmgen replay`
on every backend are read back by rosbags alone (no swarmgen in the reading process), in mcap and
sqlite3; the timeline of a known set of runs gives the statistics computed by hand; legacy
CPSwarm ROS 1 bags are read; `swarmgen timeline` writes its table, CSV, PNG and SVG; the runtime
tracer and the live rclpy recorder write the same bags.
"""

from __future__ import annotations

import asyncio
import csv
import importlib.util
import io
import json
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rosbags", reason="rosbags comes with the `ros` extra: run `make ros`")

from swarmgen.trace import timeline as timelines
from swarmgen.trace.bag import states_topic
from swarmgen.trace.reader import camel, legacy_event, read_events, read_run
from swarmgen.trace.recorder import BagRecorder, VirtualClock
from tests.conftest import ROOT, run_cli

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
MISSION = ROOT / "sample_models" / "sar" / "scenarios" / "uav_mission.json"
HAS_RCLPY = importlib.util.find_spec("rclpy") is not None
BACKENDS = ["asyncio", "smach", "scxml", *(["rclpy"] if HAS_RCLPY else [])]
S = 1_000_000_000  # ns per second

# Reads bags with rosbags only: swarmgen cannot even be imported in this process, and no type is
# registered by hand, so the definitions must come from the bag itself.
ROSBAGS_ONLY = textwrap.dedent(
    """
    import json, sys
    sys.modules["swarmgen"] = None  # any import of swarmgen fails
    from pathlib import Path
    from rosbags.highlevel import AnyReader

    def plain(value):
        if hasattr(value, "__dataclass_fields__"):
            return {k: plain(getattr(value, k)) for k in value.__dataclass_fields__}
        if isinstance(value, list):
            return [plain(v) for v in value]
        return value

    out = {}
    for bag in sys.argv[1:]:
        with AnyReader([Path(bag)]) as reader:
            out[bag] = {
                "types": {c.topic: c.msgtype for c in reader.connections},
                "messages": [
                    [c.topic, t, plain(reader.deserialize(raw, c.msgtype))]
                    for c, t, raw in reader.messages()
                ],
            }
    assert not [m for m in sys.modules if m.startswith("swarmgen") and sys.modules[m]]
    print(json.dumps(out))
    """
)


def read_with_rosbags_only(*bags: Path) -> dict[str, Any]:
    completed = subprocess.run(
        [sys.executable, "-I", "-c", ROSBAGS_ONLY, *map(str, bags)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    result: dict[str, Any] = json.loads(completed.stdout)
    return result


# --- bags recorded by `swarmgen replay --record` on every backend


@pytest.fixture(scope="module")
def replayed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The SAR mission replayed on every backend (in parallel), each recorded into `<dir>/run`:
    mcap on every backend, sqlite3 on asyncio and scxml."""
    root = tmp_path_factory.mktemp("replayed")
    jobs = [(b, "mcap") for b in BACKENDS] + [("asyncio", "sqlite3"), ("scxml", "sqlite3")]
    procs = {}
    for backend, storage in jobs:
        bag = root / f"{backend}-{storage}" / "run"
        command = [
            sys.executable, "-m", "swarmgen", "replay", str(SAR), "--member", "UAV",
            "--script", str(MISSION), "--backend", backend, "--record", str(bag),
            "--storage", storage,
        ]  # fmt: skip
        procs[backend, storage] = (
            bag,
            subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True),
        )
    results: dict[tuple[str, str], tuple[Path, list[dict[str, Any]]]] = {}
    for key, (bag, proc) in procs.items():
        stdout, stderr = proc.communicate(timeout=300)
        assert proc.returncode == 0, f"{key}: {stderr}"
        assert f"recorded 10 step(s) into {bag}" in stderr
        results[key] = (bag, [json.loads(line) for line in stdout.splitlines()])
    return {"bags": results, "steps": json.loads(MISSION.read_text())["steps"]}


@pytest.mark.skipif(not HAS_RCLPY, reason="rclpy comes with the `ros` extra: run `make ros`")
def test_replay_is_recorded_on_rclpy_too(replayed: dict[str, Any]) -> None:
    """`replayed` leaves rclpy out without the `ros` extra: that shows here as a skip."""
    assert ("rclpy", "mcap") in replayed["bags"]


def test_replay_bags_are_read_by_rosbags_alone(replayed: dict[str, Any]) -> None:
    bags = replayed["bags"]
    read = read_with_rosbags_only(*(bag for bag, _ in bags.values()))
    for (backend, storage), (bag, trace) in bags.items():
        content = read[str(bag)]
        assert content["types"] == {
            "/swarm/events": "swarmgen_msgs/msg/Event",
            "/UAV/active_states": "swarmgen_msgs/msg/ActiveStates",
        }, backend
        events = [m for topic, _, m in content["messages"] if topic == "/swarm/events"]
        states = [m for topic, _, m in content["messages"] if topic == "/UAV/active_states"]
        assert [e["name"] for e in events] == [
            "launch", "TakeOff.succeeded", "missionStart", "targetFound",
            "TaskAllocation.succeeded", "Tracking.targetLost", "LocalCoverage.succeeded",
            "Tracking.succeeded", "targetFound", "missionAbort", "Land.succeeded",
        ], backend  # fmt: skip
        # virtual stamps: step n at n s, the second input of the burst (step 9) 1 ms later
        stamps = [(e["stamp"]["sec"], e["stamp"]["nanosec"]) for e in events]
        assert stamps == [(n, 0) for n in range(1, 10)] + [(9, 1_000_000), (10, 0)]
        assert [e["sender"] for e in events][:2] == ["station", "replay"]
        assert json.loads(events[3]["data"]) == {  # as the scenario gives it
            "pose": {
                "header": {"frame_id": "map"},
                "pose": {"position": {"x": 1.0, "y": 2.0, "z": 0.0}},
            },
            "target_id": 7,
        }
        assert json.loads(events[4]["data"]) == {"rover_id": 3}
        assert [e["id"] for e in events if e["sender"] == "station"] == list(range(1, 6))
        # one ActiveStates per trace record (the initial configuration, then after each step)
        assert [s["states"] for s in states] == [r["active"] for r in trace], backend
        assert {s["member"] for s in states} == {"UAV"}
        metadata = (bag / "metadata.yaml").read_text()
        assert f"storage_identifier: {storage}" in metadata
        assert (bag / f"run.{'mcap' if storage == 'mcap' else 'db3'}").is_file()


def test_replay_bags_are_deterministic_across_backends(replayed: dict[str, Any]) -> None:
    """The backends' traces agree, and the stamps are virtual: the bags are byte-identical."""
    for storage, suffix in (("mcap", "mcap"), ("sqlite3", "db3")):
        bags = [bag for (_, s), (bag, _) in replayed["bags"].items() if s == storage]
        assert len(bags) >= 2
        contents = {(bag / f"run.{suffix}").read_bytes() for bag in bags}
        assert len(contents) == 1, storage
        assert len({(bag / "metadata.yaml").read_text() for bag in bags}) == 1


def test_replay_bags_read_by_swarmgen(replayed: dict[str, Any]) -> None:
    bag, trace = replayed["bags"]["asyncio", "sqlite3"]
    (run,) = read_events([bag])
    assert run.start_ns == 0
    assert run.launch_ns == 1 * S
    assert run.first("missionStart") is not None
    assert [e.name for e in run.events][:3] == ["launch", "TakeOff.succeeded", "missionStart"]
    assert [list(s.states) for s in run.states] == [r["active"] for r in trace]


def test_record_refuses_an_existing_directory(tmp_path: Path) -> None:
    result = run_cli(
        "replay", str(SAR), "--member", "UAV", "--script", str(MISSION), "--record", str(tmp_path)
    )
    assert result.returncode == 2
    assert "exists" in result.stderr
    assert result.stdout == ""


# --- the timeline over a known set of runs

# Seconds since launch per run (None: the event does not occur in that run). Run 4 has no launch
# event: its launch is the start of its bag (its first message, states at the start).
RUNS: list[dict[str, float | None]] = [
    {"launch": 0, "missionStart": 1, "targetFound": 10, "targetAssigned": 0.5, "targetRescued": 30},
    {"launch": 0, "missionStart": 2, "targetFound": 12, "targetAssigned": 20, "targetRescued": 31},
    {"launch": 0, "missionStart": 2.5, "targetFound": 40, "targetAssigned": 21, "targetRescued": 35},
    {"launch": 0, "missionStart": 3, "targetFound": 14, "targetAssigned": 22, "targetRescued": 50},
    {"launch": None, "missionStart": 3.5, "targetFound": 16, "targetAssigned": 23},
]  # fmt: skip
# By hand, with linear interpolation between ranks (h = (n-1) p): (lower whisker, Q1, median,
# Q3, upper whisker, outliers, runs).
EXPECTED = {
    # all 0
    "launch": (0.0, 0.0, 0.0, 0.0, 0.0, (), 4),
    # 1 2 2.5 3 3.5: Q1 2, Q3 3, IQR 1, fences 0.5 .. 4.5: whiskers 1 .. 3.5
    "missionStart": (1.0, 2.0, 2.5, 3.0, 3.5, (), 5),
    # 10 12 14 16 40: Q1 12, Q3 16, IQR 4, fences 6 .. 22: 40 is an outlier, whiskers 10 .. 16
    "targetFound": (10.0, 12.0, 14.0, 16.0, 16.0, (40.0,), 5),
    # 0.5 20 21 22 23: Q1 20, Q3 22, IQR 2, fences 17 .. 25: 0.5 is an outlier
    "targetAssigned": (20.0, 20.0, 21.0, 22.0, 23.0, (0.5,), 5),
    # 30 31 35 50: Q1 = 30 + 0.75 (31-30) = 30.75, median (31+35)/2 = 33,
    # Q3 = 35 + 0.25 (50-35) = 38.75, IQR 8, fences 18.75 .. 50.75: whiskers 30 .. 50
    "targetRescued": (30.0, 30.75, 33.0, 38.75, 50.0, (), 4),
}
MISSION_ORDER = ["launch", "missionStart", "targetFound", "targetAssigned", "targetRescued"]


@pytest.fixture(scope="module")
def known_runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """RUNS as bags (alternately mcap and sqlite3), launched at different wall-clock times, with
    a repeated targetFound (only the first counts) and the events written out of order."""
    root = tmp_path_factory.mktemp("known") / "runs"
    for index, run in enumerate(RUNS):
        launch = (1_700_000_000 + 1000 * index) * S
        storage = "mcap" if index % 2 == 0 else "sqlite3"
        with BagRecorder(root / f"run_{index}", storage=storage, clock=VirtualClock()) as bag:
            bag.record_states("uav_1", ["Idle"], launch)
            for name in reversed(list(run)):
                seconds = run[name]
                if seconds is not None:
                    bag.record_event(name, None, "uav_1", launch + round(seconds * S))
            bag.record_event("targetFound", {"again": True}, "uav_2", launch + 60 * S)
    return root


def test_timeline_statistics_match_the_hand_computed_ones(known_runs: Path) -> None:
    runs = read_events([known_runs])
    assert len(runs) == len(RUNS)
    result = timelines.build(runs)
    assert result.total_runs == 5
    assert [s.event for s in result.events] == MISSION_ORDER
    for stats in result.events:
        got = (
            stats.lower_whisker, stats.lower_quartile, stats.median, stats.upper_quartile,
            stats.upper_whisker, stats.outliers, stats.runs,
        )  # fmt: skip
        assert got == EXPECTED[stats.event], stats.event


def test_timeline_agrees_with_matplotlib_boxplot_stats(known_runs: Path) -> None:
    from matplotlib import cbook

    result = timelines.build(read_events([known_runs]))
    for stats in result.events:
        (reference,) = cbook.boxplot_stats(list(stats.times), whis=1.5)
        assert stats.lower_whisker == reference["whislo"]
        assert stats.lower_quartile == reference["q1"]
        assert stats.median == reference["med"]
        assert stats.upper_quartile == reference["q3"]
        assert stats.upper_whisker == reference["whishi"]
        assert list(stats.outliers) == list(reference["fliers"])


def test_timeline_chosen_events_keep_their_order(known_runs: Path) -> None:
    result = timelines.build(read_events([known_runs]), ["targetRescued", "nothing", "launch"])
    assert [s.event for s in result.events] == ["targetRescued", "nothing", "launch"]
    nothing = result.get("nothing")
    assert nothing is not None and nothing.runs == 0 and nothing.median is None


def test_timeline_cli_table_csv_png_svg(known_runs: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = run_cli(
        "timeline", str(known_runs), "--csv", str(out / "t.csv"), "--plot", str(out / "t.png")
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split()[:2] == ["event", "runs"]
    assert [line.split()[0] for line in lines[1:]] == MISSION_ORDER
    found = ["targetFound", "5/5", "10.000", "12.000", "14.000", "16.000", "16.000", "40.000"]
    assert lines[3].split() == found
    rows = list(csv.DictReader(io.StringIO((out / "t.csv").read_text())))
    assert [r["event"] for r in rows] == MISSION_ORDER
    for row in rows:
        low, q1, med, q3, high, outliers, count = EXPECTED[row["event"]]
        assert [float(row[k]) for k in ("lower_whisker", "lower_quartile", "median")] == [
            low, q1, med,
        ]  # fmt: skip
        assert [float(row["upper_quartile"]), float(row["upper_whisker"])] == [q3, high]
        assert tuple(float(t) for t in row["outliers"].split()) == outliers
        assert (int(row["runs"]), int(row["total_runs"])) == (count, 5)
    assert (out / "t.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    svgs = []
    for name in ("a.svg", "b.svg"):
        events = "launch,missionStart,targetFound,targetAssigned,targetRescued"
        result = run_cli("timeline", str(known_runs), "--events", events, "--plot", str(out / name))
        assert result.returncode == 0, result.stderr
        root = ET.parse(out / name).getroot()
        assert root.tag == "{http://www.w3.org/2000/svg}svg"
        svgs.append((out / name).read_bytes())
    assert svgs[0] == svgs[1]  # deterministic: fixed hash salt, no date


def test_timeline_cli_errors(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("not a bag")
    result = run_cli("timeline", str(tmp_path / "notes.txt"))
    assert result.returncode == 2 and "not a bag" in result.stderr
    empty = tmp_path / "empty"
    empty.mkdir()
    result = run_cli("timeline", str(empty))
    assert result.returncode == 2 and "no bags" in result.stderr
    result = run_cli("timeline", str(empty), "--plot", str(tmp_path / "x.pdf"))
    assert result.returncode == 2


# --- legacy ROS 1 bags of the CPSwarm tools

SWARMROS = {
    "swarmros/msg/EventHeader": "string name\nstring node\n",
    "swarmros/msg/SimpleEvent": "swarmros/EventHeader swarmio\n",
    "cpswarm_msgs/msg/TargetPositionEvent": (
        "Header header\nswarmros/EventHeader swarmio\nint32 id\ngeometry_msgs/PoseStamped pose\n"
    ),
    "cpswarm_msgs/msg/TaskAllocatedEvent": (
        "Header header\nswarmros/EventHeader swarmio\nint32 task_id\nstring cps_id\n"
    ),
    "cpswarm_msgs/msg/TakeoffGoal": "float64 altitude\n",
    "cpswarm_msgs/msg/TakeoffResult": "",
    "cpswarm_msgs/msg/TakeoffActionGoal": (
        "Header header\nactionlib_msgs/GoalID goal_id\ncpswarm_msgs/TakeoffGoal goal\n"
    ),
    "cpswarm_msgs/msg/TakeoffActionResult": (
        "Header header\nactionlib_msgs/GoalStatus status\ncpswarm_msgs/TakeoffResult result\n"
    ),
}


def _write_legacy_bag(path: Path) -> None:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    types: dict[str, Any] = {}
    for name, text in SWARMROS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    t = store.types
    time = t["builtin_interfaces/msg/Time"]

    def header(seconds: float) -> Any:
        sec, nsec = divmod(round(seconds * S), S)
        return t["std_msgs/msg/Header"](seq=0, stamp=time(sec=sec, nanosec=nsec), frame_id="")

    def swarmio(name: str) -> Any:
        return t["swarmros/msg/EventHeader"](name=name, node="a1b2")

    def pose(x: float) -> Any:
        point = t["geometry_msgs/msg/Point"](x=x, y=2.0, z=0.0)
        rotation = t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
        return t["geometry_msgs/msg/PoseStamped"](
            header=header(0), pose=t["geometry_msgs/msg/Pose"](position=point, orientation=rotation)
        )

    goal_id = t["actionlib_msgs/msg/GoalID"](stamp=time(sec=0, nanosec=0), id="g1")
    ns = "/cpswarm/uav_1"
    # (topic, type, message, bag time in s); header stamps are set a little before bag time
    messages = [
        (f"{ns}/bridge/events/launch", "swarmros/msg/SimpleEvent",
         t["swarmros/msg/SimpleEvent"](swarmio=swarmio("launch")), 100.0),
        (f"{ns}/cmd/takeoff/goal", "cpswarm_msgs/msg/TakeoffActionGoal",
         t["cpswarm_msgs/msg/TakeoffActionGoal"](
             header=header(100.5), goal_id=goal_id,
             goal=t["cpswarm_msgs/msg/TakeoffGoal"](altitude=1.5)), 100.6),
        (f"{ns}/cmd/takeoff/result", "cpswarm_msgs/msg/TakeoffActionResult",
         t["cpswarm_msgs/msg/TakeoffActionResult"](
             header=header(104.0),
             status=t["actionlib_msgs/msg/GoalStatus"](goal_id=goal_id, status=3, text=""),
             result=t["cpswarm_msgs/msg/TakeoffResult"]()), 104.1),
        (f"{ns}/bridge/events/mission_start", "swarmros/msg/SimpleEvent",
         t["swarmros/msg/SimpleEvent"](swarmio=swarmio("missionStart")), 105.0),
        (f"{ns}/pos_provider/pose", "geometry_msgs/msg/PoseStamped", pose(0.5), 106.0),
        (f"{ns}/position", "geometry_msgs/msg/PoseStamped", pose(0.5), 106.0),
        (f"{ns}/target_found", "cpswarm_msgs/msg/TargetPositionEvent",
         t["cpswarm_msgs/msg/TargetPositionEvent"](
             header=header(110.0), swarmio=swarmio("target_found"), id=7, pose=pose(1.0)), 110.2),
        ("/cpswarm/uav_2/bridge/events/target_found", "cpswarm_msgs/msg/TargetPositionEvent",
         t["cpswarm_msgs/msg/TargetPositionEvent"](
             header=header(110.1), swarmio=swarmio("target_found"), id=7, pose=pose(1.0)), 110.3),
        (f"{ns}/cps_selected", "cpswarm_msgs/msg/TaskAllocatedEvent",
         t["cpswarm_msgs/msg/TaskAllocatedEvent"](
             header=header(0), swarmio=swarmio("cps_selected"), task_id=7, cps_id="ugv_1"),
         112.0),
        (f"{ns}/target_done", "cpswarm_msgs/msg/TargetPositionEvent",
         t["cpswarm_msgs/msg/TargetPositionEvent"](
             header=header(130.0), swarmio=swarmio("target_done"), id=7, pose=pose(1.0)), 130.5),
    ]  # fmt: skip
    with Writer(path) as writer:
        connections: dict[str, Any] = {}
        for topic, msgtype, message, bag_time in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(
                connections[topic], round(bag_time * S), store.serialize_ros1(message, msgtype)
            )


def test_legacy_topic_mapping() -> None:
    assert camel("mission_start") == "missionStart"
    assert camel("targetFound") == "targetFound"
    assert legacy_event("/cpswarm/uav_1/bridge/events/mission_start") == (
        "missionStart", "cpswarm/uav_1", "incoming",
    )  # fmt: skip
    assert legacy_event("bridge/events/launch") == ("launch", "", "incoming")
    assert legacy_event("/cpswarm/uav_1/target_found") == (
        "targetFound", "cpswarm/uav_1", "outgoing",
    )  # fmt: skip
    assert legacy_event("/uav_1/cmd/task_allocation_auction/goal") == (
        "taskAllocationAuction.goal", "uav_1", "action",
    )  # fmt: skip
    assert legacy_event("/cpswarm/uav_1/position") is None
    assert legacy_event("/cpswarm/uav_1/cmd/takeoff/feedback") is None
    assert states_topic("uav_1") == "/uav_1/active_states"
    assert states_topic("3 drones!") == "/m3_drones/active_states"


def test_legacy_ros1_bag_is_read(tmp_path: Path) -> None:
    bag = tmp_path / "cpswarm.bag"
    _write_legacy_bag(bag)
    (run,) = read_events([bag])
    assert run.start_ns == 100 * S
    assert [(e.name, e.stamp_ns, e.sender) for e in run.events] == [
        ("launch", 100 * S, "cpswarm/uav_1"),  # no header: bag time
        ("takeoff.goal", 100_500_000_000, "cpswarm/uav_1"),  # header stamps
        ("takeoff.succeeded", 104 * S, "cpswarm/uav_1"),  # actionlib status 3
        ("missionStart", 105 * S, "cpswarm/uav_1"),
        ("targetFound", 110 * S, "cpswarm/uav_1"),
        ("targetFound", 110_100_000_000, "cpswarm/uav_2"),
        ("cpsSelected", 112 * S, "cpswarm/uav_1"),  # zero header stamp: bag time
        ("targetDone", 130 * S, "cpswarm/uav_1"),
    ]
    found = run.events[4]
    assert found.data["id"] == 7
    assert found.data["swarmio"] == {"name": "target_found", "node": "a1b2"}
    assert found.data["pose"]["pose"]["position"] == {"x": 1.0, "y": 2.0, "z": 0.0}
    assert run.events[1].data["goal"] == {"altitude": 1.5}

    renamed = read_run([bag], {"targetDone": "targetRescued", "cpsSelected": "targetAssigned"})
    result = timelines.build([renamed], MISSION_ORDER)
    assert [(s.event, s.median) for s in result.events] == [
        ("launch", 0.0), ("missionStart", 5.0), ("targetFound", 10.0),
        ("targetAssigned", 12.0), ("targetRescued", 30.0),
    ]  # fmt: skip

    result = run_cli("timeline", str(bag), "--alias", "targetDone=targetRescued")
    assert result.returncode == 0, result.stderr
    assert "targetRescued" in result.stdout and "targetDone" not in result.stdout


# --- recording hooks


def test_runtime_tracer_records_events_once_and_state_changes(tmp_path: Path) -> None:
    """Two asyncio members on one bus with the recorder as their tracer: an event both members
    process is written once; each member's states are written when they change."""
    from swarmgen.runtime.chart import ChartBuilder
    from swarmgen.runtime.engine import Event
    from swarmgen.runtime.member import InMemoryBus, Member

    builder = ChartBuilder("Drone")
    builder.node("Idle", "state")
    builder.node("Flying", "state")
    builder.node("Done", "final")
    builder.initial(None, ["Idle"])
    builder.transition("Idle", ["go"], ["Flying"])
    builder.transition("Flying", ["stop"], ["Done"])
    chart = builder.build()

    async def main(recorder: BagRecorder) -> None:
        bus = InMemoryBus()
        members = [
            Member(chart, "Drone", name, _NoLibrary(), bus, tracer=recorder)
            for name in ("d1", "d2")
        ]
        tasks = [asyncio.create_task(m.run()) for m in members]
        await asyncio.sleep(0)
        bus.publish(Event("go", None, 1, 5.0, "station"), "swarm")
        bus.publish(Event("noise", {"k": 1}, 2, 6.0, "station"), "swarm")
        bus.publish(Event("stop", None, 3, 7.5, "station"), "swarm")
        await asyncio.gather(*tasks)

    bags = []
    for name in ("a", "b"):
        with BagRecorder(tmp_path / name / "run", clock=VirtualClock(4 * S)) as recorder:
            asyncio.run(main(recorder))
        bags.append(tmp_path / name / "run")
    assert (bags[0] / "run.mcap").read_bytes() == (bags[1] / "run.mcap").read_bytes()
    (run,) = read_events([bags[0]])
    assert [(e.name, e.stamp_ns, e.id, e.data) for e in run.events] == [
        ("go", 5 * S, 1, {}), ("noise", 6 * S, 2, {"k": 1}), ("stop", 7_500_000_000, 3, {}),
    ]  # fmt: skip
    assert [(s.member, s.states, s.stamp_ns) for s in run.states] == [
        ("d1", ("Idle",), 4 * S), ("d2", ("Idle",), 4 * S),
        ("d1", ("Flying",), 5 * S), ("d2", ("Flying",), 5 * S),
        ("d1", ("Done",), 7_500_000_000), ("d2", ("Done",), 7_500_000_000),
    ]  # fmt: skip


class _NoLibrary:
    def get(self, name: str) -> None:
        return None


LIVE = textwrap.dedent(
    """
    import sys, time, json
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from swarmgen.trace.recorder import BagRecorder
    from swarmgen.trace.live import LiveRecorder
    package, out = sys.argv[1], sys.argv[2]
    msg = __import__(package + ".msg", fromlist=["Event"])
    rclpy.init()
    node = rclpy.create_node("swarm")
    events = node.create_publisher(msg.Event, "/swarm/events", QoSProfile(depth=100,
        reliability=ReliabilityPolicy.RELIABLE))
    states = node.create_publisher(msg.ActiveStates, "/uav_1/active_states", QoSProfile(depth=1,
        reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    with BagRecorder(out, package=package) as recorder:
        states.publish(msg.ActiveStates(member="uav_1", states=["Idle"]))  # before recording
        live = LiveRecorder(node, recorder, package)
        def spin(seconds):
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                rclpy.spin_once(node, timeout_sec=0.02)
        spin(0.5)
        for i, name in enumerate(["launch", "missionStart", "targetFound"], start=1):
            stamp = node.get_clock().now().to_msg()
            events.publish(msg.Event(id=i, stamp=stamp, sender="station", name=name, data="{}"))
            spin(0.05)
        states.publish(msg.ActiveStates(member="uav_1", states=["Flying"]))
        deadline = time.monotonic() + 10
        while live.received < 5 and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
        print(json.dumps({"received": live.received, "topics": sorted(live.topics)}))
    node.destroy_node()
    rclpy.try_shutdown()
    """
)


@pytest.mark.skipif(not HAS_RCLPY, reason="rclpy comes with the `ros` extra: run `make ros`")
def test_live_rclpy_topics_are_recorded_raw(tmp_path: Path) -> None:
    from swarmgen import pipeline
    from swarmgen import ros_harness as harness
    from swarmgen.backends.rclpy_backend import interfaces_package

    result = pipeline.compile_model(SAR, backends=["rclpy"])
    model = result.validation.model
    assert result.files and model is not None
    pipeline.write_tree(result.files, tmp_path / "sar")
    prefix = harness.build_interfaces(tmp_path / "sar" / "rclpy", model)
    package = interfaces_package(model)
    bag = tmp_path / "live"
    env = harness.ros_env(tmp_path / "roslog", discovery="OFF", prefixes=[prefix])
    completed = subprocess.run(
        ["timeout", "-k", "5", "60", sys.executable, "-c", LIVE, package, str(bag)],
        capture_output=True,
        text=True,
        env=env,
        timeout=90,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr[-3000:]
    summary = json.loads(completed.stdout.splitlines()[-1])
    assert summary == {"received": 5, "topics": ["/uav_1/active_states"]}

    content = read_with_rosbags_only(bag)[str(bag)]
    assert content["types"] == {
        "/swarm/events": f"{package}/msg/Event",
        "/uav_1/active_states": f"{package}/msg/ActiveStates",
    }
    (run,) = read_events([bag])
    assert [e.name for e in run.events] == ["launch", "missionStart", "targetFound"]
    assert [s.states for s in run.states] == [("Idle",), ("Flying",)]
