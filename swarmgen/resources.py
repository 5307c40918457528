"""Where the shipped data lives: `templates/` and `schemas/` of the repository, which the wheel
carries inside the package as `swarmgen/_data/` (see pyproject.toml)."""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Literal

_PACKAGE = Path(__file__).resolve().parent


@cache
def data_dir(kind: Literal["templates", "schemas"]) -> Path:
    """The shipped templates or schemas directory: inside the wheel, else the checkout's."""
    for candidate in (_PACKAGE / "_data" / kind, _PACKAGE.parent / kind):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"swarmgen's {kind} directory is missing; reinstall swarmgen")
