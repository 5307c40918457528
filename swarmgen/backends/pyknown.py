"""The statements known to be in black's layout: `pylayout` records each statement it printed,
`pyformat` copies those lines when it meets them at the start of a statement.

What is recorded is a fact about the text alone (black prints that statement so wherever it
stands at that indentation), so the record is shared by every source in the process; it only
saves time, so it is bounded, and it is never written to disk (docs/security.md).
"""

from __future__ import annotations

# the statements' texts (lines joined, indentation included), and per first line the numbers
# of lines of those that begin with it
_LAID_OUT: set[str] = set()
_LAID_HEADS: dict[str, set[int]] = {}
_LAID_LIMIT = 1 << 18


def register_laid_out(lines: list[str]) -> None:
    """Record `lines` (one statement, indentation included) as what black prints for that
    statement (`pylayout` lays out only the forms it reproduces), for `format_source` to copy
    when it meets exactly these lines at the start of a statement."""
    if len(_LAID_OUT) >= _LAID_LIMIT:
        _LAID_OUT.clear()
        _LAID_HEADS.clear()
    _LAID_OUT.add("\n".join(lines))
    _LAID_HEADS.setdefault(lines[0], set()).add(len(lines))


def register_line(line: str) -> None:
    """Record `line` (indentation included) as a one-line statement, or a `def` header, that
    black prints as it is at that indentation (`register_laid_out` of one line)."""
    register_laid_out([line])


def laid_out(lines: list[str], start: int) -> int:
    """The number of lines of the recorded statement that begins at `lines[start]`, else 0."""
    counts = _LAID_HEADS.get(lines[start])
    if counts is None:
        return 0
    for count in counts:
        text = lines[start] if count == 1 else "\n".join(lines[start : start + count])
        if text in _LAID_OUT:
            return count
    return 0
