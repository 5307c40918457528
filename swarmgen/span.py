"""Source positions carried by every raw element, IR node and diagnostic."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class Span(BaseModel):
    """Where an element comes from: file, 1-based line and column, its xmi:id and model path."""

    model_config = ConfigDict(frozen=True, extra="forbid")

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
