"""Lowering transitions: event descriptors, guards, targets, joins, timers, transient
pseudostates' transitions and the actions of effects (docs/scxml.md)."""

from __future__ import annotations

from swarmgen import expr
from swarmgen.chart import model as c
from swarmgen.chart.lowering import Context, Copy
from swarmgen.ir.nodes import (
    OpaqueCode,
    PseudoKind,
    Pseudostate,
    State,
    Transition,
    Trigger,
    TriggerKind,
    Vertex,
)
from swarmgen.ir.query import connection_owner
from swarmgen.names import event_name, identifier


def cond(guard: expr.Expr | None) -> expr.Expr | None:
    """The guard a lowered transition tests: none for no guard and for `else` (ordered last)."""
    return None if guard is None or isinstance(guard, expr.Else) else guard


class Transitions(Context):
    """The transition and action half of the lowering (the structure is in `lower`)."""

    def _default(self, copy: Copy, transition: Transition) -> c.Transition:
        """An eventless, unguarded transition (an initial or a history default)."""
        return c.Transition(
            events=(),
            targets=tuple(self._targets(copy, transition.target)),
            actions=self._actions(transition.effect, transition.opaque),
        )

    @staticmethod
    def _ordered(transitions: list[Transition]) -> list[Transition]:
        """Model order, with `else` guards last (the first enabled transition is taken)."""
        return sorted(transitions, key=lambda t: isinstance(t.guard, expr.Else))

    def _transition(
        self, copy: Copy, transition: Transition, source: Vertex, sid: str
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
            targets=()
            if internal_self
            else (*self._targets(copy, transition.target), *self._reentered(copy, transition)),
            cond=cond(guard),
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
        self, transition: Transition, source: Vertex, sid: str, copy: Copy
    ) -> tuple[str, ...]:
        if transition.triggers:
            return tuple(
                dict.fromkeys(
                    self._descriptor(t, transition, sid, copy) for t in transition.triggers
                )
            )
        if transition.eventless or not isinstance(source, State) or transition.source != source.id:
            return ()
        if source.activity is not None and not source.regions and not source.submachine:
            return (f"outcome.{sid}",)
        if source.regions or source.submachine:
            return (f"done.state.{sid}",)
        return ()

    def _descriptor(self, trigger: Trigger, transition: Transition, sid: str, copy: Copy) -> str:
        if trigger.kind == TriggerKind.OUTCOME:
            return f"outcome.{sid}.{identifier(trigger.name)}"
        if trigger.kind == TriggerKind.TIME:
            return self._timer_event(sid, transition, trigger, copy)
        if trigger.kind == TriggerKind.ANY:
            return "*"
        if trigger.kind in (TriggerKind.ERROR, TriggerKind.DONE):
            return trigger.name  # done.state.<name>: the state's id by `chart.instates`
        event = self.index.events.get(trigger.event or "")
        return event.ident if event is not None else event_name(trigger.name)

    def _joins(self, copy: Copy, state: State) -> list[c.Transition]:
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
                    cond=cond(guard),
                    in_states=tuple(self._id(copy.instance, s) for s in sources),
                    actions=actions,
                    join=vertex.name or self._id(copy.instance, vertex_id),
                )
            )
        return found

    @staticmethod
    def _common_ancestor(copy: Copy, sources: list[str]) -> str | None:
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

    def _reentered(self, copy: Copy, transition: Transition) -> tuple[str, ...]:
        """The state the transition exits and enters again as a whole, as a further target
        after its own: what SCXML's `target="a1 p"` means, with `p` a parallel holding `a1`
        (its other regions entered by default, `a1`'s by the first target)."""
        state = transition.reenters
        if state is None:
            return ()
        if state == copy.machine.id:  # the machine's own regions: the root's parallel node
            key = (copy.instance, f"{state}#parallel")
            return (self.vertex_ids[key],) if key in self.vertex_ids else ()
        return (self._id(copy.instance, state),)

    def _targets(self, copy: Copy, vertex_id: str) -> list[str]:
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

    def _timers(self, copy: Copy, state: State, sid: str) -> list[c.Timer]:
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

    def _timer_event(self, sid: str, transition: Transition, trigger: Trigger, copy: Copy) -> str:
        timed = [
            (t.id, n)
            for t in copy.leaving.get(transition.source, [])
            for n, tr in enumerate(t.triggers)
            if tr.kind == TriggerKind.TIME
        ]
        return f"after.{sid}.{timed.index((transition.id, transition.triggers.index(trigger)))}"

    def _transient_transitions(self, copy: Copy, vertex: Pseudostate) -> list[c.Transition]:
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

    def _exit_point(self, copy: Copy, vertex: Pseudostate) -> list[c.Transition]:
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

    def _data_ident(self, name: str) -> str:
        prop = self.data.get(name)
        return prop.ident if prop is not None else identifier(name)

    def _event_ident(self, name: str) -> str:
        event = self.index.events_by_name.get(name)
        return event.ident if event is not None else event_name(name)

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
                lowered.append(self._assign(action))
                continue
            if isinstance(action, expr.Cancel):
                lowered.append(c.Cancel(action.sendid, action.expr))
                continue
            if isinstance(action, expr.Done):  # a final state's done data: `donedata`
                continue
            if isinstance(action, expr.Log):
                lowered.append(c.Log(action.label, action.value))
                continue
            if isinstance(action, expr.Block):
                lowered.append(c.Block(self._actions(action.actions, ())))
                continue
            if isinstance(action, expr.If):
                lowered.append(self._if(action))
                continue
            if isinstance(action, expr.ForEach):
                index = self._data_ident(action.index) if action.index is not None else None
                inner = self._actions(action.actions, ())
                item = self._data_ident(action.item)
                lowered.append(c.ForEach(action.array, item, index, inner))
                continue
            if isinstance(action, expr.Raise):
                lowered.append(self._raise(action))
            else:
                params = self._params(action.event, action.args)
                lowered.append(c.Send(self._event_ident(action.event), params))
        lowered += [c.Opaque(code.language or "unspecified", code.body) for code in opaque]
        return tuple(lowered)

    def _assign(self, action: expr.Assign) -> c.Assign:
        """To a datum by its id; a system variable keeps its name (read-only), an invalid
        location its text (both assign nothing and fail when they run)."""
        target = action.target
        if isinstance(target, expr.Invalid):
            return c.Assign(target.location, action.value, invalid=True)
        if target in expr.SYSTEM_VARIABLES:
            return c.Assign(target, action.value)
        return c.Assign(self._data_ident(target), action.value)

    def _raise(self, action: expr.Raise) -> c.Raise:
        """A raise with its fields (or its content value), its event's runtime name ("" when
        computed: `named`) and the options of W3C's `<send>`."""
        delay = action.delay
        if action.event is not None:
            params = self._params(action.event, action.args)
        else:  # `raise (expr)(f = ...)`: no declared event, so only the given fields
            params = tuple(c.Param(identifier(a.name), a.value) for a in action.args)
        return c.Raise(
            self._event_ident(action.event) if action.event is not None else "",
            params,
            c.Delay(delay.amount, delay.unit) if delay is not None else None,
            action.sendid,
            action.target,
            action.via,
            self._data_ident(action.into) if action.into is not None else None,
            action.named,
            action.content,
        )

    def _if(self, action: expr.If) -> c.If:
        """An `if` with each branch's actions lowered (outputs were read in `_actions`)."""
        return c.If(tuple((b.cond, self._actions(b.actions, ())) for b in action.branches))

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


def _read_outputs(action: expr.Action, outputs: dict[str, str]) -> expr.Action:
    return expr.map_action(action, lambda e: expr.replace_fields(e, outputs))
