"""`swarmgen simulate`: compile the model, run the scenario's sweep, and write the result files.

The simulator's parts: `machines` (each member type's compiled module), `member` (a runtime
member on the simulator's host), `batch` (repetitions of one configuration and their time loop),
`sweep` (every configuration, over processes), `world`, `library`, `stats` and `plots`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from swarmgen import outtree
from swarmgen.sim.machines import compile_variants
from swarmgen.sim.params import Variant, data_overrides
from swarmgen.sim.scenario import Scenario
from swarmgen.sim.sweep import Simulation, simulate

if TYPE_CHECKING:
    from swarmgen.pipeline import Validation
    from swarmgen.sim.executors import Executor


def outputs(sim: Simulation, figures: bool = True) -> dict[str, bytes]:
    """The result files: tables (CSV), everything as JSON, and (with `figures`) the figures
    (PNG, SVG)."""
    import json
    from dataclasses import asdict

    from swarmgen import __version__
    from swarmgen.sim import plots, stats

    summary = stats.summarise(sim)
    types, params = summary.types, summary.params
    files: dict[str, bytes] = {}
    files["runs.csv"] = stats.runs_table(sim).encode()
    files["coverage.csv"] = stats.table(summary.coverage, types, "coverage", params).encode()
    if summary.search:
        files["search.csv"] = stats.table(summary.search, types, "targets", params).encode()
        files["rescue.csv"] = stats.table(summary.rescue, types, "targets", params).encode()
    payload = {
        "generator": "swarmgen simulate",
        "version": __version__,
        "model": sim.machines.model,
        "source": sim.machines.source,
        "scenario": sim.scenario.to_json(),
        "configurations": [
            {
                "members": dict(c.counts),
                "targets": c.targets,
                **({"params": dict(c.params)} if c.params else {}),
            }
            for c in sim.configs
        ],
        "summary": stats.to_json(summary),
        "runs": [asdict(r) for r in sim.runs],
    }
    files["results.json"] = (json.dumps(payload, indent=1, sort_keys=True) + "\n").encode()
    if not figures:
        return files
    title = f"{sim.machines.model}: {sim.scenario.name}"
    for name, figure in (
        ("coverage", plots.coverage_figure(summary, title)),
        ("sar", plots.sar_figure(summary, title)),
    ):
        for fmt, data in (figure or {}).items():
            files[f"{name}.{fmt}"] = data
    return files


def write_outputs(
    files: Mapping[str, bytes], out_dir: Path, source: str, command: str = "simulate"
) -> None:
    """Make `out_dir` hold exactly `files` and their manifest (written by `command`: simulate
    or optimize), under the rules of `swarmgen.outtree` (only swarmgen's own unedited files
    are replaced; crash-safe)."""
    tree: dict[PurePosixPath, str | bytes] = {PurePosixPath(n): d for n, d in files.items()}
    tree[PurePosixPath(outtree.MANIFEST)] = outtree.manifest_text(command, source, tree)
    outtree.write(tree, out_dir)


def simulate_model(
    model: Path,
    scenario: Scenario,
    out_dir: Path | None,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    record: Path | None = None,
    storage: str = "mcap",
    *,
    variants: Sequence[Variant] | None = None,
    executor: Executor | None = None,
    validation: Validation | None = None,
) -> tuple[Simulation, dict[str, bytes]]:
    """`swarmgen simulate`: compile MODEL, run the scenario's sweep (each of `variants`, the
    points of `--param`/`--sweep`, if given) through `executor` (default: `workers` local
    processes), write the results (and with `record`, one bag per run into that new
    directory). Without `out_dir` the files returned leave out the figures. `validation`:
    MODEL's, when the caller has already validated it."""
    if out_dir is not None:
        outtree.preflight(out_dir, "simulate")  # a bad -o is refused before the runs, not after
    datas = data_overrides(variants) if variants else [{}]
    compiled = compile_variants(model, datas, validation)
    points = [
        (compiled[datas.index(v.data)], v.scenario, v.columns()) for v in variants or ()
    ] or None
    sim = simulate(
        compiled[0], scenario, workers=workers, progress=progress, record=record,
        storage=storage, points=points, executor=executor,
    )  # fmt: skip
    # without -o only the tables are printed: drawing the figures (matplotlib, about a second
    # with its import) would be wasted
    files = outputs(sim, figures=out_dir is not None)
    if out_dir is not None:
        write_outputs(files, out_dir, model.name)
    return sim, files
