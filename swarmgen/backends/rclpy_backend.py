"""The rclpy backend: ROS 2 packages for a swarm.

Output under `rclpy/`:

- `<swarm>_interfaces/`: an ament_cmake/rosidl package (`swarmgen.ros.interfaces`): the `Event`
  and `ActiveStates` messages and one action per library behaviour that has no resolvable
  declared type, named after the behaviour (goal = inputs, result = outputs + outcome, feedback
  = status). A behaviour whose `rosType` binds (`rclpy_declared`) runs on that type instead
  (`BehaviourSpec(binding=Binding(...))`), and the types found only in the user's interface
  directories become interface packages of the workspace (`<pkg>/`, definitions as they are).
- `<swarm>_nodes/`: an ament_python package: a node module per member type (its statechart,
  behaviours, parameters), scripted action servers that simulate the behaviours, the swarm
  launcher (`launch_swarm`, all members in one process), `launch/<swarm>.launch.py`, and
  vendored copies of `swarmgen.runtime` (`_runtime/`) and `swarmgen.ros.runtime` (`_ros/`).

Names: packages, modules, nodes, action and parameter names go through `names.ros_name` and are
checked against ROS rules; action types and fields through `interfaces.check_*`. Model text
reaches generated code only as `repr()` literals or `names.one_line` comments.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable
from pathlib import PurePosixPath
from typing import Any

from swarmgen.backends import Files, pycommon
from swarmgen.backends.pycommon import common_view, member_view, package_name, script_specs
from swarmgen.backends.pyrender import chart_code, format_python
from swarmgen.backends.pytypes import MODULE, render_types
from swarmgen.backends.rclpy_declared import (
    Declared,
    declared_bindings,
    exec_depends,
    user_packages,
)
from swarmgen.backends.rclpy_messages import DataMessages, camel, data_messages
from swarmgen.backends.rclpy_parameters import (
    FieldView,
    field_type,
    field_view,
    member_parameters,
)
from swarmgen.backends.vendor import ros_runtime_files, runtime_files
from swarmgen.chart.model import BehaviourInfo, Chart
from swarmgen.generated import header, markdown_cell, xml_text
from swarmgen.ir.nodes import Model
from swarmgen.ir.query import composition as swarm_composition
from swarmgen.names import doc_text, one_line, ros_name
from swarmgen.records import dataclass
from swarmgen.render import render
from swarmgen.ros.idl_index import InterfaceIndex
from swarmgen.ros.interfaces import (
    ACTIVE_STATES_MSG,
    EVENT_MSG,
    behaviour_action,
    check_package_name,
    check_type_name,
    render_interface_package,
)

__all__ = ["RclpyBackend", "field_type", "interfaces_package", "member_modules", "nodes_package"]

RUNTIME_MODULES = (
    "values", "chart", "host", "microstep", "plans", "configuration", "engine", "sends",
    "sessions", "member", "replay", "args", "plugins",
)  # fmt: skip
ROS_RUNTIME_MODULES = (
    "spec",
    "messages",
    "scheduler",
    "lockstep",
    "convert",
    "bindings",
    "declared",
    "process",
    "goals",
    "node",
    "expressions",
    "scripts",
    "served",
    "servers",
    "simulated",
    "station",
    "usercode",
    "launcher",
    "replay",
)
_RESERVED_TYPES = ("Event", "ActiveStates")
_NO_MESSAGES = DataMessages()
# Module names double as executables and as launcher options (`--uav 2`): keep them clear of
# the package's other modules and of the launcher's own options.
_RESERVED_MODULES = (
    "behaviours", "launch_swarm", "simulated_behaviours", "help", "h", "script", "time_scale",
    "station", "duration", "no_simulation", "trace", "events", "server_timeout",
    "library", "no_plugins", "executor", MODULE,
)  # fmt: skip
# A relative ROS name: tokens of letters, digits and underscores (not leading digits), no `__`.
_ROS_TOKEN = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def swarm_name(model: Model) -> str:
    """The swarm's ROS name, the stem of both package names."""
    return check_package_name(ros_name(model.name or "swarm"))


