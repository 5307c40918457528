"""Running generated rclpy code from swarmgen (replay, tests, benchmarks): the environment every
ROS 2 process gets, and the replay of one member node in a subprocess.

Every ROS process runs with `ROS_AUTOMATIC_DISCOVERY_RANGE` set (LOCALHOST: no multicast on the
real network; OFF: in-process only, used by replay, which then cannot meet any other ROS
process), its own `ROS_LOG_DIR`, a `HOME` (rclpy's logging needs one) and under
`timeout -k 5 <s>`, because a wedged rclpy process ignores SIGTERM.

Interface packages: the swarm's own (`<swarm>_interfaces`) is installed into this venv; the
packages built from the user's definitions (`cpswarm_msgs`, beside it in `rclpy/`) go into a
prefix per swarm, `<venv>/var/swarmgen/<swarm>/`, never into the venv: an installed copy would
change what the next compile resolves, and two models may define one package differently (the
samples' `cpswarm_msgs`). `build_interfaces` returns that prefix; `ros_env(prefixes=[...])` puts
the prefixes it is given on the subprocess's `PYTHONPATH`, `LD_LIBRARY_PATH` and
`AMENT_PREFIX_PATH` (in order, first wins). Nothing is remembered between calls: a caller
passes the prefixes it built.
"""

from __future__ import annotations

import functools
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from swarmgen.backends.rclpy_backend import (
    interfaces_package,
    member_modules,
    nodes_package,
    swarm_name,
)
from swarmgen.chart.model import Chart
from swarmgen.errors import SwarmgenError
from swarmgen.ir.nodes import Model
from swarmgen.ros import domains
from swarmgen.ros.interfaces import InterfaceBuildError, build_and_install


class RosUnavailable(SwarmgenError, RuntimeError):
    """rclpy (the `ros` extra) is not installed, or the interfaces cannot be built."""


class RosRunError(SwarmgenError, RuntimeError):
    """A ROS subprocess failed or timed out."""


def user_prefix(model: Model) -> Path:
    """Where the swarm's user interface packages are installed (module docstring)."""
    return Path(sys.prefix) / "var" / "swarmgen" / swarm_name(model)


def prefix_env(prefixes: Sequence[Path], env: dict[str, str]) -> None:
    """Put interface prefixes first on the Python, library and ament paths of `env`."""
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    paths = {
        "PYTHONPATH": [p / "lib" / version / "site-packages" for p in prefixes],
        "LD_LIBRARY_PATH": [p / "lib" for p in prefixes],
        "AMENT_PREFIX_PATH": list(prefixes),
    }
    for variable, entries in paths.items():
        parts = [str(e) for e in entries]
        if env.get(variable):
            parts.append(env[variable])
        if parts:
            env[variable] = os.pathsep.join(parts)


@functools.cache
def own_domain() -> int:
    """This process's ROS domain for the subprocesses it starts: one, leased for its lifetime
    (swarmgen/ros/domains.py), so two harnesses on one machine never share a domain."""
    return domains.hold(1, 139, start=1 + os.getpid() % 139)


def ros_env(
    log_dir: Path,
    *,
    domain_id: int | None = None,
    discovery: str = "LOCALHOST",
    python_path: Sequence[Path] = (),
    base: Mapping[str, str] | None = None,
    prefixes: Sequence[Path] = (),
) -> dict[str, str]:
    """The environment of a ROS 2 subprocess (see the module docstring); `prefixes`: the user
    interface prefixes to put first (those `build_interfaces` returned; none by default)."""
    env = dict(os.environ if base is None else base)
    prefix_env(prefixes, env)
    env.pop("ROS_LOCALHOST_ONLY", None)  # ignored by Kilted; do not pretend it isolates
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = discovery
    if domain_id is not None:
        env["ROS_DOMAIN_ID"] = str(domain_id)
    if "ROS_DOMAIN_ID" not in env:  # this process's own, leased (never another run's)
        env["ROS_DOMAIN_ID"] = str(own_domain())
    env["ROS_LOG_DIR"] = str(log_dir)
    env.setdefault("HOME", str(log_dir))
    if python_path:
        paths = [str(p) for p in python_path]
        if env.get("PYTHONPATH"):
            paths.append(env["PYTHONPATH"])
        env["PYTHONPATH"] = os.pathsep.join(paths)
    return env


