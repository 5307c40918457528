"""`emit`: Model -> SCXML documents, one per member type (or per top-level machine).

Mapping (documented in docs/scxml.md):
- regions: one region is the state's content; two or more make a `<parallel>` whose children
  are one `<state>` per region; submachine states are inlined, their vertices get unique ids;
- a behaviour run by a state is `<sg:call>` in `<onentry>`; its outcome arrives as the event
  `outcome.<stateId>.<outcome>` (scoped to the state, so parallel regions never mix outcomes);
- triggerless transitions: `outcome.<stateId>` (any outcome) from a behaviour state,
  `done.state.<stateId>` from a composite state, eventless from any other state;
- time events: `<send delay>` on entry, `<cancel>` on exit; choice/junction/fork/entry/exit points:
  transient states with eventless transitions (`else` last); join: an eventless transition on the
  sources' common ancestor with `In()` conditions; history: `<history>` with its default;
- guards become ECMAScript `cond`s rendered from the expression AST (never from model text).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field

from lxml import etree

from swarmgen import __version__
from swarmgen.ir import expr
from swarmgen.ir.nodes import (
    Behaviour,
    Event,
    FinalState,
    Machine,
    MemberType,
    Model,
    OpaqueCode,
    Property,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    Transition,
    Trigger,
    TriggerKind,
    Value,
    Vertex,
)
from swarmgen.ir.query import (
    ModelIndex,
    Placed,
    connection_owner,
    incoming,
    initial_of,
    outgoing,
    walk,
)
from swarmgen.names import IdAllocator, identifier, qualified

SCXML_NS = "http://www.w3.org/2005/07/scxml"
SG_NS = "urn:swarmgen:scxml:1"
_NSMAP = {None: SCXML_NS, "sg": SG_NS}
_TRANSIENT = {
    PseudoKind.CHOICE,
    PseudoKind.JUNCTION,
    PseudoKind.FORK,
    PseudoKind.ENTRY_POINT,
    PseudoKind.EXIT_POINT,
}
_HISTORY = {PseudoKind.SHALLOW_HISTORY, PseudoKind.DEEP_HISTORY}

_STATE_TAGS = ("state", "parallel", "final", "history")

Instance = tuple[str, ...]  # ids of the submachine states that lead to a machine's copy
Key = tuple[Instance, str]  # one copy of one vertex


@dataclass(frozen=True)
class ScxmlDocument:
    name: str  # file stem
    member: str | None  # member type name, if the document is a member's behaviour
    machine: str  # root machine name
    text: str
    states: int  # <state>, <parallel>, <final> and <history> elements
    transitions: int


def emit(model: Model) -> tuple[ScxmlDocument, ...]:
    """One document per member type with a machine, then one per remaining top-level machine."""
    index = ModelIndex(model)
    files = IdAllocator()
    documents: list[ScxmlDocument] = []
    covered: set[str] = set()
    for member in model.member_types:
        machine = index.machines.get(member.machine or "")
        if machine is None:
            continue
        covered.update(m.id for m in index.reachable_machines(machine))
        documents.append(_Emitter(index, machine, member).document(files.claim(member.ident)))
    used_as_sub = {s for m in model.machines for s in index.submachines(m)}
    for machine in model.machines:
        if machine.id not in covered and machine.id not in used_as_sub:
            documents.append(_Emitter(index, machine, None).document(files.claim(machine.ident)))
    return tuple(documents)


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
    return expr.to_ecmascript(expr.parse_expr(_literal_text(value)))


def _literal_text(value: Value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value) if value >= 0 else f"-{-value!r}"
    return expr.to_text(expr.Const(value=value))


@dataclass
class _Copy:
    """One machine's copy under one submachine path, with its lookup tables."""

    machine: Machine
    instance: Instance
    placed: dict[str, Placed]
    leaving: dict[str, list[Transition]]
    arriving: dict[str, list[Transition]]
    parents: dict[str, str | None]  # vertex id -> id of the state holding it


