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
from typing import TypeGuard

from swarmgen import expr
from swarmgen.chart import model as c
from swarmgen.chart.cycles import bound_cycles
from swarmgen.chart.instates import resolve_in_states
from swarmgen.chart.lowering import Copy, Instance
from swarmgen.chart.transitions import Transitions
from swarmgen.ir.nodes import (
    Behaviour,
    Event,
    FinalState,
    Invoke,
    Machine,
    Model,
    PseudoKind,
    Pseudostate,
    Region,
    State,
    TriggerKind,
    Vertex,
)
from swarmgen.ir.query import ModelIndex, initial_of, walk
from swarmgen.names import IdAllocator, identifier

_TRANSIENT = {
    PseudoKind.CHOICE,
    PseudoKind.JUNCTION,
    PseudoKind.FORK,
    PseudoKind.ENTRY_POINT,
    PseudoKind.EXIT_POINT,
}
_HISTORY = {PseudoKind.SHALLOW_HISTORY, PseudoKind.DEEP_HISTORY}


def lower(model: Model) -> tuple[c.Chart, ...]:
    """One chart per member type with a machine, then one per remaining top-level machine.

    The pipeline lowers a model once, after the model-level checks passed (`check.may_lower`),
    and hands the charts to the chart-level checks and every output."""
    # `In(name)` to chart ids, then the step bound's marks
    return tuple(bound_cycles(resolve_in_states(chart)) for chart in _lower(model))


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


class _Lowering(Transitions):
    """Lowers one machine (with its submachines) into one chart: data, structure, metadata."""

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
                c.DataItem(p.ident, p.name, p.type, p.default, *self._initial_and_blank(p))
                for p in sorted(self.data.values(), key=lambda p: p.name)
            ),
            initial=initial,
            children=tuple(children),
            hardware=tuple(
                c.HardwareInfo(p.name, p.type_name, p.count)
                for p in (member.hardware if member else ())
            ),
            behaviours=tuple(
                self._behaviour_info(b)
                for b in sorted(self.used_behaviours.values(), key=lambda b: b.name)
            ),
            events=tuple(self._event_info(e) for e in self._used_events()),
        )

    def _event_info(self, event: Event) -> c.EventInfo:
        return c.EventInfo(
            name=event.name,
            ident=event.ident,
            sender=event.sender,
            scope=event.scope,
            fields=tuple((f.ident, f.type) for f in event.fields),
            defaults=tuple((f.ident, self._initial(f)) for f in event.fields),
        )

    def _behaviour_info(self, behaviour: Behaviour) -> c.BehaviourInfo:
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
            sequences=frozenset(p.ident for p in (*behaviour.inputs, *behaviour.outputs) if p.many),
            output_initials=tuple((p.ident, self._initial(p)) for p in behaviour.outputs),
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

    def _region_nodes(self, copy: Copy, regions: Sequence[Region]) -> list[c.Node]:
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
        self, copy: Copy, region: Region, at_root: bool
    ) -> tuple[c.Transition | None, list[c.Node]]:
        initial = None
        initials = initial_of(region)
        if initials:
            leaving = copy.leaving.get(initials[0].id, [])
            if leaving:
                initial = self._default(copy, leaving[0])
        children = [n for v in region.vertices if (n := self._vertex(copy, v)) is not None]
        return initial, children

    def _vertex(self, copy: Copy, vertex: Vertex) -> c.Node | None:
        if isinstance(vertex, FinalState):
            return c.Node(
                self._id(copy.instance, vertex.id),
                "final",
                name=vertex.name or None,
                onentry=self._actions(vertex.entry, ()),
                onexit=self._actions(vertex.exit, ()),
                donedata=tuple(c.Param(identifier(a.name), a.value) for a in vertex.donedata),
                donecontent=vertex.done_content,
            )
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

    def _state(self, copy: Copy, state: State) -> c.Node:
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
            invokes=tuple(self._invoke(i) for i in state.invokes),
        )

    def _invoke(self, invoke: Invoke) -> c.Invoke:
        """The child's own chart (lowered as a model of its own) and what the parent gives
        it: params by the child's data ids (a name the child does not declare sets nothing,
        but one that reads an invalid location stays: it fails when the invoke starts, and W3C
        6.4 cancels the invoke with error.execution)."""
        chart = lower(invoke.session)[0]
        child_ids = {d.name: d.id for d in chart.data}
        location = self.data.get(invoke.idlocation or "")
        return c.Invoke(
            chart=chart,
            invokeid=invoke.invokeid,
            idlocation=location.ident if location is not None else None,
            kind=invoke.kind,
            kind_expr=invoke.kind_expr,
            autoforward=invoke.autoforward,
            params=tuple(
                c.Param(child_ids.get(p.name, p.name), p.value)
                for p in invoke.params
                if p.name in child_ids
                or any(isinstance(e, expr.Invalid) for e in expr.walk(p.value))
            ),
            finalize=self._actions(invoke.finalize, ()),
        )

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

    def _history(self, copy: Copy, vertex: Pseudostate) -> c.Node:
        hid = self._id(copy.instance, vertex.id)
        leaving = copy.leaving.get(vertex.id, [])
        placed = copy.placed[vertex.id]
        default: c.Transition | None = None
        if leaving:
            default = self._default(copy, leaving[0])
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

    def _used_events(self) -> list[Event]:
        names: set[str] = set()
        for machine in self.index.reachable_machines(self.root):
            for transition in machine.transitions:
                names.update(t.name for t in transition.triggers if t.kind == TriggerKind.EVENT)
                names.update(a.event or "" for a in expr.flat(transition.effect) if _names_event(a))
            for placed in walk(machine):
                if isinstance(placed.vertex, State):
                    actions = (*placed.vertex.entry, *placed.vertex.exit)
                    names.update(a.event or "" for a in expr.flat(actions) if _names_event(a))
        return [e for e in self.index.model.events if e.name in names]


def _names_event(action: expr.Action) -> TypeGuard[expr.Raise | expr.Send]:
    """Whether the action raises or sends a named event (an assignment or `cancel` names none,
    nor does `raise (expr)`, whose name is computed)."""
    return isinstance(action, expr.Raise | expr.Send) and action.event is not None
