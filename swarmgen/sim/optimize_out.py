"""The files of `swarmgen optimize`: best parameters, trials CSV, figures, and the best point
written back as a model variant.

The variant: member counts, data defaults and camera radii are model facts, so they go into a
copy of the XMI (`best.xmi`: the single Swarm part of the type gets the count as its multiplicity,
the datum its `defaultValue`, the camera's hardware class its parameter's `defaultValue` when no
other part uses that class); scenario parameters (world, targets, timing, ...) are not in the model, so the
whole scenario with the best point applied goes beside it (`best-scenario.json`), ready for
`swarmgen simulate best.xmi --scenario best-scenario.json`. A model that is not XMI (SCXML,
Modelio), or a count spread over several parts, gets the scenario file only, and best.json says
why.
"""

from __future__ import annotations

import csv
import io
import json
import math
from typing import TYPE_CHECKING, Any

from lxml import etree

from swarmgen.sim import params

if TYPE_CHECKING:
    from pathlib import Path

    import optuna

    from swarmgen.ir.nodes import Model

XMI_ID = "{http://schema.omg.org/spec/XMI/2.1}id"
XMI_TYPE = "{http://schema.omg.org/spec/XMI/2.1}type"
_LITERAL = {bool: "uml:LiteralBoolean", int: "uml:LiteralInteger", float: "uml:LiteralReal"}


def best_trials(study: optuna.Study) -> list[optuna.trial.FrozenTrial]:
    """The best trial (one objective) or the Pareto front (two), or none when nothing completed."""
    from optuna.trial import TrialState

    if not study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
        return []
    return list(study.best_trials) if len(study.directions) > 1 else [study.best_trial]


def trials_csv(study: optuna.Study, names: list[str], objectives: list[str]) -> str:
    """One line per trial: number, state, every parameter, every objective value, attributes."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["number", "state", *names, *objectives, "runs", "failed_runs", "note"])
    for t in study.get_trials(deepcopy=False):
        values = list(t.values) if t.values is not None else [None] * len(objectives)
        note = (
            "interrupted, retried" if t.user_attrs.get("swarmgen.interrupted")
            else "cached" if t.user_attrs.get("swarmgen.cached") else ""
        )  # fmt: skip
        writer.writerow(
            [
                t.number,
                t.state.name,
                *(_cell(t.params.get(n, "")) for n in names),
                *("" if v is None else repr(float(v)) for v in values),
                t.user_attrs.get("swarmgen.runs", ""),
                t.user_attrs.get("swarmgen.failed_runs", ""),
                note,
            ]
        )
    return out.getvalue()


def _cell(value: Any) -> Any:
    return ("true" if value else "false") if isinstance(value, bool) else value


def figures(study: optuna.Study, objectives: list[str]) -> dict[str, bytes]:
    """History (each objective), parameter importance (>= 2 parameters, >= 2 completed trials)
    and, for two objectives, the Pareto front; PNG and SVG, with matplotlib."""
    import warnings

    import matplotlib

    matplotlib.use("Agg")
    from optuna.trial import TrialState
    from optuna.visualization import matplotlib as ovm

    done = study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
    files: dict[str, bytes] = {}
    if not done:
        return files
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # optuna's matplotlib plots are "experimental"
        for i, name in enumerate(objectives):
            target = None if len(objectives) == 1 else (lambda t, i=i: t.values[i])
            axes = ovm.plot_optimization_history(study, target=target, target_name=name)
            files.update(_saved(axes, f"history-{i + 1}" if len(objectives) > 1 else "history"))
        varied = {
            n for t in done for n in t.params if len({str(u.params.get(n)) for u in done}) > 1
        }
        if len(varied) >= 2 and len(done) >= 2:
            first = None if len(objectives) == 1 else (lambda t: t.values[0])
            axes = ovm.plot_param_importances(study, target=first, target_name=objectives[0])
            files.update(_saved(axes, "importance"))
        if len(objectives) == 2:
            axes = ovm.plot_pareto_front(study, target_names=objectives)
            files.update(_saved(axes, "pareto"))
    return files


def _saved(axes: Any, stem: str) -> dict[str, bytes]:
    """The figure of `axes` as PNG and SVG, deterministic (no dates), then closed."""
    import matplotlib.pyplot as plt

    figure = axes.figure
    figure.set_size_inches(7, 4.5)
    figure.tight_layout()
    files = {}
    for fmt, meta in (("png", {"Software": None}), ("svg", {"Date": None})):
        buffer = io.BytesIO()
        figure.savefig(buffer, format=fmt, dpi=100, metadata=meta)
        files[f"{stem}.{fmt}"] = buffer.getvalue()
    plt.close(figure)
    return files


def best_json(study: optuna.Study, objectives: list[str], notes: list[str]) -> bytes:
    """The best trial(s): number, parameters, objective values; and the variant's notes."""
    best = [
        {
            "number": t.number,
            "params": t.params,
            "values": dict(zip(objectives, t.values, strict=True)),
        }
        for t in best_trials(study)
    ]
    payload = {
        "generator": "swarmgen optimize",
        "study": study.study_name,
        "objectives": objectives,
        "directions": [d.name.lower() for d in study.directions],
        "best": best,
        "notes": notes,
    }
    return (json.dumps(payload, indent=1, sort_keys=True, default=_finite) + "\n").encode()