def interfaces_package(model: Model) -> str:
    """The interface (rosidl) package's name."""
    return f"{swarm_name(model)}_interfaces"


def nodes_package(model: Model) -> str:
    """The node (ament_python) package's name."""
    return f"{swarm_name(model)}_nodes"


def member_modules(charts: Iterable[Chart]) -> dict[str, str]:
    """chart name -> module (and node, executable) name: lower snake case, unique."""
    return pycommon.member_modules(charts, _RESERVED_MODULES, "_member")


def is_relative_ros_name(name: str) -> bool:
    """Whether `name` is a valid relative ROS name (tokens of `_ROS_TOKEN`, no `__`)."""
    tokens = name.split("/")
    return all(_ROS_TOKEN.fullmatch(t) and "__" not in t for t in tokens)


@dataclass(frozen=True)
class BehaviourView:
    """A behaviour as the rclpy backend renders it: its action, ROS name and fields."""

    info: BehaviourInfo
    action: str
    ros_name: str
    inputs: tuple[FieldView, ...]
    outputs: tuple[FieldView, ...]
    note: str  # why the action name differs from the declared rosName ("" if it does not)
    declared: Declared | None = None  # runs on its declared type (no private action)
    enumerations: frozenset[str] = frozenset()  # the model's enumeration names
    messages: DataMessages = _NO_MESSAGES  # the model's data types as messages

    @property
    def runs_as(self) -> str:
        """How the behaviour runs, for parameter descriptions and the README."""
        if self.declared is not None:
            return f"run as {self.declared.binding.kind} {self.declared.binding.type} at {self.ros_name}"
        return f"run as action {self.action} at {self.ros_name}"

    @property
    def action_text(self) -> str:
        """The behaviour's `.action` file."""
        return behaviour_action(
            [(f.field, f.model_type) for f in self.inputs],
            [(f.field, f.model_type) for f in self.outputs],
            self.enumerations,
            self.messages.types,
        )

    def spec(self) -> str:
        """The `BehaviourSpec(...)` literal of generated code."""
        declared = (
            self.info.ros_kind or "",
            self.info.ros_name or "",
            self.info.ros_type or "",
        )

        def fields(items: tuple[FieldView, ...], decoded: bool = False) -> str:
            inner = "".join(
                f"Field({f.name!r}, {f.field!r}, {f.type!r}"
                f"{f', {f.renames!r}' if f.renames else ''}{self._enums(f) if decoded else ''}), "
                for f in items
            )
            return f"({inner})"

        if self.declared is not None:  # no private action: its fields are the binding's
            action, io, binding = "", "", f", binding={self.declared.literal(self.ros_name)}"
        else:
            action, binding = self.action, ""
            # only outputs are read back from ROS by the member (the goal client's `decode`)
            io = f"inputs={fields(self.inputs)}, outputs={fields(self.outputs, True)}, "
        return (
            f"BehaviourSpec(name={self.info.name!r}, action={action!r}, "
            f"ros_name={self.ros_name!r}, kind={self.info.kind!r}, {io}"
            f"outcomes={tuple(self.info.outcomes)!r}, declared={declared!r}{binding})"
        )

    def _enums(self, field: FieldView) -> str:
        """`, enums=...` of a message field whose data type holds enumerations, else ""."""
        if "/" not in field.type:  # a plain enumeration field: empty is "not given"
            return ""
        blanks = self.messages.enums.get((field.model_type or "").removesuffix("[]"))
        return f", enums={blanks!r}" if blanks else ""


