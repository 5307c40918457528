"""SCXML `<send>` and `<cancel>` into the action language's `raise ... [to] [via] [after]
[as|into]` and `cancel` (docs/scxml-input.md), with the namelist and `<param>` fields of an
event; `Actions` inherits them (`scxml_actions`)."""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import TYPE_CHECKING

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.frontend.scxml_expr import json_fields
from swarmgen.frontend.scxml_raw import Builder, children

# an invalid namelist entry's field: its identifier characters (`"foo` gives `foo`)
_NOT_IDENT = re.compile(r"[^A-Za-z0-9_]")
_LITERAL_DELAY = re.compile(r"\s*(\d+(?:\.\d*)?|\.\d+)(ms|s)\s*", re.ASCII)
_OWN_DELAY = re.compile(r"\$sg\.(?:delay\((.*), (1|1000)\)|duration\((.*)\))", re.DOTALL)
_PROCESSOR = "http://www.w3.org/TR/scxml/#SCXMLEventProcessor"
_HTTP = "http://www.w3.org/TR/scxml/#BasicHTTPEventProcessor"


def _unread_send(node: etree._Element) -> str | None:
    """Why swarmgen does not read this `<send>`, or None."""
    sendid = node.get("id")
    if node.get("type") in (_HTTP, "basichttp"):
        return "swarmgen has no Basic HTTP event I/O processor"
    if node.get("event") is not None and node.get("eventexpr") is not None:
        return "event and eventexpr exclude each other"
    if children(node, "content") and (node.get("namelist") or children(node, "param")):
        return "a <content> excludes namelist and <param> (W3C 6.2)"
    location = node.get("idlocation")
    if location is not None and (not location.isidentifier() or location.startswith("_")):
        return "an idlocation is a data id"
    if sendid is not None and location is not None:
        return "id and idlocation exclude each other"
    if sendid is not None and (not sendid.isidentifier() or sendid.startswith("__")):
        return "a send id is an identifier"
    return None


