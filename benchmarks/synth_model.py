"""Generate a synthetic swarm model of N states in Modelio's EMF XMI form (like sar.xmi).

    python benchmarks/synth_model.py --states 10000 -o /tmp/m10k.xmi

The model has the profile's stereotypes, a «Swarm» of two «SwarmMember» types (Scout, Relay), a
«BehaviorLibrary» of four behaviours of three kinds, «SwarmEvent» signals and one state machine per
member type. Each machine is `Main` (two orthogonal regions: `Work` and `Monitor`) followed by a
final state. `Work` chains composite groups; each group holds a chain of leaf states (plain, running
a behaviour with outcome triggers, guarded event triggers with effects that assign data and `send`
events) and a composite `Sense` state with two orthogonal regions. `Work` ends in a submachine state
that reuses the L2 machine `Recharge`. N counts states (uml:State and uml:FinalState, the groups,
the composites and the L2 machine's states included; pseudostates excluded) and is exact. The
output depends only on N: the same arguments give the same bytes.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field
from pathlib import Path

MIN_STATES = 40
LEAVES_PER_GROUP = 10  # a group is 1 composite + leaves + Sense (1 + 2 regions x 2 leaves)
GROUP_OVERHEAD = 6  # the group itself, Sense and Sense's four leaves
# Per member machine: Main, Done, Watching (Monitor region), the Recharge submachine state;
# plus the three states of the shared L2 machine Recharge.
FIXED_STATES = 2 * 4 + 3
MEMBERS = ("Scout", "Relay")

PRIMITIVES = "pathmap://UML_LIBRARIES/UMLPrimitiveTypes.library.uml#"
HEADER = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<xmi:XMI xmi:version="2.1" xmlns:xmi="http://schema.omg.org/spec/XMI/2.1" '
    'xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
    'xmlns:ecore="http://www.eclipse.org/emf/2002/Ecore" '
    'xmlns:uml="http://www.eclipse.org/uml2/3.0.0/UML" '
    'xmlns:CPSwarm="http:///schemas/CPSwarm/_L1oOEIo-Ee-0HcfyqRPQXg/0" '
    'xsi:schemaLocation="http:///schemas/CPSwarm/_L1oOEIo-Ee-0HcfyqRPQXg/0 '
    'CPSwarm.profile.xmi#_L1oOGIo-Ee-0HcfyqRPQXg">'
)
# name, type, default (None: EMF leaves the default value out)
MEMBER_DATA = (
    ("altitude", "Real", "1.5"),
    ("goal", "Real", None),
    ("home", "Real", None),
    ("counter", "Integer", None),
    ("limit", "Integer", "5"),
    ("found", "Integer", None),
    ("target_id", "Integer", None),
    ("partner", "Integer", None),
    ("retries", "Integer", None),
    ("alarms", "Integer", None),
    ("busy", "Boolean", None),
)
# name, sender, scope, fields
EVENTS = (
    ("stop", "station", "swarm", ()),
    ("advance", "station", "swarm", (("step", "Integer"),)),
    ("tick", "member", "local", ()),
    ("targetFound", "member", "swarm", (("target_id", "Integer"),)),
    ("report", "member", "swarm", (("target_id", "Integer"),)),
    ("alarm", "member", "swarm", (("level", "Integer"),)),
)
OUTCOMES = ("succeeded", "aborted", "lost")
# name, stereotype, inputs, outputs, extra outcomes, events it emits, requires, ROS kind/name/type
BEHAVIOURS = (
    (
        "Search",
        "SwarmBehavior",
        (("altitude", "Real"),),
        (("target_id", "Integer"),),
        "lost",
        "targetFound",
        "Camera",
        ("action", "search", "synth_msgs/action/Search"),
    ),
    (
        "MoveTo",
        "HardwareFunction",
        (("goal", "Real"),),
        (),
        "",
        "",
        "Drive",
        ("action", "cmd/moveto", "synth_msgs/action/MoveTo"),
    ),
    (
        "Monitor",
        "HardwareFunction",
        (),
        (),
        "",
        "tick alarm",
        "Camera",
        ("topic", "monitor", "synth_msgs/msg/Alarm"),
    ),
    (
        "Allocate",
        "SwarmFunction",
        (("target_id", "Integer"),),
        (("partner", "Integer"),),
        "",
        "",
        "Radio",
        ("action", "cmd/allocate", "synth_msgs/action/Allocate"),
    ),
)
HARDWARE = (("Camera", "Sensor"), ("Drive", "Actuator"), ("Radio", "CommunicationInterface"))


def attr(text: str) -> str:
    """An XML attribute value, escaped the way EMF writes it."""
    return (
        text.replace("&", "&amp;")
        .replace("<", "&lt;")
        .replace(">", "&gt;")
        .replace('"', "&quot;")
        .replace("\n", "&#xA;")
    )


def body(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


_ALPHABET = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_"


class Ids:
    """EMF-style ids (`_` + 22 characters), deterministic: a counter in base 64 + a fixed tail."""

    def __init__(self) -> None:
        self.count = 0

    def new(self) -> str:
        self.count += 1
        n, digits = self.count, []
        for _ in range(7):
            n, r = divmod(n, 64)
            digits.append(_ALPHABET[r])
        return "_S" + "".join(reversed(digits)) + "o-Ee-0SynthMod"


Lines = list[str]  # XML lines, indented relative to the first; a <body> may span lines


def indent(lines: Lines) -> Lines:
    """Two more spaces on every line (text inside a multi-line <body> keeps column 0)."""
    return ["  " + line for line in lines]


@dataclass
class Transition:
    source: str
    target: str
    trigger: tuple[str, str] | None = None  # (name, SignalEvent id)
    guard: str | None = None
    effect: str | None = None


@dataclass
class Region:
    name: str
    transitions: list[Transition] = field(default_factory=list)
    vertices: list[Lines] = field(default_factory=list)  # the subvertices' XML, in order


@dataclass
class Plan:
    """How many groups each member machine has, and the leaves of each group."""

    groups: dict[str, list[int]]

    @classmethod
    def for_states(cls, states: int) -> Plan:
        if states < MIN_STATES:
            raise ValueError(f"--states must be at least {MIN_STATES}")
        budget = states - FIXED_STATES
        count = max(2, budget // (GROUP_OVERHEAD + LEAVES_PER_GROUP))
        leaves = budget - count * GROUP_OVERHEAD
        per_group = [leaves // count + (1 if i < leaves % count else 0) for i in range(count)]
        groups: dict[str, list[int]] = {m: [] for m in MEMBERS}
        for i, n in enumerate(per_group):
            groups[MEMBERS[i % len(MEMBERS)]].append(n)
        return cls(groups)


class Writer:
    def __init__(self, states: int) -> None:
        self.plan = Plan.for_states(states)
        self.ids = Ids()
        self.lines: list[str] = []
        self.stereotypes: list[str] = []
        self.states = 0
        # ids of declarations referenced by machines, made up front
        self.member_ids = {m: self.ids.new() for m in MEMBERS}
        self.machine_ids = {m: self.ids.new() for m in MEMBERS}
        self.hardware_ids = {h: self.ids.new() for h, _ in HARDWARE}
        self.behaviour_ids = {b[0]: self.ids.new() for b in BEHAVIOURS}
        self.signal_ids = {e[0]: self.ids.new() for e in EVENTS}
        self.event_ids = {e: self.ids.new() for e in (*(e[0] for e in EVENTS), *OUTCOMES)}
        self.recharge_id = self.ids.new()
        self.recharge_uses: list[str] = []

    def out(self, depth: int, text: str) -> None:
        self.lines.append("  " * depth + text)

    # --- the document

    def document(self) -> str:
        self.out(0, HEADER)
        self.out(1, f'<uml:Model xmi:id="{self.ids.new()}" name="SyntheticSwarm">')
        self.out(2, f'<eAnnotations xmi:id="{self.ids.new()}" source="Objing">')
        self.out(
            3,
            f'<contents xmi:type="uml:Property" xmi:id="{self.ids.new()}" name="exporterVersion">',
        )
        self.out(
            4,
            f'<defaultValue xmi:type="uml:LiteralString" xmi:id="{self.ids.new()}" value="3.0.0"/>',
        )
        self.out(3, "</contents>")
        self.out(2, "</eAnnotations>")
        self.architecture()
        self.hardware()
        self.library()
        self.events()
        self.behaviors_package()
        self.profile_application()
        self.out(1, "</uml:Model>")
        self.lines.extend("  " + s for s in self.stereotypes)
        self.out(0, "</xmi:XMI>")
        return "\n".join(self.lines) + "\n"

    def stereotype(self, name: str, base: str, target: str, **tags: str) -> None:
        extra = "".join(f' {k}="{attr(v)}"' for k, v in tags.items())
        self.stereotypes.append(
            f'<CPSwarm:{name} xmi:id="{self.ids.new()}" base_{base}="{target}"{extra}/>'
        )

    def typed(self, depth: int, tag: str, name: str, type_: str, extra: str = "") -> None:
        self.out(depth, f'<{tag} xmi:id="{self.ids.new()}" name="{attr(name)}"{extra}>')
        self.out(depth + 1, f'<type xmi:type="uml:PrimitiveType" href="{PRIMITIVES}{type_}"/>')
        self.out(depth, f"</{tag.split()[0]}>")

    def architecture(self) -> None:
        self.out(
            2,
            f'<packagedElement xmi:type="uml:Package" xmi:id="{self.ids.new()}" '
            'name="SwarmArchitecture">',
        )
        swarm = self.ids.new()
        self.out(3, f'<packagedElement xmi:type="uml:Class" xmi:id="{swarm}" name="SynthSwarm">')
        for member, count in zip(MEMBERS, (4, 2), strict=True):
            self.out(
                4,
                f'<ownedAttribute xmi:id="{self.ids.new()}" name="{member.lower()}s" '
                f'type="{self.member_ids[member]}" aggregation="composite">',
            )
            self.out(
                5,
                f'<upperValue xmi:type="uml:LiteralUnlimitedNatural" xmi:id="{self.ids.new()}" '
                f'value="{count}"/>',
            )
            self.out(
                5,
                f'<lowerValue xmi:type="uml:LiteralInteger" xmi:id="{self.ids.new()}" '
                f'value="{count}"/>',
            )
            self.out(4, "</ownedAttribute>")
        self.out(3, "</packagedElement>")
        self.stereotype("Swarm", "Class", swarm)
        for member in MEMBERS:
            self.member(member)
        self.out(2, "</packagedElement>")

    def member(self, member: str) -> None:
        cls = self.member_ids[member]
        self.out(
            3,
            f'<packagedElement xmi:type="uml:Class" xmi:id="{cls}" name="{member}" '
            f'classifierBehavior="{self.machine_ids[member]}">',
        )
        for hardware, _ in HARDWARE:
            self.out(
                4,
                f'<ownedAttribute xmi:id="{self.ids.new()}" name="{hardware.lower()}" '
                f'type="{self.hardware_ids[hardware]}" aggregation="composite"/>',
            )
        for name, type_, default in MEMBER_DATA:
            self.out(4, f'<ownedAttribute xmi:id="{self.ids.new()}" name="{name}">')
            self.out(5, f'<type xmi:type="uml:PrimitiveType" href="{PRIMITIVES}{type_}"/>')
            literal = {"Real": "LiteralReal", "Integer": "LiteralInteger"}.get(
                type_, "LiteralBoolean"
            )
            value = f' value="{default}"' if default is not None else ""
            self.out(
                5, f'<defaultValue xmi:type="uml:{literal}" xmi:id="{self.ids.new()}"{value}/>'
            )
            self.out(4, "</ownedAttribute>")
        self.machine(member)
        self.out(3, "</packagedElement>")
        self.stereotype("SwarmMember", "Class", cls, role=member.lower())

    def hardware(self) -> None:
        self.out(
            2, f'<packagedElement xmi:type="uml:Package" xmi:id="{self.ids.new()}" name="Hardware">'
        )
        for name, stereotype in HARDWARE:
            self.out(
                3,
                f'<packagedElement xmi:type="uml:Class" xmi:id="{self.hardware_ids[name]}" '
                f'name="{name}">',
            )
            self.out(4, f'<ownedAttribute xmi:id="{self.ids.new()}" name="rate">')
            self.out(5, f'<type xmi:type="uml:PrimitiveType" href="{PRIMITIVES}Real"/>')
            self.out(
                5,
                f'<defaultValue xmi:type="uml:LiteralReal" xmi:id="{self.ids.new()}" value="10.0"/>',
            )
            self.out(4, "</ownedAttribute>")
            self.out(3, "</packagedElement>")
            tags = (
                {"communicationType": "wifi", "communicationParams": "ifname=wlan0"}
                if stereotype == "CommunicationInterface"
                else {}
            )
            self.stereotype(stereotype, "Class", self.hardware_ids[name], **tags)
        self.out(2, "</packagedElement>")

    def library(self) -> None:
        package = self.ids.new()
        self.out(
            2, f'<packagedElement xmi:type="uml:Package" xmi:id="{package}" name="Behaviours">'
        )
        self.out(
            3, f'<packagedElement xmi:type="uml:Class" xmi:id="{self.ids.new()}" name="Behaviours">'
        )
        for name, stereotype, inputs, outputs, extra, emits, requires, ros in BEHAVIOURS:
            operation = self.behaviour_ids[name]
            if not inputs and not outputs:
                self.out(
                    4,
                    f'<ownedOperation xmi:type="uml:Operation" xmi:id="{operation}" name="{name}"/>',
                )
            else:
                self.out(
                    4,
                    f'<ownedOperation xmi:type="uml:Operation" xmi:id="{operation}" name="{name}">',
                )
                for p, type_ in inputs:
                    self.typed(5, "ownedParameter", p, type_)
                for p, type_ in outputs:
                    self.typed(5, "ownedParameter", p, type_, ' direction="out"')
                self.out(4, "</ownedOperation>")
            tags = {"requires": requires, "rosKind": ros[0], "rosName": ros[1], "rosType": ros[2]}
            if extra:
                tags["outcomes"] = extra
            if emits:
                tags["emits"] = emits
            self.stereotype(stereotype, "Operation", operation, **tags)
        self.out(3, "</packagedElement>")
        self.out(2, "</packagedElement>")
        self.stereotype("BehaviorLibrary", "Package", package)

    def events(self) -> None:
        self.out(
            2, f'<packagedElement xmi:type="uml:Package" xmi:id="{self.ids.new()}" name="Events">'
        )
        for name, sender, scope, fields in EVENTS:
            signal = self.signal_ids[name]
            if not fields:
                self.out(
                    3, f'<packagedElement xmi:type="uml:Signal" xmi:id="{signal}" name="{name}"/>'
                )
            else:
                self.out(
                    3, f'<packagedElement xmi:type="uml:Signal" xmi:id="{signal}" name="{name}">'
                )
                for f, type_ in fields:
                    self.typed(4, "ownedAttribute", f, type_)
                self.out(3, "</packagedElement>")
            self.stereotype("SwarmEvent", "Signal", signal, sender=sender, scope=scope)
        for name, *_ in EVENTS:
            self.out(
                3,
                f'<packagedElement xmi:type="uml:SignalEvent" xmi:id="{self.event_ids[name]}" '
                f'name="{name}" signal="{self.signal_ids[name]}"/>',
            )
        for name in OUTCOMES:
            self.out(
                3,
                f'<packagedElement xmi:type="uml:SignalEvent" xmi:id="{self.event_ids[name]}" '
                f'name="{name}"/>',
            )
        self.out(2, "</packagedElement>")

    def profile_application(self) -> None:
        self.out(2, f'<profileApplication xmi:id="{self.ids.new()}">')
        self.out(
            3,
            f'<eAnnotations xmi:id="{self.ids.new()}" '
            'source="http://www.eclipse.org/uml2/2.0.0/UML">',
        )
        self.out(
            4,
            '<references xmi:type="ecore:EPackage" '
            'href="CPSwarm.profile.xmi#_L1oOGIo-Ee-0HcfyqRPQXg"/>',
        )
        self.out(3, "</eAnnotations>")
        self.out(3, '<appliedProfile href="CPSwarm.profile.xmi#_L1oOEYo-Ee-0HcfyqRPQXg"/>')
        self.out(2, "</profileApplication>")

    # --- state machines

    def trigger(self, name: str) -> tuple[str, str]:
        return name, self.event_ids[name]

    def state(
        self,
        name: str,
        state_id: str,
        regions: list[Region] | None = None,
        activity: tuple[str, str] | None = None,
        submachine: str | None = None,
    ) -> Lines:
        """The XML lines of one uml:State (counted)."""
        self.states += 1
        sub = f' submachine="{submachine}"' if submachine else ""
        head = f'<subvertex xmi:type="uml:State" xmi:id="{state_id}" name="{attr(name)}"{sub}'
        inner: Lines = []
        if activity is not None:
            behaviour, bindings = activity
            spec = self.behaviour_ids[behaviour]
            do = (
                f'<doActivity xmi:type="uml:OpaqueBehavior" xmi:id="{self.ids.new()}" '
                f'name="{behaviour}" specification="{spec}"'
            )
            if bindings:
                inner += [do + ">", f"  <body>{body(bindings)}</body>", "</doActivity>"]
            else:
                inner.append(do + "/>")
        for region in regions or []:
            inner += self.region_lines(region)
        if not inner:
            return [head + "/>"]
        return [head + ">", *indent(inner), "</subvertex>"]

    def final(self, name: str, state_id: str) -> Lines:
        self.states += 1
        return [f'<subvertex xmi:type="uml:FinalState" xmi:id="{state_id}" name="{name}"/>']

    def initial(self, region: Region, target: str) -> None:
        initial = self.ids.new()
        region.vertices.insert(
            0, [f'<subvertex xmi:type="uml:Pseudostate" xmi:id="{initial}" name="Initial"/>']
        )
        region.transitions.insert(0, Transition(initial, target))

    def region_lines(self, region: Region) -> Lines:
        inner: Lines = []
        for t in region.transitions:
            inner += self.transition_lines(t)
        for vertex in region.vertices:
            inner += vertex
        head = f'<region xmi:id="{self.ids.new()}" name="{attr(region.name)}">'
        return [head, *indent(inner), "</region>"]

    def transition_lines(self, t: Transition) -> Lines:
        tid = self.ids.new()
        inner: Lines = []
        guard_attr = ""
        if t.guard is not None:
            guard = self.ids.new()
            guard_attr = f' guard="{guard}"'
            inner += [
                f'<ownedRule xmi:id="{guard}" name="{attr(t.guard)}">',
                f'  <specification xmi:type="uml:LiteralString" xmi:id="{self.ids.new()}" '
                f'value="{attr(t.guard)}"/>',
                "</ownedRule>",
            ]
        if t.effect is not None:
            inner += [
                f'<effect xmi:type="uml:OpaqueBehavior" xmi:id="{self.ids.new()}" '
                f'name="{attr(t.effect)}">',
                f"  <body>{body(t.effect)}</body>",
                "</effect>",
            ]
        if t.trigger is not None:
            name, event = t.trigger
            inner.append(f'<trigger xmi:id="{self.ids.new()}" name="{name}" event="{event}"/>')
        head = f'<transition xmi:id="{tid}"{guard_attr} source="{t.source}" target="{t.target}"'
        if not inner:
            return [head + "/>"]
        return [head + ">", *indent(inner), "</transition>"]

    def group(self, prefix: str, leaves: int) -> Region:
        """One composite group: a chain of leaves, then the orthogonal composite Sense."""
        steps = Region("Steps")
        ids = [self.ids.new() for _ in range(leaves)]
        sense_id = self.ids.new()
        first = ids[0]
        for i, leaf in enumerate(ids):
            name = f"{prefix}_L{i + 1}"
            after = ids[i + 1] if i + 1 < leaves else sense_id
            kind = i % 4
            if kind == 0:
                steps.vertices.append(self.state(name, leaf))
                steps.transitions.append(
                    Transition(
                        leaf,
                        after,
                        self.trigger("tick"),
                        "counter < limit",
                        "counter = counter + 1",
                    )
                )
            elif kind == 1:
                steps.vertices.append(self.state(name, leaf, activity=("Search", "")))
                steps.transitions += [
                    Transition(leaf, after, self.trigger("succeeded"), effect="found = found + 1"),
                    Transition(leaf, first, self.trigger("lost")),
                    Transition(leaf, first, self.trigger("aborted")),
                ]
            elif kind == 2:
                steps.vertices.append(
                    self.state(name, leaf, activity=("MoveTo", "goal = goal + 1.0"))
                )
                steps.transitions += [
                    Transition(leaf, after, self.trigger("succeeded")),
                    Transition(
                        leaf, first, self.trigger("aborted"), effect="retries = retries + 1"
                    ),
                ]
            else:
                steps.vertices.append(self.state(name, leaf))
                steps.transitions.append(
                    Transition(
                        leaf,
                        after,
                        self.trigger("targetFound"),
                        "event.target_id > 0 and not busy",
                        "target_id = event.target_id\nsend report(target_id = target_id)",
                    )
                )
        steps.vertices.append(self.sense(f"{prefix}_Sense", sense_id))
        steps.transitions.append(
            Transition(
                sense_id,
                first,
                self.trigger("targetFound"),
                "event.target_id > 0",
                "target_id = event.target_id\nbusy = false",
            )
        )
        self.initial(steps, first)
        return steps

    def sense(self, name: str, state_id: str) -> Lines:
        left, right = Region("Left"), Region("Right")
        a, b, c, d = (self.ids.new() for _ in range(4))
        left.vertices += [
            self.state(f"{name}_Allocate", a, activity=("Allocate", "")),
            self.state(f"{name}_Idle", b),
        ]
        left.transitions += [
            Transition(a, b, self.trigger("succeeded"), effect="busy = true"),
            Transition(a, b, self.trigger("aborted")),
            Transition(b, a, self.trigger("tick")),
        ]
        right.vertices += [self.state(f"{name}_Quiet", c), self.state(f"{name}_Alert", d)]
        right.transitions += [
            Transition(c, d, self.trigger("alarm"), "event.level > 1", "alarms = alarms + 1"),
            Transition(d, c, self.trigger("report")),
        ]
        self.initial(left, a)
        self.initial(right, c)
        return self.state(name, state_id, regions=[left, right])

    def machine(self, member: str) -> None:
        groups = self.plan.groups[member]
        work, monitor, top = Region("Work"), Region("Monitor"), Region("Region")
        group_ids = [self.ids.new() for _ in groups]
        recharge_state = self.ids.new()
        self.recharge_uses.append(recharge_state)
        for j, (gid, leaves) in enumerate(zip(group_ids, groups, strict=True)):
            prefix = f"{member}_G{j + 1}"
            steps = self.group(prefix, leaves)
            work.vertices.append(self.state(prefix, gid, regions=[steps]))
            after = group_ids[j + 1] if j + 1 < len(group_ids) else recharge_state
            work.transitions.append(
                Transition(
                    gid, after, self.trigger("advance"), f"event.step == {j + 1}", "counter = 0"
                )
            )
        work.vertices.append(
            self.state(f"{member}_Recharge", recharge_state, submachine=self.recharge_id)
        )
        work.transitions.append(Transition(recharge_state, group_ids[0]))  # on completion
        self.initial(work, group_ids[0])
        watching = self.ids.new()
        monitor.vertices.append(
            self.state(f"{member}_Watching", watching, activity=("Monitor", ""))
        )
        monitor.transitions.append(
            Transition(
                watching,
                watching,
                self.trigger("alarm"),
                "event.level >= 3",
                "alarms = alarms + 1",
            )
        )
        self.initial(monitor, watching)
        main, done = self.ids.new(), self.ids.new()
        top.vertices += [
            self.state(f"{member}_Main", main, regions=[work, monitor]),
            self.final(f"{member}_Done", done),
        ]
        top.transitions.append(Transition(main, done, self.trigger("stop")))
        self.initial(top, main)
        self.out(
            4,
            f'<ownedBehavior xmi:type="uml:StateMachine" xmi:id="{self.machine_ids[member]}" '
            f'name="{member}Mission">',
        )
        for line in self.region_lines(top):
            self.out(5, line)
        self.out(4, "</ownedBehavior>")

    def behaviors_package(self) -> None:
        region = Region("Region")
        docking, charging, charged = self.ids.new(), self.ids.new(), self.ids.new()
        region.vertices += [
            self.state("Docking", docking, activity=("MoveTo", "goal = home")),
            self.state("Charging", charging),
            self.final("Charged", charged),
        ]
        region.transitions += [
            Transition(docking, charging, self.trigger("succeeded"), effect="retries = 0"),
            Transition(docking, docking, self.trigger("aborted"), "retries < limit"),
            Transition(charging, charged, self.trigger("tick"), "counter >= limit"),
        ]
        self.initial(region, docking)
        self.out(
            2,
            f'<packagedElement xmi:type="uml:Package" xmi:id="{self.ids.new()}" name="Behaviors">',
        )
        self.out(
            3,
            f'<packagedElement xmi:type="uml:StateMachine" xmi:id="{self.recharge_id}" '
            f'name="Recharge" submachineState="{" ".join(self.recharge_uses)}">',
        )
        for line in self.region_lines(region):
            self.out(4, line)
        self.out(3, "</packagedElement>")
        self.out(2, "</packagedElement>")


def generate(states: int) -> str:
    """The XMI text of a model with exactly `states` states."""
    writer = Writer(states)
    text = writer.document()
    assert writer.states == states, (writer.states, states)
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--states", type=int, required=True, help=f"number of states (>= {MIN_STATES})"
    )
    parser.add_argument("-o", "--output", type=Path, required=True, help="the .xmi file to write")
    args = parser.parse_args(argv)
    try:
        text = generate(args.states)
    except ValueError as err:
        parser.error(str(err))
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text, encoding="utf-8")
    print(f"{args.output}: {args.states} states, {len(text) / 2**20:.1f} MiB", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