def behaviour_views(
    charts: tuple[Chart, ...],
    bound: dict[str, Declared] | None = None,
    enumerations: frozenset[str] = frozenset(),
    messages: DataMessages | None = None,
) -> dict[str, BehaviourView]:
    """Every behaviour the charts run, by model name, with its action type, name and fields,
    and its binding when it runs on its declared type (`bound`, by model name);
    `enumerations` (the model's) travel as strings, sequences as arrays (`field_type`), data
    types as the messages of `messages` (None: as JSON)."""
    messages = messages or _NO_MESSAGES
    bound = bound or {}
    infos: dict[str, BehaviourInfo] = {}
    for chart in charts:
        for info in chart.behaviours:
            infos.setdefault(info.name, info)
    types: set[str] = set(_RESERVED_TYPES)
    names: set[str] = set()
    views = {}
    for name in sorted(infos):
        info = infos[name]
        action = camel(info.ident or info.name)
        candidate, n = action, 2
        while candidate in types:
            candidate, n = f"{action}{n}", n + 1
        types.add(check_type_name(candidate))
        note = ""
        declared = (info.ros_name or "").strip()
        if declared.startswith("/"):
            declared, note = declared.lstrip("/"), "absolute rosName made relative to the member"
        if declared and not is_relative_ros_name(declared):
            declared, note = "", f"rosName {declared!r} is not a valid ROS name"
        action_name = declared or ros_name(info.name)
        if action_name in names:
            note = note or f"rosName {action_name!r} is used by another behaviour"
            base = ros_name(info.name)
            action_name = base
            n = 2
            while action_name in names:
                action_name, n = f"{base}_{n}", n + 1
        names.add(action_name)
        in_taken: set[str] = set()
        out_taken: set[str] = {"outcome"}
        inputs = tuple(field_view(info, p, in_taken, enumerations, messages) for p in info.inputs)
        outputs = tuple(
            field_view(info, p, out_taken, enumerations, messages) for p in info.outputs
        )
        views[name] = BehaviourView(
            info,
            candidate,
            action_name,
            inputs,
            outputs,
            note,
            bound.get(name),
            enumerations,
            messages,
        )
    return views


class RclpyBackend:
    """The ROS 2 output: interface packages and a node package with launcher. `interfaces` is
    the index the check resolved the declared types in (None: every behaviour private)."""

    name = "rclpy"

    def __init__(self, interfaces: InterfaceIndex | None = None) -> None:
        self.interfaces = interfaces

    def render(self, model: Model, charts: tuple[Chart, ...]) -> Files:
        """The interface packages, the node package and README.md (the module docstring)."""
        if not charts:
            return {}  # no state machine, nothing to run
        names = sorted({info.name for chart in charts for info in chart.behaviours})
        own = (interfaces_package(model), nodes_package(model))
        declared = declared_bindings(model, names, self.interfaces, own)
        views = private_views(model, charts, declared)
        view = package_view(model, charts)
        listed = ("action_msgs", "builtin_interfaces", "rcl_interfaces")  # package.xml.j2's
        used = next(iter(views.values())).messages.packages(own) if views else set()
        view["depends"] = sorted({*exec_depends(declared.values(), (*own, *listed)), *used})
        files = interface_files(model, views)
        packages = user_packages(declared.values(), self.interfaces) if self.interfaces else {}
        view["user_packages"] = sorted(packages)
        for package, rendered in packages.items():
            files.update({PurePosixPath(package) / p: t for p, t in rendered.items()})
        files.update(node_modules(model, charts, views, view))
        files.update(package_files(model, charts, view))
        files[PurePosixPath("README.md")] = readme(model, views, view)
        return files


def private_views(
    model: Model, charts: tuple[Chart, ...], declared: dict[str, Declared]
) -> dict[str, BehaviourView]:
    """`behaviour_views` with the data types of the private actions as messages, named after
    the actions (which keep their names: the messages give way on a collision)."""
    enums = frozenset(e.name for e in model.enumerations)
    first = behaviour_views(charts, declared, enums)
    private = [v for v in first.values() if v.declared is None]
    used = [t for v in private for _, t in (*v.info.inputs, *v.info.outputs)]
    taken = {*_RESERVED_TYPES, *(v.action for v in private)}
    messages = data_messages(model, interfaces_package(model), used, taken)
    return behaviour_views(charts, declared, enums, messages)


