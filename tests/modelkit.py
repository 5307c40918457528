"""Write small swarm models as Modelio XMI (EMF format, CPSwarm stereotypes at the root) from a
compact Python description: minimal failing models for every check, and random models for the
property tests.

    kit = ModelKit("Demo")
    kit.hardware("Camera", "Sensor")
    kit.behaviour("Coverage", requires=["Camera"], outputs={"target_id": "Integer"})
    kit.event("missionAbort", sender="station")
    m = kit.machine("UavMission")
    m.initial("Idle"); m.state("Idle"); m.state("Cover", do="Coverage"); m.final("Done")
    m.transition("Idle", "Cover", "missionStart"); m.transition("Cover", "Done", "succeeded")
    kit.member("UAV", machine=m, parts={"cam": "Camera"}, data={"target_id": ("Integer", 0)})
    kit.swarm("Swarm", {"UAV": 2})
    text = kit.xmi()
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from xml.sax.saxutils import escape, quoteattr

OUTCOMES = ("succeeded", "aborted", "preempted")
PRIMITIVES = {"Real", "Integer", "Boolean", "String"}


@dataclass
class _State:
    name: str
    region: str  # "" for the machine's top region, else "<state>/<region>"
    kind: str = "State"  # State, FinalState, Pseudostate
    pseudo: str = ""
    do: str | None = None
    bindings: str = ""
    entry: str = ""
    exit: str = ""
    submachine: str | None = None


@dataclass
class _Transition:
    source: str
    target: str
    triggers: tuple[str, ...]
    guard: str = ""
    effect: str = ""


@dataclass
class Machine:
    name: str
    states: list[_State] = field(default_factory=list)
    transitions: list[_Transition] = field(default_factory=list)
    regions: dict[str, list[str]] = field(default_factory=dict)  # state name -> its region names

    def _add(self, state: _State) -> str:
        assert all(s.name != state.name for s in self.states), f"duplicate vertex {state.name}"
        self.states.append(state)
        return state.name

    def state(
        self,
        name: str,
        *,
        do: str | None = None,
        bindings: str = "",
        entry: str = "",
        exit: str = "",
        region: str = "",
        submachine: str | None = None,
    ) -> str:
        return self._add(
            _State(
                name,
                region,
                do=do,
                bindings=bindings,
                entry=entry,
                exit=exit,
                submachine=submachine,
            )
        )

    def final(self, name: str, region: str = "", *, entry: str = "", exit: str = "") -> str:
        """A final state; entry and exit actions (with `done(...)`) are swarmgen's extension."""
        return self._add(_State(name, region, kind="FinalState", entry=entry, exit=exit))

    def pseudo(self, name: str, kind: str, region: str = "") -> str:
        return self._add(_State(name, region, kind="Pseudostate", pseudo=kind))

    def initial(self, target: str, region: str = "") -> None:
        name = f"__init_{region.replace('/', '_') or 'top'}"
        self.pseudo(name, "initial", region)
        self.transition(name, target)

    def composite(
        self, name: str, regions: list[str] | None = None, region: str = "", **options: str
    ) -> list[str]:
        """A composite state; returns the region paths to put its vertices in (`name/region`)."""
        self.state(name, region=region, **options)  # type: ignore[arg-type]
        names = regions or ["main"]
        self.regions[name] = names
        return [f"{name}/{r}" for r in names]

    def transition(
        self, source: str, target: str, *triggers: str, guard: str = "", effect: str = ""
    ) -> None:
        self.transitions.append(_Transition(source, target, triggers, guard, effect))


