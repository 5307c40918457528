"""The CPSwarm code generator's SCXML dialect (docs/scxml-input.md, "CPSwarm dialect").

A CPSwarm state calls a ROS interface by convention: `<datamodel><data id="invoke">` holds a
`<rosaction>`, `<rosservice>` or `<rosmonitor>` and `<invoke type="ROS_ACTION|ROS_SERVICE|
ROS_MONITOR"/>` says which. `lower` rewrites those states, in place and before the SCXML reader
looks at the document, into swarmgen's own extension (docs/scxml.md): an `<sg:behaviour>` per
state with the profile's rosKind/rosName/rosType, an `<sg:call>` in the state's `<onentry>`,
outcome transitions as `outcome.S.o`, monitored topics as events raised by a topic behaviour.
Everything the reader does afterwards is the plain SCXML path, so nothing downstream knows the
dialect existed. Each rule the dialect leaves open is a located warning or note.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Iterator

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.frontend.scxml_expr import ExprUnsupported, literal
from swarmgen.frontend.scxml_raw import SG_NS, Builder, children, in_scxml, local

INVOKE_TYPES = {"ROS_ACTION": "rosaction", "ROS_SERVICE": "rosservice", "ROS_MONITOR": "rosmonitor"}
OUTCOMES = ("succeeded", "aborted", "preempted")
LIBRARY = "CPSwarm"  # the «BehaviorLibrary» that holds one behaviour per calling state
BEHAVIOUR_KIND = "SwarmFunction"
# payload -> (type element, request element, answer element, rosKind)
_SHAPES = {
    "rosaction": ("action", "goal", "result", "action"),
    "rosservice": ("srv", "request", "response", "service"),
}
_REQUEST_POLICIES = ("empty", "fixed", "callback", "userdata")
_ANSWER_POLICIES = ("empty", "callback", "userdata")
_LEGACY_POLICIES = {"slot": "userdata", "object": "fixed"}  # 2019 and the wiki's spellings
_MIDDLE = {"action": "action", "service": "srv", "topic": "msg"}
# The 2019 files name types without their package: the packages those names came from.
DEFAULT_PACKAGES = {
    "service": {"Empty": "std_srvs", "Trigger": "std_srvs", "SetBool": "std_srvs"},
    "topic": {"SimpleEvent": "swarmros", "Bool": "std_msgs", "Empty": "std_msgs"},
}
DEFAULT_PACKAGE = "cpswarm_msgs"  # every other CPSwarm action, service and message


def lower(b: Builder, root: etree._Element) -> None:
    """Rewrite the dialect's states of the document (nothing when it has none)."""
    _Dialect(b, root).lower()


