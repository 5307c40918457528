"""The registry's codes of the checks: limits, well-formedness, livelocks and the analyses.

Registered after `codes` (SG0xx-SG12x), in the same `CODES`, the same way.
"""

from __future__ import annotations

from swarmgen.diagnostics.codes import ERROR, NOTE, WARNING, M, register

_EXCLUSIVE_GUARDS = "make the guards exclusive (e.g. `[x < 20]` and `[x >= 20]`), or use `else`"
_TOO_MANY_HINT = (
    "set the multiplicity to the swarm's real size; simulate sweeps sizes with --members"
)
# The note that points at the other of two transitions (forks, joins, nondeterminism).
_OTHER_TRANSITION = {"other-at": "the other transition is at {where}"}
# The fork and join codes report branches outside orthogonal regions with one wording.
_BAD_BRANCHES = M(
    "the {what} '{first}' and '{second}' of {label} are not in different regions of one "
    "parallel state",
    "the {what} of a fork or join must lie in orthogonal regions (one per region) of the same "
    "composite state",
)

# --- limits on the work a small model may ask for (SG130-SG139)
MODEL_TOO_LARGE = register(
    "SG130",
    "model-too-large",
    "a machine is too large once its submachines are inlined",
    message="machine '{machine}' has {total:,} states once its submachines are inlined; "
    "the limit is {limit:,}",
    hint="each submachine state is a copy of its machine: a machine used twice per level doubles "
    "at every level; use fewer submachine states per level",
    notes={
        "inlines": "'{machine}::{state}' inlines '{sub}' ({states:,} states; {users} states use it)",
        "inlines-once": "'{machine}::{state}' inlines '{sub}' ({states:,} states; 1 state uses it)",
    },
)
TOO_MANY_MEMBERS = register(
    "SG131",
    "too-many-members",
    "a swarm has more members of one type than the limit",
    message="swarm '{swarm}' has {total:,} members of type '{type}'; the limit is {limit:,} "
    "per type",
    hint=_TOO_MANY_HINT,
    variants={
        "summed": M(
            "swarm '{swarm}' has {total:,} members of type '{type}' in all (over {parts} parts); "
            "the limit is {limit:,} per type",
            _TOO_MANY_HINT,
        )
    },
    notes={"part": "part '{part}' has {count:,}"},
)
NONDETERMINISM_UNDECIDED = register(
    "SG132",
    "nondeterminism-undecided",
    "SG204 could not decide some pairs of guards within its budget",
    NOTE,
    message="could not decide whether {count} pair(s) of transitions from '{source}' on {what} "
    "exclude each other: the check's search budget ran out",
    hint="simpler guards (comparisons of one name with constants) are decided at once",
    notes={"first-pair": "the first such pair: {first} and {second}"},
)
# --- well-formedness of machines and classes (SG140-SG159): models that would compile wrong
UNEXPECTED_ELEMENT = register(
    "SG140",
    "unexpected-element",
    "an element of a kind that does not belong where it stands",
    variants={
        "not-a-region": M(
            "{feature} {label} is a {kind}, but only a Region may stand there",
            "make it a uml:Region",
        ),
        "not-a-connection-point": M(
            "{feature} {label} is a {kind}, but connection points are entryPoint and exitPoint "
            "pseudostates",
            "move it into a region, or make it an entry or exit point",
        ),
        "not-a-transition": M(
            "{feature} {label} is a {kind}, but only a Transition may stand there",
            "make it a uml:Transition",
        ),
        "not-a-vertex": M(
            "{feature} {label} is a {kind}, but a region holds states, final states and "
            "pseudostates",
            "a state machine used inside another is a submachine state: a uml:State with "
            'submachine="<machine id>"',
        ),
        "point-in-region": M(
            "{feature} {label} is a {kind}, but an {point} belongs to the connectionPoint list "
            "of a state or machine",
            "make it a connectionPoint of the state or machine it enters or leaves",
        ),
    },
)
SEVERAL_REFS = register(
    "SG141",
    "several-references",
    "a single-valued reference names more than one element",
    message="{kind} {label}: {feature} names {count} elements ({shown}); it takes exactly one",
    hint="keep one id in {feature}",
)
INITIAL_LEAVES_REGION = register(
    "SG142",
    "initial-leaves-region",
    "an initial or default history transition leaves its region",
    message="the {kind} transition of region '{region}' targets '{target}', which is not in "
    "that region",
    hint="target a state of region '{region}' (or one nested in it)",
    notes={"leaves-active": "it would leave another state of the region active beside it"},
)
ENTERS_INITIAL = register(
    "SG143",
    "enters-initial",
    "a transition targets an initial pseudostate",
    message="a transition from '{source}' targets the initial pseudostate '{target}'; nothing "
    "may enter one",
    hint="target the state the initial pseudostate leads to, or the region's state",
    variants={
        "itself": M(
            "a transition from '{source}' targets the initial pseudostate '{target}' (itself); "
            "nothing may enter one",
            "target the state the initial pseudostate leads to, or the region's state",
        )
    },
)
BAD_FORK = register(
    "SG144",
    "bad-fork",
    "fork targets that are not in distinct orthogonal regions of one state",
    variants={
        "guard": M(
            "a transition leaving {label} has a guard; all branches of a fork fire together",
            "move the guard to the transition that enters the fork",
        ),
        "not-orthogonal": _BAD_BRANCHES,
    },
    notes=_OTHER_TRANSITION,
)
BAD_JOIN = register(
    "SG145",
    "bad-join",
    "join sources not in distinct orthogonal regions, or no single way out",
    variants={
        "outgoing": M(
            "{label} has {count} outgoing transitions; it needs exactly one",
            "give the join one transition to the state entered when all branches end",
        ),
        "not-from-state": M(
            "{label} is entered from '{source}', which is not a state: a join waits for states "
            "of orthogonal regions to be active"
        ),
        "not-orthogonal": _BAD_BRANCHES,
    },
    notes=_OTHER_TRANSITION,
)
SINGLE_BRANCH = register(
    "SG146",
    "single-branch",
    "a fork or join with a single branch",
    WARNING,
    message="{label} has a single {direction} transition; it synchronises nothing",
    hint="use an ordinary transition, or add the branch of the other region",
)
CHOICE_WITHOUT_ELSE = register(
    "SG147",
    "choice-without-else",
    "a choice or junction whose guards can all be false",
    message="{label} has guards on every outgoing transition: when none holds, it would stay "
    "active as if it were a state",
    hint="add a transition with the guard `else` (or without a guard)",
    notes={"guards": "guards: {guards}"},
)
BAD_OUTCOME_NAME = register(
    "SG148",
    "bad-outcome-name",
    "an outcome name that is not a plain identifier",
    message="outcome '{outcome}' of '{name}' is not a plain name: outcomes are matched as SCXML "
    "event tokens, where '.' separates tokens and '*' matches any",
    hint="rename it to '{suggestion}' (letters, digits and '_', not a reserved word)",
)
GENERALISATION_CYCLE = register(
    "SG149",
    "generalisation-cycle",
    "a class specialises itself, directly or not",
    message="'{name}' specialises itself: {cycle}",
    hint="remove one of these generalizations",
)
COMPOSITION_CYCLE = register(
    "SG150",
    "composition-cycle",
    "a class is a part of itself or a data type contains itself",
    message="'{name}' is a part of itself: {cycle} -> {name}",
    hint="make one of these attributes a reference (aggregation none), or remove it",
)
RESERVED_FILE_NAME = register(
    "SG151",
    "reserved-file-name",
    "a generated file name that Windows reserves",
    WARNING,
    message="{what} '{name}' gives the file {file}, a name Windows reserves for a device: the "
    "output cannot be checked out or written there",
    hint="rename the {what} (CON, PRN, AUX, NUL, COM1-9, LPT1-9 are reserved)",
    notes={"also": "also: {files}"},
)
PATH_TOO_LONG = register(
    "SG152",
    "path-too-long",
    "a generated path too long for Windows",
    WARNING,
    message="{what} '{name}' gives the path {path} ({length} characters inside the output "
    "directory): with the directory itself it may pass Windows' {limit}-character limit",
    hint="shorten the {what}'s name",
)
BAD_FINAL_STATE = register(
    "SG153",
    "bad-final-state",
    "a final state with regions, behaviours or a submachine",
    message="final state '{state}' has {content}; a final state has none",
    hint="make it an ordinary state followed by a final state",
)
UNKNOWN_KIND = register(
    "SG154",
    "unknown-kind",
    "a pseudostate or transition kind that UML does not define",
    variants={
        "pseudostate": M(
            "pseudostate '{name}' has kind '{kind}', which UML does not define",
            "use one of: {kinds}",
        ),
        "transition": M(
            "transition {label} has kind '{kind}', which UML does not define",
            "use external, local or internal",
        ),
    },
)
BAD_INTERNAL = register(
    "SG155",
    "bad-internal-transition",
    "an internal transition whose source and target differ",
    message="the internal transition from '{source}' targets '{target}'; an internal "
    "transition stays in its state",
    hint="make it external (kind omitted), or let it target its own source",
)
SUBMACHINE_WITH_REGIONS = register(
    "SG156",
    "submachine-with-regions",
    "a submachine state that has regions of its own",
    message="state '{state}' runs a submachine and also has regions of its own; only the "
    "submachine's would be emitted",
    hint="move the regions into the submachine, or drop the submachine",
)
DUPLICATE_REGION_NAME = register(
    "SG157",
    "duplicate-region-name",
    "two regions of one state share a name",
    WARNING,
    message="'{owner}' has two regions named '{region}'",
    hint="rename one of them",
    notes={"other-at": "the other is at {where}"},
)
INVALID_LOCATION = register(
    "SG158",
    "invalid-location",
    "an SCXML document reads or assigns a location that is none: error.execution when it runs",
    WARNING,
    message="{what} {verb} `{location}`, which is no location the document declares: it raises "
    "error.execution when it runs (W3C 5.4, 5.9, 6.4)",
    hint="declare it (`<data id=...>`), or remove the reference if the error is not intended",
)
DECLARED_INVALID_LOCATION = register(
    "SG159",
    "declared-invalid-location",
    'an assignment to invalid("x") where x is member data',
    message="{what} assigns `{location}` as an invalid location, but '{name}' is member data: "
    "the SCXML document would assign it",
    hint="write `{name} = ...` to assign it (invalid(...) is a location that is none)",
)
LIVELOCK = register(
    "SG160",
    "livelock",
    "transitions that loop forever without an external event",
    message="{loop}: once taken, these transitions take each other forever without an input "
    "from outside (no guard, no trigger from outside, no behaviour to wait for)",
    hint="give one of these transitions a guard or a trigger, or let its state run a behaviour "
    "(left as it is, the member would spin without end at run time)",
    notes={"then": "then the transition from {source} at {where}"},
)
# --- analysis: swarm bugs before flight
UNREACHABLE_STATE = register(
    "SG201",
    "unreachable-state",
    "no path from the initial state reaches the state",
    WARNING,
    message="state '{state}' of '{machine}' can never be entered",
    hint="add a transition to it, or remove it",
)
NO_WAY_OUT = register(
    "SG202",
    "no-way-out",
    "a state that is not final has no way out",
    WARNING,
    message="state '{state}' of '{machine}' has no way out: no transition leaves it or a state "
    "that contains it",
    hint="add a transition out of it, or make it a final state",
)
NEVER_ENDS = register(
    "SG203",
    "never-ends",
    "a member's machine can never reach a final state",
    WARNING,
    message="state machine '{machine}' can never end: no final state of its top level is reachable",
    hint="add a final state reached on the mission's end or abort (e.g. after landing)",
)
NONDETERMINISTIC = register(
    "SG204",
    "nondeterministic",
    "two transitions on one trigger whose guards can both hold",
    WARNING,
    message="'{source}' has two transitions on {what} that can both fire; the first in model "
    "order wins",
    hint=_EXCLUSIVE_GUARDS,
    variants={
        "unguarded": M(
            "'{source}' has {count} transitions on {what} without a guard; the first in model "
            "order always wins",
            _EXCLUSIVE_GUARDS,
        )
    },
    notes={
        **_OTHER_TRANSITION,
        "first-at": "the first is at {where}",
        "never-taken": "never taken: {shown}",
        "never-taken-more": "never taken: {shown} and {more} more",
        "witness": "both guards hold when {values}",
        "no-guards": "neither has a guard",
        "one-guard": "one has no guard, and the other's guard can hold",
    },
)
UNHANDLED_OUTCOME = register(
    "SG205",
    "unhandled-outcome",
    "a behaviour outcome that no transition of its state handles",
    WARNING,
    message="'{state}' handles {handled} of '{behaviour}' but not '{outcome}': the state would "
    "be stuck with a finished behaviour",
    hint="add a transition from '{state}' on '{outcome}'",
)
NEVER_SENT = register(
    "SG206",
    "event-never-sent",
    "a trigger on an event that nobody sends",
    WARNING,
    message="transition waits for '{event}', which nobody sends",
    hint="set sender=station on '{event}', send it from an effect (`send ...`), or name it in "
    "the `emits` tag of the behaviour that sends it",
)
NEVER_HANDLED = register(
    "SG207",
    "event-never-handled",
    "an event is sent but no member type reacts to it",
    WARNING,
    message="event '{event}' is sent, but no member type reacts to it",
    hint="add a transition on it, or stop sending it",
)
TYPE_ERROR = register(
    "SG208",
    "type-error",
    "an expression combines values of incompatible types",
    message="type error: {error}",
)
INPUT_MAYBE_UNSET = register(
    "SG209",
    "input-maybe-unset",
    "a behaviour input may be unset when its state is entered",
    WARNING,
    message="'{behaviour}' in '{state}' reads '{name}', which may be unset (no default, not "
    "assigned on every path)",
    hint="give '{name}' a default value, or assign it on the way (an effect `{name} = ...`)",
    notes={"path": "a path that never assigns it: {path}"},
)
OUTPUT_UNUSED = register(
    "SG210",
    "output-unused",
    "a behaviour output is written to member data nobody reads",
    NOTE,
    message="output '{output}' of '{behaviour}' is written to '{location}', which nothing in "
    "'{member}' reads",
)
QT_ORDER = register(
    "SG216",
    "qt-transition-order",
    "two transitions in different regions of a parallel state (or one above it) that one event "
    "enables together, the later region's deeper: Qt SCXML gives the deeper one precedence, W3C "
    "and every other backend document order, so the emitted SCXML in Qt may run their actions in "
    "the other order or take the other one (docs/semantics.md)",
    WARNING,
    message="in '{chart}', Qt SCXML gives the transition from '{second}' precedence over the one "
    "from '{first}' (its actions first, or it alone when the two conflict); every other backend "
    "follows W3C's document order",
    hint="make the two transitions' actions independent of their order (different data, no "
    "raise or send in both) and their targets alike, or take the event in one region",
)
MISSING_CAPABILITY = register(
    "SG211",
    "missing-capability",
    "a behaviour requires hardware the member type does not have",
    message="state '{state}' of '{member}' runs '{behaviour}', which requires {need}; "
    "'{member}' has no {need}",
    hint="give '{member}' a part whose class is or specialises {need}, or run another "
    "behaviour in '{state}'",
    notes={
        "has": "'{member}' has: {hardware}",
        "has-nothing": "'{member}' has: no hardware",
        "requires": "'{behaviour}' requires: {needs}",
    },
)
MISSING_PARAMETER = register(
    "SG212",
    "missing-parameter",
    "a behaviour input is neither bound, member data nor a hardware parameter",
    ERROR,
    message="input '{input}' of '{behaviour}' (state '{state}' of '{member}') is neither bound, "
    "member data nor a hardware parameter",
    hint="bind it in the doActivity (`{input} = ...`), declare member data '{input}', or give a "
    "hardware part the parameter '{input}'",
    variants={
        "no-hardware": M(
            "input '{input}' of '{behaviour}' is neither bound nor member data",
            "bind it in the doActivity body (`{input} = ...`)",
        )
    },
)
BAD_COUNT = register(
    "SG214",
    "bad-member-count",
    "a swarm has fewer than one member of a type",
    message="part '{part}' of swarm '{swarm}' has {count} member(s) of type '{type}'",
    hint="set the part's multiplicity to at least 1, or remove the part",
)
ROS_NAME_COLLISION = register(
    "SG215",
    "ros-name-collision",
    "two elements get the same ROS name",
    message="{what} '{other}' and '{name}' both become the ROS name '{ros}'",
    hint="rename one of them",
    variants={
        "types": M(
            "behaviours '{other}' and '{behaviour}' both use the ROS name '{ros}' with different "
            "types",
            "give one of them another rosName",
        )
    },
    notes={"at": "'{name}' is at {where}"},
)
UNKNOWN_LITERAL = register(
    "SG218",
    "unknown-literal",
    "an expression names a literal its enumeration does not have",
    ERROR,
    message="enumeration '{enum}' has no literal '{literal}': `{text}`",
    hint="did you mean `{enum}.{suggestion}`?",
    variants={
        "none-close": M(
            "enumeration '{enum}' has no literal '{literal}': `{text}`",
            "write one of: {literals}",
        )
    },
)