class Sends:
    """What `Actions` gives the `<send>` readers (its fields and text readers)."""

    b: Builder
    name: Callable[[str], str]
    event_name: Callable[[str], str]

    if TYPE_CHECKING:

        def text(self, source: str, node: etree._Element) -> str | None:
            """`Actions.text`."""

        def location(self, source: str, node: etree._Element) -> str | None:
            """`Actions.location`."""

        def is_location(self, source: str) -> bool:
            """`Actions.is_location`."""

        def invalid(self, source: str, node: etree._Element) -> str | None:
            """`Actions.invalid`."""

        def content(self, content: etree._Element) -> str | None:
            """`Actions.content`."""

    def internal_send(self, node: etree._Element) -> list[str]:
        """`<send>` to this session: `#_internal` without a delay is a raise with data; with a
        delay, or without a target (the session's external queue), a delayed raise (`after 0
        ms` without a delay); any other send is reported."""
        why = _unread_send(node)
        if why is not None:
            self.b.report(dg.SCXML_UNSUPPORTED, node, element="send", why=why)
            return []
        lines = self.event_action(node, "raise", children(node, "param"))
        target, targetexpr = node.get("target"), node.get("targetexpr")
        to = ""
        if targetexpr is not None or target not in (None, "#_internal"):
            text = (
                self.text(targetexpr, node)
                if targetexpr is not None
                else expr.to_text(expr.Const(value=str(target)))
            )
            if text is None:
                return []
            to = f" to ({text})"  # W3C's <send target>: docs/semantics.md, "Targets"
        via = self.via(node)
        if via is None:
            return []
        to += via
        into = f" into {self.name(node.get('idlocation', ''))}" if node.get("idlocation") else ""
        delayed = target is None or {"delay", "delayexpr"} & set(node.attrib)
        if not lines or not (delayed or to or into):
            return lines
        if not delayed:
            return [f"{lines[0]}{to}{into}"]
        delay = self.delay(node)
        if delay is None:
            return []
        sendid = node.get("id")
        return [f"{lines[0]}{to} after {delay}" + (f" as {sendid}" if sendid else into)]

    def via(self, node: etree._Element) -> str | None:
        """` via (p)` of `<send type|typeexpr>` ("" for the SCXML event processor, which is
        the default; None when `typeexpr` is not read)."""
        kind, computed = node.get("type"), node.get("typeexpr")
        if computed is not None:
            text = self.text(computed, node)
            return f" via ({text})" if text is not None else None
        if kind in (None, _PROCESSOR, "scxml"):
            return ""
        return f" via ({expr.to_text(expr.Const(value=str(kind)))})"  # error.execution

    def delay(self, node: etree._Element) -> str | None:
        """The `after` of a delayed send: `N ms`/`N s` from `delay`, an expression from
        `delayexpr` (swarmgen's own `$sg.delay(e, scale)` and `$sg.duration(e)` read back)."""
        literal, source = node.get("delay"), node.get("delayexpr")
        if source is None:
            found = _LITERAL_DELAY.fullmatch(literal or "0ms")
            if found is None:
                self.b.report(
                    dg.SCXML_UNSUPPORTED,
                    node,
                    "attribute",
                    attribute="delay",
                    value=str(literal)[:200],
                    element="send",
                    why="a delay is a number of ms or s (`500ms`, `1.5s`)",
                )
                return None
            return f"{found.group(1)} {found.group(2)}"
        own = _OWN_DELAY.fullmatch(source)
        if own is not None:
            inner = self.text(own.group(1) or own.group(3), node)
            unit = "" if own.group(2) is None else (" s" if own.group(2) == "1000" else " ms")
            return f"({inner}){unit}" if inner is not None else None
        text = self.text(source, node)
        return f"({text})" if text is not None else None

    def namelist_entry(self, entry: str, node: etree._Element) -> str | None:
        """A namelist's datum (a data id), or `invalid("...")` for one that is none."""
        return self.name(entry) if self.is_location(entry) else self.invalid(entry, node)

    def cancel(self, node: etree._Element) -> list[str]:
        """`<cancel sendid>`: `cancel id` (the timer pattern's is read with its state)."""
        sendid, computed = node.get("sendid"), node.get("sendidexpr")
        if computed is not None and sendid is None:
            text = self.text(computed, node)
            return [f"cancel ({text})"] if text is not None else []
        if sendid is None or not sendid.isidentifier() or sendid.startswith("__"):
            self.b.report(
                dg.SCXML_UNSUPPORTED,
                node,
                element="cancel",
                why="swarmgen cancels by a literal sendid that is an identifier",
            )
            return []
        return [f"cancel {sendid}"]

    def event_action(
        self, node: etree._Element, verb: str, params: list[etree._Element]
    ) -> list[str]:
        """`raise`/`send` of an event with its fields (defaults left to the emitter)."""
        fields = [
            f"{namelist_field(n)} = {self.namelist_entry(n, node)}"
            for n in str(node.get("namelist", "")).split()
        ]  # W3C: each named datum as a field of its name
        for param in params:
            source = str(param.get("expr", ""))
            if source.lstrip().startswith(("{", "[")):
                continue  # a field's default, which the emitter fills in again
            if param.get("location") is not None:
                value = self.location(str(param.get("location")), param)
            else:
                value = self.text(source, param)
            if value is not None:
                fields.append(f"{param.get('name')} = {value}")
        computed = node.get("eventexpr") if verb == "raise" else None
        if computed is not None:  # W3C's eventexpr: `raise (expr)`
            named = self.text(computed, node)
            if named is None:
                return []
            event = f"({named})"
        else:
            event = self.event_name(str(node.get("event", "")))
        contents = children(node, "content") if verb == "raise" else []
        inline = (contents[0].text or "") if contents and not len(contents[0]) else ""
        fielded = json_fields(inline) if contents and contents[0].get("expr") is None else None
        if fielded is not None:  # a JSON object: the event's fields, `raise e(f = v, ...)`
            return [f"{verb} {event}({', '.join(f'{n} = {v}' for n, v in fielded)})"]
        if contents:  # the event's whole data: `raise e(expr)`
            value = self.content(contents[0])
            return [f"{verb} {event}({value})"] if value is not None else []
        return [f"{verb} {event}({', '.join(fields)})" if fields else f"{verb} {event}"]


def namelist_field(entry: str) -> str:
    """The event field of a namelist's entry: its name, or for an entry that is no data id (an
    invalid location, whose send fails when it runs) its identifier characters."""
    if entry.isidentifier() and not entry.startswith("__"):
        return entry
    kept = _NOT_IDENT.sub("", entry).lstrip("_0123456789")
    return kept or "invalid"
