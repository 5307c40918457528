"""SCXML executable content, conditions and event descriptors into UML behaviours, guards and
triggers (the reverse of docs/scxml.md's mapping), with a located diagnostic for the rest."""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import field

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen import expr
from swarmgen.frontend.raw import RawElement
from swarmgen.frontend.scxml_expr import (
    ExprUnsupported,
    InState,
    Marker,
    conjuncts,
    literal,
    translate,
)
from swarmgen.frontend.scxml_raw import Builder, children, in_scxml, in_sg, local
from swarmgen.frontend.scxml_send import Sends
from swarmgen.records import dataclass

# a location's root: a name, then its members (`a.b`, `a["b"]`) or nothing
_LOCATION_ROOT = re.compile(r"\s*([A-Za-z_$][A-Za-z0-9_$]*)\s*(?:[.\[].*)?", re.DOTALL)

_NOT_IN_IR = {
    "elseif": "<elseif> is read only inside <if>",
    "else": "<else> is read only inside <if>",
    "foreach": "loops are not in the IR yet",
    "script": "scripts other than swarmgen's $sg support script are not run",
    "invoke": "invoking other sessions is not in the IR",
}


@dataclass
class Actions(Sends):
    """Translates one document's conditions, actions and events (`name`: data id -> name)."""

    b: Builder
    name: Callable[[str], str]
    event_name: Callable[[str], str]  # an event's identifier -> its model name
    event_ref: Callable[[str], str]  # an event's model name -> its SignalEvent's id
    time_ref: Callable[[int], str]  # a delay in ms -> a TimeEvent's id
    any_ref: Callable[[], str]  # the AnyReceiveEvent's id
    behaviours: dict[str, str]  # behaviour name -> operation id
    language: str  # "ecmascript", "null" or "swarmgen"
    declare: Callable[[str, etree._Element], None]  # a datum `<foreach>` names, if new
    declared: Callable[[str], bool]  # whether the document declares a datum (a data id)
    timers: dict[str, int] = field(default_factory=dict)  # timer event -> delay (ms)

    def text(self, source: str, node: etree._Element) -> str | None:
        """Model text of an expression, or None (reported)."""
        try:
            if self.language == "swarmgen":
                return expr.to_text(expr.parse_expr(source))
            return expr.to_text(translate(source, self.name))
        except (ExprUnsupported, expr.ExprError, ValueError) as err:
            self.b.report(
                dg.SCXML_EXPRESSION, node, text=source[:200], why=str(err).splitlines()[0]
            )
            return None

    def location(self, source: str, node: etree._Element) -> str | None:
        """Model text of a location read (a `<param location>`, a namelist's entry); one that
        is none is `invalid("...")`, error.execution when it runs (`invalid`)."""
        return self.text(source, node) if self.is_location(source) else self.invalid(source, node)

    def is_location(self, source: str) -> bool:
        """Whether the text starts with a datum the document declares or a system variable: a
        location if it reads (what follows its root is the expression reader's and checker's)."""
        root = _LOCATION_ROOT.fullmatch(source)
        ident = root.group(1) if root is not None else ""
        return ident in expr.SYSTEM_VARIABLES or (bool(ident) and self.declared(ident))

    def invalid(self, source: str, node: etree._Element) -> str | None:
        """`invalid("...")`: a location no `<data>` declares, or text that is no location. W3C
        raises error.execution when it is read or assigned (5.4, 5.9.2, 6.2, 6.4), where the
        typed datamodel would refuse the document: so it stays, as written, to fail when it
        runs (the checker's SG158 warning shows it)."""
        try:
            return expr.to_text(expr.Invalid(location=source.strip()))
        except ValueError as err:
            self.b.report(
                dg.SCXML_EXPRESSION, node, text=source[:200], why=str(err).splitlines()[-1]
            )
            return None

    def state_behaviour(self, node: etree._Element, vertex: RawElement) -> str | None:
        """onentry/onexit into entry/exit behaviours, the sg:call into the doActivity, timers
        remembered for the transitions. Returns the called behaviour's name."""
        entries: list[list[str]] = []
        call: str | None = None
        for block in children(node, "onentry"):
            entries.append([])
            for kid in block.iterchildren(tag=etree.Element):
                if in_sg(kid) and local(kid) == "call":
                    call = self.call(kid, vertex)
                elif in_scxml(kid) and local(kid) == "send" and self.timer(kid):
                    continue
                else:
                    entries[-1].extend(self.action(kid))
        exits: list[list[str]] = []
        for block in children(node, "onexit"):
            exits.append([])
            for kid in block.iterchildren(tag=etree.Element):
                if (
                    in_scxml(kid)
                    and local(kid) == "cancel"
                    and str(kid.get("sendid")) in self.timers
                ):
                    continue
                exits[-1].extend(self.action(kid))
        entry, exit_ = _blocked(entries), _blocked(exits)
        for feature, lines, source in (("entry", entry, "onentry"), ("exit", exit_, "onexit")):
            if lines:
                self.body(vertex, feature, lines, children(node, source)[0])
        return call

    def final_behaviour(self, node: etree._Element, vertex: RawElement) -> None:
        """A `<final>`'s onentry and onexit (swarmgen's extension of UML's final state) and its
        `<donedata>` `<param>`s as the entry's last action, `done(f = expr, ...)`."""
        for source, feature in (("onentry", "entry"), ("onexit", "exit")):
            blocks = children(node, source)
            lines = [
                line
                for block in blocks
                for kid in block.iterchildren(tag=etree.Element)
                for line in self.action(kid)
            ]
            if source == "onentry":
                lines += self.donedata(node)
            if lines:
                self.body(vertex, feature, lines, blocks[0] if blocks else node)

    def donedata(self, node: etree._Element) -> list[str]:
        """`<donedata>` with `<param name expr|location>`s: `done(name = expr, ...)`."""
        found: list[str] = []
        for block in children(node, "donedata"):
            contents = children(block, "content")
            if contents:  # the whole data: `done(expr)`
                value = self.content(contents[0])
                found += [f"done({value})"] if value is not None else []
                continue
            fields = []
            for param in children(block, "param"):
                given = (
                    param.get("expr") if param.get("expr") is not None else param.get("location")
                )
                if param.get("expr") is None:
                    value = self.location(str(given or ""), param)
                else:
                    value = self.text(str(given or ""), param)
                if value is not None:
                    fields.append(f"{param.get('name')} = {value}")
            found.append(f"done({', '.join(fields)})")
        return found

    def content(self, content: etree._Element) -> str | None:
        """A `<content>`'s value as the language's expression: its `expr`, or its inline text
        (JSON, else the text itself as a space-normalized string, W3C B.2.2); XML content is
        reported (None); swarmgen's own `$sg.content(e)` is read back as `e`."""
        text = content.get("expr")
        own = _OWN_CONTENT.fullmatch(text) if text is not None else None
        text = own.group(1) if own is not None else text
        if text is None and not len(content):  # inline: JSON, else the text itself
            inline = (content.text or "").strip()
            try:
                constant = literal(inline)
            except ExprUnsupported:
                constant = None
            if not isinstance(constant, bool | int | float | str) or constant is None:
                constant = " ".join(inline.split())
            text = expr.to_ecmascript(expr.Const(value=constant))
        value = self.text(text, content) if text is not None else None
        if value is None and len(content):
            why = "a <content> is an expression, not XML"
            self.b.report(dg.SCXML_UNSUPPORTED, content, element="content", why=why)
        return value

    def timer(self, node: etree._Element) -> bool:
        """`<send event="after.S.n" id=... delay="Nms"/>`: the emitted time-event pattern."""
        event, delay = str(node.get("event", "")), str(node.get("delay", ""))
        if not (event.startswith("after.") and node.get("id") == event and delay.endswith("ms")):
            return False
        if not delay[:-2].isdigit() or len(node):
            return False
        self.timers[event] = int(delay[:-2])
        return True

    def call(self, node: etree._Element, vertex: RawElement) -> str | None:
        """The `<sg:call>`: a doActivity calling the library operation, bindings as its body."""
        behaviour = str(node.get("behaviour", ""))
        operation = self.behaviours.get(behaviour)
        if operation is None:
            self.b.report(
                dg.SCXML_BAD_DOCUMENT, node, "unknown-target", attribute="behaviour", id=behaviour
            )
            return None
        lines = []
        for arg in children(node, "arg", sg_ns=True):
            if arg.get("implicit") == "true":
                continue
            value = self.text(str(arg.get("expr", "")), arg)
            if value is not None:
                lines.append(f"{arg.get('name')} = {value}")
        activity = self.b.make(
            "doActivity",
            "OpaqueBehavior",
            vertex,
            node,
            {"name": behaviour, "specification": operation},
        )
        if lines:
            self.b.make("body", "", activity, node, text="\n".join(lines))
        return behaviour

    def body(self, owner: RawElement, feature: str, lines: list[str], node: etree._Element) -> None:
        """An OpaqueBehavior (entry, exit, effect) with the lines as its body."""
        language = None
        if lines and lines[0].startswith("\0"):  # an sg:opaque block: language \0 text
            language, _, text = lines[0][1:].partition("\0")
            lines = [text]
        behaviour = self.b.make(feature, "OpaqueBehavior", owner, node)
        if language is not None:
            self.b.make("language", "", behaviour, node, text=language)
        self.b.make("body", "", behaviour, node, text="\n".join(lines))

    def action(self, node: etree._Element) -> list[str]:
        """The model-language lines of one executable-content element ([] when reported)."""
        tag = local(node)
        if in_sg(node) and tag == "opaque":
            return [f"\0{node.get('language', '')}\0{node.text or ''}"]
        if in_sg(node) and tag == "send":
            return self.event_action(node, "send", children(node, "param", sg_ns=True))
        if not in_scxml(node):
            return []  # foreign elements are ignored, as SCXML engines do
        if tag in ("assign", "data"):  # a `<data expr>` computed at the start: an assignment
            location, value = (
                str(node.get("location" if tag == "assign" else "id", "")),
                node.get("expr"),
            )
            if value is None and not len(node) and (node.text or "").strip():
                value = (node.text or "").strip()  # inline content: an expression's text
            if location in expr.SYSTEM_VARIABLES and tag == "data":
                why = "a system variable is no data id"
                self.b.report(dg.SCXML_UNSUPPORTED, node, element=tag, why=why)
                return []
            text = self.text(str(value), node) if value is not None else None
            if location in expr.SYSTEM_VARIABLES:  # read-only: error.execution when it runs
                return [f"{location} = {text}"] if text is not None else []
            if tag == "assign" and value is not None and not self.is_location(location):
                target = self.invalid(location, node)  # no datum: error.execution when it runs
                return [f"{target} = {text}"] if text is not None and target is not None else []
            if value is None or not location.isidentifier():
                self.b.report(
                    dg.SCXML_UNSUPPORTED,
                    node,
                    "attribute",
                    attribute="location",
                    value=location,
                    element=tag,
                    why="swarmgen assigns member data by name, with expr",
                )
            return [f"{self.name(location)} = {text}"] if text is not None else []
        if tag == "raise":
            return [f"raise {self.event_name(str(node.get('event', '')))}"]
        if tag == "send":
            return self.internal_send(node)
        if tag == "cancel":
            return self.cancel(node)
        if tag == "if":
            return self.conditional(node)
        if tag == "foreach":
            return self.loop(node)
        if tag == "log":  # `log "label", expr` (a log without expr logs its label)
            label = str(node.get("label", ""))
            value = self.text(str(node.get("expr")), node) if node.get("expr") else '""'
            if value is None:
                return []
            quoted = expr.to_text(expr.Const(value=label))
            return [f"log {quoted}, {value}" if label else f"log {value}"]
        self.b.report(
            dg.SCXML_UNSUPPORTED,
            node,
            element=tag,
            why=_NOT_IN_IR.get(tag, "not an action swarmgen reads"),
        )
        return []

    def conditional(self, node: etree._Element) -> list[str]:
        """`<if cond>` ... `<elseif cond/>` ... `<else/>` ... `</if>` as `if c then ... elif c
        then ... else ... end` (a cond that does not translate is reported, and the if too)."""
        cond = self.text(str(node.get("cond", "")), node)
        lines = [f"if {cond} then"]
        ok = cond is not None
        for kid in node.iterchildren(tag=etree.Element):
            if in_scxml(kid) and local(kid) == "elseif":
                cond = self.text(str(kid.get("cond", "")), kid)
                ok = ok and cond is not None
                lines.append(f"elif {cond} then")
            elif in_scxml(kid) and local(kid) == "else":
                lines.append("else")
            else:
                inner = self.action(kid)
                ok = ok and not (in_scxml(kid) and not inner and local(kid) != "log")
                lines += inner
        return [*lines, "end"] if ok else []

    def loop(self, node: etree._Element) -> list[str]:
        """`<foreach array item index>` as `for item, index in array do ... end`; an item or
        index no `<data>` declares is declared (W3C creates it)."""
        item, index = node.get("item"), node.get("index")
        names = [n for n in (item, index) if n is not None]
        if item is None or not all(n.isidentifier() and not n.startswith("__") for n in names):
            why = "item and index name data (identifiers)"
            self.b.report(dg.SCXML_UNSUPPORTED, node, element="foreach", why=why)
            return []
        array = self.text(str(node.get("array", "")), node)
        if array is None:
            return []
        for name in names:
            self.declare(name, node)
        targets = ", ".join(self.name(n) for n in names)
        lines = [f"for {targets} in {array} do"]
        for kid in node.iterchildren(tag=etree.Element):
            inner = self.action(kid)
            if in_scxml(kid) and not inner:
                return []  # reported
            lines += inner
        return [*lines, "end"]

    def effect(
        self, transition: RawElement, node: etree._Element, body: list[etree._Element]
    ) -> None:
        """A transition's executable content as its effect."""
        lines = [line for kid in body for line in self.action(kid)]
        if any(line.startswith("\0") for line in lines) and len(lines) > 1:
            self.b.report(
                dg.SCXML_UNSUPPORTED,
                node,
                element="sg:opaque",
                why="opaque code is read only as a transition's whole effect",
            )
            return
        if lines:
            self.body(transition, "effect", lines, node)

    def guard(
        self, transition: RawElement, node: etree._Element, cond: str | None, join: str | None
    ) -> list[str]:
        """The guard (an ownedRule); returns the In() states when the transition is a join."""
        if cond is None:
            return []
        try:
            pieces = (
                conjuncts(cond, self.name)
                if self.language != "swarmgen"
                else [expr.parse_expr(cond)]
            )
        except (ExprUnsupported, expr.ExprError, ValueError) as err:
            self.b.report(dg.SCXML_EXPRESSION, node, text=cond[:200], why=str(err).splitlines()[0])
            return []
        states = [p.state for p in pieces if isinstance(p, InState)] if join else []
        terms: list[expr.Expr] = [
            expr.InState(state=p.state) if isinstance(p, InState) else p
            for p in pieces
            if not isinstance(p, Marker) and not (join and isinstance(p, InState))
        ]
        if terms:
            whole = terms[0]
            for term in terms[1:]:
                whole = expr.Binary(op="and", left=whole, right=term)
            rule = self.b.make("ownedRule", "Constraint", transition, node)
            self.b.make(
                "specification", "LiteralString", rule, node, {"value": expr.to_text(whole)}
            )
            transition.attrs["guard"] = str(rule.id)
        return states

    def triggers(
        self, node: etree._Element, events: list[str], state: str, call: str | None
    ) -> list[tuple[str, str | None]] | None:
        """(trigger name, event id) per descriptor; [] for the triggerless forms."""
        found: list[tuple[str, str | None]] = []
        triggerless = {f"done.state.{state}", *([f"outcome.{state}"] if call else [])}
        for event in events:
            if event in triggerless and len(events) == 1:
                return []
            outcome = f"outcome.{state}."
            if call and event.startswith(outcome):
                found.append((event[len(outcome) :], None))
            elif event in self.timers:
                found.append((event, self.time_ref(self.timers[event])))
            elif event == "*":
                found.append(("*", self.any_ref()))
            elif event.removesuffix(".*") in ("error", "error.execution", "error.communication"):
                found.append((event.removesuffix(".*"), None))
            elif event.removesuffix(".*") in ("done", "done.state", "done.invoke") or (
                event.startswith(("done.state.", "done.invoke.")) and not event.endswith(".")
            ):
                found.append((event.removesuffix(".*"), None))  # another state's completion
            elif (
                event.split(".")[0] in ("done", "error", "outcome", "after") or event in triggerless
            ):
                why = "platform events (done.*, error.*) other than swarmgen's own patterns are not in the IR"
                self.b.report(dg.SCXML_UNSUPPORTED, node, "event", event=event, why=why)
                return None
            else:
                name = self.event_name(event.removesuffix(".*"))
                found.append((name, self.event_ref(name)))
        return found


# what swarmgen's emitter writes for a computed delay (docs/scxml.md)
_OWN_CONTENT = re.compile(r"\$sg\.content\((.*)\)", re.DOTALL)  # the emitter's (docs/scxml.md)


def _blocked(blocks: list[list[str]]) -> list[str]:
    """The lines of several `<onentry>` (`<onexit>`) elements: each a `block ... end` of its
    own when more than one holds actions (W3C: an error ends only its block), else as they are."""
    full = [lines for lines in blocks if lines]
    if len(full) <= 1:
        return full[0] if full else []
    return [line for lines in full for line in ("block", *lines, "end")]
