"""The statechart structure generated code builds and the engine runs (standard library only).

Generated modules call `ChartBuilder` with ids, events, targets and the guard and action
functions swarmgen rendered from the model's expressions; `build()` links and checks it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from swarmgen.runtime.values import (
    PLAIN,
    Filler,
    Record,
    defaults_maker,
    duration_ms,
    fields_filler,
    fill,
    fill_fields,
    filler,
    record,
    zero_like,
)

# The value rule's helpers moved to `values`; they are still importable from here (the ROS
# runtime and older generated packages import them from `chart`).
__all__ = [
    "CACHE_LIMIT",
    "FINALIZE_PREFIX",
    "OUTCOME_PREFIX",
    "STEP_BOUND",
    "Action",
    "Call",
    "Chart",
    "ChartBuilder",
    "CommunicationError",
    "Cond",
    "Context",
    "Filler",
    "Invoke",
    "Node",
    "Record",
    "StepBoundExceeded",
    "Transition",
    "defaults_maker",
    "duration_ms",
    "fields_filler",
    "fill",
    "fill_fields",
    "filler",
    "record",
    "zero_like",
]

Cond = Callable[["Context"], bool]
Action = Callable[["Context"], None]


FINALIZE_PREFIX = "done.invoke."  # the host's word that a state's behaviour ended
OUTCOME_PREFIX = "outcome."  # the outcome as the state's transitions see it
# The step bound (docs/semantics.md): how many times the transitions that lie on a potential
# microstep cycle (`bounded`, decided by lowering) may be taken in one macrostep. The next one
# raises error.execution and is not taken, and they stay disabled until the next external event:
# a livelock ends its macrostep instead of spinning forever. The one place this number is
# defined; the SCXML support script and every Python backend read it from here.
STEP_BOUND = 1000
# How many event names a node's lookup caches keep before they start over (events of names no
# chart knows arrive from the swarm and from outside, and must not fill memory).
CACHE_LIMIT = 1024


class CommunicationError(RuntimeError):
    """An event that cannot be dispatched (a send to another session): error.communication."""


class StepBoundExceeded(RuntimeError):
    """The error.execution of the step bound: a macrostep took bounded transitions more than
    STEP_BOUND times."""


@dataclass(frozen=True, slots=True)
class Call:
    """The library behaviour a state runs: name, how to compute its inputs, where outputs go."""

    behaviour: str
    kind: str
    args: Callable[[Context], dict[str, Any]]
    results: tuple[tuple[str, str], ...] = ()  # (output, data key)
    outcomes: tuple[str, ...] = ()  # the declared outcomes (raised after the outputs are written)


@dataclass(frozen=True, slots=True)
class Invoke:
    """A child SCXML session a state starts while it is active (W3C `<invoke>`,
    docs/semantics.md "Invoked sessions"): its chart, id or idlocation, the type its
    `typeexpr` computes, the data it is given (`namelist` and `<param>`s), `<finalize>` and
    `autoforward`. The engine runs it (`sessions`), on the parent's host."""

    chart: Callable[[Context], Chart]  # builds the child's chart (once: `sessions.chart_of`)
    invokeid: str | None = None  # `id`; None: the engine makes `<state id>.<n>`
    idlocation: str | None = None  # the datum the made id is written to
    type: Callable[[Context], Any] | None = None  # `typeexpr`
    args: Callable[[Context], dict[str, Any]] | None = None  # namelist and params
    finalize: Action | None = None
    autoforward: bool = False