def package_view(model: Model, charts: tuple[Chart, ...]) -> dict[str, Any]:
    """What the node package's templates share: names, members and their counts."""
    swarm = swarm_name(model)
    interfaces = interfaces_package(model)
    modules = member_modules(charts)
    members = {chart.member or chart.name: modules[chart.name] for chart in charts}
    counts = swarm_composition(model)
    composition = {kind: counts.get(kind, 1) for kind in members}
    common = common_view(charts)
    return {
        **common,
        "markup_header": header(common["source"], syntax="<!--"),
        "model": doc_text(model.name),
        "model_repr": repr(model.name),
        "package": nodes_package(model),
        "interfaces": interfaces,
        "swarm": swarm,
        "chart_modules": modules,
        "modules": sorted(modules.values()),
        "members": members,
        "composition": composition,
        "composition_literal": repr(composition),
        "interfaces_literal": repr(interfaces),
        "launch_file": f"{swarm}.launch.py",
        "first_flags": " ".join(f"--{m.replace('_', '-')} 2" for m in members.values()),
    }


def interface_files(model: Model, views: dict[str, BehaviourView]) -> Files:
    """`<swarm>_interfaces/`: the messages and one action per behaviour."""
    interfaces = interfaces_package(model)
    description = one_line(f"ROS 2 interfaces of swarm {model.name} (generated by swarmgen)")
    messages = next(iter(views.values())).messages.texts if views else {}
    rendered = render_interface_package(
        interfaces,
        {"Event": EVENT_MSG, "ActiveStates": ACTIVE_STATES_MSG, **messages},
        {v.action: v.action_text for v in views.values() if v.declared is None},
        description,
    )
    return {PurePosixPath(interfaces) / path: text for path, text in rendered.items()}


def node_modules(
    model: Model, charts: tuple[Chart, ...], views: dict[str, BehaviourView], view: dict[str, Any]
) -> Files:
    """The Python package of the nodes: member modules, `__init__`, behaviours, launcher and
    the vendored runtimes."""
    python = PurePosixPath(view["package"]) / view["package"]
    modules = view["chart_modules"]
    common = common_view(charts)
    files: Files = {}
    for chart in charts:
        module = modules[chart.name]
        files[python / f"{module}.py"] = render_member(
            chart, model, views, module, view["interfaces"], common
        )
    events: dict[str, tuple[str, str]] = {}
    for key in ("name", "ident"):  # by name first, then by identifier where names are taken
        for event in model.events:
            events.setdefault(getattr(event, key), (event.ident, event.scope or "swarm"))
    init = render(
        "rclpy/package_init.py.j2",
        **view,
        member_modules=repr(view["members"]),
        events_literal=repr(dict(sorted(events.items()))),
    )
    files[python / "__init__.py"] = format_python(init)
    behaviours = render("rclpy/behaviours.py.j2", **view, scripts=repr(script_specs(charts)))
    files[python / "behaviours.py"] = format_python(behaviours)
    files[python / "launch_swarm.py"] = format_python(render("rclpy/launch_swarm.py.j2", **view))
    # the asyncio package's contract and entry-point group: one plug-in serves every backend
    typed = render_types(model, charts, package_name(model), {**common, "runtime": "._runtime"})
    files[python / f"{MODULE}.py"] = format_python(typed)
    files.update(runtime_files(python / "_runtime", RUNTIME_MODULES))
    files.update(ros_runtime_files(python / "_ros", ROS_RUNTIME_MODULES))
    return files