class ModelKit:
    def __init__(self, name: str = "Model") -> None:
        self.name = name
        self._ids = (f"_K{n:05d}aaaaaaaaaaaaaaaa" for n in itertools.count(1))
        self.hardware_classes: dict[str, tuple[str, list[str], dict[str, tuple[str, object]]]] = {}
        self.behaviours: dict[str, dict[str, object]] = {}
        self.events: dict[str, tuple[dict[str, str], str, str]] = {}
        self.machines: dict[str, Machine] = {}
        self.members: dict[
            str, tuple[Machine | None, dict[str, tuple[str, int]], dict[str, tuple[str, object]]]
        ] = {}
        self.swarms: dict[str, list[tuple[str, str, int]]] = {}  # swarm -> (part, type, count)
        self.properties: dict[str, list[tuple[str, str]]] = {}  # swarm -> (name, text)
        self.datatypes = {"Pose": {"x": "Real", "y": "Real"}}
        self.enumerations: dict[str, list[str]] = {}  # name -> literals

    def enumeration(self, name: str, *literals: str) -> None:
        """A UML Enumeration; `Type[*]` anywhere a type is named makes a sequence of Type."""
        self.enumerations[name] = list(literals)

    def hardware(
        self,
        name: str,
        kind: str = "Sensor",
        generals: list[str] | None = None,
        params: dict[str, tuple[str, object]] | None = None,
    ) -> None:
        self.hardware_classes[name] = (kind, list(generals or []), dict(params or {}))

    def behaviour(
        self,
        name: str,
        kind: str = "SwarmBehavior",
        *,
        inputs: dict[str, str] | None = None,
        outputs: dict[str, str] | None = None,
        outcomes: list[str] | None = None,
        requires: list[str] | None = None,
        emits: list[str] | None = None,
    ) -> None:
        self.behaviours[name] = {
            "kind": kind, "inputs": dict(inputs or {}), "outputs": dict(outputs or {}),
            "outcomes": list(outcomes or []), "requires": list(requires or []), "emits": list(emits or []),
        }  # fmt: skip

    def event(
        self,
        name: str,
        fields: dict[str, str] | None = None,
        sender: str = "member",
        scope: str = "swarm",
    ) -> None:
        self.events[name] = (dict(fields or {}), sender, scope)

    def machine(self, name: str) -> Machine:
        self.machines[name] = Machine(name)
        return self.machines[name]

    def member(
        self,
        name: str,
        machine: Machine | None = None,
        parts: dict[str, str | tuple[str, int]] | None = None,
        data: dict[str, tuple[str, object]] | None = None,
    ) -> None:
        normal = {k: (v if isinstance(v, tuple) else (v, 1)) for k, v in (parts or {}).items()}
        self.members[name] = (machine, normal, dict(data or {}))

    def property(self, swarm: str, name: str, text: str) -> None:
        """A user property of a swarm class: a Constraint it owns, stereotyped «Property»,
        whose specification is an OpaqueExpression with the property's text."""
        self.properties.setdefault(swarm, []).append((name, text))

    def swarm(self, name: str, members: dict[str, int] | list[tuple[str, str, int]]) -> None:
        """A Swarm class: {member type: count} (one part per type, named `<type>s`), or
        [(part name, member type, count), ...] for several parts of one type."""
        if isinstance(members, dict):
            self.swarms[name] = [(m.lower() + "s", m, n) for m, n in members.items()]
        else:
            self.swarms[name] = list(members)

    # --- writing

    def xmi(self) -> str:
        ids = _Ids(self._ids)
        stereos: list[str] = []
        body: list[str] = []
        for dt, fields in self.datatypes.items():
            body.append(
                f'    <packagedElement xmi:type="uml:DataType" xmi:id="{ids["dt:" + dt]}" name="{dt}">'
            )
            body += [f"      {_attribute(ids, f, t)}" for f, t in fields.items()]
            body.append("    </packagedElement>")
        for enum, literals in self.enumerations.items():
            body.append(
                f'    <packagedElement xmi:type="uml:Enumeration" xmi:id="{ids["dt:" + enum]}" name="{enum}">'
            )
            body += [
                f'      <ownedLiteral xmi:id="{ids.new()}" name={quoteattr(lit)}/>'
                for lit in literals
            ]
            body.append("    </packagedElement>")
        for hw, (kind, generals, params) in self.hardware_classes.items():
            body.append(
                f'    <packagedElement xmi:type="uml:Class" xmi:id="{ids["class:" + hw]}" name={quoteattr(hw)}>'
            )
            body += [
                f'      <generalization xmi:id="{ids.new()}" general="{ids["class:" + g]}"/>'
                for g in generals
            ]
            body += [f"      {_attribute(ids, p, t, d)}" for p, (t, d) in params.items()]
            body.append("    </packagedElement>")
            stereos.append(
                f'  <CPSwarm:{kind} xmi:id="{ids.new()}" base_Class="{ids["class:" + hw]}"/>'
            )
        body += self._library(ids, stereos)
        body += self._events(ids, stereos)
        for machine in self.machines.values():
            if not any(m is machine for m, _, _ in self.members.values()):
                body += _machine(ids, machine, "packagedElement", self.behaviours, "    ")
        for member, (machine, parts, data) in self.members.items():
            behaviour = f' classifierBehavior="{ids["sm:" + machine.name]}"' if machine else ""
            body.append(
                f'    <packagedElement xmi:type="uml:Class" xmi:id="{ids["class:" + member]}" name={quoteattr(member)}{behaviour}>'
            )
            for part, (hw, count) in parts.items():
                body.append(
                    f'      <ownedAttribute xmi:id="{ids.new()}" name={quoteattr(part)} type="{ids["class:" + hw]}" aggregation="composite">'
                )
                body += _multiplicity(ids, count, "        ")
                body.append("      </ownedAttribute>")
            body += [f"      {_attribute(ids, d, t, v)}" for d, (t, v) in data.items()]
            if machine is not None:
                body += _machine(ids, machine, "ownedBehavior", self.behaviours, "      ")
            body.append("    </packagedElement>")
            stereos.append(
                f'  <CPSwarm:SwarmMember xmi:id="{ids.new()}" base_Class="{ids["class:" + member]}"/>'
            )
        for swarm, swarm_parts in self.swarms.items():
            body.append(
                f'    <packagedElement xmi:type="uml:Class" xmi:id="{ids["class:" + swarm]}" name={quoteattr(swarm)}>'
            )
            for part, member, count in swarm_parts:
                body.append(
                    f'      <ownedAttribute xmi:id="{ids.new()}" name={quoteattr(part)} type="{ids["class:" + member]}" aggregation="composite">'
                )
                body += _multiplicity(ids, count, "        ")
                body.append("      </ownedAttribute>")
            for prop_name, text in self.properties.get(swarm, []):
                rule = ids.new()
                body.append(
                    f'      <ownedRule xmi:id="{rule}" name={quoteattr(prop_name)}>'
                    f'<specification xmi:type="uml:OpaqueExpression" xmi:id="{ids.new()}">'
                    f"<body>{escape(text)}</body></specification></ownedRule>"
                )
                stereos.append(
                    f'  <CPSwarm:Property xmi:id="{ids.new()}" base_Constraint="{rule}"/>'
                )
            body.append("    </packagedElement>")
            stereos.append(
                f'  <CPSwarm:Swarm xmi:id="{ids.new()}" base_Class="{ids["class:" + swarm]}"/>'
            )
        return _document(self.name, ids, body, stereos)

    def _library(self, ids: _Ids, stereos: list[str]) -> list[str]:
        if not self.behaviours:
            return []
        lines = [f'    <packagedElement xmi:type="uml:Package" xmi:id="{ids["lib"]}" name="Library">',
                 f'      <packagedElement xmi:type="uml:Class" xmi:id="{ids.new()}" name="Behaviours">']  # fmt: skip
        for name, spec in self.behaviours.items():
            lines.append(
                f'        <ownedOperation xmi:type="uml:Operation" xmi:id="{ids["op:" + name]}" name={quoteattr(name)}>'
            )
            for direction, key in (("", "inputs"), (' direction="out"', "outputs")):
                for param, type_ in spec[key].items():  # type: ignore[attr-defined]
                    lines.append(
                        f'          <ownedParameter xmi:id="{ids.new()}" name={quoteattr(param)}{direction}>'
                    )
                    lines.append(f"            {_type(ids, type_)}{_upper(ids, type_)}")
                    lines.append("          </ownedParameter>")
            lines.append("        </ownedOperation>")
            tags = "".join(
                f" {tag}={quoteattr(' '.join(spec[tag]))}"  # type: ignore[arg-type]
                for tag in ("outcomes", "requires", "emits")
                if spec[tag]
            )
            stereos.append(
                f'  <CPSwarm:{spec["kind"]} xmi:id="{ids.new()}" base_Operation="{ids["op:" + name]}"{tags}/>'
            )
        lines += ["      </packagedElement>", "    </packagedElement>"]
        stereos.append(
            f'  <CPSwarm:BehaviorLibrary xmi:id="{ids.new()}" base_Package="{ids["lib"]}"/>'
        )
        return lines

    def _events(self, ids: _Ids, stereos: list[str]) -> list[str]:
        lines = [f'    <packagedElement xmi:type="uml:Package" xmi:id="{ids.new()}" name="Events">']
        for name, (fields, sender, scope) in self.events.items():
            lines.append(
                f'      <packagedElement xmi:type="uml:Signal" xmi:id="{ids["signal:" + name]}" name={quoteattr(name)}>'
            )
            lines += [f"        {_attribute(ids, f, t)}" for f, t in fields.items()]
            lines.append("      </packagedElement>")
            lines.append(
                f'      <packagedElement xmi:type="uml:SignalEvent" xmi:id="{ids["event:" + name]}" name={quoteattr(name)} signal="{ids["signal:" + name]}"/>'
            )
            stereos.append(
                f'  <CPSwarm:SwarmEvent xmi:id="{ids.new()}" base_Signal="{ids["signal:" + name]}" sender="{sender}" scope="{scope}"/>'
            )
        outcomes = {o for spec in self.behaviours.values() for o in spec["outcomes"]} | set(
            OUTCOMES
        )  # type: ignore[attr-defined]
        for outcome in sorted(outcomes - set(self.events)):
            lines.append(
                f'      <packagedElement xmi:type="uml:SignalEvent" xmi:id="{ids["event:" + outcome]}" name={quoteattr(outcome)}/>'
            )
        lines.append("    </packagedElement>")
        return lines


