"""`swarmgen timeline`: each event's time since launch over many recorded runs (bags)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from swarmgen import console
from swarmgen.commands.common import PATH, guarded, require_trace


@click.command()
@click.argument("bags", nargs=-1, required=True, type=PATH)
@click.option(
    "--events", help="Comma-separated event names, shown in this order (default: all of them, "
    "in mission order).",
)  # fmt: skip
@click.option(
    "--plot", "plot_path", type=PATH,
    help="Write a horizontal box plot (.png or .svg).",
)  # fmt: skip
@click.option("--csv", "csv_path", type=PATH, help="Write the statistics as CSV.")
@click.option(
    "--alias", "aliases", multiple=True, metavar="OLD=NEW",
    help="Rename an event while reading (repeatable), e.g. --alias targetDone=targetRescued.",
)  # fmt: skip
@guarded
def timeline(
    bags: tuple[Path, ...],
    events: str | None,
    plot_path: Path | None,
    csv_path: Path | None,
    aliases: tuple[str, ...],
) -> None:
    """Each event's time since launch over many runs (one run per bag; a directory holds bags).

    Prints lower whisker, quartiles, median, upper whisker (1.5 IQR) and outliers in seconds,
    and the number of runs in which the event occurred; see docs/trace.md.
    """
    renames = _renames(aliases)
    if plot_path is not None and plot_path.suffix.lower() not in (".png", ".svg"):
        shown = console.shown(plot_path)
        raise click.BadParameter(f"{shown}: use a .png or .svg file", param_hint="--plot")
    require_trace("timeline")
    from swarmgen.trace import timeline as timelines
    from swarmgen.trace.bag import TraceError
    from swarmgen.trace.reader import read_events

    made: list[Path] = []  # the output files' directories, checked (made) before reading
    for path, option in ((csv_path, "--csv"), (plot_path, "--plot")):
        made += console.check_file(path, option) if path is not None else []
    try:
        runs = read_events(bags, renames)
    except TraceError:
        console.remove_made(made)
        raise
    chosen = [e.strip() for e in events.split(",") if e.strip()] if events else None
    result = timelines.build(runs, chosen)
    picture = timelines.render(result, plot_path.suffix.lower()[1:]) if plot_path else b""
    click.echo(timelines.table(result), nl=False)
    sys.stdout.flush()
    if csv_path is not None:
        console.write_file(csv_path, timelines.csv_text(result).encode(), "--csv")
    if plot_path is not None:
        console.write_file(plot_path, picture, "--plot")
    click.echo(f"swarmgen: {len(runs)} run(s), {len(result.events)} event(s)", err=True)


def _renames(aliases: tuple[str, ...]) -> dict[str, str]:
    """--alias OLD=NEW pairs as a mapping, or a usage error for one that is not OLD=NEW."""
    renames: dict[str, str] = {}
    for alias in aliases:
        old, sep, new = alias.partition("=")
        if not sep or not old.strip() or not new.strip():
            raise click.BadParameter(f"{alias!r} is not OLD=NEW", param_hint="--alias")
        renames[old.strip()] = new.strip()
    return renames
