"""Copies of swarmgen's runtimes inside generated packages, so generated code runs without
swarmgen installed: `swarmgen.runtime` (standard library only) and `swarmgen.ros.runtime`."""

from __future__ import annotations

import functools
import re
from pathlib import Path, PurePosixPath

from swarmgen.generated import header

_PACKAGE = Path(__file__).resolve().parent.parent
RUNTIME_DIR = _PACKAGE / "runtime"
ROS_RUNTIME_DIR = _PACKAGE / "ros" / "runtime"
# Absolute imports of the runtime become relative to the vendored copy (`._runtime/`); the ROS
# runtime's `...runtime` (two packages up in swarmgen) is `.._runtime` beside it (`_ros/`).
_IMPORT = re.compile(r"\bfrom swarmgen\.runtime\.(\w+) import")
_ROS_IMPORT = re.compile(r"^from \.\.\.runtime\.(\w+) import", re.MULTILINE)


def runtime_files(folder: PurePosixPath, modules: tuple[str, ...]) -> dict[PurePosixPath, str]:
    """`swarmgen.runtime`'s modules in `folder`, imports made relative, with a generated header."""
    return _copies(folder, RUNTIME_DIR, "swarmgen.runtime", modules, _IMPORT, r"from .\1 import")


def ros_runtime_files(folder: PurePosixPath, modules: tuple[str, ...]) -> dict[PurePosixPath, str]:
    """`swarmgen.ros.runtime`'s modules in `folder`: `...runtime` becomes `.._runtime`."""
    return _copies(
        folder,
        ROS_RUNTIME_DIR,
        "swarmgen.ros.runtime",
        modules,
        _ROS_IMPORT,
        r"from .._runtime.\1 import",
    )


def _copies(
    folder: PurePosixPath,
    directory: Path,
    dotted: str,
    modules: tuple[str, ...],
    imports: re.Pattern[str],
    replacement: str,
) -> dict[PurePosixPath, str]:
    return {
        folder / f"{module}.py": _copy(directory, dotted, module, imports, replacement)
        for module in ("__init__", *modules)
    }


@functools.cache
def _copy(
    directory: Path, dotted: str, module: str, imports: re.Pattern[str], replacement: str
) -> str:
    """One module's vendored text. Memoised in the process (the asyncio, smach and rclpy
    packages vendor the same modules; swarmgen's own sources, never written to disk)."""
    text = imports.sub(replacement, (directory / f"{module}.py").read_text(encoding="utf-8"))
    return header(copy_of=f"{dotted}.{module}") + "\n" + text