class _Dialect:
    def __init__(self, b: Builder, root: etree._Element) -> None:
        self.b, self.root = b, root
        self.ns = etree.QName(root).namespace
        self.library: etree._Element | None = None
        self.calls: set[str] = set()  # ids of the states that call a ROS action or service
        self.declare: dict[str, etree._Element] = {}  # member data to declare -> where
        self.events: dict[str, etree._Element] = {}  # monitored events -> the monitor

    def lower(self) -> None:
        states = [n for n in self.root.iter(tag=etree.Element) if _is_state(n)]
        dialect = [s for s in states if _invokes(s) or _payload_data(s)]
        for state in dialect:
            self.state(state)
        if dialect:
            self.propagate_outcomes(states)
            self.declare_data()
            self.declare_events()

    # --- one state -------------------------------------------------------------------------
    def state(self, node: etree._Element) -> None:
        ident = str(node.get("id", ""))
        invokes, datas = _invokes(node), _payload_data(node)
        payloads = [kid for data in datas for kid in children(data)]
        if len(invokes) > 1:
            self.b.report(dg.CPSWARM_INVOKE, invokes[1], "several", state=ident, count=len(invokes))
        elif invokes and not payloads:
            kind = str(invokes[0].get("type"))
            self.b.report(
                dg.CPSWARM_INVOKE, invokes[0], state=ident, type=kind, payload=INVOKE_TYPES[kind]
            )
        elif payloads and not invokes:
            expected = {v: k for k, v in INVOKE_TYPES.items()}.get(local(payloads[0]), "ROS_ACTION")
            self.b.report(
                dg.CPSWARM_INVOKE,
                payloads[0],
                "no-invoke",
                state=ident,
                payload=local(payloads[0]),
                type=expected,
            )
        elif invokes:
            self.payload(node, ident, invokes[0], payloads[0])
        self.ignored_data(node)
        for element in [*invokes, *datas]:
            _remove(element)
        for block in children(node, "datamodel"):
            if not len(block):
                _remove(block)

    def payload(
        self, node: etree._Element, ident: str, invoke: etree._Element, payload: etree._Element
    ) -> None:
        kind = str(invoke.get("type"))
        if local(payload) != INVOKE_TYPES[kind]:
            self.b.report(
                dg.CPSWARM_INVOKE,
                payload,
                "mismatch",
                type=kind,
                state=ident,
                payload=local(payload),
            )
        elif kind == "ROS_MONITOR":
            self.monitor(node, ident, payload)
        else:
            self.call(node, ident, payload)

    def ignored_data(self, node: etree._Element) -> None:
        """The state's other `<data>` (`adf`, the empty `input`): reported, then left out."""
        for block in children(node, "datamodel"):
            for data in children(block, "data"):
                if data.get("id") == "invoke":
                    continue
                why = (
                    "the ADF function's C++ skeleton is not generated (swarmgen reads no ADF file)"
                    if data.get("id") == "adf"
                    else "a CPSwarm state's datamodel holds only its invoke payload"
                )
                self.b.report(dg.CPSWARM_NOTE, data, "ignored", id=data.get("id"), why=why)
                _remove(data)

    # --- rosaction / rosservice -------------------------------------------------------------
    def call(self, node: etree._Element, ident: str, payload: etree._Element) -> None:
        """A ROS action or service: a behaviour of that interface, called by the state."""
        type_tag, request_tag, answer_tag, ros_kind = _SHAPES[local(payload)]
        name, type_node = self.part(payload, "name"), self.part(payload, type_tag)
        if name is None or type_node is None:
            return
        request, answer = _child(payload, request_tag), _child(payload, answer_tag)
        request_policy = self.policy(request, request_tag, _REQUEST_POLICIES, ident)
        answer_policy = self.policy(answer, answer_tag, _ANSWER_POLICIES, ident)
        if request_policy is None or answer_policy is None:
            return
        args = self.fixed(request) if request_policy == "fixed" else []
        inputs = _vars(request) if request_policy == "userdata" else []
        outputs = _vars(answer) if answer_policy == "userdata" else []
        ros_type = self.ros_type(type_node, ros_kind)
        behaviour = self.behaviour(payload, ros_kind, _text(name), ros_type)
        for var in inputs:
            self.sub(behaviour, f"{{{SG_NS}}}input", var, name=_text(var))
        for arg, _ in args:
            self.sub(behaviour, f"{{{SG_NS}}}input", request, name=arg)
        for var in outputs:
            self.sub(behaviour, f"{{{SG_NS}}}output", var, name=_text(var))
        bound, assigns = self.mappings(payload, ident, inputs, outputs)
        for var in inputs:
            if _text(var) not in {x for x, _ in bound}:
                self.declare.setdefault(_text(var), var)
        call = self.call_element(node, ident)
        for arg, value in [*args, *bound]:
            self.sub(call, f"{{{SG_NS}}}arg", node, name=arg, expr=value)
        self.calls.add(ident)
        self.outcome_transitions(node, ident, assigns)

    def fixed(self, request: etree._Element | None) -> list[tuple[str, str]]:
        """`<param>`s: positional goal/request values, bound to the inputs arg1, arg2, ..."""
        params = children(request, "param") if request is not None else []
        return [(f"arg{n}", _value(_text(p))) for n, p in enumerate(params, 1)]

    def mappings(
        self,
        payload: etree._Element,
        ident: str,
        inputs: list[etree._Element],
        outputs: list[etree._Element],
    ) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
        """`<map><x/><y/></map>` (SMACH's remapping: the state's key x is member data y): an
        input x bound to y, an output x assigned to y on the outcome. (Identity maps: nothing.)"""
        names_in, names_out = {_text(v) for v in inputs}, {_text(v) for v in outputs}
        bound: list[tuple[str, str]] = []
        assigns: list[tuple[str, str]] = []
        data = payload.getparent()
        for block in children(data, "mappings") if data is not None else []:
            for item in children(block, "map"):
                x, y = _text(_child(item, "x")), _text(_child(item, "y"))
                if x not in names_in | names_out:
                    self.b.report(dg.CPSWARM_CAVEAT, item, "mapping", name=x, state=ident)
                elif x != y:
                    (bound if x in names_in else assigns).append((x, y))
                    self.declare.setdefault(y, item)
        return bound, assigns

    def outcome_transitions(
        self, node: etree._Element, ident: str, assigns: list[tuple[str, str]]
    ) -> None:
        """`event="succeeded"` on the calling state is the outcome of its behaviour."""
        for transition in children(node, "transition"):
            events = str(transition.get("event", "")).split()
            if not any(e in OUTCOMES for e in events):
                continue
            renamed = [f"outcome.{ident}.{e}" if e in OUTCOMES else e for e in events]
            transition.set("event", " ".join(renamed))
            for position, (x, y) in enumerate(assigns):
                assign = self.element("assign", transition, location=y, expr=x)
                transition.remove(assign)
                transition.insert(position, assign)

    # --- rosmonitor -------------------------------------------------------------------------
    def monitor(self, node: etree._Element, ident: str, payload: etree._Element) -> None:
        """A monitored topic: a topic behaviour waiting for the next message, whose outcome
        raises the event the enclosing parallel reacts to, and waits again."""
        topic, msg = self.part(payload, "topic"), self.part(payload, "msg")
        if topic is None or msg is None:
            return
        self.behaviour(payload, "topic", _text(topic), self.ros_type(msg, "topic"))
        event, why = self.monitor_event(node, _text(topic))
        self.b.report(dg.CPSWARM_NOTE, topic, "monitor", topic=_text(topic), event=event, why=why)
        self.events.setdefault(event, payload)
        self.call_element(node, ident)
        again = self.element("transition", node, event=f"outcome.{ident}.succeeded", target=ident)
        self.element("raise", again, event=event)
        # aborted comes only from a timeout (behaviours.<key>.timeout_s, 0 by default): wait again
        self.element("transition", node, event=f"outcome.{ident}.aborted", target=ident)

    def monitor_event(self, node: etree._Element, topic: str) -> tuple[str, str]:
        """The event of a monitored topic: the one of the parallel's events that the topic's
        last segment names in camelCase (`mission_start` -> missionStart), else the parallel's
        only event when the state is its only monitor, else that camelCase name."""
        words = topic.rstrip("/").rsplit("/", 1)[-1].split("_")
        camel = words[0] + "".join(w[:1].upper() + w[1:] for w in words[1:])
        parent = node.getparent()
        if parent is None or local(parent) != "parallel":
            return camel, "the topic's last segment; the state is in no <parallel>"
        events = [
            e
            for t in children(parent, "transition")
            for e in str(t.get("event", "")).split()
            if e not in OUTCOMES
        ]
        monitors = [s for s in children(parent, "state") if _monitor_of(s)]
        if camel in events:
            return camel, "the <parallel>'s event its last segment names"
        if len(events) == 1 and len(monitors) == 1:
            return events[0], "the <parallel>'s only event, and this its only monitor"
        return camel, "the topic's last segment; no transition of the <parallel> takes it"

    # --- outcomes of containers -------------------------------------------------------------
    def propagate_outcomes(self, states: list[etree._Element]) -> None:
        """SMACH's rule: an outcome a child state has no transition for ends its container
        with that outcome. A container's `event="succeeded"` therefore becomes a transition of
        every calling state inside it that does not take that outcome itself."""
        moves = []
        for container in states:
            if str(container.get("id")) in self.calls:
                continue
            for transition in children(container, "transition"):
                for outcome in str(transition.get("event", "")).split():
                    if outcome in OUTCOMES:
                        found = list(self.outcome_sources(container, outcome))
                        moves.append((container, transition, outcome, found))
        for container, transition, outcome, found in moves:
            if not found:
                state = container.get("id")
                self.b.report(
                    dg.CPSWARM_CAVEAT, transition, "outcome", state=state, outcome=outcome
                )
            for source in found:
                moved = copy.deepcopy(transition)
                moved.set("event", f"outcome.{source.get('id')}.{outcome}")
                moved.sourceline = transition.sourceline
                source.append(moved)
            _remove(transition)

    def outcome_sources(self, node: etree._Element, outcome: str) -> Iterator[etree._Element]:
        for kid in children(node, "state", "parallel"):
            ident = str(kid.get("id", ""))
            taken = {outcome, f"outcome.{ident}.{outcome}"}
            if any(
                taken & set(str(t.get("event", "")).split()) for t in children(kid, "transition")
            ):
                continue
            if ident in self.calls:
                yield kid
            else:
                yield from self.outcome_sources(kid, outcome)

    # --- declarations -----------------------------------------------------------------------
    def declare_data(self) -> None:
        """Goal/request vars and mapping targets the document does not declare: member data."""
        blocks = children(self.root, "datamodel")
        known = {str(d.get("id")) for block in blocks for d in children(block, "data")}
        block = blocks[0] if blocks else self.element("datamodel", self.root)
        for name, where in self.declare.items():
            if name not in known:
                self.b.report(dg.CPSWARM_NOTE, where, "declared", name=name)
                self.element("data", block, id=name)
        if not len(block):
            _remove(block)

    def declare_events(self) -> None:
        if not self.events:
            return
        block = etree.SubElement(self.root, f"{{{SG_NS}}}events")
        for name, where in self.events.items():
            self.sub(block, f"{{{SG_NS}}}event", where, name=name)

    # --- helpers ----------------------------------------------------------------------------
    def behaviour(
        self, payload: etree._Element, ros_kind: str, ros_name: str, ros_type: str
    ) -> etree._Element:
        if self.library is None:
            self.library = etree.SubElement(self.root, f"{{{SG_NS}}}library")
        return self.sub(
            self.library,
            f"{{{SG_NS}}}behaviour",
            payload,
            library=LIBRARY,
            name=_state_id(payload),
            type=BEHAVIOUR_KIND,
            rosKind=ros_kind,
            rosName=ros_name,
            rosType=ros_type,
        )

    def call_element(self, node: etree._Element, ident: str) -> etree._Element:
        entry = next(iter(children(node, "onentry")), None)
        if entry is None:
            entry = self.element("onentry", node)
            node.remove(entry)
            node.insert(0, entry)
        return self.sub(entry, f"{{{SG_NS}}}call", node, behaviour=ident)

    def ros_type(self, node: etree._Element, ros_kind: str) -> str:
        """`pkg/Name`, `pkg/middle/Name`, 2019's `pkg.srv.Name` and bare `Name` as rosType."""
        text, middle = _text(node), _MIDDLE[ros_kind]
        if "." in text and "/" not in text:
            read = text.replace(".", "/")
            self.b.report(dg.CPSWARM_CAVEAT, node, "legacy", what=f"'{text}'", read=f"'{read}'")
            text = read
        parts = text.split("/")
        if len(parts) == 1 and text:
            package = DEFAULT_PACKAGES.get(ros_kind, {}).get(text, DEFAULT_PACKAGE)
            read = f"{package}/{middle}/{text}"
            self.b.report(dg.CPSWARM_CAVEAT, node, what=f"<{local(node)}>", value=text, read=read)
            return read
        if len(parts) == 2:
            return f"{parts[0]}/{middle}/{parts[1]}"
        return text  # pkg/middle/Name, or a form the ROS check reports (SG302)

    def policy(
        self, node: etree._Element | None, tag: str, allowed: tuple[str, ...], state: str
    ) -> str | None:
        """A goal/request/result/response's type (None: reported); absent means empty."""
        if node is None:
            return "empty"
        value = node.get("type")
        if value is None and node.get("empty") is not None:  # 2019: <request empty="true">
            value = "empty" if node.get("empty") == "true" else _implied(node)
            what = f'<{tag} empty="{node.get("empty")}">'
            self.b.report(dg.CPSWARM_CAVEAT, node, "legacy", what=what, read=f'type="{value}"')
        elif value in _LEGACY_POLICIES:
            read = _LEGACY_POLICIES[value]
            what = f'<{tag} type="{value}">'
            self.b.report(dg.CPSWARM_CAVEAT, node, "legacy", what=what, read=f'type="{read}"')
            value = read
        value = value or "empty"
        if value not in allowed:
            self.b.report(
                dg.CPSWARM_INVOKE,
                node,
                "policy",
                element=tag,
                value=value,
                allowed=", ".join(allowed),
            )
            return None
        if value == "callback":
            self.b.report(dg.CPSWARM_NOTE, node, element=f"<{tag}>", state=state)
        return value

    def part(self, payload: etree._Element, tag: str) -> etree._Element | None:
        """A required child with text (reported when missing)."""
        found = _child(payload, tag)
        if found is None or not _text(found):
            self.b.report(dg.CPSWARM_INVOKE, payload, "missing", element=local(payload), child=tag)
            return None
        return found

    def element(self, tag: str, parent: etree._Element, **attrs: str) -> etree._Element:
        """A new SCXML element (in the document's namespace), located at its parent."""
        name = f"{{{self.ns}}}{tag}" if self.ns else tag
        return self.sub(parent, name, parent, **attrs)

    def sub(
        self, parent: etree._Element, tag: str, origin: etree._Element | None, **attrs: str
    ) -> etree._Element:
        made = etree.SubElement(parent, tag, {k: v for k, v in attrs.items()})
        where = origin if origin is not None else parent
        if isinstance(where.sourceline, int):
            made.sourceline = where.sourceline
        return made


