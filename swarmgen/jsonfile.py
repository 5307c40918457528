"""The user's JSON side files (simulation scenarios, replay scripts): read through the bounded
reader, parsed strictly, and checked with errors that name the JSON path of the bad value.

Strict means: no duplicate keys (JSON allows them and keeps the last, silently), no `NaN` or
`Infinity` and no number too large for a float (they are not JSON and would become nonsense
results), and no nesting deeper than `MAX_DEPTH` (a document nested 100,000 deep would exhaust
the recursion of the parser or of whatever walks it later). Standard library only.

Paths are written as JSONPath: `$.world.spacing`, `$.steps[3].burst[0]`, `$.placement["*"]`.
"""

from __future__ import annotations

import difflib
import json
import math
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from swarmgen.console import shown
from swarmgen.errors import SwarmgenError
from swarmgen.inputs import InputRefused, read_limited

MAX_DEPTH = 64  # objects and lists inside each other; the shipped files use 3
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class JsonError(SwarmgenError):
    """A JSON side file that cannot be used; the message is one line (file: path: problem)."""


class _Object(dict[str, Any]):
    """A JSON object that remembers the keys it saw twice (checked where its path is known)."""

    duplicates: tuple[str, ...] = ()


def _pairs(pairs: list[tuple[str, Any]]) -> _Object:
    result = _Object(pairs)
    if len(result) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                result.duplicates = (key,)
                break
            seen.add(key)
    return result


def _constant(name: str) -> float:
    return float(name)  # NaN, Infinity, -Infinity: kept so the walk can say where they are


def load(path: Path, limit: int) -> Any:
    """The parsed document of `path` (at most `limit` bytes); `JsonError` names the file and,
    for a bad value, its JSON path."""
    where = shown(path)
    try:
        data = read_limited(path, limit)
    except InputRefused as err:
        raise JsonError(f"{where}: {err}") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise JsonError(f"{where}: not UTF-8 text (byte {err.start})") from None
    try:
        document = json.loads(text, object_pairs_hook=_pairs, parse_constant=_constant)
    except json.JSONDecodeError as err:
        raise JsonError(f"{where}:{err.lineno}:{err.colno}: not JSON: {err.msg}") from None
    except RecursionError:
        raise JsonError(f"{where}: nested too deeply (the limit is {MAX_DEPTH} levels)") from None
    try:
        _walk(document)
    except JsonError as err:
        raise JsonError(f"{where}: {err}") from None
    return document


def _walk(document: Any) -> None:
    """Depth, duplicate keys and non-finite numbers, everywhere (iteratively: no recursion)."""
    stack: list[tuple[Any, str, int]] = [(document, "$", 1)]
    while stack:
        value, where, depth = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            raise JsonError(f"{where}: {_number_text(value)} is not a JSON number")
        if not isinstance(value, dict | list):
            continue
        if depth > MAX_DEPTH:
            raise JsonError(f"{where}: nested too deeply (the limit is {MAX_DEPTH} levels)")
        if isinstance(value, dict):
            duplicates = getattr(value, "duplicates", ())
            if duplicates:
                raise JsonError(f"{where}: duplicate key {json.dumps(duplicates[0])}")
            stack.extend((v, key_path(where, k), depth + 1) for k, v in value.items())
        else:
            stack.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value))


def _number_text(value: float) -> str:
    if math.isnan(value):
        return "NaN"
    return "Infinity (or a number too large for a float)" if value > 0 else "-Infinity"


def key_path(base: str, key: str) -> str:
    """The path of `key` under `base` as a message shows it (`a.b`, or `a["odd key"]`)."""
    return f"{base}.{key}" if _NAME.fullmatch(key) else f"{base}[{json.dumps(key)}]"


def got(value: Any) -> str:
    """How a wrong value is shown: `got "abc"`, `got true`, `got a list`."""
    if isinstance(value, dict):
        return "got an object"
    if isinstance(value, list):
        return "got a list"
    text = json.dumps(value)
    return f"got {text if len(text) <= 40 else text[:37] + '...'}"


def check_keys(value: dict[str, Any], known: Iterable[str], where: str) -> None:
    """Unknown keys are errors (a typo would otherwise be ignored), with a suggestion."""
    names = sorted(known)
    for key in value:
        if key not in names:
            close = difflib.get_close_matches(key, names, n=1)
            hint = f"; did you mean {json.dumps(close[0])}?" if close else ""
            raise JsonError(
                f"{key_path(where, key)}: unknown key{hint} (known: {', '.join(names)})"
            )


def expect_object(value: Any, where: str) -> dict[str, Any]:
    """`value` if it is a JSON object, else a JsonError at `where`."""
    if not isinstance(value, dict):
        raise JsonError(f"{where}: expected an object, {got(value)}")
    return value


def expect_list(value: Any, where: str, *, empty: bool = True) -> list[Any]:
    """`value` if it is a JSON list (non-empty unless `empty`), else a JsonError."""
    if not isinstance(value, list):
        raise JsonError(f"{where}: expected a list, {got(value)}")
    if not value and not empty:
        raise JsonError(f"{where}: expected a non-empty list")
    return value


def expect_str(value: Any, where: str, *, empty: bool = True) -> str:
    """`value` if it is a JSON string (non-empty unless `empty`), else a JsonError."""
    if not isinstance(value, str):
        raise JsonError(f"{where}: expected a string, {got(value)}")
    if not value and not empty:
        raise JsonError(f"{where}: expected a non-empty string")
    return value


def expect_int(value: Any, where: str, low: int, high: int) -> int:
    """An integer in [low, high] (booleans and floats are not integers here)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise JsonError(f"{where}: expected an integer from {low:,} to {high:,}, {got(value)}")
    if not low <= value <= high:
        raise JsonError(f"{where}: expected an integer from {low:,} to {high:,}, {got(value)}")
    return value


def expect_number(value: Any, where: str, low: float, high: float, *, above: bool) -> float:
    """A finite number in (low, high] (`above`) or [low, high]."""
    interval = f"{'(' if above else '['}{low:g}, {high:g}]"
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    if ok and (value > low if above else value >= low) and value <= high:
        return float(value)
    kind = "a positive number" if above and low == 0 else "a number"
    raise JsonError(f"{where}: expected {kind} in {interval}, {got(value)}")
