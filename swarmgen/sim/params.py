"""Sweep parameters: names, values from the command line and sweep files, and their checks.

A parameter is named as in the model or the scenario:

- `TYPE.count`: a member type's count (`UAV.count`), the same as `--members TYPE=...`;
- `TYPE.data.NAME`: the default of a member datum with a primitive type (the machines read it);
- `targets`, `seed`, `max_ticks`, `stop_level`, `allocation`, `world.width`, `world.height`,
  `world.view`, `timing.KEY`, `placement.TYPE.spacing`, `placement.TYPE.headings`: the scenario's;
- `TYPE.PART.fovRadius`: a camera's field-of-view radius, in the model's metres: the type's view
  becomes `floor(r / patch_m)` patches (`r` the largest of its cameras' radii, the swept one and
  the others' model defaults; `patch_m` the scenario's `detailed.patch_m`, the one conversion
  between the model's metres and the grid). A point that sweeps no camera of a type leaves it
  `world.view`, so a model's defaults never change a scenario's results. Any other hardware
  parameter (`maxSpeed`: members move one patch per tick, the world's unit of time) is an error
  that says so, never a sweep that silently changes nothing.

Values: `V1,V2,...` (each a JSON scalar, else a string) or a range `START:STOP:STEP` with STOP
included when the steps reach it. Sweep files (JSON, or TOML by extension) hold
`{"factorial": {NAME: [values]}}` (every combination) or `{"design": [{NAME: value}, ...]}`
(the points as listed), or both (their product). Every point is checked (name, type and range,
through the scenario's own checks) before any run starts.
"""

from __future__ import annotations

import difflib
import itertools
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmgen import jsonfile
from swarmgen.console import shown
from swarmgen.inputs import InputRefused, read_limited
from swarmgen.ir.primitives import Primitive, primitive
from swarmgen.records import dataclass
from swarmgen.sim.limits import MAX_LIST, MAX_RUNS, MAX_VIEW, SCENARIO_BYTES
from swarmgen.sim.scenario import TIMING_DEFAULTS, Scenario, ScenarioError, parse

if TYPE_CHECKING:
    from swarmgen.chart.model import Chart
    from swarmgen.ir.nodes import Model

Value = bool | int | float | str
Point = tuple[tuple[str, Value], ...]  # (name, value) in the order the sweep names them
CAMERA = "fovRadius"  # the hardware parameter the abstract world reads (a type's view)

# scenario parameters -> the JSON path of the scenario file they set
_SCENARIO = {
    "targets": ("targets",),
    "seed": ("seed",),
    "max_ticks": ("max_ticks",),
    "stop_level": ("stop_level",),
    "allocation": ("allocation",),
    "world.width": ("world", "width"),
    "world.height": ("world", "height"),
    "world.view": ("world", "view"),
    **{f"timing.{key}": ("timing", key) for key in TIMING_DEFAULTS},
}
_PLACEMENT = ("spacing", "headings")


class ParamError(ScenarioError):
    """A sweep parameter that cannot be used: unknown, ill-typed or out of range (exit 2)."""


@dataclass(frozen=True)
class Names:
    """What a model offers to sweep: member types, their data (primitive type by name) and
    their hardware parameters (`part.param`)."""

    types: tuple[str, ...]
    data: dict[str, dict[str, Primitive]] = field(default_factory=dict)
    hardware: dict[str, tuple[str, ...]] = field(default_factory=dict)
    unread: dict[str, frozenset[str]] = field(default_factory=dict)  # data nothing reads
    # per type: its cameras' `part.fovRadius` -> the model's default radius (None: none given)
    cameras: dict[str, dict[str, float | None]] = field(default_factory=dict)
    behaviours: dict[str, tuple[str, ...]] = field(default_factory=dict)  # what each type runs

    def known(self) -> list[str]:
        """Every name that may be swept, for suggestions."""
        names = list(_SCENARIO)
        for kind in self.types:
            names.append(f"{kind}.count")
            names += [f"{kind}.data.{d}" for d in self.data.get(kind, {})]
            names += [f"placement.{kind}.{p}" for p in _PLACEMENT]
            names += [f"{kind}.{c}" for c in self.cameras.get(kind, {})]
        return names + [f"placement.*.{p}" for p in _PLACEMENT]