@dataclass
class _Emitter:
    index: ModelIndex
    root: Machine
    member: MemberType | None
    ids: IdAllocator = field(default_factory=IdAllocator)
    vertex_ids: dict[Key, str] = field(default_factory=dict)
    copies: dict[Instance, _Copy] = field(default_factory=dict)
    data: dict[str, Property] = field(default_factory=dict)
    terminate_id: str | None = None
    used_behaviours: dict[str, Behaviour] = field(default_factory=dict)

    # --- document

    def document(self, name: str) -> ScxmlDocument:
        self._collect_data()
        self._allocate(self.root, ())
        if self._needs_terminate():
            self.terminate_id = self.ids.claim("terminated")
        scxml = etree.Element(f"{{{SCXML_NS}}}scxml", nsmap=_NSMAP)  # type: ignore[arg-type]
        scxml.set("version", "1.0")
        scxml.set("datamodel", "ecmascript")
        scxml.set("name", self.member.ident if self.member else self.root.ident)
        scxml.set(_sg("machine"), self.root.name)
        if self.member is not None:
            scxml.set(_sg("member"), self.member.name)
        self._emit_datamodel(scxml)
        self._emit_machine(scxml, self.root, (), at_root=True)
        if self.terminate_id:
            _sub(scxml, "final", {"id": self.terminate_id, _sg("name"): "terminate"})
        self._emit_metadata(scxml)
        comment = etree.Comment(
            _comment_text(
                f" @generated by swarmgen {__version__} from {self.index.model.source.rsplit('/', 1)[-1]}"
                f" ({'member type ' + self.member.name if self.member else 'state machine ' + self.root.name})."
                " Do not edit. "
            )
        )
        body = etree.tostring(scxml, pretty_print=True, encoding="unicode")
        header = '<?xml version="1.0" encoding="UTF-8"?>\n' + etree.tostring(
            comment, encoding="unicode"
        )
        text = header + "\n" + body
        states = sum(1 for e in scxml.iter(*(f"{{{SCXML_NS}}}{t}" for t in _STATE_TAGS)))
        transitions = sum(1 for _ in scxml.iter(f"{{{SCXML_NS}}}transition"))
        member = self.member.name if self.member else None
        return ScxmlDocument(name, member, self.root.name, text, states, transitions)

    def _collect_data(self) -> None:
        for machine in self.index.reachable_machines(self.root):
            for name, prop in self.index.data_scope[machine.id].items():
                self.data.setdefault(name, prop)
        for name in sorted(self.data):
            self.ids.claim(self.data[name].ident)

    def _needs_terminate(self) -> bool:
        return any(
            isinstance(p.vertex, Pseudostate) and p.vertex.kind == PseudoKind.TERMINATE
            for m in self.index.reachable_machines(self.root)
            for p in walk(m)
        )

    def _emit_datamodel(self, scxml: etree._Element) -> None:
        if not self.data:
            return
        datamodel = _sub(scxml, "datamodel")
        for name in sorted(self.data):
            prop = self.data[name]
            attrs = {
                "id": prop.ident,
                "expr": js_value(prop.default if _is_value(prop.default) else None),
            }
            if prop.name != prop.ident:
                attrs[_sg("name")] = prop.name
            if prop.type:
                attrs[_sg("type")] = prop.type
            _sub(datamodel, "data", attrs)

    # --- ids

    def _copy(self, machine: Machine, instance: Instance) -> _Copy:
        if instance not in self.copies:
            placed = {p.vertex.id: p for p in walk(machine)}
            parents = {vid: (p.parent.id if p.parent else None) for vid, p in placed.items()}
            self.copies[instance] = _Copy(
                machine, instance, placed, outgoing(machine), incoming(machine), parents
            )
        return self.copies[instance]

    def _allocate(self, machine: Machine, instance: Instance) -> None:
        """Give every emitted vertex copy a readable id: its name if unique, else qualified."""
        chains: dict[Key, list[str]] = {}
        self._chains(machine, instance, [], chains)
        for length in range(1, max((len(c) for c in chains.values()), default=0) + 1):
            pending = {k: c for k, c in chains.items() if k not in self.vertex_ids}
            counts: dict[str, int] = {}
            for chain in pending.values():
                candidate = qualified(*chain[-length:])
                counts[candidate] = counts.get(candidate, 0) + 1
            for key, chain in pending.items():
                candidate = qualified(*chain[-length:])
                if counts[candidate] == 1 and (candidate not in self.ids or length == len(chain)):
                    self.vertex_ids[key] = self.ids.claim(candidate)
        for key, chain in chains.items():
            if key not in self.vertex_ids:
                self.vertex_ids[key] = self.ids.claim(qualified(*chain))

    def _chains(
        self, machine: Machine, instance: Instance, prefix: list[str], out: dict[Key, list[str]]
    ) -> None:
        copy = self._copy(machine, instance)
        if len(machine.regions) > 1:
            own = [*prefix, machine.ident] if not instance else prefix
            if not instance:
                out[(instance, f"{machine.id}#parallel")] = own
            prefix = own
        for point in machine.connection_points:
            out[(instance, point.id)] = [*prefix, _vertex_name(point)]
        self._region_chains(copy, machine.regions, instance, prefix, out)

    def _region_chains(
        self,
        copy: _Copy,
        regions: Sequence[Region],
        instance: Instance,
        prefix: list[str],
        out: dict[Key, list[str]],
    ) -> None:
        for number, region in enumerate(regions):
            region_prefix = prefix
            if len(regions) > 1:
                region_prefix = [*prefix, identifier(region.name, f"region{number + 1}")]
                out[(instance, region.id)] = region_prefix
            for vertex in region.vertices:
                if isinstance(vertex, Pseudostate) and vertex.kind in {
                    PseudoKind.INITIAL,
                    PseudoKind.JOIN,
                    PseudoKind.TERMINATE,
                }:
                    continue
                chain = [*region_prefix, _vertex_name(vertex)]
                out[(instance, vertex.id)] = chain
                if isinstance(vertex, State):
                    for point in vertex.connection_points:
                        out[(instance, point.id)] = [*chain, _vertex_name(point)]
                    if vertex.submachine and vertex.submachine in self.index.machines:
                        sub = self.index.machines[vertex.submachine]
                        self._chains(sub, (*instance, vertex.id), chain, out)
                    else:
                        self._region_chains(copy, vertex.regions, instance, chain, out)

    def _id(self, instance: Instance, vertex_id: str) -> str:
        return self.vertex_ids[(instance, vertex_id)]

    # --- structure

    def _emit_machine(
        self, parent: etree._Element, machine: Machine, instance: Instance, at_root: bool
    ) -> None:
        copy = self._copy(machine, instance)
        for point in machine.connection_points:
            self._emit_vertex(parent, copy, point)
        if len(machine.regions) > 1 and at_root:
            container = _sub(
                parent, "parallel", {"id": self._id(instance, f"{machine.id}#parallel")}
            )
            container.set(_sg("name"), machine.name)
            parent.set("initial", container.get("id", ""))
            self._emit_parallel_regions(container, copy, machine.regions)
        elif len(machine.regions) > 1:
            self._emit_parallel_regions(parent, copy, machine.regions)
        elif machine.regions:
            self._emit_region(parent, copy, machine.regions[0], at_root)

    def _emit_parallel_regions(
        self, parallel: etree._Element, copy: _Copy, regions: Sequence[Region]
    ) -> None:
        for region in regions:
            state = _sub(parallel, "state", {"id": self._id(copy.instance, region.id)})
            if region.name:
                state.set(_sg("region"), region.name)
            self._emit_region(state, copy, region, at_root=False)

    def _emit_region(
        self, parent: etree._Element, copy: _Copy, region: Region, at_root: bool
    ) -> None:
        initials = initial_of(region)
        if initials:
            self._emit_initial(parent, copy, initials[0], at_root)
        for vertex in region.vertices:
            self._emit_vertex(parent, copy, vertex)

    def _emit_initial(
        self, parent: etree._Element, copy: _Copy, initial: Pseudostate, at_root: bool
    ) -> None:
        leaving = copy.leaving.get(initial.id, [])
        if not leaving:
            return
        transition = leaving[0]
        targets = self._targets(copy, transition.target)
        if at_root and not (transition.effect or transition.opaque):
            parent.set("initial", " ".join(targets))
            return
        if at_root:  # <scxml> has no <initial>: a transient state runs the initial effect
            transient = _sub(parent, "state", {"id": self.ids.claim("initial")})
            parent.set("initial", transient.get("id", ""))
            holder = transient
        else:
            holder = _sub(parent, "initial")
        element = _sub(holder, "transition", {"target": " ".join(targets)})
        self._emit_actions(element, transition.effect, transition.opaque)

    def _emit_vertex(self, parent: etree._Element, copy: _Copy, vertex: Vertex) -> None:
        if isinstance(vertex, FinalState):
            self._named(_sub(parent, "final", {"id": self._id(copy.instance, vertex.id)}), vertex)
        elif isinstance(vertex, State):
            self._emit_state(parent, copy, vertex)
        elif vertex.kind in _HISTORY:
            self._emit_history(parent, copy, vertex)
        elif vertex.kind in _TRANSIENT:
            element = _sub(parent, "state", {"id": self._id(copy.instance, vertex.id)})
            self._named(element, vertex)
            element.set(_sg("pseudostate"), vertex.kind.value)
            self._emit_transient_transitions(element, copy, vertex)

    def _named(self, element: etree._Element, vertex: Vertex | Machine) -> None:
        if vertex.name:
            element.set(_sg("name"), vertex.name)

    def _emit_state(self, parent: etree._Element, copy: _Copy, state: State) -> None:
        sub = self.index.machines.get(state.submachine or "") if state.submachine else None
        regions = sub.regions if sub is not None else state.regions
        tag = "parallel" if len(regions) > 1 else "state"
        sid = self._id(copy.instance, state.id)
        element = _sub(parent, tag, {"id": sid})
        self._named(element, state)
        if sub is not None:
            element.set(_sg("submachine"), sub.name)
        self._emit_entry_exit(element, copy, state, sid)
        for transition in self._ordered(copy.leaving.get(state.id, [])):
            self._emit_transition(element, copy, transition, state)
        self._emit_joins(element, copy, state)
        for point in state.connection_points:
            self._emit_vertex(element, copy, point)
        if sub is not None:
            self._emit_machine(element, sub, (*copy.instance, state.id), at_root=False)
        elif len(regions) > 1:
            self._emit_parallel_regions(element, copy, regions)
        elif regions:
            self._emit_region(element, copy, regions[0], at_root=False)

    def _emit_entry_exit(
        self, element: etree._Element, copy: _Copy, state: State, sid: str
    ) -> None:
        timers = self._timers(copy, state, sid)
        entry_code = tuple(o for o in state.opaque if o.role in {"entry", "do"})
        exit_code = tuple(o for o in state.opaque if o.role == "exit")
        if state.entry or state.activity or timers or entry_code:
            onentry = _sub(element, "onentry")
            self._emit_actions(onentry, state.entry, entry_code)
            if state.activity is not None:
                self._emit_call(onentry, state)
            for event, delay in timers:
                _sub(onentry, "send", {"event": event, "id": event, "delay": f"{delay}ms"})
        if state.exit or timers or exit_code:
            onexit = _sub(element, "onexit")
            self._emit_actions(onexit, state.exit, exit_code)
            for event, _ in timers:
                _sub(onexit, "cancel", {"sendid": event})

    def _timers(self, copy: _Copy, state: State, sid: str) -> list[tuple[str, int]]:
        timers = []
        for transition in copy.leaving.get(state.id, []):
            for trigger in transition.triggers:
                if trigger.kind == TriggerKind.TIME:
                    timers.append(
                        (self._timer_event(sid, transition, trigger, copy), trigger.delay_ms or 0)
                    )
        return timers

    def _timer_event(self, sid: str, transition: Transition, trigger: Trigger, copy: _Copy) -> str:
        position = [
            (t.id, n)
            for t in copy.leaving.get(transition.source, [])
            for n, tr in enumerate(t.triggers)
            if tr.kind == TriggerKind.TIME
        ].index((transition.id, transition.triggers.index(trigger)))
        return f"after.{sid}.{position}"

    def _emit_call(self, onentry: etree._Element, state: State) -> None:
        assert state.activity is not None
        behaviour = self.index.behaviours[state.activity.behaviour]
        self.used_behaviours[behaviour.id] = behaviour
        call = _sub(
            onentry, _sg("call"), {"behaviour": behaviour.name, "type": behaviour.kind.value}
        )
        bound = {b.name: b.value for b in state.activity.bindings}
        for prop in behaviour.inputs:
            value = bound.get(prop.name)
            if value is not None:
                _sub(call, _sg("arg"), {"name": prop.ident, "expr": self._js(value)})
            elif prop.name in self.data:
                _sub(
                    call,
                    _sg("arg"),
                    {"name": prop.ident, "expr": self.data[prop.name].ident, "implicit": "true"},
                )
        for prop in behaviour.outputs:
            if prop.name in self.data:
                _sub(
                    call,
                    _sg("result"),
                    {"name": prop.ident, "location": self.data[prop.name].ident},
                )

    def _emit_history(self, parent: etree._Element, copy: _Copy, vertex: Pseudostate) -> None:
        hid = self._id(copy.instance, vertex.id)
        leaving = copy.leaving.get(vertex.id, [])
        placed = copy.placed[vertex.id]
        if placed.parent is None and not copy.instance:  # SCXML puts <history> inside states only
            element = _sub(parent, "state", {"id": hid})
            element.set(_sg("pseudostate"), vertex.kind.value)
        else:
            kind = "deep" if vertex.kind == PseudoKind.DEEP_HISTORY else "shallow"
            element = _sub(parent, "history", {"id": hid, "type": kind})
        self._named(element, vertex)
        if leaving:
            transition = leaving[0]
            default = _sub(
                element, "transition", {"target": " ".join(self._targets(copy, transition.target))}
            )
            self._emit_actions(default, transition.effect, transition.opaque)
            return
        region = placed.region
        initials = initial_of(region) if region is not None else []
        first = copy.leaving.get(initials[0].id, []) if initials else []
        if first:  # no default given: UML enters the region's default state
            _sub(element, "transition", {"target": " ".join(self._targets(copy, first[0].target))})

    def _emit_transient_transitions(
        self, element: etree._Element, copy: _Copy, vertex: Pseudostate
    ) -> None:
        leaving = copy.leaving.get(vertex.id, [])
        if vertex.kind == PseudoKind.FORK and leaving:
            targets = [t for tr in leaving for t in self._targets(copy, tr.target)]
            fork = _sub(element, "transition", {"target": " ".join(targets)})
            for tr in leaving:
                self._emit_actions(fork, tr.effect, tr.opaque)
            return
        if vertex.kind == PseudoKind.EXIT_POINT and copy.instance:
            self._emit_exit_point(element, copy, vertex)
        for transition in self._ordered(leaving):
            self._emit_transition(element, copy, transition, vertex)

    def _emit_exit_point(self, element: etree._Element, copy: _Copy, vertex: Pseudostate) -> None:
        """A submachine's exit point continues with the outgoing transitions of the
        ConnectionPointReferences that name it, in the machine that holds the submachine state."""
        outer = self.copies[copy.instance[:-1]]
        holder = outer.placed.get(copy.instance[-1])
        if holder is None or not isinstance(holder.vertex, State):
            return
        for conn in holder.vertex.connections:
            if vertex.id in conn.exit:
                for transition in self._ordered(outer.leaving.get(conn.id, [])):
                    self._emit_transition(element, outer, transition, holder.vertex)

    # --- transitions

    @staticmethod
    def _ordered(transitions: list[Transition]) -> list[Transition]:
        """Model order, with `else` guards last (SCXML picks the first enabled transition)."""
        return sorted(transitions, key=lambda t: isinstance(t.guard, expr.Else))

    def _emit_transition(
        self, parent: etree._Element, copy: _Copy, transition: Transition, source: Vertex
    ) -> None:
        target = copy.placed.get(transition.target)
        if (
            target is not None
            and isinstance(target.vertex, Pseudostate)
            and target.vertex.kind == PseudoKind.JOIN
        ):
            return  # emitted once, on the sources' common ancestor (see _emit_joins)
        attrs: dict[str, str] = {}
        sid = parent.get("id", "")
        event = self._event_attr(transition, source, sid, copy)
        if event:
            attrs["event"] = event
        if transition.guard is not None and not isinstance(transition.guard, expr.Else):
            attrs["cond"] = self._js(transition.guard)
        internal = transition.kind == "internal" and transition.source == transition.target
        if not internal:
            attrs["target"] = " ".join(self._targets(copy, transition.target))
        if transition.kind == "local":
            attrs["type"] = "internal"
        element = _sub(parent, "transition", attrs)
        if transition.name and not transition.name.startswith("Transition"):
            element.set(_sg("name"), transition.name)
        self._emit_writeback(element, transition, source)
        self._emit_actions(element, transition.effect, transition.opaque)

    def _event_attr(
        self, transition: Transition, source: Vertex, sid: str, copy: _Copy
    ) -> str | None:
        if transition.triggers:
            return " ".join(
                dict.fromkeys(
                    self._descriptor(t, transition, sid, copy) for t in transition.triggers
                )
            )
        if not isinstance(source, State) or transition.source != source.id:
            return None
        if source.activity is not None and not source.regions and not source.submachine:
            return f"outcome.{sid}"
        if source.regions or source.submachine:
            return f"done.state.{sid}"
        return None

    def _descriptor(self, trigger: Trigger, transition: Transition, sid: str, copy: _Copy) -> str:
        if trigger.kind == TriggerKind.OUTCOME:
            return f"outcome.{sid}.{identifier(trigger.name)}"
        if trigger.kind == TriggerKind.TIME:
            return self._timer_event(sid, transition, trigger, copy)
        if trigger.kind == TriggerKind.ANY:
            return "*"
        event = self.index.events.get(trigger.event or "")
        return event.ident if event is not None else identifier(trigger.name)

    def _emit_writeback(
        self, element: etree._Element, transition: Transition, source: Vertex
    ) -> None:
        """Outputs of the behaviour, carried as the outcome event's data, become member data."""
        if (
            not isinstance(source, State)
            or source.activity is None
            or transition.source != source.id
        ):
            return
        if transition.triggers and not any(
            t.kind == TriggerKind.OUTCOME for t in transition.triggers
        ):
            return
        behaviour = self.index.behaviours[source.activity.behaviour]
        for prop in behaviour.outputs:
            if prop.name in self.data:
                location = self.data[prop.name].ident
                field_ = f"_event.data.{prop.ident}"
                value = f"(_event.data && {field_} !== undefined) ? {field_} : {location}"
                _sub(element, "assign", {"location": location, "expr": value})

    def _emit_joins(self, element: etree._Element, copy: _Copy, state: State) -> None:
        for vertex_id, placed in copy.placed.items():
            vertex = placed.vertex
            if not (isinstance(vertex, Pseudostate) and vertex.kind == PseudoKind.JOIN):
                continue
            sources = [t.source for t in copy.arriving.get(vertex_id, [])]
            if not sources or self._common_ancestor(copy, sources) != state.id:
                continue
            conds = [f"In('{self._id(copy.instance, s)}')" for s in sources]
            leaving = copy.leaving.get(vertex_id, [])
            guard = leaving[0].guard if leaving else None
            if guard is not None and not isinstance(guard, expr.Else):
                conds.append(self._js(guard))
            attrs = {"cond": " && ".join(conds)}
            events = [
                self._descriptor(t, tr, self._id(copy.instance, tr.source), copy)
                for tr in copy.arriving.get(vertex_id, [])
                for t in tr.triggers
            ]
            if events:
                attrs["event"] = " ".join(dict.fromkeys(events))
            if leaving:
                attrs["target"] = " ".join(self._targets(copy, leaving[0].target))
            join = _sub(element, "transition", attrs)
            join.set(_sg("join"), vertex.name or self._id(copy.instance, vertex_id))
            for transition in [*copy.arriving.get(vertex_id, []), *leaving]:
                self._emit_actions(join, transition.effect, transition.opaque)

    @staticmethod
    def _common_ancestor(copy: _Copy, sources: list[str]) -> str | None:
        def chain(vertex_id: str) -> list[str]:
            result = []
            current = copy.parents.get(vertex_id)
            while current is not None:
                result.append(current)
                current = copy.parents.get(current)
            return result

        chains = [chain(s) for s in sources]
        for candidate in chains[0]:
            if all(candidate in c for c in chains[1:]):
                return candidate
        return None

    def _targets(self, copy: _Copy, vertex_id: str) -> list[str]:
        placed = copy.placed.get(vertex_id)
        if placed is None:
            owners = connection_owner(copy.machine)
            owner = owners.get(vertex_id)
            if owner is None:
                return []
            conn = next(c for c in owner.connections if c.id == vertex_id)
            inner = (*copy.instance, owner.id)
            if conn.entry and inner in self.copies:
                return [self._id(inner, e) for e in conn.entry]
            return [self._id(copy.instance, owner.id)]
        vertex = placed.vertex
        if isinstance(vertex, Pseudostate) and vertex.kind == PseudoKind.TERMINATE:
            return [self.terminate_id or ""]
        return [self._id(copy.instance, vertex_id)]

    # --- executable content

    def _js(self, e: expr.Expr) -> str:
        return expr.to_ecmascript(e, self._data_ident)

    def _data_ident(self, name: str) -> str:
        prop = self.data.get(name)
        return prop.ident if prop is not None else identifier(name)

    def _emit_actions(
        self,
        parent: etree._Element,
        actions: tuple[expr.Action, ...],
        opaque: tuple[OpaqueCode, ...],
    ) -> None:
        for action in actions:
            if isinstance(action, expr.Assign):
                _sub(
                    parent,
                    "assign",
                    {"location": self._data_ident(action.target), "expr": self._js(action.value)},
                )
            elif isinstance(action, expr.Raise) and not action.args:
                _sub(parent, "raise", {"event": self._event_ident(action.event)})
            elif isinstance(action, expr.Raise):
                send = _sub(
                    parent,
                    "send",
                    {"event": self._event_ident(action.event), "target": "#_internal"},
                )
                self._emit_params(send, action, "param")
            else:
                send = _sub(
                    parent,
                    _sg("send"),
                    {"event": self._event_ident(action.event), "scope": "swarm"},
                )
                self._emit_params(send, action, _sg("param"))
        for code in opaque:
            element = _sub(parent, _sg("opaque"), {"language": code.language or "unspecified"})
            element.text = code.body

    def _emit_params(self, send: etree._Element, action: expr.Raise | expr.Send, tag: str) -> None:
        for arg in action.args:
            _sub(send, tag, {"name": identifier(arg.name), "expr": self._js(arg.value)})

    def _event_ident(self, name: str) -> str:
        event = self.index.events_by_name.get(name)
        return event.ident if event is not None else identifier(name)

    # --- metadata

    def _emit_metadata(self, scxml: etree._Element) -> None:
        """Library, events and hardware in the swarmgen namespace (ignored by SCXML engines)."""
        if self.member is not None:
            member = _sub(scxml, _sg("member"), {"name": self.member.name})
            if self.member.role:
                member.set("role", self.member.role)
            for part in self.member.hardware:
                _sub(
                    member,
                    _sg("hardware"),
                    {"part": part.name, "type": part.type_name, "count": str(part.count)},
                )
        if self.used_behaviours:
            library = _sub(scxml, _sg("library"))
            for behaviour in sorted(self.used_behaviours.values(), key=lambda b: b.name):
                self._emit_behaviour(library, behaviour)
        events = self._used_events()
        if events:
            declared = _sub(scxml, _sg("events"))
            for event in events:
                element = _sub(declared, _sg("event"), {"name": event.name, "id": event.ident})
                for key in ("sender", "scope"):
                    value = getattr(event, key)
                    if value:
                        element.set(key, value)
                for prop in event.fields:
                    _sub(
                        element,
                        _sg("field"),
                        {"name": prop.ident, **({"type": prop.type} if prop.type else {})},
                    )

    def _emit_behaviour(self, library: etree._Element, behaviour: Behaviour) -> None:
        element = _sub(
            library, _sg("behaviour"), {"name": behaviour.name, "type": behaviour.kind.value}
        )
        if behaviour.library:
            element.set("library", behaviour.library)
        element.set("outcomes", " ".join(behaviour.outcomes))
        if behaviour.requires:
            element.set("requires", " ".join(behaviour.requires))
        if behaviour.ros is not None:
            element.set("rosKind", behaviour.ros.kind)
            for key in ("name", "type"):
                value = getattr(behaviour.ros, key)
                if value:
                    element.set(f"ros{key.title()}", value)
        for tag, props in (("input", behaviour.inputs), ("output", behaviour.outputs)):
            for prop in props:
                _sub(
                    element,
                    _sg(tag),
                    {"name": prop.ident, **({"type": prop.type} if prop.type else {})},
                )

    def _used_events(self) -> list[Event]:
        names: set[str] = set()
        for machine in self.index.reachable_machines(self.root):
            for transition in machine.transitions:
                names.update(t.name for t in transition.triggers if t.kind == TriggerKind.EVENT)
                names.update(a.event for a in transition.effect if not isinstance(a, expr.Assign))
            for placed in walk(machine):
                if isinstance(placed.vertex, State):
                    actions = (*placed.vertex.entry, *placed.vertex.exit)
                    names.update(a.event for a in actions if not isinstance(a, expr.Assign))
        return [e for e in self.index.model.events if e.name in names]


def _vertex_name(vertex: Vertex) -> str:
    if vertex.name:
        return identifier(vertex.name)
    if isinstance(vertex, FinalState):
        return "final"
    if isinstance(vertex, Pseudostate):
        return identifier(vertex.kind.value)
    return "state"


def _is_value(value: Value) -> bool:
    return not isinstance(value, str) or len(value) < 10_000
