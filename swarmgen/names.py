"""Safe, deterministic identifiers derived from model names.

Model names may hold spaces and any Unicode ("Select Rover"); generated code, SCXML ids and ROS
names need identifiers. The original names are always kept beside them (SCXML attributes,
traces). One function makes identifiers, so every backend agrees on them.
"""

from __future__ import annotations

import keyword
import re
import unicodedata
from collections.abc import Iterable

# Words that may not be used as identifiers in any target: Python, ECMAScript (Qt SCXML's
# datamodel), SCXML's system variables and the names generated code reserves.
_RESERVED = frozenset(keyword.kwlist) | frozenset(keyword.softkwlist) | {
    "abstract", "arguments", "await", "boolean", "break", "byte", "case", "catch", "char", "class",
    "const", "continue", "debugger", "default", "delete", "do", "double", "else", "enum", "eval",
    "export", "extends", "false", "final", "finally", "float", "for", "function", "goto", "if",
    "implements", "import", "in", "instanceof", "int", "interface", "let", "long", "native", "new",
    "null", "package", "private", "protected", "public", "return", "short", "static", "super",
    "switch", "synchronized", "this", "throw", "throws", "transient", "true", "try", "typeof",
    "undefined", "var", "void", "volatile", "while", "with", "yield", "NaN", "Infinity",
    "In", "_event", "_sessionid", "_name", "_ioprocessors", "_x",
    "event", "outcome", "done", "error", "self", "sg",
}  # fmt: skip

_NON_WORD = re.compile(r"[^0-9A-Za-z_]+")
_UNDERSCORES = re.compile(r"_{2,}")
MAX_LENGTH = 80


def identifier(name: str, fallback: str = "unnamed") -> str:
    """A safe ASCII identifier for `name`: `Select Rover` -> `Select_Rover`.

    Accents are stripped, other characters become `_`, runs of `_` collapse (so `__` stays free
    as the separator of qualified ids), reserved words get a trailing `_`.
    """
    ascii_text = unicodedata.normalize("NFKD", name).encode("ascii", "ignore").decode("ascii")
    text = _UNDERSCORES.sub("_", _NON_WORD.sub("_", ascii_text)).strip("_")
    if not text:
        text = fallback
    if text[0].isdigit():
        text = f"n{text}"
    if len(text) > MAX_LENGTH:
        text = text[:MAX_LENGTH].rstrip("_")
    if text in _RESERVED:
        text = f"{text}_"
    return text


# W3C SCXML event names: tokens of ASCII letters, digits, `_` and `-` separated by dots (a
# transition's descriptor `a.b` takes `a.b` and `a.b.c`, by whole tokens: docs/semantics.md).
_EVENT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*(?:\.[A-Za-z0-9_-]+)*", re.ASCII)
# the platform's own first tokens: a model event named `done.x` would be matched by `done.*`
_PLATFORM_TOKENS = frozenset({"done", "error", "outcome", "after"})


def event_name(name: str) -> str:
    """The name an event has at run time, in descriptors, on the wire and in every output: the
    model's name when it is a dotted W3C event name (`foo.bar`, `In-s11p112`), else its
    identifier (`Select Rover` -> `Select_Rover`; a plain name keeps its identifier, so `done` is
    `done_`). A name whose first token is the platform's (`done.x`, `error.x`) is made an
    identifier too, so a model event never matches a platform descriptor. The one mapping from
    an event's model name to its run-time name; it is never used as code, only as a string."""
    if (
        ("." in name or "-" in name)
        and len(name) <= MAX_LENGTH
        and not name.startswith("__")
        and _EVENT_NAME.fullmatch(name)
        and name.split(".", 1)[0] not in _PLATFORM_TOKENS
    ):
        return name
    return identifier(name)


def dot_prefixes(names: Iterable[str]) -> set[str]:
    """Every name and each of its dot-prefixes (`a.b.c`: `a`, `a.b`, `a.b.c`): a descriptor
    matches one of `names` exactly when it is in this set, so a chart with thousands of
    `done.state.*` names is matched in linear time, not names x descriptors."""
    found: set[str] = set()
    for name in names:
        parts = name.split(".")
        found.update(".".join(parts[: k + 1]) for k in range(len(parts)))
    return found


def qualified(*parts: str) -> str:
    """Join identifiers of nested elements: `Mission__SarBehavior__Idle`."""
    return "__".join(p for p in parts if p)


def ros_name(name: str) -> str:
    """A ROS 2 name segment: lower snake case (`SelectRover` -> `select_rover`)."""
    snake = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", identifier(name)).lower()
    return _UNDERSCORES.sub("_", snake).strip("_") or "unnamed"


class IdAllocator:
    """Hands out unique ids in one namespace, in the order asked; deterministic."""

    def __init__(self, taken: Iterable[str] = ()) -> None:
        self._taken = set(taken)
        # per base: the last number handed out; every `base_2` .. `base_n` is taken (names are
        # never given back), so the search for the next free one starts there, not at 2 (from
        # 2 it was quadratic in the names sharing a base: thousands in a big diagram)
        self._numbered: dict[str, int] = {}

    def claim(self, preferred: str, *alternatives: str) -> str:
        """The first free one of the names given, else the last one numbered (`_2`, `_3`, ...)."""
        for candidate in (preferred, *alternatives):
            if candidate and candidate not in self._taken:
                self._taken.add(candidate)
                return candidate
        base = alternatives[-1] if alternatives else preferred
        n = self._numbered.get(base, 2)
        while f"{base}_{n}" in self._taken:
            n += 1
        self._numbered[base] = n
        self._taken.add(f"{base}_{n}")
        return f"{base}_{n}"

    def __contains__(self, name: str) -> bool:
        return name in self._taken


def one_line(text: str) -> str:
    """Model text inside a generated comment or docstring line: no line breaks, no controls."""
    flat = " ".join(text.splitlines())
    return "".join(ch if ch.isprintable() else " " for ch in flat)


def doc_text(text: str) -> str:
    """Model text inside a generated docstring: one line, no quote or backslash to end it early."""
    return one_line(text).replace("\\", "/").replace('"', "'")
