"""Copies of swarmgen's runtimes inside generated packages, so generated code runs without
swarmgen installed: `swarmgen.runtime` (standard library only) and `swarmgen.ros.runtime`."""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from pathlib import Path, PurePosixPath

from swarmgen.generated import header

_PACKAGE = Path(__file__).resolve().parent.parent
RUNTIME_DIR = _PACKAGE / "runtime"
ROS_RUNTIME_DIR = _PACKAGE / "ros" / "runtime"
# Absolute imports of the runtime become relative to the vendored copy (`._runtime/`); the ROS
# runtime's `...runtime` (two packages up in swarmgen) is `.._runtime` beside it (`_ros/`): at a
# word's start (`\bfrom swarmgen...`) and at a line's start (`^from ...` in MULTILINE mode).
# The patterns begin with their literal text, so that `re` skips ahead to it; a leading `\b` or
# `^` made it try every position of the ~450 kB of sources (~20 ms of a compile): `_word_start`
# and `_line_start` check each match for the boundary those anchors asked for.
_IMPORT = re.compile(r"from swarmgen\.runtime\.(\w+) import")
_ROS_IMPORT = re.compile(r"from \.\.\.runtime\.(\w+) import")
_WORD = re.compile(r"\w")
Starts = Callable[[str, int], bool]  # whether a match at this index of the text may be replaced


def _word_start(text: str, index: int) -> bool:
    """`\\b` before a word character: the text starts there or a non-word character precedes."""
    return index == 0 or _WORD.match(text, index - 1) is None


def _line_start(text: str, index: int) -> bool:
    """`^` with re.MULTILINE: the text starts there or a newline precedes."""
    return index == 0 or text[index - 1] == "\n"


def runtime_files(folder: PurePosixPath, modules: tuple[str, ...]) -> dict[PurePosixPath, str]:
    """`swarmgen.runtime`'s modules in `folder`, imports made relative, with a generated header."""
    return _copies(
        folder, RUNTIME_DIR, "swarmgen.runtime", modules, _IMPORT, r"from .\1 import", _word_start
    )


def ros_runtime_files(folder: PurePosixPath, modules: tuple[str, ...]) -> dict[PurePosixPath, str]:
    """`swarmgen.ros.runtime`'s modules in `folder`: `...runtime` becomes `.._runtime`."""
    return _copies(
        folder,
        ROS_RUNTIME_DIR,
        "swarmgen.ros.runtime",
        modules,
        _ROS_IMPORT,
        r"from .._runtime.\1 import",
        _line_start,
    )


def _copies(
    folder: PurePosixPath,
    directory: Path,
    dotted: str,
    modules: tuple[str, ...],
    imports: re.Pattern[str],
    replacement: str,
    starts: Starts,
) -> dict[PurePosixPath, str]:
    return {
        folder / f"{module}.py": _copy(directory, dotted, module, imports, replacement, starts)
        for module in ("__init__", *modules)
    }


@functools.cache
def _copy(
    directory: Path,
    dotted: str,
    module: str,
    imports: re.Pattern[str],
    replacement: str,
    starts: Starts,
) -> str:
    """One module's vendored text. Memoised in the process (the asyncio, smach and rclpy
    packages vendor the same modules; swarmgen's own sources, never written to disk)."""
    text = (directory / f"{module}.py").read_text(encoding="utf-8")
    return header(copy_of=f"{dotted}.{module}") + "\n" + rewrite(text, imports, replacement, starts)


def rewrite(text: str, imports: re.Pattern[str], replacement: str, starts: Starts) -> str:
    """`text` with each match of `imports` where `starts` allows it replaced (`replacement`
    may refer to the groups, as in `re.sub`). A match that may not be replaced is kept, and
    no other can begin inside it: the patterns' text holds no other start of themselves."""

    def one(match: re.Match[str]) -> str:
        if starts(match.string, match.start()):
            return match.expand(replacement)
        return match.group(0)

    return imports.sub(one, text)