def _finite(value: Any) -> Any:
    return None if isinstance(value, float) and not math.isfinite(value) else str(value)


def variant_files(
    model_path: Path, model: Model, variant: params.Variant
) -> tuple[dict[str, bytes], list[str]]:
    """`best.xmi` (counts and data defaults written in) and `best-scenario.json`; notes for
    what could not be written into the model."""
    files = {
        "best-scenario.json": (json.dumps(variant.scenario.to_json(), indent=1) + "\n").encode()
    }
    notes: list[str] = []
    model_values = [(k, v) for k, v in variant.params if k.endswith(".count") or ".data." in k] + [
        (f"{t}.{k}", v) for t, values in variant.hardware.items() for k, v in values.items()
    ]
    if model_path.suffix.lower() != ".xmi":
        notes.append("the model is not XMI: its best point is in best-scenario.json only")
        return files, notes
    from swarmgen.frontend.safexml import parse_safely

    tree = parse_safely(model_path.read_bytes(), str(model_path))
    by_id = {e.get(XMI_ID): e for e in tree.iter() if isinstance(e.tag, str) and e.get(XMI_ID)}
    for name, value in model_values:
        problem = _write_value(by_id, model, name, value)
        if problem:
            notes.append(f"{name}: {problem}")
    files["best.xmi"] = etree.tostring(tree, xml_declaration=True, encoding="UTF-8") + b"\n"
    return files, notes


def _write_value(
    by_id: dict[str | None, etree._Element], model: Model, name: str, value: params.Value
) -> str | None:
    """Write one count, datum or hardware default into the XMI tree; the reason when it
    cannot."""
    kind, _, rest = name.partition(".")
    if rest.count(".") == 1 and not rest.startswith("data."):
        return _write_hardware(by_id, model, kind, rest, value)
    if rest == "count":
        parts = [p for s in model.swarms for p in s.members if p.type_name == kind]
        if len(parts) != 1 or parts[0].span.xmi_id not in by_id:
            return f"{len(parts)} Swarm parts of {kind}: the count is in best-scenario.json only"
        attribute = by_id[parts[0].span.xmi_id]
        for feature in ("lowerValue", "upperValue"):
            _replace(attribute, feature, "uml:LiteralInteger", str(value), parts[0].span.xmi_id)
        return None
    datum = rest.removeprefix("data.")
    member = next((m for m in model.member_types if m.name == kind), None)
    prop = next((d for d in (member.data if member else ()) if d.name == datum), None)
    if prop is None or prop.span.xmi_id not in by_id:
        return "not an attribute of the member class: in best-scenario.json only"
    literal = _LITERAL.get(type(value), "uml:LiteralString")
    text = ("true" if value else "false") if isinstance(value, bool) else str(value)
    _replace(by_id[prop.span.xmi_id], "defaultValue", literal, text, prop.span.xmi_id)
    return None


def _write_hardware(
    by_id: dict[str | None, etree._Element], model: Model, kind: str, rest: str, value: Any
) -> str | None:
    """A hardware parameter's default, in its component class (`part.param` of type `kind`)."""
    part_name, _, param = rest.partition(".")
    member = next((m for m in model.member_types if m.name == kind), None)
    part = next((p for p in (member.hardware if member else ()) if p.name == part_name), None)
    component = next((h for h in model.hardware if part and h.id == part.type_id), None)
    prop = next((p for p in (component.parameters if component else ()) if p.name == param), None)
    if part is None or prop is None or prop.span.xmi_id not in by_id:
        return "not a parameter of the part's hardware class: in best-scenario.json only"
    users = [p for m in model.member_types for p in m.hardware if p.type_id == part.type_id]
    if len(users) > 1:
        return (
            f"its class {component.name if component else ''} is used by {len(users)} parts: "
            "the view is in best-scenario.json only"
        )
    _replace(by_id[prop.span.xmi_id], "defaultValue", _LITERAL[float], str(value), prop.span.xmi_id)
    return None


def _replace(
    owner: etree._Element, feature: str, literal: str, text: str, owner_id: str | None
) -> None:
    """Replace (or add) the `feature` value specification of `owner` with a literal."""
    for old in [c for c in owner if isinstance(c.tag, str) and etree.QName(c).localname == feature]:
        owner.remove(old)
    node = etree.SubElement(owner, feature)
    node.set(XMI_TYPE, literal)
    node.set(XMI_ID, f"{owner_id}-{feature}-best")
    node.set("value", text)
