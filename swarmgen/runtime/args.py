"""Argument parsing shared by the generated command lines (standard library only): one-line
errors and finite-number option types."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import NoReturn


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr with exit status 2."""

    def error(self, message: str) -> NoReturn:
        """One line on stderr, exit 2 (argparse would print the usage first)."""
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def finite(text: str, low: float, low_ok: bool) -> float:
    """`text` as a finite number above `low` (or equal to it when `low_ok`), else an
    argparse.ArgumentTypeError saying what was expected."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value) or value < low or (value == low and not low_ok):
        bound = f">= {low:g}" if low_ok else f"> {low:g}"
        raise argparse.ArgumentTypeError(f"expected a finite number {bound}, got {text!r}")
    return value


def number(low: float, low_ok: bool) -> Callable[[str], float]:
    """An argparse type: a finite number above `low` (or equal to it when `low_ok`)."""

    def parse(text: str) -> float:
        return finite(text, low, low_ok)

    return parse