def names_of(model: Model, charts: Sequence[Chart]) -> Names:
    """The sweepable names of a validated model and its lowered charts."""
    components = {h.id: h for h in model.hardware}
    data: dict[str, dict[str, Primitive]] = {}
    unread: dict[str, frozenset[str]] = {}
    for chart in charts:
        if chart.member is not None:
            typed = ((d.name, primitive(d.type)) for d in chart.data)
            data[chart.member] = {name: kind for name, kind in typed if kind is not None}
            unread[chart.member] = _unread(chart)
    hardware: dict[str, tuple[str, ...]] = {}
    cameras: dict[str, dict[str, float | None]] = {}
    for member in model.member_types:
        found = []
        for part in member.hardware:
            component = components.get(part.type_id)
            for p in component.parameters if component else ():
                found.append(f"{part.name}.{p.name}")
                if p.name == CAMERA:
                    default = p.default
                    number = isinstance(default, int | float) and not isinstance(default, bool)
                    radius = float(default) if number else None  # type: ignore[arg-type]
                    cameras.setdefault(member.name, {})[f"{part.name}.{p.name}"] = radius
        hardware[member.name] = tuple(found)
    types = tuple(c.member for c in charts if c.member is not None)
    behaviours = {c.member: tuple(b.name for b in c.behaviours) for c in charts if c.member}
    return Names(types, data, hardware, unread, cameras, behaviours)


def _unread(chart: Chart) -> frozenset[str]:
    """The data no guard, effect or behaviour input of the chart's module reads: their default
    cannot change a run. Read off the module the simulator runs (`sim.machines`), where member
    data is `d["id"]`; `d["id"] = ...` alone is a write."""
    from swarmgen import __version__
    from swarmgen.backends.asyncio_backend import render_member

    common = {"version": __version__, "source": chart.source, "runtime": "swarmgen.runtime"}
    code = render_member(chart, common)
    return frozenset(
        d.name
        for d in chart.data
        if not re.search(rf"d\[{re.escape(json.dumps(d.id))}\](?!\s*=[^=])", code)
    )


# --- values ------------------------------------------------------------------------------------


def _scalar(word: str) -> Value:
    """A JSON scalar (`2`, `0.5`, `true`), else the word as a string."""
    try:
        value = json.loads(word)
    except ValueError:
        return word
    if isinstance(value, float) and not math.isfinite(value):
        return word  # NaN, Infinity: not numbers here (a typed check refuses the word)
    return value if isinstance(value, bool | int | float | str) else word


def _range(text: str, where: str) -> list[Value]:
    """`START:STOP:STEP`, STOP included when reached (`1:10:3` is 1, 4, 7, 10)."""
    parts = [_scalar(p.strip()) for p in text.split(":")]
    if len(parts) != 3 or not all(
        isinstance(p, int | float) and not isinstance(p, bool) and math.isfinite(p) for p in parts
    ):
        raise ParamError(f"{where}: range {shown(text)!r}: write START:STOP:STEP (numbers)")
    start, stop, step = (float(p) if isinstance(p, float) else int(p) for p in parts)
    if step <= 0 or stop < start:
        raise ParamError(f"{where}: range {shown(text)!r}: needs STEP > 0 and STOP >= START")
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count > MAX_LIST:
        raise ParamError(f"{where}: range {shown(text)!r}: more than {MAX_LIST:,} values")
    if all(isinstance(p, int) for p in (start, step)):
        return [start + i * step for i in range(count)]
    # each value from its index (no accumulated error), rounded to what the steps can say
    return [round(start + i * step, 12) for i in range(count)]


def parse_option(text: str) -> tuple[str, list[Value]]:
    """`--param NAME=V1,V2,...` or `--param NAME=START:STOP:STEP`."""
    name, sep, values = text.partition("=")
    name = name.strip()
    where = f"--param {shown(name or text)}"
    if not sep or not name or not values.strip():
        raise ParamError(f"--param {shown(text)!r}: write NAME=V1,V2,... or NAME=START:STOP:STEP")
    if ":" in values and "," not in values:
        return name, _range(values, where)
    words = [w.strip() for w in values.split(",")]
    if "" in words:
        raise ParamError(f"{where}: an empty value in {shown(values)!r}")
    if len(words) > MAX_LIST:
        raise ParamError(f"{where}: more than {MAX_LIST:,} values")
    return name, [_scalar(w) for w in words]


