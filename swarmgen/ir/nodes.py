"""The intermediate representation: frozen pydantic models, every node with its source span.

Names are the model's own; `ident` fields hold the safe identifier made from them once, in
`ir.build`, so that every backend uses the same one. Collections are tuples, so the IR is
hashable and comparable in tests. References between nodes are by `id` (the xmi:id).
"""

from enum import StrEnum
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from swarmgen import fastnode
from swarmgen.expr import Action, Arg, Binding, Expr
from swarmgen.span import Span

Value = bool | int | float | str | None

DEFAULT_OUTCOMES = ("succeeded", "aborted", "preempted")


class Node(BaseModel):
    """The base of every IR node: frozen, no unknown fields. Made as validation makes it; the
    pydantic validators are built on first need only (`swarmgen.fastnode`)."""

    model_config = ConfigDict(frozen=True, extra="forbid", defer_build=True)

    def __init__(self, **data: Any) -> None:
        """The node of `data`: as given when validation would keep it so, else validated."""
        if not fastnode.fill(self, data):
            super().__init__(**data)


# --- data


class Property(Node):
    """An attribute: member data, a hardware parameter, an event field, a behaviour parameter."""

    id: str
    name: str
    ident: str
    type: str | None = None  # a primitive (Real, Integer, String, Boolean), data type, enumeration
    default: Value = None
    many: bool = False  # upper multiplicity `*` or above 1: a sequence (a list) of `type`
    span: Span


class DataType(Node):
    """A structured data type: named fields an event or a property can carry."""

    id: str
    name: str
    ident: str
    fields: tuple[Property, ...]
    ros_type: str | None = None  # the ROS message it is (`geometry_msgs/msg/Pose`), «RosMessage»
    span: Span


class Enumeration(Node):
    """A UML Enumeration: a value is the name of one of its literals (a string at run time)."""

    id: str
    name: str
    ident: str
    literals: tuple[str, ...]  # in model order; the first is the zero
    span: Span


# --- swarm and hardware


class HardwareKind(StrEnum):
    """What a hardware component is, by its profile stereotype."""

    SENSOR = "Sensor"
    ACTUATOR = "Actuator"
    CONTROLLER = "Controller"
    COMMUNICATION_INTERFACE = "CommunicationInterface"


class HardwareComponent(Node):
    """A hardware class (sensor, actuator, ...): what it can do and its parameters."""

    id: str
    name: str
    ident: str
    kind: HardwareKind
    generals: tuple[str, ...]  # names of the classes it specialises, directly
    capabilities: tuple[str, ...]  # its own name and every ancestor's, sorted
    parameters: tuple[Property, ...]
    communication_type: str | None = None
    communication_params: str | None = None
    communication_span: Span | None = None  # the stereotype application that gives them
    span: Span


class Part(Node):
    """A composite part: `uavs: UAV[4]` in a swarm, `sonar: SonarRangeFinder[4]` in a member."""

    name: str
    type_id: str
    type_name: str
    count: int
    span: Span


class MemberType(Node):
    """A kind of swarm member: its hardware parts, its data and its state machine."""

    id: str
    name: str
    ident: str
    role: str | None = None
    hardware: tuple[Part, ...]
    data: tuple[Property, ...]  # member data and parameters (attributes that are not parts)
    machine: str | None  # id of its behaviour state machine
    span: Span


class SwarmProperty(Node):
    """A user property of the swarm (a UML Constraint owned by the swarm class, stereotyped
    «Property»; docs/profile.md): its name, its text in the property language and where."""

    name: str
    text: str
    span: Span


class Swarm(Node):
    """A swarm composition: which member types, how many of each, and its properties."""

    id: str
    name: str
    ident: str
    members: tuple[Part, ...]
    properties: tuple[SwarmProperty, ...] = ()
    span: Span


# --- behaviour library and events