class _Ids:
    def __init__(self, source: object) -> None:
        self._source = source
        self._named: dict[str, str] = {}

    def new(self) -> str:
        return next(self._source)  # type: ignore[call-overload, no-any-return]

    def __getitem__(self, key: str) -> str:
        if key not in self._named:
            self._named[key] = self.new()
        return self._named[key]


def _upper(ids: _Ids, type_: str) -> str:
    if not type_.endswith("[*]"):
        return ""
    return f'<upperValue xmi:type="uml:LiteralUnlimitedNatural" xmi:id="{ids.new()}" value="*"/>'


def _type(ids: _Ids, type_: str) -> str:
    type_ = type_.removesuffix("[*]")
    if type_ in PRIMITIVES:
        return f'<type xmi:type="uml:PrimitiveType" href="pathmap://UML_LIBRARIES/UMLPrimitiveTypes.library.uml#{type_}"/>'
    return f'<type xmi:type="uml:DataType" href="#{ids["dt:" + type_]}"/>'


def _attribute(ids: _Ids, name: str, type_: str, default: object = None) -> str:
    text = f'<ownedAttribute xmi:id="{ids.new()}" name={quoteattr(name)}>{_type(ids, type_)}'
    text += _upper(ids, type_)
    if default is not None:
        kind = {bool: "LiteralBoolean", int: "LiteralInteger", float: "LiteralReal"}.get(
            type(default), "LiteralString"
        )
        value = str(default).lower() if isinstance(default, bool) else str(default)
        text += (
            f'<defaultValue xmi:type="uml:{kind}" xmi:id="{ids.new()}" value={quoteattr(value)}/>'
        )
    return text + "</ownedAttribute>"