def _state_id(payload: etree._Element) -> str:
    """The id of the state whose `<data id="invoke">` holds the payload."""
    state = next(a for a in payload.iterancestors() if _is_state(a))
    return str(state.get("id", ""))


def _is_state(node: etree._Element) -> bool:
    return in_scxml(node) and local(node) in ("state", "parallel")


def _invokes(node: etree._Element) -> list[etree._Element]:
    return [i for i in children(node, "invoke") if i.get("type") in INVOKE_TYPES]


def _payload_data(node: etree._Element) -> list[etree._Element]:
    return [
        d
        for block in children(node, "datamodel")
        for d in children(block, "data")
        if d.get("id") == "invoke"
    ]


def _monitor_of(node: etree._Element) -> bool:
    return any(i.get("type") == "ROS_MONITOR" for i in children(node, "invoke")) or any(
        local(p) == "rosmonitor" for d in _payload_data(node) for p in children(d)
    )


def _child(node: etree._Element | None, tag: str) -> etree._Element | None:
    found = children(node, tag) if node is not None else []
    return found[0] if found else None


def _text(node: etree._Element | None) -> str:
    return (node.text or "").strip() if node is not None else ""


def _vars(node: etree._Element | None) -> list[etree._Element]:
    return [v for v in children(node, "var") if _text(v)] if node is not None else []


def _implied(node: etree._Element) -> str:
    """2019's `empty="false"`: fixed when it lists params, userdata when it lists vars."""
    if children(node, "param"):
        return "fixed"
    return "userdata" if children(node, "var") else "empty"


def _value(text: str) -> str:
    """A `<param>` as an expression: a literal stays one, anything else is a string."""
    try:
        value = literal(text)
    except ExprUnsupported:
        value = None
    return text if isinstance(value, (int, float, bool, str)) else json.dumps(text)


def _remove(node: etree._Element) -> None:
    parent = node.getparent()
    if parent is not None:
        parent.remove(node)
