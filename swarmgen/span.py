"""Source positions carried by every raw element, IR node and diagnostic."""

from __future__ import annotations

from typing import ClassVar

from pydantic import ConfigDict

from swarmgen.records import dataclass


@dataclass(frozen=True, slots=True)
class Span:
    """Where an element comes from: file, 1-based line and column, its xmi:id and model path."""

    # A frozen dataclass, not a pydantic model: a model has one per raw element and IR node
    # (~80,000 at 10,000 states), and a dataclass builds four times faster. Inside the IR's
    # pydantic models it validates, serialises and appears in `swarmgen schema` as the model
    # did (this config gives the schema's `additionalProperties: false`); mypy checks the
    # argument types at every construction, which pydantic checked at run time.
    __pydantic_config__: ClassVar[ConfigDict] = ConfigDict(extra="forbid")

    file: str
    line: int = 0
    col: int = 0
    xmi_id: str | None = None
    path: str = ""

    def location(self) -> str:
        """`file:line:col`, leaving out what is unknown."""
        if self.line <= 0:
            return self.file
        return f"{self.file}:{self.line}:{max(self.col, 1)}"
