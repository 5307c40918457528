"""A reader of W3C SCXML 1.0 documents (docs/scxml-input.md): one document into a raw model of
the UML shape the XMI reader gives, so the unchanged pipeline (IR, checks, every backend) runs
on it. swarmgen's own `sg:` extension (docs/scxml.md) reads back to the model it came from:
the member type with its data and hardware, the library behaviours, the events, submachines.

Chosen by content (`frontend.formats`): the root element `scxml`, in the W3C namespace or none.
"""

from __future__ import annotations

import re
from pathlib import Path

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.diagnostics import Diagnostic, Severity
from swarmgen.frontend import scxml_cpswarm, scxml_invoke
from swarmgen.frontend.raw import RawElement, RawModel
from swarmgen.frontend.safexml import InputError
from swarmgen.frontend.scxml_actions import Actions
from swarmgen.frontend.scxml_expr import ExprUnsupported, json_fields, literal
from swarmgen.frontend.scxml_raw import PRIMITIVES, Builder, children, in_scxml, in_sg, local, sg
from swarmgen.frontend.scxml_send import namelist_field
from swarmgen.frontend.scxml_src import inline_src
from swarmgen.frontend.scxml_states import States

DATAMODELS = ("ecmascript", "null", "swarmgen")
_SCXML_ELEMENTS = {
    "scxml", "state", "parallel", "transition", "initial", "final", "onentry", "onexit",
    "history", "raise", "if", "elseif", "else", "foreach", "log", "datamodel", "data",
    "assign", "donedata", "content", "param", "script", "send", "cancel", "invoke", "finalize",
}  # fmt: skip
_SG_ELEMENTS = {
    "call", "arg", "result", "send", "param", "opaque", "member", "hardware", "library",
    "behaviour", "input", "output", "events", "event", "field",
}  # fmt: skip
# where an element is read: (its possible parents, why elsewhere is not)
_PLACES = {
    "donedata": (("final",), "done data is read in a <final> only"),
    "finalize": (("invoke",), "<finalize> is read in an <invoke> only"),
    "invoke": (("state", "parallel"), "an invoke is read in a <state> or <parallel> only"),
}
_DEFAULT_OUTCOMES = ("succeeded", "aborted", "preempted")


def from_tree(
    tree: etree._ElementTree, text: str, shown: str
) -> tuple[RawModel | None, list[Diagnostic]]:
    """The raw model of a parsed SCXML document (`text`: its decoded source, for columns)."""
    b = Builder(shown, text.splitlines())
    try:
        model = _Document(b, tree.getroot(), Path(shown).parent).read()
    except InputError as err:
        return None, [err.diagnostic]
    if any(d.severity == Severity.ERROR for d in b.diagnostics):
        return None, b.diagnostics
    return model, b.diagnostics


