"""`swarmgen replay`: run one member of a compiled model against a scenario on one backend and
return its trace (one record per step: input, active states, member data).

Backends: `asyncio` and `smach` run the generated Python packages (their vendored runtime, behaviours as
tasks); `rclpy` runs one member node of the generated ROS 2 package on real rclpy in a
subprocess (its interfaces built into the venv first; see swarmgen.ros_harness);
`scxml` runs the emitted SCXML in Qt SCXML (system python3 + PySide2), the independent
reference. Each backend compiles into a temporary directory and imports or loads from there.
"""

from __future__ import annotations

import asyncio
import importlib
import importlib.util
import itertools
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

from swarmgen import diagnostics as dg
from swarmgen import jsonfile, pipeline
from swarmgen.backends import runnable
from swarmgen.backends.asyncio_backend import member_modules, package_name
from swarmgen.chart.model import Chart
from swarmgen.console import shown
from swarmgen.errors import SwarmgenError
from swarmgen.ir.nodes import Model

SYSTEM_PYTHON = "/usr/bin/python3"
QT_SCRIPT = Path(__file__).resolve().parent / "scxml" / "qt_script.py"
BACKENDS = tuple(runnable())  # from the registry: every output replay can run
_unique = itertools.count()


class ReplayError(SwarmgenError):
    """The model, member, scenario or backend cannot be replayed (a user error)."""


SCRIPT_BYTES = 8 << 20  # a replay script (docs/trace.md, "Limits"; a step is about 100 bytes)
MAX_STEPS = 100_000  # steps of a script, and inputs of one burst
MAX_WAIT = 60_000  # ms one `wait` step lets pass (in real time: timers and delayed raises)
_TOP_KEYS = {"member", "steps", "description"}
_EVENT_KEYS = {"event": str, "data": dict}
_COMPLETE_KEYS = {"complete": str, "outcome": str, "outputs": dict, "state": str}


def load_scenario(path: Path) -> tuple[str | None, list[dict[str, Any]]]:
    """(member type or None, steps) from a JSON script file; see swarmgen.runtime.replay.
    `ReplayError` names the file and the JSON path of a bad value."""
    try:
        payload = jsonfile.load(path, SCRIPT_BYTES)
        return _script(payload)
    except jsonfile.JsonError as err:
        message = str(err)
        prefix = shown(path)
        raise ReplayError(
            message if message.startswith(prefix) else f"{prefix}: {message}"
        ) from None


def _script(payload: Any) -> tuple[str | None, list[dict[str, Any]]]:
    where = "$"
    member = None
    if isinstance(payload, dict):
        jsonfile.check_keys(payload, _TOP_KEYS, "$")
        if "steps" not in payload:
            raise jsonfile.JsonError('$: a script is a list of steps or {"steps": [...]}')
        if payload.get("member") is not None:
            member = jsonfile.expect_str(payload["member"], "$.member", empty=False)
        jsonfile.expect_str(payload.get("description", ""), "$.description")
        payload, where = payload["steps"], "$.steps"
    steps = jsonfile.expect_list(payload, where)
    if len(steps) > MAX_STEPS:
        raise jsonfile.JsonError(f"{where}: more than {MAX_STEPS:,} steps")
    for number, step in enumerate(steps):
        _check_step(step, f"{where}[{number}]", burst_allowed=True)
    return member, steps


def _check_step(step: object, where: str, *, burst_allowed: bool) -> None:
    item = jsonfile.expect_object(step, where)
    if "burst" in item:
        if not burst_allowed:
            raise jsonfile.JsonError(f"{where}: a burst cannot contain a burst")
        jsonfile.check_keys(item, {"burst"}, where)
        inner = jsonfile.expect_list(item["burst"], f"{where}.burst", empty=False)
        if len(inner) > MAX_STEPS:
            raise jsonfile.JsonError(f"{where}.burst: more than {MAX_STEPS:,} inputs")
        for number, each in enumerate(inner):
            _check_step(each, f"{where}.burst[{number}]", burst_allowed=False)
        return
    if "wait" in item:
        jsonfile.check_keys(item, {"wait"}, where)
        wait = item["wait"]
        if isinstance(wait, bool) or not isinstance(wait, int | float) or not 0 <= wait <= MAX_WAIT:
            raise jsonfile.JsonError(f"{where}.wait: milliseconds, from 0 to {MAX_WAIT:,}")
        return
    if "event" in item:
        keys = _EVENT_KEYS
    elif "complete" in item:
        keys = _COMPLETE_KEYS
    else:
        raise jsonfile.JsonError(f"{where}: a step needs `event`, `complete`, `wait` or `burst`")
    jsonfile.check_keys(item, set(keys), where)
    for key, kind in keys.items():
        value, at = item.get(key), jsonfile.key_path(where, key)
        if kind is dict and value is not None:
            jsonfile.expect_object(value, at)
        elif kind is str and (value is not None or key in ("event", "complete")):
            jsonfile.expect_str(value, at, empty=False)


def replay(
    model: Path, member: str, steps: Sequence[dict[str, Any]], backend: str
) -> list[dict[str, Any]]:
    """One scenario of events through a member's generated code: its trace (see `replay_many`)."""
    return replay_many(model, member, [steps], backend)[0]


