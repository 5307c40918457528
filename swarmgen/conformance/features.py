"""The feature an IRP test needs that swarmgen does not have, read from the front end's refusal.

The SCXML reader refuses what the IR cannot express with a located diagnostic (SG060
unsupported element, SG062 expression, SG063 datamodel; SG112 from the checks when a name is
no member data). The diagnostic and the element it points at (the converted document, at the
span's line) give a short feature name: "delayed send", "if/elseif/else", "expression:
_event.name", ... The conformance table counts tests by these names, so the names are stable.
"""

from __future__ import annotations

import re

from lxml import etree

from swarmgen.diagnostics.model import Diagnostic

SCXML = "http://www.w3.org/2005/07/scxml"
_ELEMENTS = {
    "if": "if/elseif/else",
    "elseif": "if/elseif/else",
    "else": "if/elseif/else",
    "foreach": "foreach",
    "log": "log",
    "script": "script",
    "invoke": "invoke",
    "finalize": "invoke",
    "donedata": "donedata",
    "content": "send content",
    "cancel": "cancel",
    "onentry": "onentry/onexit in a final",
    "onexit": "onentry/onexit in a final",
}
_NAMES = (  # (pattern in the refused text, feature), first match wins
    (r"typeof|undefined", "expression: typeof/undefined"),
    (r"_event\.data ==|_event\.data is only", "expression: _event.data as a value"),
    (r"_event(?!\.data)", "expression: _event fields"),
    (r"_sessionid|_name|_ioprocessors|_x", "expression: system variables"),
    (r"\bin\b", "expression: in"),
    (r"function|\(", "expression: calls/functions"),
    (r"return", "expression: illegal (error.execution)"),
    (r"\[", "expression: arrays/objects"),
)


def feature(diagnostic: Diagnostic, root: etree._Element | None = None) -> str:
    """A short name for what the refused construct needs (`root`: the converted document)."""
    code, message = diagnostic.code.id, diagnostic.message
    if code == "SG063":
        return f"datamodel {_quoted(message) or '?'}"
    if code == "SG062":
        return _expression(_between(message, "translate '", "' into"))
    if code == "SG112":
        name = _between(message, "uses '", "',")
        return "data in a state's <datamodel>" if name.startswith("Var") else _expression(name)
    if code == "SG061" and message.startswith("src="):
        return "data src/content"
    if code == "SG070":
        return _invoke(message)
    if code == "SG061" and "is not an element of SCXML" in message:
        return "XML content (data, assign, send)"
    if code != "SG060":
        return f"{code}: {message}"
    if "event descriptor" in message:
        event = _quoted(message, "'") or ""
        return f"event {event.split('.')[0]}.*"
    if "In()" in message:
        return "In() in a cond"
    element = _element(message)
    if element == "send":
        return _send(_at(root, diagnostic.span.line, "send"))
    if element == "data":
        return "data src/content"
    if element == "assign" and "read-only" in message:
        return "assign to a system variable (refused when compiled)"
    if element == "assign":
        return "assign: location or content"
    return _ELEMENTS.get(element, f"<{element}>")


def _invoke(message: str) -> str:
    """What an `<invoke>` swarmgen does not run needs: a computed document, a document in
    `<content expr>`, a namelist of no data ids, another type."""
    if "srcexpr" in message:
        return "invoke: srcexpr (a document computed at run time)"
    if "no document" in message:
        return "invoke: <content expr> (a document computed at run time)"
    if "namelist" in message:
        return "invoke: a namelist naming no data"
    return "invoke"


def _quoted(message: str, quote: str = '"') -> str | None:
    found = re.search(f"{quote}(.*?){quote}", message)
    return found.group(1) if found else None


def _between(message: str, before: str, after: str) -> str:
    """The text the message quotes between `before` and the last `after` (it may hold quotes)."""
    start = message.find(before)
    end = message.rfind(after)
    return message[start + len(before) : end] if 0 <= start < end else message


def _element(message: str) -> str:
    found = re.search(r"<([A-Za-z_:]+)>", message)
    return found.group(1) if found else "?"


def _expression(text: str) -> str:
    for pattern, name in _NAMES:
        if re.search(pattern, text):
            return name
    return f"expression: {text[:40]}"


def _at(root: etree._Element | None, line: int, local: str) -> etree._Element | None:
    if root is None:
        return None
    for element in root.iter(f"{{{SCXML}}}{local}"):
        if getattr(element, "sourceline", None) == line:  # the stubs type it oddly
            return element
    return None


def _send(send: etree._Element | None) -> str:
    """Which part of `<send>` is missing: delays, targets, types, data or the external queue."""
    if send is None:
        return "send"
    attributes = set(send.attrib)
    target = send.get("target", "")
    if attributes & {"delay", "delayexpr"}:
        return "delayed send"
    if target == "#_parent":
        return "invoke"
    if (target and target != "#_internal") or "targetexpr" in attributes:
        return "send to an external target"
    if attributes & {"type", "typeexpr", "eventexpr", "idlocation", "id"}:
        return "send type/eventexpr/id"
    if "namelist" in attributes or len(send):
        return "send with data"
    return "send to the external queue"
