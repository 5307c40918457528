"""The lowered statechart: one member's machine with submachines inlined, pseudostates resolved
and every id, event descriptor and action decided. Every output (SCXML, smach, rclpy, asyncio) is
rendered from this one structure, so they agree on structure and names by construction.
"""

from __future__ import annotations

from dataclasses import field
from typing import Any, Literal

from swarmgen import expr
from swarmgen.ir.nodes import Value
from swarmgen.records import dataclass

NodeKind = Literal["state", "parallel", "final", "history"]


@dataclass(frozen=True, slots=True)
class Assign:
    """`location = value` on member data; an invalid location (an SCXML document's, kept as
    written) assigns nothing and fails when it runs (error.execution)."""

    location: str  # data id, a system variable, or the invalid location's text
    value: expr.Expr
    invalid: bool = False


@dataclass(frozen=True, slots=True)
class FieldDefault:
    """A JSON-like value the compiler supplies (a field's default when an effect omits it)."""

    value: Any


@dataclass(frozen=True, slots=True)
class Param:
    """One field of a raised or sent event: its name and value."""

    name: str  # identifier
    value: expr.Expr | FieldDefault


@dataclass(frozen=True, slots=True)
class Delay:
    """When a delayed raise arrives: `amount` in `unit` (ms, s; "": a duration string)."""

    amount: expr.Expr
    unit: str


@dataclass(frozen=True, slots=True)
class Raise:
    """An event for this member only: the internal queue; with a delay, its external queue
    once the delay is over (unless cancelled by its send id first)."""

    event: str
    params: tuple[Param, ...] = ()
    delay: Delay | None = None
    sendid: str | None = None
    target: expr.Expr | None = None  # W3C's <send target> (docs/semantics.md, "Targets")
    via: expr.Expr | None = None  # W3C's <send type|typeexpr> (docs/semantics.md, "Targets")
    into: str | None = None  # the datum (id) W3C's idlocation writes the generated send id to
    named: expr.Expr | None = None  # W3C's <send eventexpr>: the name, computed (`event` "")
    content: expr.Expr | None = None  # W3C's <send><content>: the event's whole data


@dataclass(frozen=True, slots=True)
class Cancel:
    """Drop the pending delayed raises of a send id (or of the one `expr` computes)."""

    sendid: str | None
    expr: expr.Expr | None = None


@dataclass(frozen=True, slots=True)
class Send:
    """An event to the rest of the swarm."""

    event: str
    params: tuple[Param, ...] = ()


@dataclass(frozen=True, slots=True)
class Opaque:
    """Code in a foreign language: kept for readers, never executed."""

    language: str
    text: str


@dataclass(frozen=True, slots=True)
class If:
    """`if`/`elif`/`else`: (condition or None for `else`, actions) per branch, in order."""

    branches: tuple[tuple[expr.Expr | None, tuple[Action, ...]], ...]


@dataclass(frozen=True, slots=True)
class ForEach:
    """`for item, index in array do ... end`: data ids written per item, then the actions."""

    array: expr.Expr
    item: str  # data id
    index: str | None  # data id
    actions: tuple[Action, ...]


@dataclass(frozen=True, slots=True)
class Log:
    """`log label, value`: to the member's log (no state or trace change)."""

    label: str
    value: expr.Expr


@dataclass(frozen=True, slots=True)
class Block:
    """`block ... end`: its own error scope (SCXML: an `<onentry>`/`<onexit>` of its own)."""

    actions: tuple[Action, ...]


Action = Assign | Raise | Send | Cancel | If | ForEach | Log | Block | Opaque


def flat(actions: tuple[Action, ...]) -> list[Action]:
    """The actions and, for an `if`, every branch's actions (pre-order)."""
    found: list[Action] = []
    for action in actions:
        found.append(action)
        if isinstance(action, If):
            for _, inner in action.branches:
                found += flat(inner)
        if isinstance(action, ForEach | Block):
            found += flat(action.actions)
    return found


@dataclass(frozen=True, slots=True)
class Arg:
    """One input of a behaviour call and the expression that gives it."""

    name: str  # input identifier
    value: expr.Expr
    implicit: bool  # read from member data of the same name (no binding in the model)


@dataclass(frozen=True, slots=True)
class Call:
    """The library behaviour a state runs while it is active."""

    behaviour: str  # model name
    ident: str
    kind: str  # ComplexBehavior, SwarmBehavior, SwarmFunction, HardwareFunction
    args: tuple[Arg, ...]
    # (output identifier, data id it is written to): written when the behaviour ends, before
    # its outcome is matched (docs/semantics.md)
    results: tuple[tuple[str, str], ...]
    outcomes: tuple[str, ...] = ()  # identifiers of the behaviour's declared outcomes


@dataclass(frozen=True, slots=True)
class Timer:
    """A timer a state starts on entry: `event` after `delay_ms`."""

    event: str
    delay_ms: int


