"""Figures laid out like the paper's (matplotlib, PNG and SVG, log2 x axes), byte-for-byte
reproducible: SVG ids are salted with a constant and no dates are written.

- coverage: time to reach each coverage level against the number of members (one line per
  level, 95 percent confidence intervals as error bars), one panel per target count and point
  of the other swept parameters (`--param`);
- sar: search (top row) and rescue (bottom row) time of the first, 50, 75, 90 and 100 percent of
  the targets against the number of targets, one line per swarm size (and swept point).
"""

from __future__ import annotations

import io
import itertools
from typing import Any

from swarmgen.sim.stats import Row, Summary, level_name

MAX_PANELS = 24  # facets of the coverage figure; a sweep with more points gets no figure
_METADATA_SVG: dict[str, Any] = {"Date": None, "Creator": "swarmgen"}
_METADATA_PNG: dict[str, Any] = {"Software": "swarmgen"}


def _figure(width: float, height: float) -> Any:
    import matplotlib

    matplotlib.rcParams["svg.hashsalt"] = "swarmgen"
    matplotlib.rcParams["svg.fonttype"] = "none"
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _save(fig: Any) -> dict[str, bytes]:
    out: dict[str, bytes] = {}
    for fmt, metadata in (("png", _METADATA_PNG), ("svg", _METADATA_SVG)):
        buffer = io.BytesIO()
        fig.savefig(buffer, format=fmt, dpi=120, metadata=metadata)
        out[fmt] = buffer.getvalue()
    return out


def _log2_axis(ax: Any, ticks: list[int]) -> None:
    from matplotlib.ticker import FixedLocator, NullLocator

    ax.set_xscale("log", base=2)
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xticklabels([str(t) for t in ticks])


def _log_y(ax: Any) -> None:
    """Log y axis with plain numbers (mathtext tick labels make drawing 10x slower)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    ax.set_yscale("log")
    ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_locator(NullLocator())


def _line(ax: Any, rows: list[Row], x_of: Any, label: str) -> None:
    points = sorted((x_of(r), r.estimate) for r in rows if r.estimate.mean is not None)
    points = [(x, e) for x, e in points if x > 0]
    if not points:
        return
    xs = [x for x, _ in points]
    ys = [e.mean for _, e in points]
    errors = [e.half or 0.0 for _, e in points]
    ax.errorbar(xs, ys, yerr=errors, marker="o", markersize=3, capsize=2, linewidth=1, label=label)


def _facets(rows: list[Row]) -> list[tuple[int, tuple[tuple[str, Any], ...]]]:
    """The panels: one per target count and point of the swept parameters, in sweep order."""
    order = {p: i for i, p in enumerate(dict.fromkeys(r.params for r in rows))}
    keys = sorted({(r.targets, order[r.params]) for r in rows})
    points = list(order)
    return [(targets, points[i]) for targets, i in keys]


def _params_text(params: tuple[tuple[str, Any], ...]) -> str:
    return ", ".join(f"{k}={v}" for k, v in params)


def coverage_figure(summary: Summary, title: str) -> dict[str, bytes] | None:
    """The coverage figure as {"png": ..., "svg": ...}; None when nothing was swept or covered.
    One panel per target count and point of the other swept parameters (at most 4 a row when
    parameters are swept)."""
    rows = summary.coverage
    swept = summary.swept
    if not rows or swept is None or not any(r.estimate.mean for r in rows):
        return None
    panels = _facets(rows)
    if len(panels) > MAX_PANELS:
        return None  # a wall of tiny panels says nothing: the tables have every point
    # one row as before when only targets facet; parameter points wrap at 4 panels a row
    columns = min(4, len(panels)) if summary.params else len(panels)
    lines = -(-len(panels) // columns)
    fig = _figure(4.2 * columns, 3.6 * lines)
    axes = list(fig.subplots(lines, columns, squeeze=False).flat)
    sizes = sorted({dict(r.counts)[swept] for r in rows if dict(r.counts)[swept] > 0})
    for ax, (targets, params) in zip(axes, panels, strict=False):
        mine = [r for r in rows if r.targets == targets and r.params == params]
        for level in sorted({r.level for r in mine}):
            _line(
                ax,
                [r for r in mine if r.level == level],
                lambda r: dict(r.counts)[swept],
                level_name(level, "coverage"),
            )
        _log2_axis(ax, sizes)
        _log_y(ax)
        ax.set_xlabel(f"number of {swept}s")
        ax.set_ylabel("time to coverage (ticks)")
        ax.grid(True, linewidth=0.3)
        parts = [] if len(panels) == 1 else [f"{targets} targets"]
        parts += [_params_text(params)] if params else []
        ax.set_title(", ".join([title, *parts]), fontsize=10 if len(parts) < 2 else 8)
        if ax.get_legend_handles_labels()[0]:  # a point where nothing covered has no lines
            ax.legend(title="coverage", fontsize=7, title_fontsize=7)
    for ax in axes[len(panels) :]:
        ax.set_axis_off()
    return _save(fig)


def sar_figure(summary: Summary, title: str) -> dict[str, bytes] | None:
    """The search and rescue figure as {"png": ..., "svg": ...}; None without search results."""
    if not summary.search or summary.swept is None:
        return None
    swept = summary.swept
    levels = sorted({r.level for r in summary.search})
    fig = _figure(2.9 * len(levels), 5.4)
    axes = fig.subplots(2, len(levels), squeeze=False, sharey="row")
    targets = sorted({r.targets for r in summary.search})
    sizes = sorted({dict(r.counts)[swept] for r in summary.search})
    points = list(dict.fromkeys(r.params for r in summary.search))  # one line per size and point
    if len(points) * len(sizes) > MAX_PANELS:
        return None  # more lines than a legend can tell apart: the tables have them
    for row, (name, rows) in enumerate((("search", summary.search), ("rescue", summary.rescue))):
        for column, level in enumerate(levels):
            ax = axes[row][column]
            for size, params in itertools.product(sizes, points):
                _line(
                    ax,
                    [
                        r
                        for r in rows
                        if r.level == level and dict(r.counts)[swept] == size and r.params == params
                    ],
                    lambda r: r.targets,
                    " ".join([f"{size} {swept}", *([_params_text(params)] if params else [])]),
                )
            _log2_axis(ax, targets)
            _log_y(ax)
            ax.grid(True, linewidth=0.3)
            ax.set_title(f"{name}: {level_name(level, 'targets')} of targets", fontsize=9)
            if row == 1:
                ax.set_xlabel("number of targets")
            if column == 0:
                ax.set_ylabel(f"{name} time (ticks)")
    if axes[0][0].get_legend_handles_labels()[0]:  # no lines when every run failed
        axes[0][0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    return _save(fig)
