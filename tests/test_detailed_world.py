"""The world node (swarmgen_library.world_node) on real rclpy, against a scripted driver
(tests/detailed_driver.py) that answers every pose with a fixed stamped velocity.

Every ROS process runs in a subprocess under `timeout -k 5`, with LOCALHOST discovery, the
ROS_DOMAIN_ID of this test run (1 + (pid + 50) % 100: apart from test_ros_interfaces' 1 + pid %
100 in the same run) and its logs in the test's tmp directory; every process is ended at the
end of its test. A bad world file needs no ROS: it is refused before rclpy starts.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
pytest.importorskip("psutil", reason="psutil comes with the `ros` extra: run `make ros`")

from swarmgen import ros_harness as harness
from swarmgen.ros.domains import hold
from tests import rosproc
from tests.conftest import ROOT

LIBRARY = ROOT / "swarmgen" / "ros" / "library"
DOMAIN = hold(1, 139, start=1 + (os.getpid() + 50) % 100)  # leased: see swarmgen/ros/domains.py
NS = 1_000_000_000


def world_file(tmp: Path, **over: Any) -> Path:
    """One UAV east from (1, 1), 1 m up (airborne: its camera sees), at 1 m/s in a 10 m
    square, dt = 0.125 (binary-exact steps)."""
    config: dict[str, Any] = {
        "area": {"width": 10, "height": 10},
        "cell": 0.5,
        "dt": 0.125,
        "robots": [
            {"name": "uav_1", "max_speed": 1.0, "fov_radius": 0.5, "start": [1, 1, 1],
             "pose_topics": ["pos_provider/pose"]},
        ],
        "targets": [{"id": 7, "x": 5.0, "y": 1.0}],
        "stop": {"time_s": 10.0},
        "output": "result.json",
        "start_timeout_s": 20,
        "status_readers": 1,  # the driver: the tests read its record of the final status
    }  # fmt: skip
    config.update(over)
    path = tmp / "world.json"
    path.write_text(json.dumps(config), encoding="utf-8")
    return path


def run(
    tmp: Path, world: Path, driver: dict[str, Any], *, sigterm_after: float | None = None
) -> tuple[int, str, dict[str, Any], dict[str, Any]]:
    """The world against the driver: exit code, stderr, result file, driver summary."""
    env = harness.ros_env(tmp / "roslog", domain_id=DOMAIN, python_path=[LIBRARY, ROOT])
    driver_cfg = tmp / "driver.json"
    driver_cfg.write_text(json.dumps({"out": str(tmp / "driver_out.json"), **driver}))
    drive = rosproc.start([sys.executable, "-m", "tests.detailed_driver", str(driver_cfg)],
                          env, ROOT, 90)  # fmt: skip
    node = rosproc.start([sys.executable, "-m", "swarmgen_library.world_node", str(world)],
                         env, tmp, 60)  # fmt: skip
    try:
        if sigterm_after is not None:
            time.sleep(sigterm_after)
            node.send_signal(signal.SIGTERM)  # `timeout` passes it on to the world
        code, _, err = rosproc.finish(node, 70)
        rosproc.finish(drive, 10)  # it ends on the world's final status
    finally:
        for proc in (node, drive):
            if proc.poll() is None:
                rosproc.stop(proc, 10)
    result_path = world.parent / "result.json"
    result = json.loads(result_path.read_text()) if result_path.exists() else {}
    out = tmp / "driver_out.json"
    return code, err, result, json.loads(out.read_text()) if out.exists() else {}


@pytest.fixture(scope="module")
def east(
    tmp_path_factory: pytest.TempPathFactory,
) -> list[tuple[int, str, dict[str, Any], dict[str, Any]]]:
    """The one-UAV world run twice with the same file."""
    runs = []
    for _ in range(2):
        tmp = tmp_path_factory.mktemp("east")
        driver = {"robots": ["uav_1"], "dt": 0.125, "velocity": [1.0, 0.0, 0.0]}
        runs.append(run(tmp, world_file(tmp), driver))
    return runs


def test_the_body_reaches_the_wall_where_geometry_says(east: list[Any]) -> None:
    code, err, result, driver = east[0]
    assert code == 0, err[-2000:]
    assert result["complete"] and result["reason"] == "time_limit"
    assert result["steps"] == 80 and result["sim_s"] == 10.0 and result["timeouts"] == 0
    poses = driver["poses"]["uav_1"]
    assert len(poses) == 80  # steps 0..79 are published; step 80 is where it stops
    for k, (stamp, x, y, z) in enumerate(poses):
        assert stamp == k * 125_000_000  # k * dt, exact
        assert (x, y, z) == (min(1.0 + k * 0.125, 10.0), 1.0, 1.0)
    assert [p[1] for p in poses].index(10.0) == 72  # (10 - 1) / (1 m/s * 0.125 s)
    # the camera disc's edge (0.5 m) reaches the target at x = 4.5: step 28, t = 3.5 s
    assert result["targets"]["7"]["first_detection"] == 3.5


def test_clock_advances_with_the_steps(east: list[Any]) -> None:
    _, _, _, driver = east[0]
    assert driver["clock"] == [k * 125_000_000 for k in range(80)]
    assert driver["counts"]["cameras"] == 80 and driver["final"]["final"] is True


def test_two_runs_of_one_file_give_the_same_result(east: list[Any]) -> None:
    (_, _, first, _), (code, err, second, _) = east
    assert code == 0, err[-2000:]
    first.pop("wall")
    second.pop("wall")
    assert first == second
    assert first["samples"][0] == [0, 0.01] and len(first["samples"]) == 81


def test_a_driver_that_stops_answering_gives_timeouts_not_a_hang(tmp_path: Path) -> None:
    world = world_file(tmp_path, step_timeout_s=0.05, stop={"time_s": 2.5})
    driver = {"robots": ["uav_1"], "dt": 0.125, "velocity": [1.0, 0.0, 0.0], "answer_until": 5}
    started = time.monotonic()
    code, err, result, _ = run(tmp_path, world, driver)
    assert code == 0, err[-2000:]
    assert result["complete"] and result["steps"] == 20
    # steps 6..19 time out for sure; on a loaded machine an early answer may miss the 50 ms too
    timeouts = result["timeouts_by_robot"]["uav_1"]
    assert 14 <= timeouts <= 20, result["timeouts_by_robot"]
    assert result["unserved"] == []  # its publisher is still there: waited for every step
    # the held command keeps it moving: x = 1 + 20 * 0.125
    assert result["samples"][-1][0] == 20
    assert time.monotonic() - started < 30


def test_sigterm_writes_a_partial_result(tmp_path: Path) -> None:
    world = world_file(tmp_path, stop={"time_s": 1e6})
    driver = {"robots": ["uav_1"], "dt": 0.125, "velocity": [0.0, 0.0, 0.0], "record": False}
    code, err, result, driver_out = run(tmp_path, world, driver, sigterm_after=4.0)
    assert code == 1, err[-2000:]
    assert "Traceback" not in err
    assert result["complete"] is False and result["reason"] == "signal"
    assert result["steps"] > 0 and result["samples"][-1][0] == result["steps"]
    assert driver_out["final"]["final"] is True  # the driver heard the end


def test_a_status_reader_that_never_comes_is_counted_not_waited_for_forever(
    tmp_path: Path,
) -> None:
    """Nobody subscribes to /world/status: the start waits start_timeout_s for the reader (and
    the robot's server), the end waits a bounded time, and the result says one was missed."""
    world = world_file(tmp_path, start_timeout_s=1.0, stop={"time_s": 0.5})
    env = harness.ros_env(tmp_path / "roslog", domain_id=DOMAIN, python_path=[LIBRARY, ROOT])
    node = rosproc.start([sys.executable, "-m", "swarmgen_library.world_node", str(world)],
                         env, tmp_path, 60)  # fmt: skip
    try:
        code, _, err = rosproc.finish(node, 50)
    finally:
        if node.poll() is None:
            rosproc.stop(node, 10)
    assert code == 0, err[-2000:]
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["complete"] and result["steps"] == 4 and result["unserved"] == ["uav_1"]
    assert result["status_unmatched"] == 1


def test_step_reports_and_settling(tmp_path: Path) -> None:
    world = world_file(tmp_path, settle_reporters=1, settle_s=0.4, stop={"time_s": 1.25})
    driver = {"robots": ["uav_1"], "dt": 0.125, "velocity": [1.0, 0.0, 0.0], "report": True,
              "settle_at": [3, 6]}  # fmt: skip
    code, err, result, driver_out = run(tmp_path, world, driver)
    assert code == 0, err[-2000:]
    assert result["steps"] == 10 and result["report_timeouts"] == 0
    assert driver_out["counts"]["reports"] == 10
    assert result["wall"]["wall_s"] >= 0.8  # two settles of 0.4 s


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"robots": []}, "robots: must be a non-empty list"),
        ({"dt": -1}, "dt: must be > 0, got -1"),
        ({"robots": [{"name": "uav_1", "max_speed": -2}]}, "robots[0].max_speed: must be > 0"),
        ({"targets": [{"id": 1, "x": 50, "y": 1}]}, "target 1 lies outside the area"),
        ({"stop": {}}, "stop.time_s: missing"),
        ({"cell": 3}, "world: cell 3.0 does not divide the area side 10.0"),
        ({"cmd_type": "twist"}, "cmd_type: must be 'twist_stamped', got 'twist'"),
        ({"airborne_z": -0.5}, "airborne_z: must be >= 0, got -0.5"),
        ({"status_readers": -1}, "status_readers: must be an integer >= 0, got -1"),
    ],
)
def test_a_bad_world_file_is_one_line_and_exit_2(
    tmp_path: Path, change: dict[str, Any], message: str
) -> None:
    world = world_file(tmp_path, **change)
    env = {**os.environ, "PYTHONPATH": str(LIBRARY)}
    done = subprocess.run(
        [sys.executable, "-m", "swarmgen_library.world_node", str(world)],
        capture_output=True, text=True, env=env, timeout=60, check=False,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert message in done.stderr, done.stderr


def test_an_output_that_cannot_be_written_is_one_line_and_exit_2(tmp_path: Path) -> None:
    (tmp_path / "afile").write_text("")  # a file where the output's folder should be
    env = {**os.environ, "PYTHONPATH": str(LIBRARY)}
    for output, why in [("afile/result.json", "is not a folder"), (".", "it is a folder")]:
        world = world_file(tmp_path, output=output)
        done = subprocess.run(
            [sys.executable, "-m", "swarmgen_library.world_node", str(world)],
            capture_output=True, text=True, env=env, timeout=60, check=False,
        )  # fmt: skip
        assert done.returncode == 2, done.stderr
        assert done.stderr.count("\n") == 1 and done.stderr.startswith("world: output: ")
        assert why in done.stderr, done.stderr


def test_a_file_that_is_not_json(tmp_path: Path) -> None:
    world = tmp_path / "world.json"
    world.write_text("{not json")
    env = {**os.environ, "PYTHONPATH": str(LIBRARY)}
    done = subprocess.run(
        [sys.executable, "-m", "swarmgen_library.world_node", str(world)],
        capture_output=True, text=True, env=env, timeout=60, check=False,
    )  # fmt: skip
    assert done.returncode == 2 and done.stderr.startswith("world: ") and "not JSON" in done.stderr


def test_a_dead_driver_costs_one_timeout_then_its_robot_is_unserved(tmp_path: Path) -> None:
    # no status reader: the killed driver's would be missed at the end (and 5 s waited for)
    world = world_file(tmp_path, step_timeout_s=0.5, stop={"time_s": 2000.0}, status_readers=0)
    env = harness.ros_env(tmp_path / "roslog", domain_id=DOMAIN, python_path=[LIBRARY, ROOT])
    driver_cfg = tmp_path / "driver.json"
    driver_cfg.write_text(json.dumps({"out": str(tmp_path / "driver_out.json"), "robots": ["uav_1"],
                                      "dt": 0.125, "velocity": [0.5, 0.0, 0.0], "record": False}))  # fmt: skip
    drive = rosproc.start([sys.executable, "-m", "tests.detailed_driver", str(driver_cfg)],
                          env, ROOT, 60)  # fmt: skip
    node = rosproc.start([sys.executable, "-m", "swarmgen_library.world_node", str(world)],
                         env, tmp_path, 60)  # fmt: skip
    try:
        time.sleep(3.0)  # the world is stepping against the driver
        rosproc.stop(drive, 10)
        code, _, err = rosproc.finish(node, 50)  # 16,000 steps: fast once nobody is waited for
    finally:
        for proc in (node, drive):
            if proc.poll() is None:
                rosproc.stop(proc, 10)
    assert code == 0, err[-2000:]
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["complete"] and result["steps"] == 16000
    assert result["unserved"] == ["uav_1"] and result["timeouts"] == 1
    assert result["wall"]["wall_s"] < 40


def test_the_world_console_script_from_a_colcon_install(tmp_path: Path) -> None:
    pytest.importorskip("colcon_core", reason="colcon comes with the `ros` extra: run `make ros`")
    venv = Path(sys.prefix)
    command = [
        venv / "bin" / "colcon", "--log-base", tmp_path / "log", "build", "--base-paths", LIBRARY,
        "--build-base", tmp_path / "build", "--install-base", tmp_path / "install",
    ]  # fmt: skip
    env = {**os.environ, "AMENT_PREFIX_PATH": str(venv), "CMAKE_PREFIX_PATH": str(venv)}
    built = subprocess.run([str(c) for c in command], cwd=tmp_path, env=env, capture_output=True,
                           text=True, timeout=300, check=False)  # fmt: skip
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    install = tmp_path / "install" / "swarmgen_library"
    script = install / "lib" / "swarmgen_library" / "world"  # where `ros2 run` looks
    site = next(install.glob("lib/python3*/site-packages"))
    world = world_file(tmp_path, dt=0)
    done = subprocess.run([sys.executable, str(script), str(world)], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(site)}, timeout=60, check=False)  # fmt: skip
    assert done.returncode == 2 and done.stderr == "world: dt: must be > 0, got 0\n", done.stderr


