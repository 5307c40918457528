"""Syntax errors of the expression language, and quoting model text inside their messages."""

from __future__ import annotations


class ExprError(Exception):
    """A syntax error in model text, located by 0-based offset, line and column."""

    def __init__(
        self, message: str, offset: int, line: int, col: int, hint: str | None = None
    ) -> None:
        # All fields go to Exception.args so that the error pickles (multiprocessing) intact.
        super().__init__(message, offset, line, col, hint)
        self.message = message
        self.offset = offset
        self.line = line
        self.col = col
        self.hint = hint

    def __str__(self) -> str:
        text = f"line {self.line + 1}, column {self.col + 1}: {self.message}"
        return f"{text} (hint: {self.hint})" if self.hint else text


def error_at(text: str, offset: int, message: str, hint: str | None = None) -> ExprError:
    """The error for `message` at `offset` of `text`, with its line and column computed."""
    line = text.count("\n", 0, offset)
    col = offset - (text.rfind("\n", 0, offset) + 1)
    return ExprError(message, offset, line, col, hint)


def escape_char(c: str) -> str:
    """A Python-style escape (`\\xHH`, `\\uHHHH`, `\\UHHHHHHHH`) for an unprintable character."""
    code = ord(c)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def show(text: str, limit: int = 30) -> str:
    """Quote model text for a message: clipped, and without raw control characters."""
    clipped = text if len(text) <= limit else text[: limit - 1] + "…"
    return "'" + "".join(c if c.isprintable() else escape_char(c) for c in clipped) + "'"
