"""The registry's codes of the ROS interface check (SG3xx): declared `rosType`s resolved against
interface definitions, and the behaviour's inputs and outputs checked against their fields.

Registered after `codes_checks`, in the same `CODES`, the same way.
"""

from __future__ import annotations

from swarmgen.diagnostics.codes import WARNING, M, register

_QUOTE = {
    "definition": "{type} {section}, as defined at {where}: {text}",
    "needed-by": "needed by behaviour '{behaviour}' at {where}",
    "searched": "searched, in order: {roots}",
}

ROS_TYPE_NOT_FOUND = register(
    "SG301",
    "ros-type-not-found",
    "a declared rosType is defined in no interface directory: the private interface is used",
    WARNING,
    message="rosType '{type}' of behaviour '{behaviour}' is not defined in any interface "
    "directory; the behaviour uses the generated private interface",
    hint="install the package, or pass --interfaces DIR with {path} (or put it in interfaces/ "
    "beside the model)",
    notes=_QUOTE,
)
ROS_TYPE_FORM = register(
    "SG302",
    "bad-ros-type",
    "a rosType that is not `pkg/action|srv|msg/Name` or `pkg/Name`",
    message="rosType '{text}' of behaviour '{behaviour}' is not `pkg/action/Name`, "
    "`pkg/srv/Name`, `pkg/msg/Name` or `pkg/Name`",
    hint="write the type as ROS names it, e.g. `std_srvs/srv/Trigger`",
)
BAD_INTERFACE = register(
    "SG303",
    "bad-interface-definition",
    "an interface definition a behaviour needs does not parse, nests itself or is incomplete",
    message="{error} (definition of {type})",
    hint="fix the definition file (the rosidl .msg/.srv/.action format)",
    variants={
        "recursive": M(
            "{type} contains itself: {error}",
            "a message cannot contain itself; use an array (`T[]`) of another type or an id",
        ),
        "too-deep": M("{type} nests message types {error} deep", "flatten the definitions"),
        "nested-missing": M(
            "the field type {type} is defined in no interface directory",
            "add {path} to an --interfaces directory, or install its package",
        ),
    },
    notes=_QUOTE,
)
ROS_KIND_MISMATCH = register(
    "SG304",
    "ros-kind-mismatch",
    "the declared rosType is of another kind than rosKind (an action type on a service)",
    message="behaviour '{behaviour}' has rosKind={ros_kind}, but {type} is a .{kind} definition",
    hint="set rosKind to {expected}, or name a {wanted} type",
    notes=_QUOTE,
)
ROS_UNKNOWN_FIELD = register(
    "SG305",
    "ros-unknown-field",
    "a behaviour input or output has no field of its name in the declared type",
    message="{side} '{name}' of behaviour '{behaviour}' has no field `{field}` in the {section} "
    "of {type}",
    hint="did you mean {suggestion}? (an input or output is matched to the field of its ros_name)",
    notes=_QUOTE,
)
ROS_FIELD_TYPE = register(
    "SG306",
    "ros-field-type",
    "a behaviour input or output cannot convert to or from its field's type",
    message="{side} '{name}' ({model_type}) of behaviour '{behaviour}' does not fit field "
    "`{field}` ({field_type}) of {type}: {detail}",
    hint="change the parameter's type to one that converts (docs/ros2.md, the mapping table)",
    notes=_QUOTE,
)
ROS_DATATYPE_UNMAPPED = register(
    "SG307",
    "ros-datatype-unmapped",
    "a data type does not map field by field to its message field: the private interface is used",
    WARNING,
    message="{side} '{name}' ({model_type}) of behaviour '{behaviour}' does not map to field "
    "`{field}` ({field_type}) of {type}: {detail}; the behaviour uses the generated private "
    "interface",
    hint="give the data type the message's fields (same names, converting types)",
    notes=_QUOTE,
)
ROS_TOPIC_DIRECTION = register(
    "SG308",
    "ros-topic-direction",
    "a topic behaviour with both inputs and outputs: neither publisher nor subscriber",
    message="topic behaviour '{behaviour}' has inputs and outputs; {type} is either published "
    "(inputs only) or subscribed to (outputs only)",
    hint="split it into a publishing and a subscribing behaviour",
    notes=_QUOTE,
)
ROS_TYPE_SHADOWED = register(
    "SG309",
    "ros-type-shadowed",
    "a type is defined differently in two interface directories; the first one is used",
    WARNING,
    message="{type} is defined differently in {others}; the definition in {used} is used",
    hint="remove one of the definitions, or make them equal",
)

__all__ = [
    "BAD_INTERFACE",
    "ROS_DATATYPE_UNMAPPED",
    "ROS_FIELD_TYPE",
    "ROS_KIND_MISMATCH",
    "ROS_TOPIC_DIRECTION",
    "ROS_TYPE_FORM",
    "ROS_TYPE_NOT_FOUND",
    "ROS_TYPE_SHADOWED",
    "ROS_UNKNOWN_FIELD",
]