def test_the_lockstep_rules_without_ros(tmp_path: Path) -> None:
    """`worldrun.Run`: answers by stamp, reports per step, rescues at their own step."""
    from swarmgen.ros.library.swarmgen_library.worldfile import load
    from swarmgen.ros.library.swarmgen_library.worldrun import Run

    assert load(world_file(tmp_path)).spec.airborne_z == 0.5  # a grounded UAV is blind
    run_ = Run(load(world_file(tmp_path, settle_reporters=1)))
    run_.begin_step()
    run_.answer("uav_1", 125_000_000, 1.0, 0.0, 0.0)  # an answer to step 1, at step 0: stale
    assert run_.waiting_for() == ["uav_1"] and run_.stale == 1
    run_.answer("uav_1", 0, 0.5, 0.0, 0.0)
    run_.answer("uav_1", 0, 0.9, 0.0, 0.0)  # a second answer to step 0: the first one wins
    assert run_.waiting_for() == [] and run_.stale == 2
    run_.report('{"k": 0, "by": "servers", "settle": false}')
    assert run_.reporters == {"servers"} and not run_.settle
    run_.apply()
    run_.advance()
    run_.begin_step()
    run_.report('{"k": 0, "by": "servers", "settle": true}')  # late, but it still settles
    assert run_.settle and run_.reporters == set()
    run_.rescue('{"target": 7, "robot": "uav_1", "k": 0}')
    run_.rescue('{"target": 8, "robot": "uav_1"}')  # no such target
    run_.apply()  # no answer to step 1: a timeout, the command held
    run_.advance()
    assert run_.world.pose("uav_1").x == 1.0 + 2 * 0.5 * 0.125
    assert run_.timeouts == {"uav_1": 1} and run_.bad_messages == 1
    assert run_.targets()["7"]["rescued"] == 0.0
