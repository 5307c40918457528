"""Behaviour plug-ins (standard library only): typed implementations adapted to the `Library`
contract, found through the package's entry-point group (docs/plugins.md).

A generated package's `behaviour_types` module declares, per behaviour, a frozen request
dataclass (its inputs), a result dataclass (the outcome first, then the outputs) and a Protocol.
A typed implementation is an async callable `(request, context) -> result`, `context` being the
runtime's `Request` (member, state, `emit`, member data). `Plugins` converts at the boundary:
the call's arguments (a dict) become the request dataclass, the result becomes an `Outcome`, so
the member and every existing `Library` see exactly what they saw before.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass
from importlib import metadata
from typing import Any

from swarmgen.runtime.member import Behaviour, Library, Outcome, Request

Typed = Callable[[Any, Request], Awaitable[Any]]  # (request dataclass, context) -> result
# A primitive input the member does not give (None) is its type's zero (the value rule,
# docs/semantics.md), so request fields are never optional.
_ZEROS: dict[Any, Any] = {float: 0.0, int: 0, bool: False, str: ""}


class PluginError(Exception):
    """A plug-in that cannot be used: two providers of one behaviour, a behaviour the package
    does not have, an entry point that does not load or is not callable."""


@dataclass(frozen=True, slots=True)
class Provider:
    """Where a behaviour's implementation comes from: its entry point and distribution."""

    behaviour: str
    target: str  # the entry point's value, `module:object`
    distribution: str  # `name version`, or `?` when the entry point has no distribution

    def __str__(self) -> str:
        return f"{self.behaviour}={self.target} ({self.distribution})"


def load_factory(text: str) -> Callable[..., Library]:
    """`--library MODULE:FACTORY`: the user's library factory (called with the time scale).
    Raises PluginError when `text` is malformed, the module does not import or has no callable
    FACTORY. The one loader of every generated package (asyncio command line, ROS nodes)."""
    module_name, _, attribute = text.partition(":")
    if not module_name or not attribute.isidentifier():
        raise PluginError(f"expected MODULE:FACTORY, got {text!r}")
    try:
        module = importlib.import_module(module_name)
    except Exception as err:  # the user's import: any error it raises is a usage error
        raise PluginError(f"cannot import {module_name}: {err!r}") from None
    factory = getattr(module, attribute, None)
    if not callable(factory):
        raise PluginError(f"{module_name} has no callable {attribute}")
    return factory  # type: ignore[no-any-return]


def request_of(cls: type, values: Mapping[str, Any]) -> Any:
    """The dataclass `cls` from a mapping: missing or None fields are their type's zero, nested
    data types are converted too, an Integer given for a Real becomes a float."""
    given = values if isinstance(values, Mapping) else {}
    return cls(**{f.name: _value(f.type, given.get(f.name)) for f in dataclasses.fields(cls)})


def _value(hint: Any, value: Any) -> Any:
    if getattr(hint, "__origin__", None) is tuple:  # a sequence, `tuple[T, ...]`: never None
        item = hint.__args__[0]
        return tuple(_value(item, v) for v in (value if isinstance(value, list | tuple) else ()))
    struct = _struct(hint)
    if struct is not None:
        return request_of(struct, value if isinstance(value, Mapping) else {})
    if value is None:
        return _ZEROS.get(hint)
    if hint is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def _struct(hint: Any) -> type | None:
    """The data type's dataclass a field holds (`Pose`, or `Pose | None`), else None."""
    for candidate in getattr(hint, "__args__", None) or (hint,):
        if isinstance(candidate, type) and dataclasses.is_dataclass(candidate):
            return candidate
    return None


def outcome_of(result: Any) -> Outcome:
    """A result dataclass as an `Outcome`: its first field is the outcome, the others are
    the outputs (data types as dicts; None stays None: "not given")."""
    first, *outputs = dataclasses.fields(result)
    values = {f.name: _plain(getattr(result, f.name)) for f in outputs}
    return Outcome(getattr(result, first.name), values)


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, list | tuple):  # sequences are lists at run time
        return [_plain(v) for v in value]
    return value