def package_files(model: Model, charts: tuple[Chart, ...], view: dict[str, Any]) -> Files:
    """The ament_python package around the nodes: launch file, setup.py/cfg, package.xml."""
    package = view["package"]
    root = PurePosixPath(package)
    composition = view["composition"]
    swarm_counts = {c.name: composition[c.member or c.name] for c in charts}
    launch = render(
        "rclpy/launch.py.j2",
        **view,
        entries=launch_entries(view["members"], composition),
        swarm_literal=repr(json.dumps(swarm_counts, sort_keys=True)),
    )
    setup = render(
        "rclpy/setup.py.j2",
        **view,
        description=repr(one_line(f"Swarm {model.name}: member nodes (generated by swarmgen)")),
        entry_points=[f"{m} = {package}.{m}:main" for m in sorted(view["members"].values())],
    )
    package_xml = render(
        "rclpy/package.xml.j2",
        **view,
        description=_xml(f"Swarm {model.name}: member nodes, simulated behaviours, launcher"),
    )
    return {
        root / "launch" / view["launch_file"]: format_python(launch),
        root / "setup.py": format_python(setup),
        root / "setup.cfg": render("rclpy/setup.cfg.j2", **view),
        root / "package.xml": package_xml,
        root / "resource" / package: "",
    }


def readme(model: Model, views: dict[str, BehaviourView], view: dict[str, Any]) -> str:
    """README.md of `rclpy/`: the packages, how to run them, each behaviour's action."""
    rows = []
    for v in views.values():
        declared = " ".join(x for x in (v.info.ros_kind, v.info.ros_name, v.info.ros_type) if x)
        bound = v.declared
        rows.append(
            {
                "name": markdown_cell(v.info.name),
                "kind": bound.binding.kind if bound else "action",
                "type": bound.binding.type if bound else f"{view['interfaces']}/action/{v.action}",
                "ros_name": v.ros_name,
                "declared": markdown_cell(declared or "-"),
            }
        )
    return render("rclpy/README.md.j2", **view, model_md=markdown_cell(model.name), behaviours=rows)


def launch_entries(members: dict[str, str], composition: dict[str, int]) -> list[dict[str, Any]]:
    """One entry per member of the composition: its kind, module, id and index."""
    entries = []
    for kind, module in members.items():
        for index in range(1, composition[kind] + 1):
            entries.append(
                {
                    "kind": repr(kind),
                    "module": module,
                    "member_id": f"{module}_{index}",
                    "index": index,
                }
            )
    return entries


def render_member(
    chart: Chart,
    model: Model,
    views: dict[str, BehaviourView],
    module: str,
    interfaces: str,
    common: dict[str, str],
) -> str:
    """A member node module: the chart's code, its behaviours' actions and its parameters."""
    code = chart_code(chart)
    behaviours = [views[b.name] for b in chart.behaviours]
    reserved = [p for v in behaviours if v.declared and (p := v.declared.timeout_parameter)]
    runs_as = {v.info.name: v.runs_as for v in behaviours}
    imports = ["BehaviourSpec", "MemberSpec", "Parameter", "run_member"]
    if any(v.declared for v in behaviours):
        imports.append("Binding")
    if any(v.declared is None for v in behaviours):
        imports.append("Field")
    text = render(
        "rclpy/member.py.j2",
        **member_view(chart, common, code, " as a ROS 2 node", chart.member or chart.name),
        node_name=repr(module),
        interfaces=repr(interfaces),
        behaviours="{" + ", ".join(f"{v.info.name!r}: {v.spec()}" for v in behaviours) + "}",
        node_imports=", ".join(sorted(imports)),
        parameters="("
        + "".join(f"{p}, " for p in member_parameters(model, chart, runs_as, reserved))
        + ")",
        notes=[f"{one_line(v.info.name)}: {one_line(v.note)}" for v in behaviours if v.note],
    )
    return format_python(text)


def _xml(text: str) -> str:
    return xml_text(" ".join(one_line(text).split()))
