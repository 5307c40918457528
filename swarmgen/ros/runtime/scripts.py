"""Simulation scripts: what a goal of each simulated behaviour does, read from JSON and checked
(the format is described in `simulated`)."""

from __future__ import annotations

import ast
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .expressions import ScriptError, check_template, compile_condition


@dataclass(frozen=True)
class Emission:
    """An event a goal publishes (`scope` overrides the event's declared scope)."""

    event: str
    data: Mapping[str, Any] = field(default_factory=dict)
    scope: str | None = None


@dataclass(frozen=True)
class Ending:
    """How a goal ends: its outcome, outputs and the events it then publishes."""

    outcome: str = "succeeded"
    outputs: Mapping[str, Any] = field(default_factory=dict)
    emit: tuple[Emission, ...] = ()


@dataclass(frozen=True)
class Periodic:
    """`every`: events published while the goal runs, every `period` from `start`."""

    period: float
    start: float
    emit: tuple[Emission, ...]
    when: ast.Expression | None = None


@dataclass(frozen=True)
class Until:
    """`until`: the goal ends early on a swarm event for which `when` holds."""

    event: str
    when: ast.Expression | None
    ending: Ending


@dataclass(frozen=True)
class Script:
    """What a goal of one behaviour does."""

    duration: float = 1.0
    ending: Ending = Ending()
    forever: bool = False
    every: Periodic | None = None
    until: Until | None = None


_SCRIPT_KEYS = {"duration", "outcome", "outputs", "emit", "forever", "every", "until"}


def _number(value: Any, where: str) -> float:
    if not isinstance(value, int | float) or isinstance(value, bool) or value < 0:
        raise ScriptError(f"{where}: expected a number >= 0, got {value!r}")
    return float(value)


def _mapping(value: Any, where: str) -> Mapping[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ScriptError(f"{where}: expected an object, got {value!r}")
    check_template(value)
    return value


def _emissions(value: Any, where: str) -> tuple[Emission, ...]:
    if value is None:
        return ()
    if not isinstance(value, list):
        raise ScriptError(f"{where}: expected a list of events")
    found = []
    for number, item in enumerate(value, start=1):
        if not isinstance(item, Mapping) or not isinstance(item.get("event"), str):
            raise ScriptError(f"{where}[{number}]: expected {{'event': name, 'data': {{...}}}}")
        scope = item.get("scope")
        if scope not in (None, "swarm", "local"):
            raise ScriptError(f"{where}[{number}]: scope is 'swarm' or 'local'")
        found.append(Emission(item["event"], _mapping(item.get("data"), where), scope))
    return tuple(found)


def _ending(raw: Mapping[str, Any], where: str) -> Ending:
    outcome = raw.get("outcome", "succeeded")
    if not isinstance(outcome, str):
        raise ScriptError(f"{where}: outcome must be a string")
    check_template(outcome)
    return Ending(
        outcome,
        _mapping(raw.get("outputs"), f"{where}.outputs"),
        _emissions(raw.get("emit"), f"{where}.emit"),
    )


def _condition(when: Any, where: str) -> ast.Expression | None:
    if when is None:
        return None
    if not isinstance(when, str):
        raise ScriptError(f"{where} must be an expression")
    return compile_condition(when)


def parse_script(raw: Any, where: str = "script") -> Script:
    """The script of one behaviour, checked (ScriptError names `where` for a bad one)."""
    if not isinstance(raw, Mapping):
        raise ScriptError(f"{where}: expected an object")
    unknown = set(raw) - _SCRIPT_KEYS
    if unknown:
        raise ScriptError(f"{where}: unknown keys {sorted(unknown)}")
    every = None
    if raw.get("every") is not None:
        block = _mapping(raw["every"], f"{where}.every")
        period = _number(block.get("period"), f"{where}.every.period")
        if period <= 0:
            raise ScriptError(f"{where}.every.period must be > 0")
        start = _number(block.get("start", period), f"{where}.every.start")
        every = Periodic(
            period,
            start,
            _emissions(block.get("emit"), f"{where}.every.emit"),
            _condition(block.get("when"), f"{where}.every.when"),
        )
    until = None
    if raw.get("until") is not None:
        block = _mapping(raw["until"], f"{where}.until")
        if not isinstance(block.get("event"), str):
            raise ScriptError(f"{where}.until needs the name of an event")
        condition = _condition(block.get("when"), f"{where}.until.when")
        until = Until(block["event"], condition, _ending(block, f"{where}.until"))
    return Script(
        duration=_number(raw.get("duration", 1.0), f"{where}.duration"),
        ending=_ending(raw, where),
        forever=bool(raw.get("forever", False)),
        every=every,
        until=until,
    )


def load_scripts(
    defaults: Mapping[str, Mapping[str, Any]],
    member_type: str,
    source: Mapping[str, Any] | str | Path | None = None,
) -> dict[str, Script]:
    """The scripts of one member type: the generated defaults, replaced behaviour by behaviour by
    the file's `behaviours`, then by its `member_types.<type>.behaviours`."""
    raw: Any = source
    if isinstance(source, str | Path):
        try:
            raw = json.loads(Path(source).read_text(encoding="utf-8"))
        except (OSError, ValueError) as err:
            raise ScriptError(f"{source}: cannot read the script: {err}") from None
    raw = raw or {}
    if not isinstance(raw, Mapping):
        raise ScriptError("a script is a JSON object")
    merged: dict[str, Any] = dict(defaults)
    merged.update(_mapping(raw.get("behaviours"), "behaviours"))
    per_type = _mapping(raw.get("member_types"), "member_types").get(member_type) or {}
    merged.update(_mapping(per_type.get("behaviours"), f"member_types.{member_type}.behaviours"))
    return {name: parse_script(value, f"behaviours.{name}") for name, value in merged.items()}