class _Document:
    def __init__(
        self,
        b: Builder,
        root: etree._Element,
        folder: Path,
        depth: int = 0,
        read: list[int] | None = None,
    ) -> None:
        self.b, self.root = b, root
        self.folder, self.depth = folder, depth  # where `src` is read; documents above it
        self.invoked = read if read is not None else [0]  # invoked documents read in all
        self.data_names: dict[str, str] = {}
        # the data `<foreach>`es write (W3C creates them): declared wherever they are read
        self.loop_data = {
            str(name)
            for loop in root.iter(f"{{{_W3C}}}foreach")
            for name in (loop.get("item"), loop.get("index"))
            if name
        }
        self.setup: list[etree._Element] = []  # `<data>` whose expr is computed at the start
        self.event_names: dict[str, str] = {}  # identifier -> model name
        self.signal_events: dict[str, str] = {}  # model name -> SignalEvent id
        self.time_events: dict[int, str] = {}
        self.types: dict[str, str] = {}  # data type name -> id
        self.behaviours: dict[str, str] = {}
        self.any_event = ""
        self.owner: RawElement | None = None

    def read(self) -> RawModel:
        root = self.root
        inline = scxml_invoke.detach(root)  # the invoked documents are read on their own
        scxml_cpswarm.lower(self.b, root)  # the CPSwarm dialect into sg: elements, in place
        self.check_elements()
        language = str(root.get("datamodel", "ecmascript"))
        if language not in DATAMODELS:
            self.b.report(dg.SCXML_DATAMODEL, root, datamodel=language)
        stem = Path(self.b.file).stem
        name = str(root.get("name") or stem)
        self.model = self.b.make("Model", "Model", None, root, {"name": name})
        self.package = self.b.make("packagedElement", "Package", self.model, root, {"name": name})
        member = sg(root, "member")
        owner = self.b.make(
            "packagedElement", "Class", self.package, root, {"name": member or name}
        )
        self.owner = owner
        self.data_types(owner)
        self.library()
        self.events()
        self.undeclared_events()
        self.datamodel(owner)
        machine = self.b.make(
            "ownedBehavior", "StateMachine", owner, root, {"name": sg(root, "machine") or name}
        )
        owner.attrs["classifierBehavior"] = str(machine.id)
        if member is not None:
            self.member(owner, machine)
        actions = Actions(
            self.b,
            self.data_name,
            self.event_name,
            self.event_ref,
            self.time_ref,
            self.any_ref,
            self.behaviours,
            language,
            self.declare,
            self.declared,
        )
        states = States(self.b, actions, self.package, emitted=sg(root, "machine") is not None)
        states.setup = self.setup
        invokes = scxml_invoke.Invokes(
            self.b, actions, inline, self.folder, self.depth, self.read_child, self.invoked
        )
        states.invokes = invokes
        states.machine(root, machine)
        states.resolve()
        model = RawModel(self.b.file, [self.model], self.b.index, self.b.stereotypes, "scxml")
        model.sessions = invokes.sessions
        return model

    def read_child(self, b: Builder, root: etree._Element, folder: Path) -> RawModel | None:
        """An invoked document, read as a document of its own one level deeper."""
        try:
            model = _Document(b, root, folder, self.depth + 1, self.invoked).read()
        except InputError as err:
            b.diagnostics.append(err.diagnostic)
            return None
        return None if any(d.severity == Severity.ERROR for d in b.diagnostics) else model

    def check_elements(self) -> None:
        """Unknown SCXML elements, duplicate ids, scripts other than the support script."""
        seen: dict[str, etree._Element] = {}
        for node in self.root.iter(tag=etree.Element):
            tag = local(node)
            if (in_scxml(node) and tag not in _SCXML_ELEMENTS) or (
                in_sg(node) and tag not in _SG_ELEMENTS
            ):
                self.b.report(dg.SCXML_BAD_DOCUMENT, node, element=tag)
            ident = node.get("id")
            if in_scxml(node) and ident is not None and tag not in ("send", "data"):
                if ident in seen:
                    where = self.b.span(seen[str(ident)]).location()
                    self.b.report(
                        dg.SCXML_BAD_DOCUMENT, node, "duplicate-id", id=ident, where=where
                    )
                seen.setdefault(str(ident), node)
            parent = node.getparent()
            owner = local(parent) if parent is not None else ""
            place = _PLACES.get(tag)
            if in_scxml(node) and place is not None and owner not in place[0]:
                self.b.report(dg.SCXML_UNSUPPORTED, node, element=tag, why=place[1])
            if in_scxml(node) and tag == "script" and not self.support_script(node):
                self.b.report(
                    dg.SCXML_UNSUPPORTED,
                    node,
                    element=tag,
                    why="only swarmgen's own $sg support script is read (and not run)",
                )

    def support_script(self, node: etree._Element) -> bool:
        return (
            node.getparent() is self.root
            and "var $sg = {" in (node.text or "")
            and node.get("src") is None
        )

    def data_name(self, ident: str) -> str:
        return self.data_names.get(ident, ident)

    def event_name(self, ident: str) -> str:
        return self.event_names.get(ident, ident)

    def event_ref(self, name: str) -> str:
        """The SignalEvent of an event (a plain Signal is made for one not declared)."""
        if name not in self.signal_events:
            self.signal(name, None)
        return self.signal_events[name]

    def time_ref(self, delay: int) -> str:
        if delay not in self.time_events:
            event = self.b.make(
                "packagedElement", "TimeEvent", self.package, None, {"name": f"after {delay} ms"}
            )
            when = self.b.make("when", "TimeExpression", event, None)
            self.b.make("expr", "LiteralInteger", when, None, {"value": str(delay)})
            self.time_events[delay] = str(event.id)
        return self.time_events[delay]

    def any_ref(self) -> str:
        if not self.any_event:
            event = self.b.make(
                "packagedElement", "AnyReceiveEvent", self.package, None, {"name": "any"}
            )
            self.any_event = str(event.id)
        return self.any_event

    def data_types(self, owner: RawElement) -> None:
        """Data types, inferred from the zero values the document writes (`<data expr>`)."""
        for data in self.data_nodes():
            type_name = sg(data, "type")
            if type_name and type_name not in PRIMITIVES:
                try:
                    value = literal(str(data.get("expr", "null")))
                except ExprUnsupported:
                    value = None
                self.data_type(type_name, value, data)
        del owner

    def data_type(self, name: str, value: object, node: etree._Element) -> str:
        if name in self.types:
            return self.types[name]
        element = self.b.make("packagedElement", "DataType", self.package, node, {"name": name})
        self.types[name] = str(element.id)
        for field, field_value in value.items() if isinstance(value, dict) else []:
            prop = self.b.make("ownedAttribute", "Property", element, node, {"name": str(field)})
            self.b.typed(prop, self.value_type(name, str(field), field_value, node), self.types)
            if not isinstance(field_value, dict):
                self.b.literal(prop, "defaultValue", field_value, node)
        return self.types[name]

    def value_type(self, owner: str, field: str, value: object, node: etree._Element) -> str | None:
        if isinstance(value, dict):
            name = f"{owner}_{field}"
            self.data_type(name, value, node)
            return name
        for kind, type_name in (
            (bool, "Boolean"),
            (int, "Integer"),
            (float, "Real"),
            (str, "String"),
        ):
            if isinstance(value, kind):
                return type_name
        return None

    def data_nodes(self, report: bool = False) -> list[etree._Element]:
        """Every `<data>` of the document: with early binding (SCXML's default) a state's
        `<datamodel>` is created and initialised at the start like the top one, so it is read
        as member data; late binding (values set when the state is first entered) is refused."""
        late = self.root.get("binding") == "late"
        found = []
        for block in self.root.iter(tag=etree.Element):
            if local(block) != "datamodel" or not in_scxml(block):
                continue
            if late and block.getparent() is not self.root:
                if report:
                    self.b.report(dg.SCXML_UNSUPPORTED, block, element="datamodel",
                                  why='binding="late" (a state\'s data set on its first entry)')  # fmt: skip
                continue
            found.extend(children(block, "data"))
        return found

    def datamodel(self, owner: RawElement) -> None:
        for data in self.data_nodes(report=True):
            if data.get("src") is not None and not inline_src(self.b, data):
                continue  # reported; else the file's text is its inline content now
            ident = str(data.get("id", ""))
            content = (data.text or "").strip()
            if len(data) or (content and data.get("expr")):
                self.b.report(
                    dg.SCXML_UNSUPPORTED,
                    data,
                    "attribute",
                    attribute="content",
                    value="XML" if len(data) else content[:200],
                    element="data",
                    why="only expr gives a datum's value",
                )
                continue
            name = sg(data, "name") or ident
            self.data_names[ident] = name
            prop = self.b.make("ownedAttribute", "Property", owner, data, {"name": name})
            source = data.get("expr") or content or "null"  # inline content: the value's text
            try:
                value = literal(source)
                if isinstance(value, list):  # a sequence: made by the language's `[...]`
                    raise ExprUnsupported("an array")
            except ExprUnsupported:
                # computed when the machine starts (W3C's early binding, before the initial
                # transition): an untyped datum, assigned by the root's initial transition
                self.setup.append(data)
                self.b.make("defaultValue", "LiteralNull", prop, data)
                continue
            type_name = sg(data, "type")
            if type_name is None and sg(self.root, "machine") is None:
                type_name = self.value_type(name, "", value, data)
            # (swarmgen wrote it: a datum without `sg:type` is untyped, whatever its value)
            if type_name is not None:
                self.b.typed(prop, type_name, self.types)
            if isinstance(value, dict) or value is None:
                self.b.make("defaultValue", "LiteralNull", prop, data)
            else:
                self.b.literal(prop, "defaultValue", value, data)

    def declared(self, ident: str) -> bool:
        """Whether a `<data>` declares the datum, or a `<foreach>` of the document writes it
        (W3C creates it: `declare`; read before or after the loop, it is the same datum)."""
        return ident in self.data_names or ident in self.loop_data

    def declare(self, ident: str, node: etree._Element) -> None:
        """A datum no `<data>` declares that `<foreach>` writes (W3C creates it): untyped."""
        if ident in self.data_names or self.owner is None:
            return
        self.data_names[ident] = ident
        prop = self.b.make("ownedAttribute", "Property", self.owner, node, {"name": ident})
        self.b.make("defaultValue", "LiteralNull", prop, node)

    def library(self) -> None:
        """`<sg:library>`: one package per library, a class, an operation per behaviour."""
        packages: dict[str, RawElement] = {}
        for block in children(self.root, "library", sg_ns=True):
            for node in children(block, "behaviour", sg_ns=True):
                library = str(node.get("library") or "Library")
                holder = packages.get(library)
                if holder is None:
                    package = self.b.make(
                        "packagedElement", "Package", self.model, node, {"name": library}
                    )
                    self.b.stereotype("BehaviorLibrary", "Package", package, {})
                    holder = packages[library] = self.b.make(
                        "packagedElement", "Class", package, node, {"name": library}
                    )
                self.behaviour(holder, node)

    def behaviour(self, holder: RawElement, node: etree._Element) -> None:
        name = str(node.get("name", ""))
        operation = self.b.make("ownedOperation", "Operation", holder, node, {"name": name})
        self.behaviours[name] = str(operation.id)
        outcomes = [o for o in str(node.get("outcomes", "")).split() if o not in _DEFAULT_OUTCOMES]
        tags = {"outcomes": " ".join(outcomes), "requires": str(node.get("requires", ""))}
        tags.update({k: str(node.get(k, "")) for k in ("rosKind", "rosName", "rosType")})
        self.b.stereotype(str(node.get("type", "SwarmBehavior")), "Operation", operation, tags)
        for tag, direction in (("input", "in"), ("output", "out")):
            for param in children(node, tag, sg_ns=True):
                element = self.b.make(
                    "ownedParameter",
                    "Parameter",
                    operation,
                    param,
                    {"name": str(param.get("name", "")), "direction": direction},
                )
                self.b.typed(element, param.get("type"), self.types)

    def events(self) -> None:
        for block in children(self.root, "events", sg_ns=True):
            for node in children(block, "event", sg_ns=True):
                self.signal(str(node.get("name", "")), node)

    def undeclared_events(self) -> None:
        """Events a document without `<sg:events>` takes or raises: plain Signals, with the
        fields its `<param>`s give and its transitions read (untyped: the value rule's 0)."""
        fields: dict[str, dict[str, None]] = {}
        for node in self.root.iter(
            f"{{{_W3C}}}transition", f"{{{_W3C}}}raise", f"{{{_W3C}}}send", f"{{{_SG}}}send"
        ):
            if local(node) == "transition":
                names = [e.removesuffix(".*") for e in str(node.get("event", "")).split()]
                read = [
                    f
                    for e in node.iter()
                    for v in e.attrib.values()
                    for f in _FIELD_READ.findall(str(v))
                ]
                params = [a or b for a, b in read]
            else:
                names = [str(node.get("event", ""))]
                params = [
                    str(p.get("name", ""))
                    for p in node
                    if isinstance(p.tag, str) and local(p) == "param"
                ] + [  # a namelist's data ids are fields
                    namelist_field(n) for n in str(node.get("namelist", "")).split()
                ]
                params += _content_fields(node)
            for name in names:
                if (
                    name
                    and name != "*"
                    and name.split(".")[0] not in _PLATFORM
                    and name not in self.event_names
                ):
                    fields.setdefault(name, {}).update(dict.fromkeys(params))
        emitted = sg(self.root, "machine") is not None
        for name, found in fields.items():
            if emitted:  # swarmgen declares every signal it uses: the others are call events
                self.call_event(name)
            else:
                self.signal(name, None, list(found))

    def call_event(self, name: str) -> None:
        """A CallEvent on an operation of the context class (a trigger UML calls `call`)."""
        assert self.owner is not None
        operation = self.b.make("ownedOperation", "Operation", self.owner, None, {"name": name})
        event = self.b.make(
            "packagedElement",
            "CallEvent",
            self.package,
            None,
            {"name": name, "operation": str(operation.id)},
        )
        self.signal_events[name] = str(event.id)

    def signal(
        self, name: str, node: etree._Element | None, fields: list[str] | None = None
    ) -> None:
        signal = self.b.make("packagedElement", "Signal", self.package, node, {"name": name})
        for field_name in fields or []:
            self.b.make("ownedAttribute", "Property", signal, node, {"name": field_name})
        if node is not None:
            self.event_names[str(node.get("id") or name)] = name
            tags = {k: str(node.get(k, "")) for k in ("sender", "scope")}
            self.b.stereotype("SwarmEvent", "Signal", signal, tags)
            for field in children(node, "field", sg_ns=True):
                prop = self.b.make(
                    "ownedAttribute",
                    "Property",
                    signal,
                    field,
                    {"name": str(field.get("name", ""))},
                )
                self.b.typed(prop, field.get("type"), self.types)
                default = field.get("default")
                if default is not None:
                    try:
                        value = literal(str(default))
                    except ExprUnsupported:
                        value = None
                    self.b.literal(prop, "defaultValue", value, field)
        event = self.b.make(
            "packagedElement",
            "SignalEvent",
            self.package,
            node,
            {"name": name, "signal": str(signal.id)},
        )
        self.signal_events[name] = str(event.id)

    def member(self, owner: RawElement, machine: RawElement) -> None:
        """The member type: its stereotype, hardware parts and a swarm holding one member."""
        del machine
        info = children(self.root, "member", sg_ns=True)
        role = str(info[0].get("role", "")) if info else ""
        self.b.stereotype("SwarmMember", "Class", owner, {"role": role})
        hardware: dict[str, RawElement] = {}
        for part in (p for m in info for p in children(m, "hardware", sg_ns=True)):
            type_name = str(part.get("type", ""))
            cls = hardware.get(type_name)
            if cls is None:
                cls = hardware[type_name] = self.b.make(
                    "packagedElement", "Class", self.package, part, {"name": type_name}
                )
                self.b.stereotype("Sensor", "Class", cls, {})
            prop = self.b.make(
                "ownedAttribute",
                "Property",
                owner,
                part,
                {
                    "name": str(part.get("part", "")),
                    "type": str(cls.id),
                    "aggregation": "composite",
                },
            )
            count = str(part.get("count", "1"))
            self.b.make("upperValue", "LiteralUnlimitedNatural", prop, part, {"value": count})
            self.b.make("lowerValue", "LiteralInteger", prop, part, {"value": count})
        self.capabilities(hardware)
        swarm = self.b.make(
            "packagedElement", "Class", self.package, self.root, {"name": f"{owner.name}Swarm"}
        )
        self.b.stereotype("Swarm", "Class", swarm, {})
        self.b.make(
            "ownedAttribute",
            "Property",
            swarm,
            self.root,
            {"name": "members", "type": str(owner.id), "aggregation": "composite"},
        )

    def capabilities(self, hardware: dict[str, RawElement]) -> None:
        """SCXML does not say which hardware provides a required capability (a class's
        ancestors): each one no part's type names is made a general class of every part."""
        required = {
            r
            for n in self.root.iter(f"{{{_SG}}}behaviour")
            for r in str(n.get("requires", "")).split()
        }
        for capability in sorted(required - set(hardware)):
            general = self.b.make(
                "packagedElement", "Class", self.package, None, {"name": capability}
            )
            for cls in hardware.values():
                self.b.make(
                    "generalization", "Generalization", cls, None, {"general": str(general.id)}
                )


_SG = "urn:swarmgen:scxml:1"
_W3C = "http://www.w3.org/2005/07/scxml"
_PLATFORM = {"done", "error", "outcome", "after"}
_FIELD_READ = re.compile(
    r'_event\.data\.([A-Za-z_][A-Za-z0-9_]*)|\$sg\.field\(_event,\s*"([^"]+)"\)'
)


def _content_fields(send: etree._Element) -> list[str]:
    """The fields a `<send>`'s inline JSON-object `<content>` gives (`json_fields`)."""
    content = children(send, "content")
    if not content or len(content[0]) or content[0].get("expr") is not None:
        return []
    return [name for name, _ in json_fields(content[0].text or "") or []]
