"""The paper's event timeline over many runs: for each event, its time since launch summarised as
a box plot (lower whisker, lower quartile, median, upper quartile, upper whisker, outliers) with
the number of runs in which it occurred. See docs/trace.md.

- Launch: the stamp of the run's first `launch` event, else the start of its bag (the earliest
  bag time). Times are in seconds and may be negative (an event before launch).
- An event that occurs several times in a run counts once, at its first occurrence.
- Quartiles and median: numpy's default percentile method (linear interpolation between closest
  ranks, `numpy.percentile(x, [25, 50, 75])`, method="linear"), as matplotlib's `boxplot` uses.
- Whiskers as matplotlib's `boxplot(whis=1.5)`: the most extreme times within 1.5 IQR of the
  box (Q1 - 1.5 IQR .. Q3 + 1.5 IQR), never inside the box; times beyond them are outliers.
- Event order (table, CSV, plot from top to bottom): as given by `events`, else mission order,
  i.e. by median time, then by name.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from swarmgen.records import dataclass
from swarmgen.trace.reader import Run

__all__ = [
    "PLOT_FORMATS",
    "EventStats",
    "Timeline",
    "build",
    "csv_text",
    "plot",
    "render",
    "summarize",
    "table",
]

PLOT_FORMATS = (".png", ".svg")
WHIS = 1.5
_SVG_SALT = "swarmgen-timeline"


@dataclass(frozen=True, slots=True)
class EventStats:
    """The box of one event; the statistics are None when it occurred in no run."""

    event: str
    runs: int  # runs in which it occurred
    times: tuple[float, ...]  # seconds since launch, one per run where it occurred, sorted
    lower_whisker: float | None = None
    lower_quartile: float | None = None
    median: float | None = None
    upper_quartile: float | None = None
    upper_whisker: float | None = None
    outliers: tuple[float, ...] = ()


@dataclass(frozen=True, slots=True)
class Timeline:
    """The boxes of every event shown, in order, over `total_runs` runs."""

    total_runs: int
    events: tuple[EventStats, ...]

    def get(self, event: str) -> EventStats | None:
        """The box of `event`, None when it is not shown."""
        return next((s for s in self.events if s.event == event), None)


def summarize(event: str, times: Sequence[float]) -> EventStats:
    """The box-plot statistics of one event's times (see the module docstring)."""
    import numpy as np

    ordered = tuple(sorted(float(t) for t in times))
    if not ordered:
        return EventStats(event, 0, ())
    x = np.asarray(ordered, dtype=np.float64)
    q1, med, q3 = (float(v) for v in np.percentile(x, [25, 50, 75]))
    iqr = q3 - q1
    low, high = q1 - WHIS * iqr, q3 + WHIS * iqr
    inside_high = [t for t in ordered if t <= high]
    upper = q3 if not inside_high or max(inside_high) < q3 else max(inside_high)
    inside_low = [t for t in ordered if t >= low]
    lower = q1 if not inside_low or min(inside_low) > q1 else min(inside_low)
    outliers = tuple(t for t in ordered if t < lower or t > upper)
    return EventStats(event, len(ordered), ordered, lower, q1, med, q3, upper, outliers)


def build(runs: Sequence[Run], events: Iterable[str] | None = None) -> Timeline:
    """The timeline of `runs`: all events they contain, or only `events`, in that order."""
    times: dict[str, list[float]] = {}
    for run in runs:
        launch = run.launch_ns
        if launch is None:
            continue
        seen: set[str] = set()
        for event in run.events:
            if event.name not in seen:
                seen.add(event.name)
                times.setdefault(event.name, []).append((event.stamp_ns - launch) / 1e9)
    if events is not None:
        chosen = list(dict.fromkeys(events))
        stats = [summarize(name, times.get(name, [])) for name in chosen]
    else:
        stats = sorted(
            (summarize(name, values) for name, values in times.items()),
            key=lambda s: (s.median if s.median is not None else math.inf, s.event),
        )
    return Timeline(len(runs), tuple(stats))


# --- output

_COLUMNS = (
    "event", "runs", "lower_whisker", "lower_quartile", "median", "upper_quartile",
    "upper_whisker", "outliers",
)  # fmt: skip
_HEADINGS = (
    "event", "runs", "lower whisker", "lower quartile", "median", "upper quartile",
    "upper whisker", "outliers",
)  # fmt: skip