def _multiplicity(ids: _Ids, count: int, indent: str) -> list[str]:
    return [
        f'{indent}<lowerValue xmi:type="uml:LiteralInteger" xmi:id="{ids.new()}" value="{count}"/>',
        f'{indent}<upperValue xmi:type="uml:LiteralUnlimitedNatural" xmi:id="{ids.new()}" value="{count}"/>',
    ]


def _machine(
    ids: _Ids, machine: Machine, feature: str, behaviours: dict[str, dict[str, object]], indent: str
) -> list[str]:
    key = "sm:" + machine.name
    lines = [
        f'{indent}<{feature} xmi:type="uml:StateMachine" xmi:id="{ids[key]}" name={quoteattr(machine.name)}>'
    ]
    lines += _region(ids, machine, "", indent + "  ")
    lines.append(f"{indent}</{feature}>")
    return lines


def _region(ids: _Ids, machine: Machine, path: str, indent: str) -> list[str]:
    lines = [
        f'{indent}<region xmi:id="{ids["region:" + machine.name + ":" + path]}" name={quoteattr(path.rsplit("/", 1)[-1] or "top")}>'
    ]
    members = [s for s in machine.states if s.region == path]
    names = {s.name for s in members}
    for transition in machine.transitions:
        if transition.source in names:
            lines += _transition(ids, machine, transition, indent + "  ")
    for state in members:
        lines += _vertex(ids, machine, state, indent + "  ")
    lines.append(f"{indent}</region>")
    return lines


def _vid(ids: _Ids, machine: Machine, name: str) -> str:
    return ids[f"v:{machine.name}:{name}"]


