"""`lower`: Model -> Charts, one per member type (or per top-level machine).

Lowering decides everything the outputs share (documented in docs/scxml.md):
- regions: one region is the state's content; two or more make a parallel node whose children
  are one state per region; submachine states are inlined, their vertices get unique ids;
- a behaviour run by a state is its `call`; its outcome arrives as the event
  `outcome.<stateId>.<outcome>` (scoped to the state, so parallel regions never mix outcomes);
- triggerless transitions: `outcome.<stateId>` (any outcome) from a behaviour state,
  `done.state.<stateId>` from a composite state, eventless from any other state;
- time events: timers started on entry and cancelled on exit; choice/junction/fork/entry/exit
  points: transient states with eventless transitions (`else` last); join: an eventless
  transition on the sources' common ancestor with `in_states`; history: a history node with its
  default transition.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from swarmgen.chart import model as c
from swarmgen.chart import values
from swarmgen.chart.cycles import bound_cycles
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

_TRANSIENT = {
    PseudoKind.CHOICE,
    PseudoKind.JUNCTION,
    PseudoKind.FORK,
    PseudoKind.ENTRY_POINT,
    PseudoKind.EXIT_POINT,
}
_HISTORY = {PseudoKind.SHALLOW_HISTORY, PseudoKind.DEEP_HISTORY}
_SKIPPED = {PseudoKind.INITIAL, PseudoKind.JOIN, PseudoKind.TERMINATE}

Instance = tuple[str, ...]  # ids of the submachine states that lead to a machine's copy
Key = tuple[Instance, str]  # one copy of one vertex


def lower(model: Model) -> tuple[c.Chart, ...]:
    """One chart per member type with a machine, then one per remaining top-level machine.

    The pipeline lowers a model once, after the model-level checks passed (`check.may_lower`),
    and hands the charts to the chart-level checks and every output."""
    return tuple(bound_cycles(chart) for chart in _lower(model))  # the step bound's marks


def _lower(model: Model) -> tuple[c.Chart, ...]:
    index = ModelIndex(model)
    names = IdAllocator()
    charts: list[c.Chart] = []
    covered: set[str] = set()
    for member in model.member_types:
        machine = index.machines.get(member.machine or "")
        if machine is None:
            continue
        covered.update(m.id for m in index.reachable_machines(machine))
        charts.append(_Lowering(index, machine, member).chart(names.claim(member.ident)))
    used_as_sub = {s for m in model.machines for s in index.submachines(m)}
    for machine in model.machines:
        if machine.id not in covered and machine.id not in used_as_sub:
            charts.append(_Lowering(index, machine, None).chart(names.claim(machine.ident)))
    return tuple(charts)


@dataclass
class _Copy:
    """One machine's copy under one submachine path, with its lookup tables."""

    machine: Machine
    instance: Instance
    placed: dict[str, Placed]
    leaving: dict[str, list[Transition]]
    arriving: dict[str, list[Transition]]
    parents: dict[str, str | None]  # vertex id -> id of the state holding it
    joins: tuple[str, ...] = ()  # ids of the join pseudostates, found once (not per state)