def _values(stats: EventStats) -> list[float | None]:
    return [
        stats.lower_whisker,
        stats.lower_quartile,
        stats.median,
        stats.upper_quartile,
        stats.upper_whisker,
    ]


def _seconds(value: float | None) -> str:
    return "" if value is None else f"{value:.3f}"


def table(timeline: Timeline) -> str:
    """A fixed-width table (seconds since launch, 3 decimals)."""
    rows = [list(_HEADINGS)]
    for stats in timeline.events:
        rows.append(
            [stats.event, f"{stats.runs}/{timeline.total_runs}"]
            + [_seconds(v) or "-" for v in _values(stats)]
            + [" ".join(_seconds(t) for t in stats.outliers) or "-"]
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(_HEADINGS))]
    lines = []
    for row in rows:
        cells = [
            cell.ljust(widths[i]) if i == 0 or i == len(row) - 1 else cell.rjust(widths[i])
            for i, cell in enumerate(row)
        ]
        lines.append("  ".join(cells).rstrip())
    return "\n".join(lines) + "\n"


def csv_text(timeline: Timeline) -> str:
    """One row per event; times in seconds (Python's shortest exact float text), outliers
    separated by spaces, empty cells for an event that never occurred; `total_runs` repeats the
    number of runs."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([*_COLUMNS[:2], "total_runs", *_COLUMNS[2:]])
    for stats in timeline.events:
        writer.writerow(
            [stats.event, stats.runs, timeline.total_runs]
            + ["" if v is None else repr(v) for v in _values(stats)]
            + [" ".join(repr(t) for t in stats.outliers)]
        )
    return buffer.getvalue()


def plot(timeline: Timeline, path: Path, *, title: str | None = None) -> None:
    """`render` into the file `path`: PNG or SVG by its suffix (its directory is made)."""
    suffix = path.suffix.lower()
    if suffix not in PLOT_FORMATS:
        raise ValueError(f"{path}: the plot is .png or .svg")
    data = render(timeline, suffix[1:], title=title)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)


def _boxes(timeline: Timeline, positions: list[int]) -> tuple[list[dict[str, Any]], list[int]]:
    """matplotlib's `bxp` statistics of the events that occurred, and their positions."""
    boxes: list[dict[str, Any]] = []
    box_positions: list[int] = []
    for position, stats in zip(positions, timeline.events, strict=True):
        if stats.median is None:
            continue
        boxes.append(
            {
                "med": stats.median,
                "q1": stats.lower_quartile,
                "q3": stats.upper_quartile,
                "whislo": stats.lower_whisker,
                "whishi": stats.upper_whisker,
                "fliers": list(stats.outliers),
            }
        )
        box_positions.append(position)
    return boxes, box_positions


def render(timeline: Timeline, fmt: str, *, title: str | None = None) -> bytes:
    """A horizontal box plot like the paper's demonstration figure: one box per event, events
    from top to bottom in timeline order, time since launch on x; `fmt` "png" or "svg" (the
    SVG is deterministic: fixed hash salt, no date). Made in memory, so that a command can
    check everything before it writes a file."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    count = len(timeline.events)
    figure = Figure(figsize=(8.0, 1.2 + 0.45 * max(count, 1)), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    positions = [count - i for i in range(count)]  # the first event at the top
    boxes, box_positions = _boxes(timeline, positions)
    if boxes:
        axes.bxp(
            boxes,
            positions=box_positions,
            orientation="horizontal",
            widths=0.6,
            manage_ticks=False,
            patch_artist=True,
            boxprops={"facecolor": "#cfe2f3", "edgecolor": "#1f4e79"},
            medianprops={"color": "#c00000", "linewidth": 1.5},
            flierprops={"marker": "o", "markersize": 4, "markerfacecolor": "none"},
        )
    axes.set_yticks(
        positions, [f"{s.event} ({s.runs}/{timeline.total_runs})" for s in timeline.events]
    )
    axes.set_ylim(0.4, count + 0.6)
    axes.set_xlabel("time since launch [s]")
    axes.grid(axis="x", linestyle=":", linewidth=0.6)
    axes.set_title(title or f"Events over {timeline.total_runs} run(s)")
    buffer = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": _SVG_SALT, "svg.fonttype": "path"}):
        if fmt == "svg":
            figure.savefig(buffer, format="svg", metadata={"Date": None})
        else:
            figure.savefig(buffer, format="png", dpi=120)
    return buffer.getvalue()
