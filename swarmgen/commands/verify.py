"""`swarmgen verify MODEL`: explore every configuration of the composed swarm, check the
built-in properties, print the violations with their shortest traces (docs/verify.md)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from swarmgen import console
from swarmgen.commands.common import FORMAT, MODEL, PATH, guarded, render_diagnostics

if TYPE_CHECKING:
    from swarmgen.verify.run import Result


@click.command()
@MODEL
@click.option("--members", metavar="TYPE=N,...", help="Member counts instead of the swarm's.")
@click.option(
    "--abort", "aborts", multiple=True, metavar="EVENT",
    help="A station event after which every member must reach a final state (repeatable; "
    "default: missionAbort when the model has it).",
)  # fmt: skip
@click.option("--max-states", type=click.IntRange(1), default=200_000, show_default=True)
@click.option("--max-depth", type=click.IntRange(1), default=10_000, show_default=True)
@click.option("--no-symmetry", is_flag=True, help="Do not merge states that differ only in "
              "which members of one type are where.")  # fmt: skip
@click.option("--no-por", is_flag=True, help="No partial-order reduction (every interleaving of "
              "independent members).")  # fmt: skip
@click.option(
    "--property", "properties", multiple=True, metavar="TEXT",
    help="A property to check besides the model's (repeatable): `always P`, `never P`, "
    "`eventually P`, `P leads to Q`, `P until Q` (docs/verify.md).",
)  # fmt: skip
@click.option(
    "--station-sends", "station_bound", type=click.IntRange(1, 100), default=1,
    show_default=True, help="Times the station may send each of its events.",
)  # fmt: skip
@click.option(
    "--emits", "emit_bound", type=click.IntRange(0, 100), default=1, show_default=True,
    help="Events of its `emits` tag a behaviour may send per activation.",
)  # fmt: skip
@click.option(
    "--counterexample", "directory", type=PATH,
    help="Write each violation's replay scenarios into DIR/<code>/<member>.json and its "
    "trace as a ROS 2 bag, DIR/<code>/bag.",
)  # fmt: skip
@click.option("--quiet", is_flag=True, help="No progress line on stderr.")
@FORMAT
@guarded
def verify(
    model: Path,
    members: str | None,
    aborts: tuple[str, ...],
    max_states: int,
    max_depth: int,
    no_symmetry: bool,
    no_por: bool,
    properties: tuple[str, ...],
    station_bound: int,
    emit_bound: int,
    directory: Path | None,
    quiet: bool,
    fmt: str,
) -> None:
    """Verify MODEL's swarm exhaustively (exit 0 verified, 1 violated, 4 bounded)."""
    from swarmgen.verify import run
    from swarmgen.verify.explore import Budget
    from swarmgen.verify.load import parse_members

    counts = parse_members(members)
    budget = Budget(max_states, max_depth, not no_symmetry, not no_por)
    progress = None if quiet else (lambda line: click.echo(line, err=True))
    result = run.verify(
        model, budget, counts, aborts, emit_bound, progress,
        station_bound=station_bound, properties=properties,
    )  # fmt: skip
    if fmt == "json":
        click.echo(_json(result), nl=False)
    else:
        text = render_diagnostics(result.diagnostics, fmt)
        if text:
            click.echo(text, nl=False)
        if fmt == "text":
            _timelines(result)
    if directory is not None:
        _write(result, directory)
    click.echo(f"swarmgen: {console.shown(model)}: {run.summary(result)}", err=True)
    sys.exit(result.exit_code)


def _timelines(result: Result) -> None:
    from swarmgen.verify.counterexample import timeline

    system = result.loaded.system
    for finding in result.findings:
        if finding.trace is None or system is None:
            continue
        click.echo(
            f"\ncounterexample of {finding.diagnostic.code.id} ({finding.trace.length} steps):"
        )
        for line in timeline(system, finding.trace):
            click.echo(line)


def _json(result: Result) -> str:
    from swarmgen import diagnostics as dg
    from swarmgen.verify import run
    from swarmgen.verify.counterexample import timeline

    payload = json.loads(dg.render_json(result.diagnostics))
    search, system = result.search, result.loaded.system
    payload["verify"] = {
        "verdict": run.summary(result).split(":", 1)[0],
        "exit_code": result.exit_code,
        "states": search.states if search else 0,
        "depth": search.max_depth if search else 0,
        "members": result.loaded.counts,
        "counterexamples": [
            {
                "code": f.diagnostic.code.id,
                "length": f.trace.length,
                "timeline": timeline(system, f.trace),
                "scenarios": f.trace.scenarios,
            }
            for f in result.findings
            if f.trace is not None and system is not None
        ],
    }
    return json.dumps(payload, indent=2, ensure_ascii=False, default=str) + "\n"


def _write(result: Result, directory: Path) -> None:
    """Per counterexample, `DIR/<code>/`: each member's replay scenario and the trace as a
    bag (`bag/`, a rosbag2 directory); a second counterexample with the same code goes to `<code>-2`, etc."""
    from swarmgen.verify.bag import BAG_NAME, write_bag
    from swarmgen.verify.counterexample import write_scenarios

    system = result.loaded.system
    used: dict[str, int] = {}
    for finding in result.findings:
        if finding.trace is None or system is None:
            continue
        code = finding.diagnostic.code.id
        used[code] = used.get(code, 0) + 1
        where = directory / (code if used[code] == 1 else f"{code}-{used[code]}")
        written = write_scenarios(system, finding.trace, where, finding.diagnostic.message)
        write_bag(finding.trace, where / BAG_NAME)
        shown = console.shown(where)
        click.echo(
            f"swarmgen: wrote {len(written)} replay scenario(s) and {BAG_NAME} into {shown}",
            err=True,
        )