def _vertex(ids: _Ids, machine: Machine, state: _State, indent: str) -> list[str]:
    vid = _vid(ids, machine, state.name)
    if state.kind == "Pseudostate":
        kind = "" if state.pseudo == "initial" else f' kind="{state.pseudo}"'
        return [
            f'{indent}<subvertex xmi:type="uml:Pseudostate" xmi:id="{vid}" name={quoteattr(state.name)}{kind}/>'
        ]
    if state.kind == "FinalState" and not (state.entry or state.exit):
        return [
            f'{indent}<subvertex xmi:type="uml:FinalState" xmi:id="{vid}" name={quoteattr(state.name)}/>'
        ]
    if state.kind == "FinalState":
        lines = [
            f'{indent}<subvertex xmi:type="uml:FinalState" xmi:id="{vid}" name={quoteattr(state.name)}>'
        ]
        for feature, text in (("entry", state.entry), ("exit", state.exit)):
            if text:
                lines.append(
                    f'{indent}  <{feature} xmi:type="uml:OpaqueBehavior" xmi:id="{ids.new()}"><body>{escape(text)}</body></{feature}>'
                )
        return [*lines, f"{indent}</subvertex>"]
    sub = f' submachine="{ids["sm:" + state.submachine]}"' if state.submachine else ""
    lines = [
        f'{indent}<subvertex xmi:type="uml:State" xmi:id="{vid}" name={quoteattr(state.name)}{sub}>'
    ]
    for feature, text in (("entry", state.entry), ("exit", state.exit)):
        if text:
            lines.append(
                f'{indent}  <{feature} xmi:type="uml:OpaqueBehavior" xmi:id="{ids.new()}"><body>{escape(text)}</body></{feature}>'
            )
    if state.do is not None:
        body = f"<body>{escape(state.bindings)}</body>" if state.bindings else ""
        lines.append(
            f'{indent}  <doActivity xmi:type="uml:OpaqueBehavior" xmi:id="{ids.new()}" name={quoteattr(state.do)} specification="{ids["op:" + state.do]}">{body}</doActivity>'
        )
    for region in machine.regions.get(state.name, []):
        lines += _region(ids, machine, f"{state.name}/{region}", indent + "  ")
    lines.append(f"{indent}</subvertex>")
    return lines


def _transition(ids: _Ids, machine: Machine, transition: _Transition, indent: str) -> list[str]:
    tid = ids.new()
    guard_id = ids.new() if transition.guard else None
    guard = f' guard="{guard_id}"' if guard_id else ""
    lines = [
        f'{indent}<transition xmi:id="{tid}" source="{_vid(ids, machine, transition.source)}" target="{_vid(ids, machine, transition.target)}"{guard}>'
    ]
    if transition.guard:
        lines.append(
            f'{indent}  <ownedRule xmi:id="{guard_id}" name={quoteattr(transition.guard)}><specification xmi:type="uml:LiteralString" xmi:id="{ids.new()}" value={quoteattr(transition.guard)}/></ownedRule>'
        )
    if transition.effect:
        lines.append(
            f'{indent}  <effect xmi:type="uml:OpaqueBehavior" xmi:id="{ids.new()}"><body>{escape(transition.effect)}</body></effect>'
        )
    for trigger in transition.triggers:
        # the platform's error events are triggers by name, without an event (docs/semantics.md)
        event = "" if trigger.startswith("error") else f' event="{ids["event:" + trigger]}"'
        lines.append(
            f"{indent}  <trigger xmi:id={quoteattr(ids.new())} name={quoteattr(trigger)}{event}/>"
        )
    lines.append(f"{indent}</transition>")
    return lines


def _document(name: str, ids: _Ids, body: list[str], stereos: list[str]) -> str:
    profile = "_Kprofileaaaaaaaaaaaaaa"
    head = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<xmi:XMI xmi:version="2.1" xmlns:xmi="http://schema.omg.org/spec/XMI/2.1" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xmlns:uml="http://www.eclipse.org/uml2/3.0.0/UML" xmlns:CPSwarm="http:///schemas/CPSwarm/{profile}/0" xsi:schemaLocation="http:///schemas/CPSwarm/{profile}/0 CPSwarm.profile.xmi#{profile}">',
        f'  <uml:Model xmi:id="{ids.new()}" name={quoteattr(name)}>',
        f'    <eAnnotations xmi:id="{ids.new()}" source="Objing"><contents xmi:type="uml:Property" xmi:id="{ids.new()}" name="exporterVersion"><defaultValue xmi:type="uml:LiteralString" xmi:id="{ids.new()}" value="3.0.0"/></contents></eAnnotations>',
    ]
    return "\n".join([*head, *body, "  </uml:Model>", *stereos, "</xmi:XMI>", ""])