__all__ = [
    "BAD_COUNT",
    "BAD_FINAL_STATE",
    "BAD_FORK",
    "BAD_INTERNAL",
    "BAD_JOIN",
    "BAD_OUTCOME_NAME",
    "CHOICE_WITHOUT_ELSE",
    "COMPOSITION_CYCLE",
    "DECLARED_INVALID_LOCATION",
    "DUPLICATE_REGION_NAME",
    "ENTERS_INITIAL",
    "GENERALISATION_CYCLE",
    "INITIAL_LEAVES_REGION",
    "INPUT_MAYBE_UNSET",
    "INVALID_LOCATION",
    "LIVELOCK",
    "MISSING_CAPABILITY",
    "MISSING_PARAMETER",
    "MODEL_TOO_LARGE",
    "NEVER_ENDS",
    "NEVER_HANDLED",
    "NEVER_SENT",
    "NONDETERMINISM_UNDECIDED",
    "NONDETERMINISTIC",
    "NO_WAY_OUT",
    "OUTPUT_UNUSED",
    "PATH_TOO_LONG",
    "QT_ORDER",
    "RESERVED_FILE_NAME",
    "ROS_NAME_COLLISION",
    "SEVERAL_REFS",
    "SINGLE_BRANCH",
    "SUBMACHINE_WITH_REGIONS",
    "TOO_MANY_MEMBERS",
    "TYPE_ERROR",
    "UNEXPECTED_ELEMENT",
    "UNHANDLED_OUTCOME",
    "UNKNOWN_KIND",
    "UNKNOWN_LITERAL",
    "UNREACHABLE_STATE",
]
