"""The swarm's network settings, from the model: the `communicationParams` of its communication
interfaces, read by the network transport's own rules (`runtime.netoptions`), so the check
(SG230, SG231) and the Python backends (the package's `NETWORK`) decide in one place.

The swarm shares one network: the transport keys (`group`, `port`, `ttl`) that the member
types' communication interfaces give must agree, and together they are the defaults of the
generated package's `--group`, `--port`, `--ttl` (the command line wins). Other keys belong to
other software (a radio's driver, the ROS node parameters that carry the text as it is) and
are not the transport's business, except a key so close to one of its own that it is probably
a misspelling of it.
"""

from __future__ import annotations

from dataclasses import field

from swarmgen.ir.nodes import HardwareComponent, HardwareKind, Model
from swarmgen.records import dataclass
from swarmgen.runtime.netoptions import (
    KNOWN_KEYS,
    TRANSPORT_KEYS,
    BadItem,
    param_items,
    param_value,
)
from swarmgen.span import Span


@dataclass(frozen=True)
class Problem:
    """What is wrong with a component's `communicationParams`: `variant` of SG230 (`item`,
    `value`, `twice`, `conflict`) or `misspelt` (SG231), with the message's fields."""

    component: HardwareComponent
    variant: str
    fields: dict[str, str]

    @property
    def span(self) -> Span:
        """Where the parameters are written (the stereotype application, else the class)."""
        return self.component.communication_span or self.component.span


@dataclass(frozen=True)
class Network:
    """The swarm's transport settings and the problems found reading them."""

    values: dict[str, str | int] = field(default_factory=dict)  # sorted by key
    sources: tuple[str, ...] = ()  # the communication interfaces that give them
    problems: tuple[Problem, ...] = ()


def swarm_network(model: Model) -> Network:
    """Read every communication interface's parameters; the transport keys of those the member
    types carry, which must agree, are the swarm's."""
    problems: list[Problem] = []
    read: dict[str, dict[str, str | int]] = {}
    for component in model.hardware:
        if (
            component.kind is HardwareKind.COMMUNICATION_INTERFACE
            and component.communication_params
        ):
            read[component.id] = _read(component, problems)
    values: dict[str, tuple[str | int, str, str]] = {}  # key -> value, component, member
    components = {h.id: h for h in model.hardware}
    for member in model.member_types:
        for part in member.hardware:
            for key, value in read.get(part.type_id, {}).items():
                first = values.setdefault(key, (value, part.type_id, member.name))
                conflict = _conflict(components[part.type_id], member.name, key, value, first)
                if first[0] != value and conflict not in problems:
                    problems.append(conflict)
    network = {key: values[key][0] for key in sorted(values)}
    sources = sorted({components[values[key][1]].name for key in values})
    return Network(network, tuple(sources), tuple(problems))


def _read(component: HardwareComponent, problems: list[Problem]) -> dict[str, str | int]:
    """The transport keys of one component's parameters (the problems added to `problems`)."""
    name = component.name
    try:
        items = param_items(component.communication_params or "")
    except BadItem as err:
        problems.append(Problem(component, "item", {"component": name, "item": err.item}))
        return {}
    found: dict[str, str | int] = {}
    given: dict[str, str] = {}
    for key, text in items:
        if key in given:
            fields = {"component": name, "key": key, "first": given[key], "second": text}
            problems.append(Problem(component, "twice", fields))
            continue
        given[key] = text
        if key in TRANSPORT_KEYS:
            try:
                found[key] = param_value(key, text)
            except ValueError as err:
                problems.append(Problem(component, "value", {"component": name, "error": str(err)}))
        elif key not in KNOWN_KEYS:
            from difflib import get_close_matches  # an unknown key only

            near = get_close_matches(key, KNOWN_KEYS, n=1, cutoff=0.6)
            if near:
                fields = {"component": name, "key": key, "near": near[0]}
                problems.append(Problem(component, "misspelt", fields))
    return found


def _conflict(
    component: HardwareComponent,
    member: str,
    key: str,
    value: str | int,
    first: tuple[str | int, str, str],
) -> Problem:
    fields = {
        "key": key,
        "member": member,
        "value": str(value),
        "component": component.name,
        "other": first[2],
        "other_value": str(first[0]),
    }
    return Problem(component, "conflict", fields)