@dataclass(eq=False, slots=True)
class Node:
    """A state of the chart (or the root, or a history node), linked by ChartBuilder.build()."""

    id: str
    kind: str  # "scxml" (the root), "state", "parallel", "final", "history"
    name: str = ""
    parent: Node | None = None
    children: list[Node] = field(default_factory=list)
    transitions: list[Transition] = field(default_factory=list)
    initial: Transition | None = None
    history: str = ""  # "shallow" or "deep" for history nodes
    onentry: Action | None = None
    onexit: Action | None = None
    call: Call | None = None
    timers: tuple[tuple[str, int], ...] = ()  # (event, delay in ms)
    donedata: Callable[[Context], Any] | None = None  # a final state's done data
    invokes: tuple[Invoke, ...] = ()  # child sessions started while it is active
    order: int = 0  # document order
    depth: int = 0
    ancestors: tuple[Node, ...] = ()  # proper ancestors, innermost first (root included)
    lineage: tuple[Node, ...] = ()  # the node, then its ancestors

    # Computed once by ChartBuilder.build(): the engine's hot path reads these.
    is_atomic: bool = False
    is_compound: bool = False
    eventless: tuple[Transition, ...] = ()
    # Evented transitions by their descriptors' first dotted token ("*" apart): a descriptor
    # can only match a name that starts with its token, so a lookup finds every candidate.
    _by_token: dict[str, tuple[Transition, ...]] = field(default_factory=dict)
    _wildcard: tuple[Transition, ...] = ()
    _by_event: dict[str, tuple[Transition, ...]] = field(default_factory=dict)

    def matching(self, name: str) -> tuple[Transition, ...]:
        """This node's transitions whose descriptors match the event name, in document order."""
        if not self._by_token and not self._wildcard:
            return ()
        found = self._by_event.get(name)
        if found is None:
            if len(self._by_event) >= CACHE_LIMIT:  # distinct names without end: start over
                self._by_event.clear()
            some = self._by_token.get(name.partition(".")[0], ())
            if self._wildcard:
                some = (*some, *self._wildcard)
            found = (
                tuple(t for t in self.transitions if t in some and t.matches(name)) if some else ()
            )
            self._by_event[name] = found
        return found

    def index_events(self) -> None:
        """Index the evented transitions by descriptor token (ChartBuilder.build() calls it)."""
        by_token: dict[str, list[Transition]] = {}
        for transition in self.transitions:
            for descriptor in transition.events:
                if descriptor != "*":
                    bucket = by_token.setdefault(descriptor.partition(".")[0], [])
                    if transition not in bucket:
                        bucket.append(transition)
        self._by_token = {token: tuple(found) for token, found in by_token.items()}
        self._wildcard = tuple(t for t in self.transitions if "*" in t.events)

    def __repr__(self) -> str:
        return f"<{self.kind} {self.id}>"


@dataclass(eq=False, slots=True)
class Transition:
    """A transition: its source, event descriptors, targets, guard and action."""

    source: Node
    events: tuple[str, ...]
    targets: tuple[Node, ...]
    cond: Cond | None = None
    action: Action | None = None
    internal: bool = False
    order: int = 0
    bounded: bool = False  # on a potential microstep cycle: counted by the step bound

    def matches(self, name: str) -> bool:
        """SCXML event descriptors: `a.b` matches `a.b` and `a.b.c`; `*` matches anything."""
        for descriptor in self.events:
            if descriptor == "*" or name == descriptor:
                return True
            prefix = descriptor[:-2] if descriptor.endswith(".*") else descriptor
            if name.startswith(prefix) and name[len(prefix) : len(prefix) + 1] == ".":
                return True
        return False


@dataclass(slots=True)
class Chart:
    """A member's built statechart: its nodes, initial data and event field defaults."""

    name: str
    root: Node
    nodes: dict[str, Node]
    data: dict[str, Any]  # initial member data
    names: dict[str, str]  # node id -> model name
    events: dict[str, dict[str, Any]] = field(default_factory=dict)  # event -> field defaults
    # The dispatch tables its engines share (configuration.Tables), made by the first engine.
    tables: Any = field(default=None, compare=False, repr=False)

    def fresh_data(self) -> Record:
        """A new copy of the initial member data, as Records."""
        return Record({key: record(value) for key, value in self.data.items()})