class MappingLibrary:
    """A `Library` of behaviours by name."""

    def __init__(self, behaviours: Mapping[str, Behaviour]) -> None:
        self.behaviours = dict(behaviours)

    def get(self, name: str) -> Behaviour | None:
        """The behaviour of `name` (None: none)."""
        return self.behaviours.get(name)


class Chain:
    """A `Library` asking each of `libraries` in turn: the first that has the behaviour wins."""

    def __init__(self, *libraries: Library) -> None:
        self.libraries = libraries

    def get(self, name: str) -> Behaviour | None:
        """The first implementation of `name` the libraries have."""
        for library in self.libraries:
            found = library.get(name)
            if found is not None:
                return found
        return None


class Plugins:
    """The typed contract of one generated package: its entry-point group and, per behaviour
    name, its request and result dataclasses."""

    def __init__(self, group: str, types: Mapping[str, tuple[type, type]]) -> None:
        self.group = group
        self.types = dict(types)

    def adapt(self, name: str, implementation: Typed) -> Behaviour:
        """The `Library` behaviour running a typed implementation of behaviour `name`."""
        request_type, result_type = self.types[name]

        async def run(context: Request) -> Outcome:
            result = await implementation(request_of(request_type, context.args), context)
            if not isinstance(result, result_type):
                # the member reports it as a failed behaviour (outcome `aborted`)
                raise TypeError(f"returned {result!r:.80}, not a {result_type.__name__}")
            return outcome_of(result)

        return run

    def library(
        self, implementations: Mapping[str, Any], fallback: Library | None = None
    ) -> Library:
        """A `Library` of typed implementations by behaviour name, then `fallback`'s."""
        unknown = sorted(set(implementations) - set(self.types))
        if unknown:
            raise PluginError(f"no behaviour {', '.join(map(repr, unknown))} in this package")
        adapted = MappingLibrary(
            {name: self.adapt(name, impl) for name, impl in implementations.items()}
        )
        return adapted if fallback is None else Chain(adapted, fallback)

    def discover(self) -> dict[str, tuple[Provider, metadata.EntryPoint]]:
        """The installed entry points of the group, by behaviour name. Raises PluginError for
        a behaviour two entry points provide and for a name that is not a behaviour."""
        found: dict[str, list[tuple[Provider, metadata.EntryPoint]]] = {}
        for point in metadata.entry_points(group=self.group):
            dist = point.dist
            where = f"{dist.name} {dist.version}" if dist is not None else "?"
            found.setdefault(point.name, []).append(
                (Provider(point.name, point.value, where), point)
            )
        for name, providers in sorted(found.items()):
            if len(providers) > 1:
                listed = "; ".join(str(p) for p, _ in providers)
                raise PluginError(
                    f"behaviour {name!r} has {len(providers)} providers in entry-point group "
                    f"{self.group!r}: {listed} (uninstall all but one)"
                )
            if name not in self.types:
                raise PluginError(
                    f"entry point {providers[0][0]} of group {self.group!r}: no behaviour "
                    f"{name!r} in this package (it has {', '.join(sorted(self.types))})"
                )
        return {name: providers[0] for name, providers in sorted(found.items())}

    def load(self) -> tuple[Library, list[Provider]]:
        """The discovered plug-ins as a `Library`, and their providers. Raises PluginError
        when one conflicts or does not load."""
        implementations: dict[str, Typed] = {}
        providers = []
        for name, (provider, point) in self.discover().items():
            try:
                implementation = point.load()
            except Exception as err:  # the plug-in's own import: any error it raises
                raise PluginError(f"entry point {provider} does not load: {err!r}") from None
            if not callable(implementation):
                raise PluginError(f"entry point {provider} is not callable")
            implementations[name] = implementation
            providers.append(provider)
        return self.library(implementations), providers
