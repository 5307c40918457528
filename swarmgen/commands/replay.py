"""`swarmgen replay`: one member against a scripted scenario, its trace as JSON lines."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from swarmgen import console
from swarmgen.commands.common import (
    MODEL,
    PATH,
    OutputChoice,
    check_record,
    guarded,
    record_options,
    runnable_outputs,
)


@click.command()
@MODEL
@click.option("--member", required=True, help="Member type to run.")
@click.option("--script", "scenario", type=PATH, required=True, help="Scenario (JSON).")
@click.option(
    "--backend", type=OutputChoice(runnable_outputs), default="asyncio", show_default=True,
    help="Where to run: the generated asyncio, smach or rclpy code, or the SCXML in Qt SCXML.",
)  # fmt: skip
@record_options("Also write the trace as a ROS 2 bag into this new directory (docs/trace.md).")
@guarded
def replay(
    model: Path, member: str, scenario: Path, backend: str, record: Path | None, storage: str
) -> None:
    """Run one member of MODEL against a scenario; print its trace as JSON lines."""
    from swarmgen import replay as replaying

    check_record(record)
    _, steps = replaying.load_scenario(scenario)
    trace = replaying.replay(model, member, steps, backend)
    for line in trace:
        click.echo(json.dumps(line, sort_keys=True))
    sys.stdout.flush()  # a full stdout is reported before the bag is written
    if record is not None:
        _record_replay(record, member, steps, trace, storage)


def _record_replay(
    path: Path, member: str, steps: list[dict[str, object]], trace: list[dict[str, object]],
    storage: str,
) -> None:  # fmt: skip
    """Write the replayed trace as a bag into `path` and say so on stderr."""
    from swarmgen.trace.recorder import record_replay

    record_replay(path, member, steps, trace, storage=storage)
    shown = console.shown(path)
    click.echo(f"swarmgen: recorded {len(steps)} step(s) into {shown} ({storage})", err=True)