class Context:
    """What guards and actions see: member data, the current event, and the engine's services."""

    __slots__ = ("_engine", "data", "event")

    def __init__(self, engine: Any, data: Record) -> None:
        self._engine = engine
        self.data = data
        self.event: Any = None

    @property
    def event_data(self) -> Record:
        """The current event's data; empty when it carries none (`_event.data` in SCXML)."""
        data = self.event.data if self.event is not None else None
        return data if isinstance(data, Record) else Record()

    def system(self, name: str) -> Any:
        """A system variable (`_event`, `_sessionid`, `_name`, `_ioprocessors`; W3C 5.10)."""
        return self._engine.system_variable(name, self.event)

    def assign_system(self, name: str) -> None:
        """`_sessionid = e`: system variables are read-only (W3C 5.10), so the assignment
        fails: the engine raises error.execution and the rest of the block is skipped."""
        raise AttributeError(f"the system variable {name} is read-only")

    def invalid(self, location: str) -> Any:
        """`invalid("x")`: a location an SCXML document reads or assigns that is none (no
        datum declares it, or the text is no location): W3C 5.4, 5.9, 6.4 raise error.execution
        when it runs, so the engine does and the rest of the block is skipped."""
        raise LookupError(f"{location!r} is not a valid location")

    @staticmethod
    def startswith(text: Any, prefix: Any) -> bool:
        """`startswith(text, prefix)`: both strings, else an error (error.execution), as the
        SCXML document's `$sg.startswith`."""
        if not isinstance(text, str) or not isinstance(prefix, str):
            raise TypeError(f"startswith takes strings, not {text!r} and {prefix!r}")
        return text.startswith(prefix)

    def is_active(self, node_id: str) -> bool:
        """`In(state)`: whether the state is active."""
        return bool(self._engine.is_active(node_id))

    def raise_event(self, name: str, data: Mapping[str, Any] | None = None) -> None:
        """`raise e`: an event to this member (the engine decides which queue)."""
        self._engine.raise_internal(name, data)

    def send(self, name: str, data: Mapping[str, Any] | None = None) -> None:
        """`send e`: an event to the swarm."""
        self._engine.send_swarm(name, data)

    def raise_later(
        self, name: str, data: Mapping[str, Any] | None, delay_ms: Any, sendid: str | None
    ) -> None:
        """`raise e after N ms [as id]`: an event to this member's external queue once the
        delay is over, unless `cancel id` comes first."""
        self._engine.raise_delayed(name, data, delay_ms, sendid)

    @staticmethod
    def each(value: Any) -> list[tuple[Any, int]]:
        """`for item, index in value`: (item, index) of a copy of the sequence (W3C's
        `<foreach>` iterates a shallow copy); anything else is an error (error.execution)."""
        if not isinstance(value, list | tuple):
            raise TypeError(f"'for' takes a sequence, not {value!r}")
        return [(item, index) for index, item in enumerate(list(value))]

    def holds(self, cond: Callable[[], Any]) -> bool:
        """The condition of an `if`/`elif`: one that fails is false and raises error.execution
        (W3C 5.9), and the actions after it go on."""
        try:
            return bool(cond())
        except Exception as err:
            self._engine.execution_error("condition of an if", err)
            return False

    def block(self, actions: Action) -> None:
        """`block ... end`: its actions; an error ends only them (error.execution), as each
        `<onentry>`/`<onexit>` element is a block of its own in SCXML."""
        try:
            actions(self)
        except Exception as err:
            self._engine.execution_error("block", err)

    def log(self, label: str, value: Any) -> None:
        """`log label, value`: to the member's log (the engine's `on_log`)."""
        self._engine.log(label, value)

    def raise_to(
        self,
        name: str,
        data: Mapping[str, Any] | None,
        target: Any,
        delay_ms: Any,
        sendid: str | None,
    ) -> None:
        """`raise e to target [after ...]`: W3C's `<send target>` (Engine.raise_targeted)."""
        self._engine.raise_targeted(name, data, target, delay_ms, sendid)

    def event_name(self, value: Any) -> str:
        """The name `raise (expr)` computed (W3C's `<send eventexpr>`): a string, as Qt SCXML
        takes it (one that is no W3C event name meets only `*`); anything else is an error
        (error.execution), nothing is raised."""
        if not isinstance(value, str) or not value:
            raise ValueError(f"{value!r} is not an event name")
        return value

    def raise_via(
        self,
        name: str,
        data: Mapping[str, Any] | None,
        options: tuple[Any, Any, str | None, Any],
        into: str | None = None,
    ) -> None:
        """`raise e [to t] via p [after d] [into v]`, options (target, delay_ms, sendid, via):
        W3C's `<send type|typeexpr idlocation>` (Engine.raise_through)."""
        self._engine.raise_through(name, data, options, into)

    def cancel(self, sendid: Any) -> None:
        """`cancel id` / `cancel (expr)`: the pending delayed events raised as that send id
        never arrive; a computed id that is no string is an error (error.execution)."""
        if not isinstance(sendid, str):
            raise TypeError(f"a send id is a string, not {sendid!r}")
        self._engine.cancel_delayed(sendid)

    @staticmethod
    def duration(value: Any) -> float:
        """A duration string (`"1.5s"`, `"200ms"`, SCXML's delay syntax) in milliseconds."""
        return duration_ms(value)

    def field(self, name: str) -> Any:
        """`event.<name>`: a field the current event does not carry is an error (SCXML's
        error.execution; the guard is false), as `$sg.field` in the emitted SCXML."""
        event = self.event
        data = event.data if event is not None else None
        if type(data) is Record:  # what the engine fills: no ABC check
            if name in data:
                return data[name]
        elif isinstance(data, Mapping) and name in data:
            return data[name]
        raise KeyError(f"the event has no field {name!r}")

    def opaque(self, language: str, text: str) -> None:
        """Code in a language swarmgen does not execute: recorded, not run."""