def check_rclpy() -> None:
    """Raise RosUnavailable (with the fix) when rclpy cannot be imported."""
    if importlib.util.find_spec("rclpy") is None:
        raise RosUnavailable("rclpy is not installed: run `make ros` (pip install -e '.[ros]')")


def build_interfaces(rclpy_dir: Path, model: Model) -> Path:
    """Build the model's interface package into this venv and its user interface packages into
    `user_prefix(model)` (each skipped when current); the user prefix."""
    check_rclpy()
    prefix = user_prefix(model)
    try:
        build_and_install(rclpy_dir / interfaces_package(model))
        for package in user_package_dirs(rclpy_dir, model):
            build_and_install(package, prefix)
    except InterfaceBuildError as err:
        raise RosUnavailable(f"cannot build the ROS 2 interfaces: {err}") from None
    return prefix


def user_package_dirs(rclpy_dir: Path, model: Model) -> list[Path]:
    """The user interface packages in `rclpy_dir`, dependencies first."""
    own = {interfaces_package(model), nodes_package(model)}
    depends: dict[str, set[str]] = {}
    for manifest in sorted(rclpy_dir.glob("*/package.xml")):
        name = manifest.parent.name
        if name in own:
            continue
        root = ET.parse(manifest).getroot()
        depends[name] = {(d.text or "").strip() for d in root.iter("depend")}
    ordered: list[str] = []
    while depends:  # a package after the user packages it depends on
        ready = [n for n in sorted(depends) if not depends[n] & (set(depends) - {n})]
        ordered.append(ready[0] if ready else min(depends))
        del depends[ordered[-1]]
    return [rclpy_dir / name for name in ordered]


def replay_rclpy(
    rclpy_dir: Path,
    model: Model,
    charts: Sequence[Chart],
    chart_name: str,
    scenarios: Sequence[Sequence[Mapping[str, Any]]],
    stats: dict[str, int] | None = None,
) -> list[list[dict[str, Any]]]:
    """Replay scenarios on one member node (real rclpy, one subprocess for all of them).
    `stats` receives the harness's counters (see `swarmgen.ros.runtime.replay`)."""
    prefix = build_interfaces(rclpy_dir, model)
    package = nodes_package(model)
    module = member_modules(charts)[chart_name]
    steps = sum(len(s) for s in scenarios)
    limit = 60 + len(scenarios) + steps // 2
    with tempfile.TemporaryDirectory(prefix="swarmgen-rclpy-replay-") as tmp:
        path = Path(tmp) / "scenarios.json"
        path.write_text(json.dumps([list(s) for s in scenarios]), encoding="utf-8")
        env = ros_env(
            Path(tmp) / "roslog",
            discovery="OFF",
            python_path=[rclpy_dir / package],
            prefixes=[prefix],
        )
        command = [
            "timeout", "-k", "5", str(limit), sys.executable,
            "-m", f"{package}._ros.replay", f"{package}.{module}", str(path),
        ]  # fmt: skip
        completed = subprocess.run(
            command, capture_output=True, text=True, env=env, check=False, timeout=limit + 30
        )
    if completed.returncode != 0:
        tail = "\n".join(completed.stderr.strip().splitlines()[-15:])
        what = "timed out" if completed.returncode in (124, 137) else "failed"
        raise RosRunError(f"rclpy replay {what} (exit {completed.returncode}):\n{tail}")
    traces: list[list[dict[str, Any]]] = [[] for _ in scenarios]
    for line in completed.stdout.splitlines():
        if line.startswith("{"):
            record = json.loads(line)
            traces[record["scenario"]] = record["trace"]
            if stats is not None:
                stats.update(record["stats"])
    return traces
