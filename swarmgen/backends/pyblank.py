"""black's empty-line rules for the shapes of swarmgen's templates, over the statements
`pyformat` printed (kept apart from the splitting: they look at whole statements only)."""

from __future__ import annotations

from swarmgen.records import dataclass


@dataclass
class Entry:
    """A printed statement, comment or verbatim line, with what black's blank-line rules need."""

    depth: int
    lines: list[str]
    first: str  # the first line without its indentation

    @property
    def is_def(self) -> bool:
        """A def or class line (black's previous_defs)."""
        return self.first.startswith(("def ", "async def ", "class "))

    @property
    def is_decorator(self) -> bool:
        """A decorator line."""
        return self.first.startswith("@")

    @property
    def is_comment(self) -> bool:
        """A comment line."""
        return self.first.startswith("#")


def blank_lines(entries: list[Entry | None]) -> list[str]:
    """black's empty-line rules for the shapes of the templates: at most two blank lines at
    the top level and one inside, two around top-level defs and classes, one around nested
    ones, none after a decorator or a def line, none at the start or the end."""
    out: list[str] = []
    blanks = 0
    prev: Entry | None = None
    defs: list[int] = []
    for entry in entries:
        if entry is None:
            blanks += 1
            continue
        depth = entry.depth
        before = min(blanks, 2 if depth == 0 else 1)
        if prev is None:
            before = 0
        else:
            closed = False
            while defs and defs[-1] >= depth:
                defs.pop()
                closed = True
            if closed:
                before = 2 if depth == 0 else 1
            if entry.is_def or entry.is_decorator:
                before = _before_def(prev, entry, before)
            elif prev.is_def and prev.depth < depth:
                before = 0
        if entry.is_def:
            defs.append(depth)
        out.extend([""] * before)
        out.extend(entry.lines)
        blanks, prev = 0, entry
    return out


def _before_def(prev: Entry, entry: Entry, before: int) -> int:
    if prev.is_decorator:
        return 0
    if prev.depth < entry.depth and prev.is_def:
        return 0
    if prev.is_comment and prev.depth == entry.depth and before == 0:
        return 0
    return 2 if entry.depth == 0 else 1
