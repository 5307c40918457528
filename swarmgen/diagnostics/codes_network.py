"""The registry's codes of the swarm's network settings (SG230-SG231): the `communicationParams`
of its communication interfaces, read by the network transport's rules (docs/network.md).

Registered after `codes_checks`, in the same `CODES`, the same way.
"""

from __future__ import annotations

from swarmgen.diagnostics.codes import ERROR, WARNING, M, register

_FORMAT = "write key=value items separated by spaces, commas or semicolons: `group=239.255.70.71 port=5670 ttl=1`"

BAD_COMMUNICATION_PARAMS = register(
    "SG230",
    "bad-communication-params",
    "a CommunicationInterface's communicationParams the network transport cannot use",
    ERROR,
    message="communicationParams of '{component}': {error}",
    hint="group is an IPv4 multicast address (224.0.0.0-239.255.255.255), port 1-65535, ttl 0-255",
    variants={
        "item": M("communicationParams of '{component}': '{item}' is not key=value", _FORMAT),
        "twice": M(
            "communicationParams of '{component}' gives '{key}' twice ('{first}', '{second}')",
            "keep one of them",
        ),
        "conflict": M(
            "member types '{other}' and '{member}' would use different {key}s: {other_value} "
            "and {value} (communication interface '{component}'); a swarm shares one network",
            "give the communication interfaces of every member type the same {key}, or leave "
            "it out of all but one",
        ),
    },
)
MISSPELT_COMMUNICATION_PARAM = register(
    "SG231",
    "misspelt-communication-param",
    "a communicationParams key the network transport does not read, close to one it reads",
    WARNING,
    message="communicationParams of '{component}' has '{key}', which the network transport "
    "does not read",
    hint="did you mean '{near}'? (it reads group, port and ttl; ifname names the radio)",
)

__all__ = ["BAD_COMMUNICATION_PARAMS", "MISSPELT_COMMUNICATION_PARAM"]