class BehaviourKind(StrEnum):
    """What a behaviour is, by its profile stereotype."""

    COMPLEX = "ComplexBehavior"
    SWARM_BEHAVIOR = "SwarmBehavior"
    SWARM_FUNCTION = "SwarmFunction"
    HARDWARE_FUNCTION = "HardwareFunction"


class RosBinding(Node):
    """How a behaviour maps to ROS: an action, a service or a topic, by name and type."""

    kind: Literal["action", "service", "topic"]
    name: str | None = None
    type: str | None = None


class Behaviour(Node):
    """A library behaviour a state can run: its inputs, outputs, outcomes and requirements."""

    id: str
    name: str
    ident: str
    kind: BehaviourKind
    library: str
    inputs: tuple[Property, ...]
    outputs: tuple[Property, ...]
    outcomes: tuple[str, ...]
    requires: tuple[str, ...]
    emits: tuple[str, ...] = ()  # events the behaviour sends (the `emits` tag, docs/profile.md)
    ros: RosBinding | None = None
    span: Span


class Event(Node):
    """An event or signal: its fields, who sends it and how far it travels."""

    id: str
    name: str
    # its run-time name (`names.event_name`): a dotted W3C event name (`foo.bar`) as the model
    # writes it, else the identifier; a string in every output, never a Python name
    ident: str
    fields: tuple[Property, ...]
    sender: Literal["station", "member"] | None = None
    scope: Literal["local", "swarm"] | None = None
    swarm_event: bool  # stereotyped «SwarmEvent» (else a plain UML signal or event)
    span: Span


# --- state machines


class OpaqueCode(Node):
    """A body in a language swarmgen does not execute (Java, bean, ...): kept, reported."""

    language: str
    body: str
    role: Literal["entry", "exit", "do", "effect"] = "effect"
    span: Span


class BehaviourCall(Node):
    """A state's `do` activity: the behaviour it runs and its argument bindings."""

    behaviour: str  # Behaviour.id
    bindings: tuple[Binding, ...]
    span: Span


class PseudoKind(StrEnum):
    """The kinds of UML pseudostate."""

    INITIAL = "initial"
    CHOICE = "choice"
    JUNCTION = "junction"
    FORK = "fork"
    JOIN = "join"
    SHALLOW_HISTORY = "shallowHistory"
    DEEP_HISTORY = "deepHistory"
    TERMINATE = "terminate"
    ENTRY_POINT = "entryPoint"
    EXIT_POINT = "exitPoint"


class Pseudostate(Node):
    """An initial, choice, junction, fork, join, history, terminate or connection point."""

    type: Literal["pseudo"] = "pseudo"
    id: str
    name: str
    kind: PseudoKind
    span: Span


class FinalState(Node):
    """A region's final state; entry and exit actions and done data are swarmgen's extension
    (SCXML's `<final>` has them: docs/semantics.md, "Final states and done data")."""

    type: Literal["final"] = "final"
    id: str
    name: str
    entry: tuple[Action, ...] = ()
    exit: tuple[Action, ...] = ()
    donedata: tuple[Arg, ...] = ()  # the fields of the done.state event it raises
    done_content: Expr | None = None  # or its whole data (`done(expr)`, W3C's <content>)
    span: Span


class ConnectionRef(Node):
    """A ConnectionPointReference on a submachine state: enters or leaves through its points."""

    type: Literal["connection"] = "connection"
    id: str
    name: str
    entry: tuple[str, ...]  # ids of entry points of the submachine
    exit: tuple[str, ...]  # ids of exit points of the submachine
    span: Span


class Invoke(Node):
    """A child SCXML session a state runs while it is active (W3C `<invoke>`, SCXML input
    only: docs/scxml-input.md): its whole model, the id or the datum its made id goes to, its
    type (`kind` as written, or `kind_expr`), the child's data it sets (`params`: namelist and
    `<param>`s), `<finalize>` and `autoforward`."""

    type: Literal["invoke"] = "invoke"
    invokeid: str | None = None
    idlocation: str | None = None  # a datum's name
    kind: str | None = None
    kind_expr: Expr | None = None
    autoforward: bool = False
    params: tuple[Binding, ...] = ()
    finalize: tuple[Action, ...] = ()
    session: "Model"
    span: Span