def replay_many(
    model: Path, member: str, scenarios: Sequence[Sequence[dict[str, Any]]], backend: str
) -> list[list[dict[str, Any]]]:
    """One trace per scenario; the model is compiled once and each scenario starts afresh."""
    validation = pipeline.validate(model)
    if validation.model is None or dg.has_errors(validation.diagnostics):
        raise ReplayError(dg.refusal_line(model, validation.diagnostics))
    charts = {c.member or c.name: c for c in validation.charts}
    if member not in charts:
        raise ReplayError(f"no member type '{member}'; choose one of: {', '.join(sorted(charts))}")
    if backend not in BACKENDS:
        raise ReplayError(f"unknown backend '{backend}'; choose one of: {', '.join(BACKENDS)}")
    result = pipeline.compile_model(model, backends=[backend])
    with tempfile.TemporaryDirectory(prefix="swarmgen-replay-") as tmp:
        out = Path(tmp) / "out"
        pipeline.write_tree(result.files, out)
        chart = charts[member]
        if backend == "scxml":
            traces = run_qt_many(out / "scxml" / f"{chart.name}.scxml", scenarios)
        elif backend == "rclpy":
            traces = _run_rclpy(
                out / "rclpy", validation.model, validation.charts, chart.name, scenarios
            )
        else:
            package = out / backend / package_name(validation.model)
            module_name = member_modules(tuple(charts.values()))[chart.name]
            traces = _run_python(package, module_name, member, scenarios)
    return [[canonical(record) for record in trace] for trace in traces]


def canonical(value: Any) -> Any:
    """Numbers as ECMAScript sees them (3.0 is 3), so traces of all backends compare as text."""
    if isinstance(value, float) and value.is_integer() and abs(value) < 2**53:
        return int(value)
    if isinstance(value, dict):
        return {k: canonical(v) for k, v in value.items()}
    if isinstance(value, list):
        return [canonical(v) for v in value]
    return value


def _import_package(package: Path) -> str:
    """Import a generated package from its directory under a fresh, unique name."""
    name = f"_swarmgen_replay_{next(_unique)}_{package.name}"
    spec = importlib.util.spec_from_file_location(
        name, package / "__init__.py", submodule_search_locations=[str(package)]
    )
    if spec is None or spec.loader is None:
        raise ReplayError(f"cannot import the generated package {package}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return name


def _run_python(
    package: Path, module_name: str, member: str, scenarios: Sequence[Sequence[dict[str, Any]]]
) -> list[list[dict[str, Any]]]:
    """Run a generated Python package's member module with its own vendored runtime."""
    name = _import_package(package)
    try:
        member_module: ModuleType = importlib.import_module(f"{name}.{module_name}")
        runtime: ModuleType = importlib.import_module(f"{name}._runtime.replay")
        return [
            asyncio.run(runtime.replay_async(member_module.build(), member, steps))
            for steps in scenarios
        ]
    finally:
        for key in [k for k in sys.modules if k == name or k.startswith(f"{name}.")]:
            del sys.modules[key]


def _run_rclpy(
    rclpy_dir: Path,
    model: Model,
    charts: Sequence[Chart],
    chart_name: str,
    scenarios: Sequence[Sequence[dict[str, Any]]],
) -> list[list[dict[str, Any]]]:
    """One member node on real rclpy, in a subprocess (see swarmgen.ros_harness)."""
    from swarmgen import ros_harness as harness

    try:
        return harness.replay_rclpy(rclpy_dir, model, charts, chart_name, scenarios)
    except (harness.RosUnavailable, harness.RosRunError) as err:
        raise ReplayError(str(err)) from None


def run_qt_many(
    document: Path, scenarios: Sequence[Sequence[dict[str, Any]]]
) -> list[list[dict[str, Any]]]:
    """Run an SCXML document in Qt SCXML once per scenario, in one Qt process."""
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
        json.dump([list(s) for s in scenarios], handle)
    try:
        records = _qt(["runmany", str(document), handle.name], document)
    finally:
        os.unlink(handle.name)
    traces: list[list[dict[str, Any]]] = [[] for _ in scenarios]
    for record in records:
        traces[record.pop("scenario")].append(record)
    return traces


def run_qt(document: Path, steps: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Run an SCXML document in Qt SCXML through the steps (see scxml/qt_script.py)."""
    return _qt(["run", str(document), json.dumps(list(steps))], document)


def _qt(arguments: list[str], document: Path) -> list[dict[str, Any]]:
    # the ROS wheels' bootstrap variables must not reach the system python
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith("_ROS_WHEELS") and k != "LD_LIBRARY_PATH"
    }
    env["QT_QPA_PLATFORM"] = "offscreen"
    try:
        completed = subprocess.run(
            [SYSTEM_PYTHON, str(QT_SCRIPT), *arguments],
            capture_output=True,
            text=True,
            timeout=600,
            env=env,
            check=False,
        )
    except FileNotFoundError:
        raise ReplayError(
            f"{SYSTEM_PYTHON} not found: Qt SCXML needs Debian's python3-pyside2.qtscxml"
        ) from None
    if completed.returncode != 0:
        raise ReplayError(f"Qt SCXML failed: {completed.stderr.strip().splitlines()[-1:]}")
    records = [json.loads(line) for line in completed.stdout.splitlines() if line.strip()]
    if records and "step" not in records[0]:  # {"errors": [...]}: the document did not load
        raise ReplayError(f"Qt SCXML cannot load {document.name}: {records[0]['errors']}")
    return records
