"""SCXML states into UML regions and vertices (the reverse of chart lowering, docs/scxml.md).

`<state>` is a State, `<parallel>` a State with one region per child, `<final>` a FinalState,
`<history>` a history Pseudostate, a transient `<state sg:pseudostate>` the pseudostate it
stands for; a state with `sg:submachine` is a submachine state, the first copy of each machine
giving the machine's content. Transitions are collected first and their targets resolved when
every vertex exists (SCXML may name states further down the document).
"""

from __future__ import annotations

from dataclasses import field

from lxml import etree

from swarmgen import diagnostics as dg
from swarmgen.frontend.raw import RawElement
from swarmgen.frontend.scxml_actions import Actions
from swarmgen.frontend.scxml_domain import is_own_region, reentered, split_reentry
from swarmgen.frontend.scxml_invoke import Invokes
from swarmgen.frontend.scxml_raw import STATE_TAGS, Builder, children, in_scxml, local, sg
from swarmgen.records import dataclass

_KINDS = {"shallow": "shallowHistory", "deep": "deepHistory"}
_POINTS = ("entryPoint", "exitPoint")


@dataclass
class _Pending:
    transition: RawElement
    targets: list[str]
    node: etree._Element


@dataclass
class States:
    """Builds one machine's vertices; `model` receives the submachines."""

    b: Builder
    actions: Actions
    model: RawElement
    vertices: dict[str, RawElement] = field(default_factory=dict)
    skipped: set[str] = field(default_factory=set)  # ids inside a second copy of a submachine
    pending: list[_Pending] = field(default_factory=list)
    machines: dict[str, RawElement] = field(default_factory=dict)
    first_region: RawElement | None = None
    emitted: bool = False  # a document swarmgen wrote (the root has sg:machine)
    # `<data expr>` computed at the start: assigned by the machine's own initial transition,
    # the first one made in a region of the machine itself (nested regions' initials are made
    # before their parents': those run after the states above them are entered)
    setup: list[etree._Element] = field(default_factory=list)
    top_regions: set[int] = field(default_factory=set)  # ids of the machine's own regions
    document_machine: RawElement | None = None  # the machine the document itself is
    invokes: Invokes | None = None  # reads each state's `<invoke>`s
    by_id: dict[str, etree._Element] = field(default_factory=dict)  # the document's states

    def machine(self, root: etree._Element, machine: RawElement) -> None:
        """The document's top level as the machine's region(s)."""
        self.document_machine = machine
        for node in root.iter(tag=etree.Element):
            if node.get("id") and in_scxml(node) and local(node) in STATE_TAGS:
                self.by_id.setdefault(str(node.get("id")), node)
        kids = children(root, *STATE_TAGS)
        name = machine.name
        whole = [k for k in kids if not (local(k) == "final" and k.get("id") == "terminated")]
        top = whole[0] if len(whole) == 1 and local(whole[0]) == "parallel" else None
        if top is not None and top.get("id") == name and sg(top, "name") is None:
            self.vertices[name] = machine  # several top regions (docs/scxml.md)
            for region in children(top, *STATE_TAGS):
                self.region_of_state(machine, region)
            for final in (k for k in kids if k is not top):
                self.vertex(final, self.first_region or machine)
            return
        self.region(machine, root, kids, "Region", root.get("initial"))

    def region(
        self,
        owner: RawElement,
        node: etree._Element,
        kids: list[etree._Element],
        name: str,
        initial_ids: str | None,
    ) -> RawElement:
        """A region of `owner` with the vertices `kids` and its initial pseudostate."""
        region = self.b.make("region", "Region", owner, node, {"name": name})
        self.first_region = self.first_region or region
        if owner is self.document_machine:
            self.top_regions.add(id(region))
        initial = children(node, "initial")
        for kid in kids:
            self.vertex(kid, region)
        if initial:
            self.initial(region, initial[0])
        elif initial_ids:
            self.initial_to(region, node, initial_ids.split(), [])
        elif kids and not self.emitted:  # swarmgen writes <initial> for every UML initial
            first = next((k for k in kids if local(k) != "history"), None)
            if first is not None and first.get("id"):
                self.initial_to(region, node, [str(first.get("id"))], [])
        return region

    def initial(self, region: RawElement, node: etree._Element) -> None:
        """`<initial><transition/></initial>`: the region's initial pseudostate."""
        transitions = children(node, "transition")
        if len(transitions) != 1 or not transitions[0].get("target"):
            self.b.report(
                dg.SCXML_BAD_DOCUMENT,
                node,
                "missing",
                element="initial",
                attribute="a transition with a target",
            )
            return
        transition = transitions[0]
        self.initial_to(
            region, transition, str(transition.get("target")).split(), _body(transition)
        )

    def initial_to(
        self,
        region: RawElement,
        node: etree._Element,
        targets: list[str],
        body: list[etree._Element],
    ) -> None:
        """An initial pseudostate; several targets enter through a fork (UML's one-target rule)."""
        if targets and targets[0].startswith("initial") and len(targets) == 1:
            transient = self.vertices.get(targets[0])
            if transient is not None and transient.attrs.get("kind") == "initial":
                return  # the root's transient `initial` state was read as the pseudostate
        if self.setup and id(region) in self.top_regions:  # the machine's own initial
            body, self.setup = [*self.setup, *body], []
        start = self.b.make("subvertex", "Pseudostate", region, node, {"name": "Initial"})
        if len(targets) > 1:
            fork = self.b.make(
                "subvertex", "Pseudostate", region, node, {"name": "InitialFork", "kind": "fork"}
            )
            self.transition(region, start, [], node, body=body, direct=fork)
            for target in targets:
                self.transition(region, fork, [target], node)
            return
        self.transition(region, start, targets, node, body=body)

    def region_of_state(self, owner: RawElement, node: etree._Element) -> None:
        """A child of `<parallel>`: a region (its children), or a region holding it when it
        has behaviour of its own (W3C parallel children are states)."""
        # a <parallel> child is never its region: its own children are regions, not states
        # one after another (W3C 3.4)
        name = sg(node, "region") or str(node.get("id") or "Region")
        if is_own_region(node):
            if node.get("id"):
                self.vertices[str(node.get("id"))] = owner
            self.region(owner, node, children(node, *STATE_TAGS), name, node.get("initial"))
        else:
            region = self.b.make("region", "Region", owner, node, {"name": name})
            if owner is self.document_machine:
                self.top_regions.add(id(region))
            self.vertex(node, region)
            self.initial_to(region, node, [str(node.get("id"))], [])

    def vertex(self, node: etree._Element, region: RawElement) -> None:
        """One state-like element as the vertex it stands for."""
        tag = local(node)
        ident = node.get("id")
        if ident is None:
            self.b.report(dg.SCXML_BAD_DOCUMENT, node, "missing", element=tag, attribute="id")
            return
        ident = str(ident)
        name = sg(node, "name") or ident
        if tag == "final" and ident == "terminated" and name == "terminate":
            self.vertices[ident] = self.b.make(
                "subvertex", "Pseudostate", region, node, {"name": "Terminate", "kind": "terminate"}
            )
        elif tag == "final":
            self.vertices[ident] = self.b.make(
                "subvertex", "FinalState", region, node, {"name": name}, ident
            )
            self.actions.final_behaviour(node, self.vertices[ident])
        elif tag == "history":
            self.history(node, region, ident, name)
        elif tag == "state" and _root_initial(node, ident):
            vertex = self.b.make(
                "subvertex",
                "Pseudostate",
                region,
                node,
                {"name": "Initial", "kind": "initial"},
                ident,
            )
            self.vertices[ident] = vertex
            self.default_transitions(node, region, vertex)
        elif sg(node, "pseudostate"):
            self.pseudostate(node, region, ident, name, str(sg(node, "pseudostate")))
        else:
            self.state(node, region, ident, name)

    def unsupported_children(self, node: etree._Element, *names: str) -> None:
        """Report content UML cannot give the element."""
        for kid in children(node, *names):
            why = (
                "a final state has no behaviour in UML"
                if local(kid) != "donedata"
                else "done data is not in the IR"
            )
            self.b.report(dg.SCXML_UNSUPPORTED, kid, element=local(kid), why=why)

    def history(self, node: etree._Element, region: RawElement, ident: str, name: str) -> None:
        """`<history>` with its default transition."""
        kind = _KINDS.get(str(node.get("type", "shallow")))
        if kind is None:
            self.b.report(
                dg.SCXML_BAD_DOCUMENT,
                node,
                "bad-value",
                attribute="type",
                value=node.get("type"),
                element="history",
                why="shallow or deep",
            )
            return
        vertex = self.b.make(
            "subvertex", "Pseudostate", region, node, {"name": name, "kind": kind}, ident
        )
        self.vertices[ident] = vertex
        self.default_transitions(node, region, vertex)

    def default_transitions(
        self, node: etree._Element, region: RawElement, vertex: RawElement
    ) -> None:
        """The transitions of an `<initial>` or `<history>` element, from its pseudostate."""
        for transition in children(node, "transition"):
            targets = str(transition.get("target", "")).split()
            self.transition(region, vertex, targets, transition, body=_body(transition))

    def pseudostate(
        self, node: etree._Element, region: RawElement, ident: str, name: str, kind: str
    ) -> None:
        """A transient `<state sg:pseudostate>` as the pseudostate it stands for."""
        if kind == "initial" or kind not in (
            "choice",
            "junction",
            "fork",
            *_POINTS,
            "shallowHistory",
            "deepHistory",
        ):
            self.b.report(
                dg.SCXML_BAD_DOCUMENT,
                node,
                "bad-value",
                attribute="sg:pseudostate",
                value=kind,
                element="state",
                why="choice, junction, fork, entryPoint, exitPoint or a history",
            )
            return
        owner, feature = (
            (region.parent or region, "connectionPoint")
            if kind in _POINTS
            else (region, "subvertex")
        )
        vertex = self.b.make(
            feature, "Pseudostate", owner, node, {"name": name, "kind": kind}, ident
        )
        self.vertices[ident] = vertex
        for transition in children(node, "transition"):
            targets = str(transition.get("target", "")).split()
            body = _body(transition)
            if kind == "fork":
                for index, target in enumerate(targets):
                    self.transition(
                        region, vertex, [target], transition, body=body if index == 0 else []
                    )
            else:
                self.transition(
                    region, vertex, targets, transition, body=body, cond=transition.get("cond")
                )

    def state(self, node: etree._Element, region: RawElement, ident: str, name: str) -> None:
        """`<state>`/`<parallel>`: a State with its behaviour, transitions and regions."""
        vertex = self.b.make("subvertex", "State", region, node, {"name": name}, ident)
        self.vertices[ident] = vertex
        call = self.actions.state_behaviour(node, vertex)
        if self.invokes is not None:
            self.invokes.state(node, vertex)
        for transition in children(node, "transition"):
            self.state_transition(region, vertex, ident, transition, call)
        submachine = sg(node, "submachine")
        if submachine:
            self.submachine(node, vertex, ident, submachine)
        elif local(node) == "parallel":
            for kid in children(node, *STATE_TAGS):
                self.region_of_state(vertex, kid)
        elif children(node, *STATE_TAGS):
            self.region(vertex, node, children(node, *STATE_TAGS), "Region", node.get("initial"))
        elif node.get("initial"):
            self.b.report(
                dg.SCXML_BAD_DOCUMENT,
                node,
                "bad-initial",
                id=node.get("initial"),
                element=local(node),
            )

    def submachine(self, node: etree._Element, vertex: RawElement, ident: str, name: str) -> None:
        """The first state inlining `name` gives the machine; later copies only refer to it."""
        known = self.machines.get(name)
        if known is None:
            known = self.b.make("packagedElement", "StateMachine", self.model, node, {"name": name})
            self.machines[name] = known
            self.region(known, node, children(node, *STATE_TAGS), "Region", node.get("initial"))
        else:
            self.skipped.update(str(d.get("id")) for d in node.iterdescendants() if d.get("id"))
        vertex.attrs["submachine"] = str(known.id)

    def state_transition(
        self,
        region: RawElement,
        vertex: RawElement,
        ident: str,
        node: etree._Element,
        call: str | None,
    ) -> None:
        """A state's `<transition>` (finalize transitions are the call's, skipped)."""
        if sg(node, "finalize") is not None:
            return  # written again from the behaviour call (docs/scxml.md, finalize)
        events = str(node.get("event", "")).split()
        triggers = self.actions.triggers(node, events, ident, call)
        if triggers is None:
            return
        targets, extra = split_reentry(str(node.get("target", "")).split(), self.by_id)
        join = sg(node, "join")
        transition = self.transition(
            region,
            vertex,
            targets,
            node,
            body=_body(node),
            cond=node.get("cond"),
            triggers=triggers,
            join=join,
        )
        if transition is not None and node.get("type") == "internal":
            transition.attrs["kind"] = "local" if targets else "internal"
        if transition is not None and not targets:
            transition.attrs["kind"] = "internal"
        if transition is not None and targets and transition.attrs["source"] == str(vertex.id):
            self.reentry(transition, node, targets[0], extra)  # (not from a join: UML's own)
        if transition is not None and not events and (call or _compound(node.getparent())):
            # SCXML takes it as soon as its cond holds; without the mark, UML would read a
            # composite's (or a behaviour's) untriggered transition as its completion
            transition.attrs["eventless"] = "true"

    def transition(
        self,
        region: RawElement,
        source: RawElement,
        targets: list[str],
        node: etree._Element,
        *,
        body: list[etree._Element] | None = None,
        cond: str | None = None,
        triggers: list[tuple[str, str | None]] | None = None,
        direct: RawElement | None = None,
        join: str | None = None,
    ) -> RawElement | None:
        """A UML transition from `source`; its target is resolved later (`resolve`)."""
        if len(targets) > 1:
            self.b.report(
                dg.SCXML_UNSUPPORTED,
                node,
                "attribute",
                attribute="target",
                value=" ".join(targets),
                element="transition",
                why='UML transitions have one target; use a fork (sg:pseudostate="fork") or an initial',
            )
            return None
        attrs = {"source": str(source.id)}
        if local(node) == "transition" and sg(node, "name"):
            attrs["name"] = str(sg(node, "name"))
        transition = self.b.make("transition", "Transition", region, node, attrs)
        if direct is not None:
            transition.attrs["target"] = str(direct.id)
        elif targets:
            self.pending.append(_Pending(transition, targets, node))
        else:
            transition.attrs["target"] = str(source.id)
        for event, ref in triggers or []:
            trigger = self.b.make("trigger", "Trigger", transition, node, {"name": event})
            if ref:
                trigger.attrs["event"] = ref
        joined = self.actions.guard(transition, node, cond, join)
        if joined:
            self.join(region, transition, joined, join or "Join", node)
        self.actions.effect(transition, node, body or [])
        return transition

    def reentry(
        self,
        transition: RawElement,
        node: etree._Element,
        target: str,
        extra: list[etree._Element],
    ) -> None:
        """Mark a transition that W3C lets leave a whole `<parallel>` where the reader's regions
        would keep it inside one child (`scxml_domain.reentered`)."""
        source, end = node.getparent(), self.by_id.get(target)
        if source is None or end is None:
            return  # an unknown target is reported when it is resolved
        state = reentered(source, end, extra, internal=node.get("type") == "internal")
        if state is not None and state.get("id"):
            self.pending.append(_Pending(transition, [f"reenters:{state.get('id')}"], node))

    def join(
        self,
        region: RawElement,
        transition: RawElement,
        sources: list[str],
        name: str,
        node: etree._Element,
    ) -> None:
        """`In('a') && In('b')` on a transition: a join pseudostate the sources lead to."""
        vertex = self.b.make(
            "subvertex", "Pseudostate", region, node, {"name": name, "kind": "join"}
        )
        for source in sources:
            edge = self.b.make("transition", "Transition", region, node, {"target": str(vertex.id)})
            self.pending.append(_Pending(edge, [f"source:{source}"], node))
        transition.attrs["source"] = str(vertex.id)

    def resolve(self) -> None:
        """Give every collected transition its target (or source) vertex, or report it."""
        for item in self.pending:
            target = item.targets[0]
            feature = "target"
            for prefix in ("source", "reenters"):
                if target.startswith(f"{prefix}:"):
                    feature, target = prefix, target[len(prefix) + 1 :]
            found = self.vertices.get(target)
            if found is None:
                why = "unknown-target"
                if target in self.skipped:
                    self.b.report(
                        dg.SCXML_UNSUPPORTED,
                        item.node,
                        "attribute",
                        attribute=feature,
                        value=target,
                        element="transition",
                        why="it enters a second copy of an inlined submachine",
                    )
                    continue
                self.b.report(dg.SCXML_BAD_DOCUMENT, item.node, why, attribute=feature, id=target)
                continue
            item.transition.attrs[feature] = str(found.id)


def _body(node: etree._Element) -> list[etree._Element]:
    """A transition's executable content: SCXML and sg: elements alike."""
    return list(node.iterchildren(tag=etree.Element))


def _root_initial(node: etree._Element, ident: str) -> bool:
    """The transient state the emitter writes for an initial effect at the root (docs/scxml.md)."""
    parent = node.getparent()
    return (
        parent is not None
        and local(parent) == "scxml"
        and parent.get("initial") == ident
        and ident.startswith("initial")
        and sg(node, "name") is None
        and not children(node, *STATE_TAGS, "onentry", "onexit")
    )


def _compound(state: etree._Element | None) -> bool:
    """Whether `state` becomes a UML composite state (regions or a submachine), by the rule
    `States.state` builds it with."""
    if state is None:
        return False
    return (
        local(state) == "parallel"
        or bool(children(state, *STATE_TAGS))
        or bool(sg(state, "submachine"))
    )
