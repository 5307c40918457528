"""The expression and action language of guards, effects and behaviour argument bindings.

Guards are side-effect-free expressions (literals, member data names, ``event.<field>``,
comparisons, ``and``/``or``/``not``, arithmetic). Effects are one action per line:
``raise <event>(field = expr, ...)``, ``send <event>(field = expr, ...)`` or
``name = expression``. Bindings are one ``name = expression`` per line.

Model text is hostile input: it is parsed by a hand-written tokenizer and a precedence-climbing
parser (never ``eval`` nor Python's ``ast``), every identifier in the tree is validated, and the
renderers quote strings with the target language's own escaping, so neither a name nor a string
can inject code into the generated ECMAScript or Python.

The package's public face, used as ``from swarmgen import expr`` then ``expr.parse_expr``,
``expr.Binary``, ``expr.to_ecmascript``: the tree and its queries (``tree``), syntax errors
(``errors``), the tokenizer (``lex``), the parser (``parse``) and the renderings (``render``).
Modules of the package import one another directly, never through this file.
"""

from swarmgen.expr.errors import ExprError
from swarmgen.expr.parse import parse_bindings, parse_expr
from swarmgen.expr.render import event_text, js_string, to_ecmascript, to_python, to_text
from swarmgen.expr.rewrite import (
    action_exprs,
    event_fields,
    free_names,
    in_states,
    map_action,
    replace_fields,
    resolve_action_enums,
    resolve_enums,
    resolve_states,
    walk,
)
from swarmgen.expr.statements import parse_actions
from swarmgen.expr.tree import (
    EVENT_META,
    MAX_DEPTH,
    MAX_INT,
    MAX_TEXT,
    RESERVED,
    SYSTEM_VARIABLES,
    Action,
    Arg,
    Assign,
    Attr,
    Binary,
    Binding,
    Block,
    Branch,
    Cancel,
    Const,
    Delay,
    Done,
    Else,
    EventField,
    Expr,
    ForEach,
    If,
    InState,
    Invalid,
    ListOf,
    Log,
    Name,
    Raise,
    Send,
    StartsWith,
    System,
    Unary,
    Value,
    flat,
)

__all__ = [
    "EVENT_META",
    "MAX_DEPTH",
    "MAX_INT",
    "MAX_TEXT",
    "RESERVED",
    "SYSTEM_VARIABLES",
    "Action",
    "Arg",
    "Assign",
    "Attr",
    "Binary",
    "Binding",
    "Block",
    "Branch",
    "Cancel",
    "Const",
    "Delay",
    "Done",
    "Else",
    "EventField",
    "Expr",
    "ExprError",
    "ForEach",
    "If",
    "InState",
    "Invalid",
    "ListOf",
    "Log",
    "Name",
    "Raise",
    "Send",
    "StartsWith",
    "System",
    "Unary",
    "Value",
    "action_exprs",
    "event_fields",
    "event_text",
    "flat",
    "free_names",
    "in_states",
    "js_string",
    "map_action",
    "parse_actions",
    "parse_bindings",
    "parse_expr",
    "replace_fields",
    "resolve_action_enums",
    "resolve_enums",
    "resolve_states",
    "to_ecmascript",
    "to_python",
    "to_text",
    "walk",
]
