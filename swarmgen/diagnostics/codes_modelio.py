"""The registry's codes of the Modelio reader (SG067-SG069): `.ramc` archives and `.exml` files
swarmgen refuses, and what it assumes where the native files lack the swarm profile.

Registered after `codes_scxml`, in the same `CODES`, the same way (docs/modelio-input.md).
"""

from __future__ import annotations

from swarmgen.diagnostics import codes_ros, codes_scxml
from swarmgen.diagnostics.codes import NOTE, M, register

# Imported for their place only: the registry (and docs/diagnostics.md) lists these codes last.
del codes_ros, codes_scxml

MODELIO_ARCHIVE = register(
    "SG067",
    "modelio-bad-archive",
    "a `.ramc` archive refused before anything in it is read: not a zip, truncated, a zip bomb, "
    "too many members, unsafe member names, links, nested archives, encryption",
    input_error=True,
    message="not a readable zip archive: {error}",
    hint="give a .ramc exported by Modelio (File > Export > Model component)",
    variants={
        "count": M(
            "the archive has {count:,} members; the limit is {limit:,}",
            "a Modelio model component has a few hundred",
        ),
        "size": M(
            "member '{member}' expands to {size:,} bytes; the limit is {limit:,}",
            "split the model component",
        ),
        "total": M(
            "the archive expands to {size:,} bytes; the limit is {limit:,}",
            "split the model component",
        ),
        "ratio": M(
            "member '{member}' expands {ratio:,.0f} times ({size:,} bytes); the limit is "
            "{limit} times (a zip bomb?)",
            "give an archive Modelio wrote",
        ),
        "name": M("member name '{member}' is unsafe: {why}", "give an archive Modelio wrote"),
        "link": M("member '{member}' is a symbolic link", "give an archive Modelio wrote"),
        "nested": M(
            "member '{member}' is an archive inside the archive; nested archives are not read",
            "give the inner model component on its own",
        ),
        "method": M(
            "member '{member}' is {why}",
            "export it again with Modelio (stored or deflated members only)",
        ),
        "member": M("member '{member}' cannot be read: {error}", "give an archive Modelio wrote"),
        "empty": M("the archive holds no .exml model file", "give a Modelio model component"),
    },
)
MODELIO_BAD_MODEL = register(
    "SG068",
    "modelio-bad-model",
    "a Modelio .exml object graph swarmgen cannot read: a missing ID, a duplicate or dangling "
    "uid where the object must be present, a file that is no EXT document",
    input_error=True,
    message="{what} has no <ID> with a uid",
    hint="give the .exml file Modelio wrote",
    variants={
        "duplicate": M(
            "uid {uid} ('{name}') is used twice (first at {where})",
            "give every object its own uid",
        ),
        "dangling": M(
            "{relation} of '{name}' names uid {uid} ('{target}'), which is no {kind} of the "
            "files read",
            "give the whole model component (.ramc), or fix the reference",
        ),
        "unsupported": M(
            "{kind} '{name}' ({relation}) is not read by swarmgen's Modelio reader",
            "express it with states, transitions, guards and effects (docs/modelio-input.md)",
        ),
        "root": M(
            "member '{member}' is no Modelio .exml file (root <{tag}>)",
            "a .ramc holds .exml files under model/",
        ),
    },
)
MODELIO_ASSUMED = register(
    "SG069",
    "modelio-assumed",
    "what swarmgen assumes where Modelio's native files lack the swarm profile or a referenced "
    "object (docs/modelio-input.md)",
    NOTE,
    message="Modelio's native files carry no swarm profile: no member type, hardware, swarm or "
    "behaviour library is read; each top-level state machine ({machines}) is compiled as its own "
    "chart",
    hint="export the model as XMI with the CPSwarm profile to give it members and hardware",
    variants={
        "submachine": M(
            "the submachine '{name}' of state '{state}' is not in the files read; the state is "
            "compiled as a simple state",
            "give the whole model component (.ramc)",
        ),
        "event": M(
            "the event '{name}' of transition '{transition}' is not in the files read; read as "
            "a signal named '{name}'",
            "give the whole model component (.ramc)",
        ),
        "initial": M(
            "the region of '{owner}' has no initial pseudostate; it is entered at its first "
            "state '{state}' (SCXML's rule, which the CPSwarm tool's SCXML export relied on)",
            "add an initial pseudostate to choose another state",
        ),
        "event-kind": M(
            "event '{name}' is a {kind}; read as a signal event named '{name}'",
            "swarmgen reads Modelio's signal events only (docs/modelio-input.md)",
        ),
        "behaviour": M(
            "state '{state}' does operation '{operation}'; read as a «SwarmBehavior» of the "
            "library '{library}' with no inputs and no ROS binding",
            "export the model as XMI with the CPSwarm profile to bind it",
        ),
        "operation": M(
            "the operation '{name}' that state '{state}' does is not in the files read; the "
            "state does nothing",
            "give the whole model component (.ramc)",
        ),
    },
)

__all__ = ["MODELIO_ARCHIVE", "MODELIO_ASSUMED", "MODELIO_BAD_MODEL"]