class State(Node):
    """A simple, composite or submachine state with its actions and activity."""

    type: Literal["state"] = "state"
    id: str
    name: str
    regions: tuple["Region", ...] = ()
    submachine: str | None = None  # Machine.id, inlined by the emitters
    connection_points: tuple[Pseudostate, ...] = ()  # entry/exit points of a composite state
    connections: tuple[ConnectionRef, ...] = ()
    activity: BehaviourCall | None = None
    entry: tuple[Action, ...] = ()
    exit: tuple[Action, ...] = ()
    opaque: tuple[OpaqueCode, ...] = ()
    invokes: tuple[Invoke, ...] = ()
    span: Span


Vertex = Annotated[State | FinalState | Pseudostate, Field(discriminator="type")]


class Region(Node):
    """A region of a state or machine: the vertices that run in it."""

    id: str
    name: str
    vertices: tuple[Vertex, ...]
    span: Span


class TriggerKind(StrEnum):
    """What fires a transition."""

    EVENT = "event"  # a swarm event or signal
    OUTCOME = "outcome"  # the outcome of the behaviour the source state runs
    TIME = "time"  # `after` a delay
    CALL = "call"  # a UML CallEvent, named after its operation
    ANY = "any"
    ERROR = "error"  # the platform's error events: error.execution, error.communication, error
    DONE = "done"  # done.state.<state name>: a state other than the source completed


class Trigger(Node):
    """One trigger of a transition: an event, an outcome, a delay, a call or anything."""

    kind: TriggerKind
    name: str  # event or outcome name (the model's)
    event: str | None = None  # Event.id when kind is EVENT
    delay_ms: int | None = None
    span: Span


class Transition(Node):
    """A transition between two vertices: triggers, guard and effect."""

    id: str
    name: str
    source: str
    target: str
    triggers: tuple[Trigger, ...] = ()
    guard: Expr | None = None
    guard_text: str | None = None
    effect: tuple[Action, ...] = ()
    opaque: tuple[OpaqueCode, ...] = ()
    kind: Literal["external", "internal", "local"] = "external"
    # an SCXML eventless transition out of a composite state or a behaviour's state: taken as
    # soon as its guard holds, not at the completion UML gives an untriggered one (only the
    # SCXML reader sets it; XMI spells it `eventless="true"`, docs/scxml-input.md)
    eventless: bool = False
    # the state (or the machine, for its own parallel regions) the transition exits and enters
    # again as a whole: W3C's domain of an SCXML transition out of a `<parallel>` child's own
    # state, which UML's regions would keep inside the child (only the SCXML reader sets it; XMI
    # spells it `reenters="<id>"`, docs/scxml-input.md)
    reenters: str | None = None
    span: Span


class Machine(Node):
    """A state machine: its regions, connection points, transitions and context data."""

    id: str
    name: str
    ident: str
    owner: str | None  # id of the class that owns it (its context), if any
    regions: tuple[Region, ...]
    connection_points: tuple[Pseudostate, ...]
    transitions: tuple[Transition, ...]
    data: tuple[Property, ...]  # the context's attributes: member data guards may read
    span: Span


class Model(Node):
    """The whole model as the IR: every element the checks and backends read."""

    name: str
    source: str
    exporter: str
    datatypes: tuple[DataType, ...]
    enumerations: tuple[Enumeration, ...] = ()
    hardware: tuple[HardwareComponent, ...]
    member_types: tuple[MemberType, ...]
    swarms: tuple[Swarm, ...]
    behaviours: tuple[Behaviour, ...]
    events: tuple[Event, ...]
    machines: tuple[Machine, ...]
    uses_profile: bool  # any swarm-profile stereotype applied: the stricter rules apply