@dataclass(frozen=True, slots=True)
class Transition:
    """A lowered transition: events, targets, guard and actions, as every output renders it."""

    events: tuple[str, ...]  # SCXML event descriptors; empty: eventless
    targets: tuple[str, ...]  # node ids; empty: targetless (internal transition of UML)
    cond: expr.Expr | None = None
    in_states: tuple[str, ...] = ()  # join: all of these must be active (ANDed with cond)
    internal: bool = False  # SCXML type="internal" (UML local transition)
    actions: tuple[Action, ...] = ()
    name: str | None = None  # the model's transition name, when meaningful
    join: str | None = None  # the join pseudostate this transition stands for
    # on a potential microstep cycle: the step bound counts it (docs/semantics.md, `cycles`)
    bounded: bool = False


def takes_outcome(events: tuple[str, ...], state_id: str) -> bool:
    """Whether a transition with these descriptors is taken by an outcome of the behaviour of
    `state_id` (`outcome.<id>` for any outcome, `outcome.<id>.<outcome>` for one)."""
    prefix = f"outcome.{state_id}"
    return any(e == prefix or e.startswith(prefix + ".") for e in events)


@dataclass(frozen=True, slots=True)
class Invoke:
    """A child SCXML session the state runs while it is active (W3C `<invoke>`): its lowered
    chart and what the parent gives it (docs/semantics.md, "Invoked sessions")."""

    chart: Chart
    invokeid: str | None = None
    idlocation: str | None = None  # the parent's data id the made invoke id is written to
    kind: str | None = None  # `type` as written
    kind_expr: expr.Expr | None = None  # `typeexpr`
    autoforward: bool = False
    params: tuple[Param, ...] = ()  # by the child's data ids: the values they start with
    finalize: tuple[Action, ...] = ()


@dataclass(frozen=True, slots=True)
class Node:
    """A state, parallel state, final state or history node of the chart, with its children."""

    id: str
    kind: NodeKind
    name: str | None = None  # the model's name
    children: tuple[Node, ...] = ()
    initial: Transition | None = None  # <initial> of a compound state, default of a history
    history: Literal["shallow", "deep"] | None = None
    onentry: tuple[Action, ...] = ()
    onexit: tuple[Action, ...] = ()
    call: Call | None = None
    timers: tuple[Timer, ...] = ()
    transitions: tuple[Transition, ...] = ()
    region: str | None = None  # the model's region name (a region of a parallel state)
    submachine: str | None = None  # name of the inlined machine
    pseudostate: str | None = None  # choice, junction, fork, entryPoint, ... (transient states)
    donedata: tuple[Param, ...] = ()  # a final state's: the fields of its done.state event
    donecontent: expr.Expr | None = None  # or the event's whole data
    invokes: tuple[Invoke, ...] = ()


@dataclass(frozen=True, slots=True)
class DataItem:
    """One datum of the member: its ids, type, default and initial value."""

    id: str
    name: str
    type: str | None
    default: Value  # the model's default (None: none given)
    initial: Any  # what it holds at start: the default, typed, else the type's zero
    zero: Any  # what an output the behaviour did not give writes (`values.blank`)


@dataclass(frozen=True, slots=True)
class BehaviourInfo:
    """A behaviour the chart calls: kind, library, outcomes, inputs, outputs and ROS binding."""

    name: str
    ident: str
    kind: str
    library: str
    outcomes: tuple[str, ...]
    requires: tuple[str, ...]
    inputs: tuple[tuple[str, str | None], ...]  # (identifier, type)
    outputs: tuple[tuple[str, str | None], ...]
    ros_kind: str | None = None
    ros_name: str | None = None
    ros_type: str | None = None
    sequences: frozenset[str] = frozenset()  # identifiers of inputs and outputs that are lists
    # (identifier, initial value) of each output: the shape a simulated behaviour fills
    # (a data type's nested fields with the model's defaults, `values.initial`)
    output_initials: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True, slots=True)
class EventInfo:
    """An event the chart raises, sends or waits for, with its fields and their defaults."""

    name: str
    ident: str
    sender: str | None
    scope: str | None
    fields: tuple[tuple[str, str | None], ...]  # (identifier, type)
    defaults: tuple[tuple[str, Any], ...] = ()  # (identifier, value when the sender omits it)


@dataclass(frozen=True, slots=True)
class HardwareInfo:
    """A hardware part of the member type: name, type and count."""

    part: str
    type: str
    count: int


@dataclass(frozen=True, slots=True)
class Chart:
    """One document: a member type's behaviour (or a stand-alone machine)."""

    name: str  # identifier of the document (member type or machine)
    machine: str  # the root machine's model name
    member: str | None  # member type's model name
    role: str | None
    source: str  # base name of the model file
    data: tuple[DataItem, ...]
    initial: tuple[str, ...]  # ids entered when the machine starts
    children: tuple[Node, ...]
    hardware: tuple[HardwareInfo, ...] = ()
    behaviours: tuple[BehaviourInfo, ...] = ()
    events: tuple[EventInfo, ...] = ()
    notes: dict[str, str] = field(default_factory=dict)

    def walk(self) -> list[Node]:
        """All nodes, in document order."""
        found: list[Node] = []
        stack = list(reversed(self.children))
        while stack:
            node = stack.pop()
            found.append(node)
            stack.extend(reversed(node.children))
        return found
