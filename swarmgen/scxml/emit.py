"""`emit`: Model -> SCXML documents, serialized from the lowered charts (see docs/scxml.md).

What SCXML has no element for (behaviour calls, swarm sends, library metadata) goes into the
`urn:swarmgen:scxml:1` extension namespace, which SCXML engines ignore.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable

from lxml import etree

from swarmgen import expr, generated
from swarmgen.chart import model as c
from swarmgen.chart.lower import lower
from swarmgen.ir.nodes import Model, Value
from swarmgen.names import identifier
from swarmgen.records import dataclass
from swarmgen.runtime.chart import FINALIZE_PREFIX, OUTCOME_PREFIX
from swarmgen.scxml.support import (
    CONTENT_SCRIPT,
    DELAY_SCRIPT,
    INVALID_CALL,
    INVALID_SCRIPT,
    META_SCRIPT,
    SPIN,
    STARTS_CALL,
    STARTS_SCRIPT,
    STEP_SCRIPT,
    SUPPORT_SCRIPT,
    TICK,
)

SCXML_NS = "http://www.w3.org/2005/07/scxml"
SG_NS = "urn:swarmgen:scxml:1"
_NSMAP = {None: SCXML_NS, "sg": SG_NS}
_STATE_TAGS = ("state", "parallel", "final", "history")
MAX_DEFAULT_LENGTH = 10_000


@dataclass(frozen=True)
class ScxmlDocument:
    """One SCXML document with the counts the CLI reports."""

    name: str  # file stem
    member: str | None  # member type name, if the document is a member's behaviour
    machine: str  # root machine name
    text: str
    states: int  # <state>, <parallel>, <final> and <history> elements
    transitions: int


def emit(model: Model) -> tuple[ScxmlDocument, ...]:
    """Lower the model and serialize each chart as an SCXML document."""
    return tuple(serialize(chart) for chart in lower(model))


def serialize(chart: c.Chart) -> ScxmlDocument:
    """One chart as an SCXML document (ECMAScript datamodel, swarmgen's extensions)."""
    scxml = _document(chart)
    what = f"member type {chart.member}" if chart.member else f"state machine {chart.machine}"
    comment = etree.Comment(_comment_text(f" {generated.header(chart.source, what, syntax='')} "))
    header = '<?xml version="1.0" encoding="UTF-8"?>\n' + etree.tostring(
        comment, encoding="unicode"
    )
    text = header + "\n" + etree.tostring(scxml, pretty_print=True, encoding="unicode")
    states = sum(1 for _ in scxml.iter(*(f"{{{SCXML_NS}}}{t}" for t in _STATE_TAGS)))
    transitions = sum(1 for _ in scxml.iter(f"{{{SCXML_NS}}}transition"))
    return ScxmlDocument(chart.name, chart.member, chart.machine, text, states, transitions)


def _document(chart: c.Chart) -> etree._Element:
    """The `<scxml>` element of a chart (an invoked chart's goes into its `<content>`)."""
    scxml = etree.Element(f"{{{SCXML_NS}}}scxml", nsmap=_NSMAP)  # type: ignore[arg-type]
    scxml.set("version", "1.0")
    scxml.set("datamodel", "ecmascript")
    scxml.set("name", chart.name)
    scxml.set(_sg("machine"), chart.machine)
    if chart.member is not None:
        scxml.set(_sg("member"), chart.member)
    if chart.initial:
        scxml.set("initial", " ".join(chart.initial))
    bounded = any(t.bounded for n in chart.walk() for t in n.transitions)
    writer = _Writer({d.name: d.id for d in chart.data}, {d.id: d for d in chart.data}, bounded)
    writer.datamodel(scxml, chart.data)
    delays = any(_computed_delay(a) for n in chart.walk() for a in c.flat(_actions_of(n)))
    meta = any(_reads_event_fields(e) for n in chart.walk() for e in _expressions_of(n))
    script = _sub(scxml, "script")
    for node in chart.children:
        writer.node(scxml, node)
    # `$sg.invalid` and `$sg.startswith` may stand in any expression the writer wrote
    written = [v for e in scxml.iter() for v in e.attrib.values()]
    invalid = any(INVALID_CALL in v for v in written)
    starts = any(STARTS_CALL in v for v in written)
    script.text = (
        SUPPORT_SCRIPT
        + (STEP_SCRIPT if bounded else "")
        + (DELAY_SCRIPT if delays else "")
        + (META_SCRIPT if meta else "")
        + (CONTENT_SCRIPT if _sends_content(chart) else "")
        + (INVALID_SCRIPT if invalid else "")
        + (STARTS_SCRIPT if starts else "")
    )
    _metadata(scxml, chart)
    return scxml


def _comment_text(text: str) -> str:
    """XML comments may not contain `--` (a file or member named `a--b` must not crash)."""
    return re.sub(r"-(?=-)", "- ", text)


def _sg(tag: str) -> str:
    return f"{{{SG_NS}}}{tag}"


def _sub(parent: etree._Element, tag: str, attrs: dict[str, str] | None = None) -> etree._Element:
    element = etree.SubElement(parent, tag if tag.startswith("{") else f"{{{SCXML_NS}}}{tag}")
    for key, value in (attrs or {}).items():
        element.set(key, value)
    return element


def js_value(value: Value) -> str:
    """An ECMAScript literal for a default value (through the expression AST: never raw text)."""
    if isinstance(value, str) and len(value) > MAX_DEFAULT_LENGTH:
        value = None
    return expr.to_ecmascript(expr.parse_expr(_literal_text(value)))


def js_literal(value: object) -> str:
    """An ECMAScript literal for a JSON-like value: scalars, objects for data types, arrays
    for sequences."""
    if isinstance(value, dict):
        items = ", ".join(f"{expr.js_string(str(k))}: {js_literal(v)}" for k, v in value.items())
        return "{" + items + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(js_literal(v) for v in value) + "]"
    scalar = value if isinstance(value, bool | int | float | str) else None
    return js_value(scalar)


def _literal_text(value: Value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value) if value >= 0 else f"-{-value!r}"
    return expr.to_text(expr.Const(value=value))


@dataclass(frozen=True)
class _Writer:
    data_ids: dict[str, str]  # model name of member data -> data id
    data: dict[str, c.DataItem]  # data id -> item
    step_bound: bool = False  # the document has bounded transitions (STEP_SCRIPT)

    def js(self, e: expr.Expr | c.FieldDefault) -> str:
        if isinstance(e, c.FieldDefault):
            return js_literal(e.value)
        name: Callable[[str], str] = lambda n: self.data_ids.get(n) or identifier(n)  # noqa: E731
        return expr.to_ecmascript(e, name)

    def datamodel(self, scxml: etree._Element, data: tuple[c.DataItem, ...]) -> None:
        if not data:
            return
        datamodel = _sub(scxml, "datamodel")
        for item in data:
            attrs = {"id": item.id, "expr": js_literal(item.initial)}
            if item.name != item.id:
                attrs[_sg("name")] = item.name
            if item.type:
                attrs[_sg("type")] = item.type
            _sub(datamodel, "data", attrs)

    def node(self, parent: etree._Element, node: c.Node) -> None:
        element = _sub(parent, node.kind, {"id": node.id})
        if node.kind == "history":
            element.set("type", node.history or "shallow")
        for key, value in (
            ("name", node.name),
            ("submachine", node.submachine),
            ("pseudostate", node.pseudostate),
            ("region", node.region),
        ):
            if value:
                element.set(_sg(key), value)
        if node.kind == "history":
            if node.initial is not None:
                self.transition(element, node.initial, selected=False)
            return
        self.onentry(element, node)
        self.onexit(element, node)
        if node.donedata:  # a final state's: the fields of its done.state event
            self.params(_sub(element, "donedata"), node.donedata, "param")
        elif node.donecontent is not None:  # or its whole data (as `raise e(value)`'s)
            value = f"$sg.content({self.js(node.donecontent)})"  # CONTENT_SCRIPT
            _sub(_sub(element, "donedata"), "content", {"expr": value})
        if node.call is not None:
            self.finalize(element, node.id, node.call)
        for invoke in node.invokes:
            self.invoke(element, invoke)
        for transition in node.transitions:
            self.transition(element, transition)
        if node.initial is not None:
            self.transition(_sub(element, "initial"), node.initial, selected=False)
        for child in node.children:
            self.node(element, child)

    def onentry(self, element: etree._Element, node: c.Node) -> None:
        """The model's entry actions, then the behaviour and timers in a block of their own
        (an error in the model's actions ends only its block, never the timers)."""
        for block in _blocks(node.onentry):
            self.actions(_sub(element, "onentry"), block)
        if not (node.call or node.timers):
            return
        onentry = _sub(element, "onentry")
        if node.call is not None:
            self.call(onentry, node.call)
        for timer in node.timers:
            _sub(
                onentry,
                "send",
                {"event": timer.event, "id": timer.event, "delay": f"{timer.delay_ms}ms"},
            )

    def onexit(self, element: etree._Element, node: c.Node) -> None:
        for block in _blocks(node.onexit):
            self.actions(_sub(element, "onexit"), block)
        if node.timers:
            onexit = _sub(element, "onexit")
            for timer in node.timers:
                _sub(onexit, "cancel", {"sendid": timer.event})

    def finalize(self, element: etree._Element, node_id: str, call: c.Call) -> None:
        """The behaviour ended (`done.invoke.<id>.<outcome>` from the host): its outputs are
        written first, then the internal event `outcome.<id>.<outcome>` is raised, so the
        state's guards see the new values (W3C `<finalize>` semantics; docs/semantics.md).
        One transition per declared outcome (`<raise>` names its event statically), and one
        for any other outcome, which only writes the outputs."""
        prefix = f"{FINALIZE_PREFIX}{node_id}"
        writes = [
            (
                location,
                f"$sg.value(_event.data, {expr.js_string(output)}, "
                f"{js_literal(self.data[location].zero)})",
            )
            for output, location in call.results
        ]
        for outcome in (*call.outcomes, None):
            event = prefix if outcome is None else f"{prefix}.{outcome}"
            transition = _sub(element, "transition", {"event": event})
            if self.step_bound:
                transition.set("cond", TICK)
            transition.set(_sg("finalize"), call.behaviour)
            for location, value in writes:
                _sub(transition, "assign", {"location": location, "expr": value})
            if outcome is not None:
                _sub(transition, "raise", {"event": f"{OUTCOME_PREFIX}{node_id}.{outcome}"})

    def invoke(self, element: etree._Element, invoke: c.Invoke) -> None:
        """W3C `<invoke>` of an SCXML session: the child's own document in `<content>`."""
        attrs = {}
        if invoke.kind_expr is not None:
            attrs["typeexpr"] = self.js(invoke.kind_expr)
        else:
            attrs["type"] = invoke.kind or "http://www.w3.org/TR/scxml/"
        if invoke.invokeid is not None:
            attrs["id"] = invoke.invokeid
        if invoke.idlocation is not None:
            attrs["idlocation"] = invoke.idlocation
        if invoke.autoforward:
            attrs["autoforward"] = "true"
        written = _sub(element, "invoke", attrs)
        self.params(written, invoke.params, "param")
        _sub(written, "content").append(_document(invoke.chart))
        if invoke.finalize:
            self.actions(_sub(written, "finalize"), invoke.finalize)

    def call(self, onentry: etree._Element, call: c.Call) -> None:
        element = _sub(onentry, _sg("call"), {"behaviour": call.behaviour, "type": call.kind})
        for arg in call.args:
            attrs = {"name": arg.name, "expr": self.js(arg.value)}
            if arg.implicit:
                attrs["implicit"] = "true"
            _sub(element, _sg("arg"), attrs)
        for name, location in call.results:
            _sub(element, _sg("result"), {"name": name, "location": location})

    def transition(
        self, parent: etree._Element, transition: c.Transition, *, selected: bool = True
    ) -> None:
        """`selected=False`: an initial or history default transition (no cond allowed)."""
        attrs: dict[str, str] = {}
        if transition.events:
            attrs["event"] = " ".join(transition.events)
        conds = [f"In('{s}')" for s in transition.in_states]
        if transition.cond is not None:
            conds.append(self.js(transition.cond))
        if self.step_bound and selected:
            conds = [TICK, *conds, *([SPIN] if transition.bounded else [])]
        if conds:
            attrs["cond"] = " && ".join(conds)
        if transition.targets:
            attrs["target"] = " ".join(transition.targets)
        if transition.internal:
            attrs["type"] = "internal"
        element = _sub(parent, "transition", attrs)
        if transition.name:
            element.set(_sg("name"), transition.name)
        if transition.join:
            element.set(_sg("join"), transition.join)
        self.actions(element, transition.actions)

    def actions(self, parent: etree._Element, actions: tuple[c.Action, ...]) -> None:
        for action in actions:
            if isinstance(action, c.Assign):
                _sub(parent, "assign", {"location": action.location, "expr": self.js(action.value)})
            elif isinstance(action, c.Raise) and (
                action.delay is not None
                or action.target is not None
                or action.via is not None
                or action.into is not None
                or action.named is not None
                or action.content is not None
            ):
                send = self.delayed(parent, action, action.delay)
                self.params(send, action.params, "param")
                if action.content is not None:  # the event's whole data (W3C 6.2.4)
                    value = f"$sg.content({self.js(action.content)})"  # CONTENT_SCRIPT
                    _sub(send, "content", {"expr": value})
            elif isinstance(action, c.Raise) and not action.params:
                _sub(parent, "raise", {"event": action.event})
            elif isinstance(action, c.Raise):
                self.params(
                    _sub(parent, "send", {"event": action.event, "target": "#_internal"}),
                    action.params,
                    "param",
                )
            elif isinstance(action, c.Send):
                send = _sub(parent, _sg("send"), {"event": action.event, "scope": "swarm"})
                self.params(send, action.params, _sg("param"))
            elif isinstance(action, c.Cancel) and action.expr is not None:
                _sub(parent, "cancel", {"sendidexpr": self.js(action.expr)})
            elif isinstance(action, c.Cancel):
                _sub(parent, "cancel", {"sendid": str(action.sendid)})
            elif isinstance(action, c.Block):  # only at the top of entry/exit (the check)
                self.actions(parent, action.actions)
            elif isinstance(action, c.Log):
                attrs = {"label": action.label} if action.label else {}
                _sub(parent, "log", {**attrs, "expr": self.js(action.value)})
            elif isinstance(action, c.If):
                self.conditional(parent, action)
            elif isinstance(action, c.ForEach):
                attrs = {"array": self.js(action.array), "item": action.item}
                if action.index is not None:
                    attrs["index"] = action.index
                self.actions(_sub(parent, "foreach", attrs), action.actions)
            else:
                _sub(parent, _sg("opaque"), {"language": action.language}).text = action.text

    def conditional(self, parent: etree._Element, action: c.If) -> None:
        """`<if cond>` actions `<elseif cond/>` actions `<else/>` actions `</if>`."""
        element: etree._Element | None = None
        for cond, actions in action.branches:
            if element is None:
                element = _sub(
                    parent, "if", {"cond": self.js(cond) if cond is not None else "true"}
                )
            elif cond is None:
                _sub(element, "else")
            else:
                _sub(element, "elseif", {"cond": self.js(cond)})
            self.actions(element, actions)

    def delayed(
        self, parent: etree._Element, action: c.Raise, delay: c.Delay | None
    ) -> etree._Element:
        """`raise e [to t] after ...`: a `<send>` (without target: the session's external
        queue) with a literal `delay` when the delay is a constant, else a `delayexpr`; a
        computed name is its `eventexpr`."""
        if action.named is not None:
            attrs = {"eventexpr": self.js(action.named)}
        else:
            attrs = {"event": action.event}
        target = action.target
        if isinstance(target, expr.Const) and isinstance(target.value, str):
            attrs["target"] = target.value
        elif target is not None:
            attrs["targetexpr"] = self.js(target)
        elif delay is None:  # `via`/`into`/a computed name or value alone: as `raise e(...)`
            attrs["target"] = "#_internal"
        via = action.via
        if isinstance(via, expr.Const) and isinstance(via.value, str):
            attrs["type"] = via.value
        elif via is not None:
            attrs["typeexpr"] = self.js(via)
        if action.into is not None:
            attrs["idlocation"] = action.into
        if delay is None:
            return _sub(parent, "send", attrs)
        amount = delay.amount
        literal = _literal_ms(delay)
        if literal is not None:  # Qt SCXML reads a literal delay in whole units only
            attrs["delay"] = f"{literal}ms"
        elif delay.unit:
            scale = "1000" if delay.unit == "s" else "1"
            attrs["delayexpr"] = f"$sg.delay({self.js(amount)}, {scale})"
        else:
            attrs["delayexpr"] = f"$sg.duration({self.js(amount)})"
        if action.sendid is not None:
            attrs["id"] = action.sendid
        return _sub(parent, "send", attrs)

    def params(self, send: etree._Element, params: tuple[c.Param, ...], tag: str) -> None:
        for param in params:
            _sub(send, tag, {"name": param.name, "expr": self.js(param.value)})


def _metadata(scxml: etree._Element, chart: c.Chart) -> None:
    """Member, library and events in the swarmgen namespace (ignored by SCXML engines)."""
    if chart.member is not None:
        member = _sub(scxml, _sg("member"), {"name": chart.member})
        if chart.role:
            member.set("role", chart.role)
        for part in chart.hardware:
            _sub(
                member,
                _sg("hardware"),
                {"part": part.part, "type": part.type, "count": str(part.count)},
            )
    if chart.behaviours:
        library = _sub(scxml, _sg("library"))
        for behaviour in chart.behaviours:
            _behaviour(library, behaviour)
    if chart.events:
        declared = _sub(scxml, _sg("events"))
        for event in chart.events:
            element = _sub(declared, _sg("event"), {"name": event.name, "id": event.ident})
            for key, value in (("sender", event.sender), ("scope", event.scope)):
                if value:
                    element.set(key, value)
            defaults = dict(event.defaults)
            for name, type_ in event.fields:
                field = _sub(element, _sg("field"), {"name": name})
                if type_:
                    field.set("type", type_)
                if name in defaults:  # JSON: what a host fills in when a sender leaves it out
                    field.set("default", json.dumps(defaults[name], sort_keys=True))


def _behaviour(library: etree._Element, behaviour: c.BehaviourInfo) -> None:
    element = _sub(library, _sg("behaviour"), {"name": behaviour.name, "type": behaviour.kind})
    if behaviour.library:
        element.set("library", behaviour.library)
    element.set("outcomes", " ".join(behaviour.outcomes))
    if behaviour.requires:
        element.set("requires", " ".join(behaviour.requires))
    for key, value in (
        ("rosKind", behaviour.ros_kind),
        ("rosName", behaviour.ros_name),
        ("rosType", behaviour.ros_type),
    ):
        if value:
            element.set(key, value)
    for tag, params in (("input", behaviour.inputs), ("output", behaviour.outputs)):
        for name, type_ in params:
            _sub(element, _sg(tag), {"name": name, **({"type": type_} if type_ else {})})


def _literal_ms(delay: c.Delay) -> int | None:
    """A constant delay as whole milliseconds, else None (the support script computes it)."""
    value = delay.amount.value if isinstance(delay.amount, expr.Const) else None
    if isinstance(value, bool) or not isinstance(value, int | float) or not delay.unit:
        return None
    ms = value * (1000 if delay.unit == "s" else 1)
    return int(ms) if ms >= 0 and ms == int(ms) else None


def _sends_content(chart: c.Chart) -> bool:
    """Whether some `raise e(value)` or `done(value)` sends a value as its event's data
    (`CONTENT_SCRIPT`)."""
    return any(n.donecontent is not None for n in chart.walk()) or any(
        isinstance(a, c.Raise) and a.content is not None
        for n in chart.walk()
        for a in c.flat(_actions_of(n))
    )


def _computed_delay(action: c.Action) -> bool:
    """Whether the action is a delayed raise whose delay the support script computes."""
    return (
        isinstance(action, c.Raise)
        and action.delay is not None
        and _literal_ms(action.delay) is None
    )


def _actions_of(node: c.Node) -> tuple[c.Action, ...]:
    """The actions of a node: entry, exit, its initial transition's and its transitions'."""
    found = [*node.onentry, *node.onexit]
    if node.initial is not None:
        found += node.initial.actions
    for transition in node.transitions:
        found += transition.actions
    return tuple(found)


def _expressions_of(node: c.Node) -> list[expr.Expr]:
    """Every expression of a node: conds, action values and conditions, call arguments."""
    found = [t.cond for t in node.transitions if t.cond is not None]
    for action in c.flat(_actions_of(node)):
        if isinstance(action, c.Assign):
            found.append(action.value)
        elif isinstance(action, c.If):
            found += [cond for cond, _ in action.branches if cond is not None]
        elif isinstance(action, c.ForEach):
            found.append(action.array)
        elif isinstance(action, c.Log):
            found.append(action.value)
        elif isinstance(action, c.Raise | c.Send):
            found += [p.value for p in action.params if not isinstance(p.value, c.FieldDefault)]
            if isinstance(action, c.Raise):
                computed = (action.target, action.via, action.named, action.content)
                found += [e for e in computed if e is not None]
    if node.call is not None:
        found += [a.value for a in node.call.args]
    return found


def _reads_event_fields(e: expr.Expr) -> bool:
    """Whether the expression reads a field of `_event` (`$sg.meta` in the document)."""
    return any(
        isinstance(s, expr.Attr) and isinstance(s.obj, expr.System) and s.obj.name == "_event"
        for s in expr.walk(e)
    )


def _blocks(actions: tuple[c.Action, ...]) -> list[tuple[c.Action, ...]]:
    """Entry or exit actions as the `<onentry>`/`<onexit>` elements that hold them: the
    actions between blocks in one, each `block ... end` in one of its own."""
    found: list[tuple[c.Action, ...]] = []
    pending: list[c.Action] = []
    for action in actions:
        if isinstance(action, c.Block):
            if pending:
                found.append(tuple(pending))
                pending = []
            found.append(action.actions)
        else:
            pending.append(action)
    if pending:
        found.append(tuple(pending))
    return found