class ChartBuilder:
    """Used by generated code: declare nodes (parents first) and transitions, then `build()`."""

    def __init__(
        self,
        name: str,
        data: Mapping[str, Any] | None = None,
        events: Mapping[str, Mapping[str, Any]] | None = None,
    ) -> None:
        self._events = {k: dict(v) for k, v in (events or {}).items()}
        self._root = Node("", "scxml")
        self._nodes: dict[str, Node] = {}
        self._pending: list[tuple[str, tuple[str, ...], tuple[str, ...], dict[str, Any]]] = []
        self._initials: list[tuple[str | None, tuple[str, ...], Action | None]] = []
        self._zeros: dict[str, Any] = {}
        self._name = name
        self._data = dict(data or {})
        self._names: dict[str, str] = {}

    def node(
        self,
        node_id: str,
        kind: str,
        parent: str | None = None,
        *,
        name: str = "",
        onentry: Action | None = None,
        onexit: Action | None = None,
        call: Call | None = None,
        timers: Sequence[tuple[str, int]] = (),
        history: str = "",
        donedata: Callable[[Context], Any] | None = None,
        invokes: Sequence[Invoke] = (),
    ) -> None:
        """Declare a node under `parent` (None: the root), after its parent; a final state's
        `donedata` gives the fields of the done.state event entering it raises; `invokes` the
        child sessions the state runs while it is active."""
        if node_id in self._nodes or not node_id:
            raise ValueError(f"duplicate or empty node id {node_id!r}")
        owner = self._nodes[parent] if parent is not None else self._root
        node = Node(
            node_id, kind, name or node_id, owner, onentry=onentry, onexit=onexit, call=call
        )
        node.timers = tuple(timers)
        node.history = history
        node.donedata = donedata
        node.invokes = tuple(invokes)
        owner.children.append(node)
        self._nodes[node_id] = node
        self._names[node_id] = name or node_id

    def transition(
        self,
        source: str,
        events: Sequence[str] = (),
        targets: Sequence[str] = (),
        *,
        cond: Cond | None = None,
        action: Action | None = None,
        internal: bool = False,
        bounded: bool = False,
    ) -> None:
        """Declare a transition of `source`; targets are resolved by build()."""
        options = {"cond": cond, "action": action, "internal": internal, "bounded": bounded}
        self._pending.append((source, tuple(events), tuple(targets), options))

    def initial(
        self, parent: str | None, targets: Sequence[str], action: Action | None = None
    ) -> None:
        """The initial transition of a compound state (or the default of a history node);
        `parent=None` is the machine's own initial configuration."""
        self._initials.append((parent, tuple(targets), action))

    def build(self) -> Chart:
        """Link the declared nodes and transitions into a Chart, in document order."""
        order = 0
        stack: list[tuple[Node, int, tuple[Node, ...]]] = [(self._root, 0, ())]
        while stack:  # document order, depth and ancestors
            node, depth, ancestors = stack.pop()
            node.order, node.depth, node.ancestors = order, depth, ancestors
            node.lineage = (node, *ancestors)
            proper = any(c.kind != "history" for c in node.children)
            node.is_atomic = node.kind in {"state", "final"} and not proper
            node.is_compound = node.kind in {"state", "scxml"} and proper
            order += 1
            for child in reversed(node.children):
                stack.append((child, depth + 1, (node, *ancestors)))
        for node in self._nodes.values():
            if node.call is not None:
                node.transitions.append(self._finalize(node, node.call))
        for number, (source, events, targets, options) in enumerate(self._pending):
            node = self._lookup(source)
            node.transitions.append(
                Transition(
                    node, events, tuple(self._lookup(t) for t in targets), order=number, **options
                )
            )
        for node in self._nodes.values():
            node.eventless = tuple(t for t in node.transitions if not t.events)
            node.index_events()
        for parent, targets, action in self._initials:
            owner = self._lookup(parent) if parent is not None else self._root
            owner.initial = Transition(
                owner, (), tuple(self._lookup(t) for t in targets), action=action
            )
        return Chart(
            self._name, self._root, dict(self._nodes), self._data, self._names, self._events
        )

    def zeros(self, values: Mapping[str, Any]) -> None:
        """What an output a behaviour did not give writes into these data, where that is not
        `zero_like` of their initial value (an enumeration's zero is its first literal)."""
        self._zeros.update(values)

    def _zero(self, key: str) -> Any:
        return self._zeros[key] if key in self._zeros else zero_like(self._data.get(key))

    def _finalize(self, node: Node, call: Call) -> Transition:
        """The first transition of a behaviour's state (SCXML `<finalize>` semantics): on
        `done.invoke.<id>.<outcome>` it writes the outputs into member data, an output the
        behaviour did not give as its type's zero (as a ROS result holds it), then raises the
        internal event `outcome.<id>.<outcome>` when the outcome is declared, so guards and
        effects (where `event.<output>` reads the datum) see the new values, whether or not a
        transition takes the outcome."""
        # `fill(given, zero)` per output, its template walked once (this runs per outcome);
        # a plain zero is filled inline (`filler`'s) rather than by a function
        outputs = tuple(
            (output, key, zero, None if type(zero) in PLAIN else filler(zero))
            for output, key in call.results
            for zero in (self._zero(key),)
        )
        prefix = f"{FINALIZE_PREFIX}{node.id}."
        # the internal event each declared outcome's `done.invoke` name raises
        raised = {f"{prefix}{o}": f"{OUTCOME_PREFIX}{node.id}.{o}" for o in call.outcomes}

        def finalize(ctx: Context) -> None:
            event = ctx.event
            if outputs:
                data = event.data if event is not None else None
                given = data if isinstance(data, Record) else Record()
                store = ctx.data
                for output, key, zero, fill_output in outputs:
                    value = given.get(output)
                    if fill_output is not None:
                        store[key] = fill_output(value)
                    elif value is None:
                        store[key] = zero
                    else:
                        store[key] = value if type(value) in PLAIN else record(value)
            outcome = raised.get(event.name) if event is not None else None
            if outcome is not None:
                ctx._engine.raise_internal(outcome, None)  # `ctx.raise_event`'s

        return Transition(node, (prefix[:-1],), (), action=finalize, order=-1)

    def _lookup(self, node_id: str) -> Node:
        try:
            return self._nodes[node_id]
        except KeyError:
            raise ValueError(f"unknown node {node_id!r}") from None
