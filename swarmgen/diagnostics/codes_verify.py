"""The registry's codes of `swarmgen verify` (SG401-SG409): properties of the composed swarm the
exhaustive search found violated, and its bounded verdict (docs/verify.md).

Registered after `codes_modelio`, in the same `CODES`, the same way. The violations are errors
(`verify` exits 1); the bounded verdict is a note (`verify` exits 4 when nothing was violated).
"""

from __future__ import annotations

from swarmgen.diagnostics.codes import NOTE, WARNING, M, register

VERIFY_DEADLOCK = register(
    "SG401",
    "swarm-deadlock",
    "a reachable swarm configuration in which nothing can happen and some member is not final",
    message="deadlock: {members} can never move again (shortest trace: {length} step(s))",
    hint="the trace below (and the replay scenarios of --counterexample) lead to it; "
    "give the waiting state a transition for what can still happen",
    variants={
        "after-abort": M(
            "deadlock after '{event}': {members} can never move again (shortest trace: "
            "{length} step(s))",
            "after the abort the station is silent: every member must reach a final state on "
            "its own",
        ),
    },
)
VERIFY_ABORT = register(
    "SG402",
    "abort-unsafe",
    "after the abort event some member can no longer reach a final state",
    message="after '{event}', {member} can no longer reach a final state (in '{state}'; "
    "shortest trace: {length} step(s))",
    hint="handle '{event}' in every region (a transition of the enclosing parallel state "
    "leaves them all), and lead every outcome of the states after it to a final state",
)
VERIFY_UNREACHABLE = register(
    "SG403",
    "unreachable-in-swarm",
    "a state of a member's machine that no reachable configuration of the composed swarm enters "
    "(stronger than SG201: the other members' events are what they really send)",
    message="state '{state}' of {member} is never entered in the swarm {swarm}",
    hint="the events that lead to it are never sent, or never in that order, by the other "
    "members or the station",
)
VERIFY_UNRECEIVED = register(
    "SG404",
    "event-never-received",
    "a swarm event members send that no delivery ever makes any member take a transition on",
    message="'{event}' is sent but no member ever takes a transition on it in the swarm {swarm}",
    hint="every receiver is elsewhere whenever it arrives: wait for it in the state it arrives "
    "in, or do not send it",
)
VERIFY_BOUNDED = register(
    "SG405",
    "verify-bounded",
    "the search stopped at its budget: the properties hold only as far as it went",
    NOTE,
    message="bounded: {states:,} states, depth {depth}: the budget (--max-states {max_states:,}, "
    "--max-depth {max_depth:,}) stopped the search before every configuration was explored",
    hint="raise --max-states or --max-depth, or verify fewer members (--members)",
)
VERIFY_LOST = register(
    "SG406",
    "event-lost",
    "a swarm event that, under some interleaving, reaches every member in a state that does not "
    "take it: no member receives it (a warning: a broadcast only some states care about is "
    "often meant to be dropped; what the loss leads to is what the other properties judge)",
    WARNING,
    message="'{event}' sent by {sender} can be lost: every member it reaches ignores it "
    "(shortest trace: {length} step(s))",
    hint="the receivers are elsewhere when it arrives under this interleaving: wait for it in "
    "the state it arrives in, or make the sender wait for the receiver",
)
VERIFY_PROPERTY = register(
    "SG407",
    "property-violated",
    "a user property (`always`, `never`, `eventually`, `leads to`, `until`) is violated in the "
    "composed swarm",
    message="property '{name}' is violated: {text} ({how}; shortest trace: {length} step(s))",
    hint="the trace below leads to it{fairness}",
)
VERIFY_VACUOUS = register(
    "SG409",
    "property-vacuous",
    "a `P leads to Q` property that holds only because P never holds before the abort in the "
    "whole explored space: it says nothing (a warning)",
    WARNING,
    message="property '{name}' holds vacuously: {text} ('{premise}' never holds before the "
    "abort in the {states:,} states explored)",
    hint="the premise names an event nobody sends or a state never entered with the rest of it: "
    "state what can happen (`eventually ...` shows whether it does)",
)
VERIFY_PROPERTY_INVALID = register(
    "SG408",
    "property-invalid",
    "a user property that does not parse, or names a member type, state, datum or event the "
    "model does not have",
    message="property '{name}': {error}",
    hint="a property is `always P`, `never P`, `eventually P`, `P leads to Q` or `P until Q` "
    "over `TYPE in STATE`, `count(TYPE in STATE) <= n`, `TYPE.datum > v` and event names "
    "(docs/verify.md)",
)