@dataclass
class _Lowering:
    index: ModelIndex
    root: Machine
    member: MemberType | None
    ids: IdAllocator = field(default_factory=IdAllocator)
    vertex_ids: dict[Key, str] = field(default_factory=dict)
    copies: dict[Instance, _Copy] = field(default_factory=dict)
    data: dict[str, Property] = field(default_factory=dict)
    terminate_id: str | None = None
    used_behaviours: dict[str, Behaviour] = field(default_factory=dict)

    # --- chart

    def chart(self, name: str) -> c.Chart:
        self._collect_data()
        self._allocate(self.root, ())
        if self._needs_terminate():
            self.terminate_id = self.ids.claim("terminated")
        initial_transition, children = self._machine_content(self.root, (), at_root=True)
        initial = initial_transition.targets if initial_transition is not None else ()
        if self.terminate_id:
            children.append(c.Node(self.terminate_id, "final", name="terminate"))
        member = self.member
        return c.Chart(
            name=name,
            machine=self.root.name,
            member=member.name if member else None,
            role=member.role if member else None,
            source=self.index.model.source.replace("\\", "/").rsplit("/", 1)[-1],
            data=tuple(
                c.DataItem(p.ident, p.name, p.type, p.default, self._initial(p))
                for p in sorted(self.data.values(), key=lambda p: p.name)
            ),
            initial=initial,
            children=tuple(children),
            hardware=tuple(
                c.HardwareInfo(p.name, p.type_name, p.count)
                for p in (member.hardware if member else ())
            ),
            behaviours=tuple(
                _behaviour_info(b)
                for b in sorted(self.used_behaviours.values(), key=lambda b: b.name)
            ),
            events=tuple(self._event_info(e) for e in self._used_events()),
        )

    def _initial(self, prop: Property) -> object:
        return values.initial(prop, self.index.datatypes)

    def _event_info(self, event: Event) -> c.EventInfo:
        return c.EventInfo(
            name=event.name,
            ident=event.ident,
            sender=event.sender,
            scope=event.scope,
            fields=tuple((f.ident, f.type) for f in event.fields),
            defaults=tuple((f.ident, self._initial(f)) for f in event.fields),
        )

    def _collect_data(self) -> None:
        machines = self.index.reachable_machines(self.root)
        for machine in machines:
            for name, prop in self.index.data_scope[machine.id].items():
                self.data.setdefault(name, prop)
        if self.member is not None:  # inputs taken from hardware parameters become data too
            parameters = self.index.hardware_parameters(self.member)
            for behaviour, bound in self._calls(machines):
                for prop in behaviour.inputs:
                    if (
                        prop.name not in bound
                        and prop.name not in self.data
                        and prop.name in parameters
                    ):
                        self.data[prop.name] = parameters[prop.name]
        for name in sorted(self.data):
            self.ids.claim(self.data[name].ident)

    def _calls(self, machines: list[Machine]) -> list[tuple[Behaviour, set[str]]]:
        found = []
        for machine in machines:
            for placed in walk(machine):
                vertex = placed.vertex
                if isinstance(vertex, State) and vertex.activity is not None:
                    behaviour = self.index.behaviours.get(vertex.activity.behaviour)
                    if behaviour is not None:
                        found.append((behaviour, {b.name for b in vertex.activity.bindings}))
        return found

    def _needs_terminate(self) -> bool:
        return any(
            isinstance(p.vertex, Pseudostate) and p.vertex.kind == PseudoKind.TERMINATE
            for m in self.index.reachable_machines(self.root)
            for p in walk(m)
        )

    # --- ids

    def _copy(self, machine: Machine, instance: Instance) -> _Copy:
        if instance not in self.copies:
            placed = {p.vertex.id: p for p in walk(machine)}
            parents = {vid: (p.parent.id if p.parent else None) for vid, p in placed.items()}
            joins = tuple(
                vid
                for vid, p in placed.items()
                if isinstance(p.vertex, Pseudostate) and p.vertex.kind == PseudoKind.JOIN
            )
            self.copies[instance] = _Copy(
                machine, instance, placed, outgoing(machine), incoming(machine), parents, joins
            )
        return self.copies[instance]

    def _allocate(self, machine: Machine, instance: Instance) -> None:
        """Give every vertex copy a readable id: its name if unique, else the shortest unique
        qualified suffix (`GoToZone__Moving`)."""
        chains: dict[Key, list[str]] = {}
        self._chains(machine, instance, [], chains)
        for length in range(1, max((len(ch) for ch in chains.values()), default=0) + 1):
            pending = {k: ch for k, ch in chains.items() if k not in self.vertex_ids}
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
        if len(machine.regions) > 1 and not instance:
            prefix = [*prefix, machine.ident]
            out[(instance, f"{machine.id}#parallel")] = prefix
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
                if isinstance(vertex, Pseudostate) and vertex.kind in _SKIPPED:
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

    def _machine_content(
        self, machine: Machine, instance: Instance, at_root: bool
    ) -> tuple[c.Transition | None, list[c.Node]]:
        """(initial transition, child nodes) of a machine's copy; at the root, several regions
        become one parallel node."""
        copy = self._copy(machine, instance)
        nodes = [n for p in machine.connection_points if (n := self._vertex(copy, p)) is not None]
        if len(machine.regions) > 1 and at_root:
            pid = self._id(instance, f"{machine.id}#parallel")
            regions = self._region_nodes(copy, machine.regions)
            nodes.append(c.Node(pid, "parallel", name=machine.name, children=tuple(regions)))
            return c.Transition(events=(), targets=(pid,)), nodes
        if len(machine.regions) > 1:
            return None, nodes + self._region_nodes(copy, machine.regions)
        if not machine.regions:
            return None, nodes
        initial, children = self._region(copy, machine.regions[0], at_root)
        if at_root and initial is not None and initial.actions:
            # <scxml> has no <initial>: a transient state runs the initial effect
            transient = c.Node(self.ids.claim("initial"), "state", transitions=(initial,))
            return c.Transition(events=(), targets=(transient.id,)), [transient, *nodes, *children]
        return initial, nodes + children

    def _region_nodes(self, copy: _Copy, regions: Sequence[Region]) -> list[c.Node]:
        nodes = []
        for region in regions:
            initial, children = self._region(copy, region, at_root=False)
            nodes.append(
                c.Node(
                    self._id(copy.instance, region.id),
                    "state",
                    children=tuple(children),
                    initial=initial,
                    region=region.name or None,
                )
            )
        return nodes

    def _region(
        self, copy: _Copy, region: Region, at_root: bool
    ) -> tuple[c.Transition | None, list[c.Node]]:
        initial = None
        initials = initial_of(region)
        if initials:
            leaving = copy.leaving.get(initials[0].id, [])
            if leaving:
                transition = leaving[0]
                initial = c.Transition(
                    events=(),
                    targets=tuple(self._targets(copy, transition.target)),
                    actions=self._actions(transition.effect, transition.opaque),
                )
        children = [n for v in region.vertices if (n := self._vertex(copy, v)) is not None]
        return initial, children

    def _vertex(self, copy: _Copy, vertex: Vertex) -> c.Node | None:
        if isinstance(vertex, FinalState):
            return c.Node(self._id(copy.instance, vertex.id), "final", name=vertex.name or None)
        if isinstance(vertex, State):
            return self._state(copy, vertex)
        if vertex.kind in _HISTORY:
            return self._history(copy, vertex)
        if vertex.kind in _TRANSIENT:
            return c.Node(
                self._id(copy.instance, vertex.id),
                "state",
                name=vertex.name or None,
                pseudostate=vertex.kind.value,
                transitions=tuple(self._transient_transitions(copy, vertex)),
            )
        return None

    def _state(self, copy: _Copy, state: State) -> c.Node:
        sub = self.index.machines.get(state.submachine or "") if state.submachine else None
        regions = sub.regions if sub is not None else state.regions
        sid = self._id(copy.instance, state.id)
        transitions = [
            self._transition(copy, t, state, sid)
            for t in self._ordered(copy.leaving.get(state.id, []))
        ]
        transitions += self._joins(copy, state)
        points = [n for p in state.connection_points if (n := self._vertex(copy, p)) is not None]
        initial: c.Transition | None = None
        if sub is not None:
            initial, inner = self._machine_content(sub, (*copy.instance, state.id), at_root=False)
            children = points + inner
        elif len(regions) > 1:
            children = points + self._region_nodes(copy, regions)
        elif regions:
            initial, inner = self._region(copy, regions[0], at_root=False)
            children = points + inner
        else:
            children = points
        entry_code = tuple(o for o in state.opaque if o.role in {"entry", "do"})
        exit_code = tuple(o for o in state.opaque if o.role == "exit")
        return c.Node(
            sid,
            "parallel" if len(regions) > 1 else "state",
            name=state.name or None,
            children=tuple(t for t in children if t is not None),
            initial=initial if len(regions) <= 1 else None,
            onentry=self._actions(state.entry, entry_code),
            onexit=self._actions(state.exit, exit_code),
            call=self._call(state),
            timers=tuple(self._timers(copy, state, sid)),
            transitions=tuple(t for t in transitions if t is not None),
            submachine=sub.name if sub is not None else None,
        )

    def _timers(self, copy: _Copy, state: State, sid: str) -> list[c.Timer]:
        timers = []
        for transition in copy.leaving.get(state.id, []):
            for trigger in transition.triggers:
                if trigger.kind == TriggerKind.TIME:
                    timers.append(
                        c.Timer(
                            self._timer_event(sid, transition, trigger, copy), trigger.delay_ms or 0
                        )
                    )
        return timers

    def _timer_event(self, sid: str, transition: Transition, trigger: Trigger, copy: _Copy) -> str:
        timed = [
            (t.id, n)
            for t in copy.leaving.get(transition.source, [])
            for n, tr in enumerate(t.triggers)
            if tr.kind == TriggerKind.TIME
        ]
        return f"after.{sid}.{timed.index((transition.id, transition.triggers.index(trigger)))}"

    def _call(self, state: State) -> c.Call | None:
        if state.activity is None:
            return None
        behaviour = self.index.behaviours[state.activity.behaviour]
        self.used_behaviours[behaviour.id] = behaviour
        bound = {b.name: b.value for b in state.activity.bindings}
        args = []
        for prop in behaviour.inputs:
            value = bound.get(prop.name)
            if value is not None:
                args.append(c.Arg(prop.ident, value, implicit=False))
            elif prop.name in self.data:
                args.append(c.Arg(prop.ident, expr.Name(name=prop.name), implicit=True))
        results = tuple(
            (prop.ident, self.data[prop.name].ident)
            for prop in behaviour.outputs
            if prop.name in self.data
        )
        outcomes = tuple(identifier(o) for o in behaviour.outcomes)
        return c.Call(
            behaviour.name, behaviour.ident, behaviour.kind.value, tuple(args), results, outcomes
        )

    def _history(self, copy: _Copy, vertex: Pseudostate) -> c.Node:
        hid = self._id(copy.instance, vertex.id)
        leaving = copy.leaving.get(vertex.id, [])
        placed = copy.placed[vertex.id]
        default: c.Transition | None = None
        if leaving:
            transition = leaving[0]
            default = c.Transition(
                events=(),
                targets=tuple(self._targets(copy, transition.target)),
                actions=self._actions(transition.effect, transition.opaque),
            )
        else:  # no default given: UML enters the region's default state
            region = placed.region
            initials = initial_of(region) if region is not None else []
            first = copy.leaving.get(initials[0].id, []) if initials else []
            if first:
                default = c.Transition(
                    events=(), targets=tuple(self._targets(copy, first[0].target))
                )
        if placed.parent is None and not copy.instance:
            # history at a machine's top level: a transient state (SCXML allows <history>
            # only inside states, and a machine is entered once)
            transitions = (default,) if default is not None else ()
            return c.Node(
                hid,
                "state",
                name=vertex.name or None,
                pseudostate=vertex.kind.value,
                transitions=transitions,
            )
        deep = vertex.kind == PseudoKind.DEEP_HISTORY
        return c.Node(
            hid,
            "history",
            name=vertex.name or None,
            history="deep" if deep else "shallow",
            initial=default,
        )

    def _transient_transitions(self, copy: _Copy, vertex: Pseudostate) -> list[c.Transition]:
        leaving = copy.leaving.get(vertex.id, [])
        if vertex.kind == PseudoKind.FORK and leaving:
            targets = tuple(t for tr in leaving for t in self._targets(copy, tr.target))
            actions = tuple(a for tr in leaving for a in self._actions(tr.effect, tr.opaque))
            return [c.Transition(events=(), targets=targets, actions=actions)]
        found: list[c.Transition] = []
        if vertex.kind == PseudoKind.EXIT_POINT and copy.instance:
            found += self._exit_point(copy, vertex)
        sid = self._id(copy.instance, vertex.id)
        for transition in self._ordered(leaving):
            lowered = self._transition(copy, transition, vertex, sid)
            if lowered is not None:
                found.append(lowered)
        return found

    def _exit_point(self, copy: _Copy, vertex: Pseudostate) -> list[c.Transition]:
        """A submachine's exit point continues with the outgoing transitions of the
        ConnectionPointReferences that name it, in the machine that holds the submachine state."""
        outer = self.copies[copy.instance[:-1]]
        holder = outer.placed.get(copy.instance[-1])
        if holder is None or not isinstance(holder.vertex, State):
            return []
        sid = self._id(copy.instance, vertex.id)
        found = []
        for conn in holder.vertex.connections:
            if vertex.id in conn.exit:
                for transition in self._ordered(outer.leaving.get(conn.id, [])):
                    lowered = self._transition(outer, transition, holder.vertex, sid)
                    if lowered is not None:
                        found.append(lowered)
        return found

    # --- transitions

    @staticmethod
    def _ordered(transitions: list[Transition]) -> list[Transition]:
        """Model order, with `else` guards last (the first enabled transition is taken)."""
        return sorted(transitions, key=lambda t: isinstance(t.guard, expr.Else))

    def _transition(
        self, copy: _Copy, transition: Transition, source: Vertex, sid: str
    ) -> c.Transition | None:
        target = copy.placed.get(transition.target)
        if (
            target is not None
            and isinstance(target.vertex, Pseudostate)
            and target.vertex.kind == PseudoKind.JOIN
        ):
            return None  # stands on the sources' common ancestor (see _joins)
        internal_self = transition.kind == "internal" and transition.source == transition.target
        events = self._events(transition, source, sid, copy)
        outputs = self._outputs_read(source, sid, events)
        guard = transition.guard
        if guard is not None and outputs:
            guard = expr.replace_fields(guard, outputs)
        return c.Transition(
            events=events,
            targets=() if internal_self else tuple(self._targets(copy, transition.target)),
            cond=None if guard is None or isinstance(guard, expr.Else) else guard,
            internal=transition.kind == "local",
            actions=self._actions(transition.effect, transition.opaque, outputs),
            name=transition.name
            if transition.name and not transition.name.startswith("Transition")
            else None,
        )

    def _outputs_read(self, source: Vertex, sid: str, events: tuple[str, ...]) -> dict[str, str]:
        """On a transition taken by the outcome of the source's behaviour, `event.<output>` is
        the member datum the output was just written to (docs/semantics.md: the outcome event
        itself carries no data, so that it stays an internal event in every engine)."""
        if not isinstance(source, State) or source.activity is None:
            return {}
        if not c.takes_outcome(events, sid):
            return {}
        behaviour = self.index.behaviours[source.activity.behaviour]
        return {p.name: p.name for p in behaviour.outputs if p.name in self.data}

    def _events(
        self, transition: Transition, source: Vertex, sid: str, copy: _Copy
    ) -> tuple[str, ...]:
        if transition.triggers:
            return tuple(
                dict.fromkeys(
                    self._descriptor(t, transition, sid, copy) for t in transition.triggers
                )
            )
        if not isinstance(source, State) or transition.source != source.id:
            return ()
        if source.activity is not None and not source.regions and not source.submachine:
            return (f"outcome.{sid}",)
        if source.regions or source.submachine:
            return (f"done.state.{sid}",)
        return ()

    def _descriptor(self, trigger: Trigger, transition: Transition, sid: str, copy: _Copy) -> str:
        if trigger.kind == TriggerKind.OUTCOME:
            return f"outcome.{sid}.{identifier(trigger.name)}"
        if trigger.kind == TriggerKind.TIME:
            return self._timer_event(sid, transition, trigger, copy)
        if trigger.kind == TriggerKind.ANY:
            return "*"
        event = self.index.events.get(trigger.event or "")
        return event.ident if event is not None else identifier(trigger.name)

    def _joins(self, copy: _Copy, state: State) -> list[c.Transition]:
        found = []
        for vertex_id in copy.joins:
            vertex = copy.placed[vertex_id].vertex
            arriving = copy.arriving.get(vertex_id, [])
            sources = [t.source for t in arriving]
            if not sources or self._common_ancestor(copy, sources) != state.id:
                continue
            leaving = copy.leaving.get(vertex_id, [])
            guard = leaving[0].guard if leaving else None
            events = tuple(
                dict.fromkeys(
                    self._descriptor(t, tr, self._id(copy.instance, tr.source), copy)
                    for tr in arriving
                    for t in tr.triggers
                )
            )
            actions = tuple(
                a for t in [*arriving, *leaving] for a in self._actions(t.effect, t.opaque)
            )
            found.append(
                c.Transition(
                    events=events,
                    targets=tuple(self._targets(copy, leaving[0].target)) if leaving else (),
                    cond=None if guard is None or isinstance(guard, expr.Else) else guard,
                    in_states=tuple(self._id(copy.instance, s) for s in sources),
                    actions=actions,
                    join=vertex.name or self._id(copy.instance, vertex_id),
                )
            )
        return found

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
            if all(candidate in ch for ch in chains[1:]):
                return candidate
        return None

    def _targets(self, copy: _Copy, vertex_id: str) -> list[str]:
        placed = copy.placed.get(vertex_id)
        if placed is None:
            owner = connection_owner(copy.machine).get(vertex_id)
            if owner is None:
                return []
            conn = next(cr for cr in owner.connections if cr.id == vertex_id)
            inner = (*copy.instance, owner.id)
            if conn.entry and any((inner, e) in self.vertex_ids for e in conn.entry):
                return [self._id(inner, e) for e in conn.entry]
            return [self._id(copy.instance, owner.id)]
        vertex = placed.vertex
        if isinstance(vertex, Pseudostate) and vertex.kind == PseudoKind.TERMINATE:
            return [self.terminate_id or ""]
        return [self._id(copy.instance, vertex_id)]

    # --- actions

    def _data_ident(self, name: str) -> str:
        prop = self.data.get(name)
        return prop.ident if prop is not None else identifier(name)

    def _event_ident(self, name: str) -> str:
        event = self.index.events_by_name.get(name)
        return event.ident if event is not None else identifier(name)

    def _actions(
        self,
        actions: tuple[expr.Action, ...],
        opaque: tuple[OpaqueCode, ...],
        outputs: dict[str, str] | None = None,
    ) -> tuple[c.Action, ...]:
        lowered: list[c.Action] = []
        for action in actions:
            if outputs:
                action = _read_outputs(action, outputs)
            if isinstance(action, expr.Assign):
                lowered.append(c.Assign(self._data_ident(action.target), action.value))
                continue
            params = self._params(action.event, action.args)
            if isinstance(action, expr.Raise):
                lowered.append(c.Raise(self._event_ident(action.event), params))
            else:
                lowered.append(c.Send(self._event_ident(action.event), params))
        lowered += [c.Opaque(code.language or "unspecified", code.body) for code in opaque]
        return tuple(lowered)

    def _params(self, event_name: str, args: tuple[expr.Arg, ...]) -> tuple[c.Param, ...]:
        """The effect's fields, then every declared field it leaves out with its default (the
        value rule: an event always carries all its fields)."""
        given = tuple(c.Param(identifier(a.name), a.value) for a in args)
        event = self.index.events_by_name.get(event_name)
        if event is None:
            return given
        named = {p.name for p in given}
        return given + tuple(
            c.Param(f.ident, c.FieldDefault(self._initial(f)))
            for f in event.fields
            if f.ident not in named
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


def _behaviour_info(behaviour: Behaviour) -> c.BehaviourInfo:
    ros = behaviour.ros
    return c.BehaviourInfo(
        name=behaviour.name,
        ident=behaviour.ident,
        kind=behaviour.kind.value,
        library=behaviour.library,
        outcomes=behaviour.outcomes,
        requires=behaviour.requires,
        inputs=tuple((p.ident, p.type) for p in behaviour.inputs),
        outputs=tuple((p.ident, p.type) for p in behaviour.outputs),
        ros_kind=ros.kind if ros else None,
        ros_name=ros.name if ros else None,
        ros_type=ros.type if ros else None,
    )


def _read_outputs(action: expr.Action, outputs: dict[str, str]) -> expr.Action:
    if isinstance(action, expr.Assign):
        return action.model_copy(update={"value": expr.replace_fields(action.value, outputs)})
    args = tuple(
        a.model_copy(update={"value": expr.replace_fields(a.value, outputs)}) for a in action.args
    )
    return action.model_copy(update={"args": args})


def _vertex_name(vertex: Vertex) -> str:
    if vertex.name:
        return identifier(vertex.name)
    if isinstance(vertex, FinalState):
        return "final"
    if isinstance(vertex, Pseudostate):
        return identifier(vertex.kind.value)
    return "state"