def load_file(path: Path) -> list[Point]:
    """The points of a sweep file: its factorial's combinations times its design's points."""
    where = shown(path)
    try:
        raw = read_limited(path, SCENARIO_BYTES)
    except InputRefused as err:
        raise ParamError(f"{where}: {err}") from None
    if path.suffix.lower() == ".toml":
        import tomllib

        try:
            payload: Any = tomllib.loads(raw.decode("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
            raise ParamError(f"{where}: not TOML: {err}") from None
    else:
        try:
            payload = jsonfile.load(path, SCENARIO_BYTES)
        except jsonfile.JsonError as err:
            raise ParamError(str(err)) from None
    try:
        return _points(payload, where)
    except jsonfile.JsonError as err:
        raise ParamError(f"{where}: {err}") from None


def _points(payload: Any, where: str) -> list[Point]:
    top = jsonfile.expect_object(payload, "$")
    jsonfile.check_keys(top, {"factorial", "design"}, "$")
    if not top:
        raise ParamError(f"{where}: $: needs `factorial` or `design`")
    axes = []
    for name, values in jsonfile.expect_object(top.get("factorial", {}), "$.factorial").items():
        items = jsonfile.expect_list(values, jsonfile.key_path("$.factorial", name), empty=False)
        axes.append((name, [_file_value(v, f"$.factorial.{name}") for v in items]))
    design = jsonfile.expect_list(top.get("design", [{}]), "$.design", empty=False)
    rows = []
    for i, row in enumerate(design):
        entry = jsonfile.expect_object(row, f"$.design[{i}]")
        rows.append(tuple((k, _file_value(v, f"$.design[{i}].{k}")) for k, v in entry.items()))
    return product(axes, rows)


def _file_value(value: Any, where: str) -> Value:
    if isinstance(value, bool | int | float | str):
        return value
    raise jsonfile.JsonError(
        f"{where}: expected a number, boolean or string, {jsonfile.got(value)}"
    )


def product(
    axes: Sequence[tuple[str, Sequence[Value]]], rows: Sequence[Point] = ((),)
) -> list[Point]:
    """Every combination of the axes' values (the first axis varies slowest), each combined
    with every row of a design; a name given twice is an error."""
    names = [name for name, _ in axes]
    for name in names:
        if names.count(name) > 1:
            raise ParamError(f"parameter {shown(name)} is swept twice")
    points: list[Point] = []
    for combo in itertools.product(*(values for _, values in axes)):
        for row in rows:
            twice = set(names) & {name for name, _ in row}
            if twice:
                raise ParamError(f"parameter {shown(min(twice))} is both swept and in the design")
            points.append((*zip(names, combo, strict=True), *row))
    if len(points) > MAX_RUNS:
        raise ParamError(f"{len(points):,} sweep points: more than the limit of {MAX_RUNS:,}")
    return points


# --- applying a point ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Variant:
    """One point of the sweep: its parameters, its scenario and the data defaults it sets
    (member type -> datum -> value)."""

    params: Point
    scenario: Scenario
    data: dict[str, dict[str, Value]] = field(default_factory=dict)
    hardware: dict[str, dict[str, Value]] = field(default_factory=dict)  # type -> part.param

    def columns(self) -> tuple[tuple[str, Value], ...]:
        """The parameters reported as their own columns (counts and targets have theirs)."""
        return tuple((k, v) for k, v in self.params if not _is_count(k) and k != "targets")


def _is_count(name: str) -> bool:
    return name.endswith(".count") and name.count(".") == 1


def variants(base: Scenario, points: Sequence[Point], names: Names, where: str) -> list[Variant]:
    """Each point applied to the scenario, checked: `where` says where the points came from."""
    return [apply(base, point, names, where) for point in points]


def apply(base: Scenario, point: Point, names: Names, where: str) -> Variant:
    """The scenario and data defaults of one point; ParamError for a bad name or value."""
    doc = base.to_json()
    data: dict[str, dict[str, Value]] = {}
    hardware: dict[str, dict[str, Value]] = {}
    given = list(base.given)
    for name, value in point:
        _check_name(name, names, where)
        kind, _, rest = name.partition(".")
        if rest in names.cameras.get(kind, {}):
            radius = _typed(value, Primitive.REAL, name, where)
            if not isinstance(radius, float) or radius < 0:
                raise ParamError(f"{where}: {shown(name)}: expected a radius >= 0, got {value}")
            hardware.setdefault(kind, {})[rest] = radius
        elif _is_count(name):
            kind = name.split(".")[0]
            doc["members"] = {**doc["members"], kind: [value]}
            given.append(kind)
        elif ".data." in name:
            kind, _, datum = name.partition(".data.")
            if datum in names.unread.get(kind, ()):
                raise ParamError(
                    f"{where}: {shown(name)}: no guard, effect or behaviour input of the "
                    f"{kind} machine reads it, so its default cannot change a run"
                )
            data.setdefault(kind, {})[datum] = _typed(value, names.data[kind][datum], name, where)
        elif name.startswith("placement."):
            _, kind, key = name.split(".", 2)
            section = dict(doc["placement"].get(kind) or doc["placement"].get("*") or {})
            doc["placement"] = {**doc["placement"], kind: {**section, key: value}}
        else:
            _set(doc, _SCENARIO[name], value)
            if name == "targets":
                doc["target_positions"] = None
    for kind, radii in hardware.items():
        _check_sees(base, names, [f"{kind}.{r}" for r in radii], where)
        view = _view_of(base, {**names.cameras[kind], **radii}, where, kind)
        doc["world"] = {**doc["world"], "views": {**doc["world"].get("views", {}), kind: view}}
    try:
        scenario = parse(doc, base.name)
    except ScenarioError as err:
        shown_point = ", ".join(f"{k}={json.dumps(v)}" for k, v in point)
        raise ParamError(f"{where}: {shown_point}: {err}") from None
    scenario = replace(scenario, given=tuple(dict.fromkeys(given)))
    return Variant(point, scenario, data, hardware)


def _check_sees(base: Scenario, names: Names, swept: list[str], where: str) -> None:
    """A type's view matters only if its machine covers or monitors: else ParamError."""
    from swarmgen.sim.library import Library

    kind = swept[0].split(".")[0]
    library = Library(base.library)
    seeing = {library.get(b).name for b in names.behaviours.get(kind, ())}
    if not seeing & {"Coverage", "TargetMonitoring"}:
        raise ParamError(
            f"{where}: {shown(', '.join(swept))}: no behaviour of the {kind} machine covers or monitors "
            "(Coverage, TargetMonitoring, or the scenario's library aliases of them), so its "
            "view cannot change a run"
        )


def _view_of(base: Scenario, radii: Mapping[str, Any], where: str, kind: str) -> int:
    """A type's view in patches from its cameras' radii in metres (module docstring)."""
    from swarmgen.sim.detailed.params import detailed_params

    patch = detailed_params(base).patch_m
    radius = max((r for r in radii.values() if isinstance(r, float)), default=0.0)
    view = math.floor(radius / patch + 1e-9)
    if view > MAX_VIEW:
        shown_radii = ", ".join(f"{kind}.{k}={v}" for k, v in radii.items())
        raise ParamError(
            f"{where}: {shown_radii}: a view of {view} patches ({radius:g} m over patches of "
            f"{patch:g} m, detailed.patch_m); the largest is {MAX_VIEW}"
        )
    return view


def _set(doc: dict[str, Any], path: tuple[str, ...], value: Value) -> None:
    node = doc
    for key in path[:-1]:
        node[key] = dict(node.get(key) or {})
        node = node[key]
    node[path[-1]] = [value] if path == ("targets",) else value


def _check_name(name: str, names: Names, where: str) -> None:
    known = names.known()
    if name in known:
        return
    kind, _, rest = name.partition(".")
    if rest in names.hardware.get(kind, ()):
        raise ParamError(
            f"{where}: {shown(name)} is a hardware parameter the abstract simulator does not "
            f"read: it reads a camera's {CAMERA} (the type's view); members move one patch per "
            'tick whatever their speed (docs/simulate.md, "Sweeping any parameter")'
        )
    close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]}?" if close else ""
    raise ParamError(
        f"{where}: unknown parameter {shown(name)}{hint} (docs/simulate.md, "
        '"Sweeping any parameter")'
    )


def _typed(value: Value, kind: Primitive, name: str, where: str) -> Value:
    if kind is Primitive.BOOLEAN and isinstance(value, bool):
        return value
    if kind is Primitive.INTEGER and isinstance(value, int) and not isinstance(value, bool):
        return value
    real = isinstance(value, int | float) and not isinstance(value, bool)
    if kind is Primitive.REAL and real and math.isfinite(float(value)):
        return float(value)
    if kind is Primitive.STRING and isinstance(value, str):
        return value
    article = "an" if kind is Primitive.INTEGER else "a"
    raise ParamError(
        f"{where}: {shown(name)}: expected {article} {kind.value}, got {json.dumps(value)}"
    )


def data_overrides(variant_list: Sequence[Variant]) -> list[Mapping[str, Mapping[str, Value]]]:
    """The distinct data defaults of the variants, in first-seen order."""
    seen: list[Mapping[str, Mapping[str, Value]]] = []
    for variant in variant_list:
        if variant.data not in seen:
            seen.append(variant.data)
    return seen
